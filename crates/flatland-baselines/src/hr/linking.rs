//! The initial linking: one link per ordered pair of surface edges that can interact, counted
//! in O(1) memory or listed once for the refinement and the budget search to share.

use super::elements::{Surfaces, interacts};
use crate::BaselineError;
use flatland_geom::Kernel;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// One initial link: sender and receiver ordinals and their unoccluded transfer.
#[derive(Clone, Copy, Debug)]
pub(super) struct InitialLink {
    pub(super) sender: u32,
    pub(super) receiver: u32,
    pub(super) transfer: f64,
}

/// Every initial link, sorted by sender, then receiver.
#[derive(Clone, Debug)]
pub(super) struct InitialLinks {
    pub(super) links: Vec<InitialLink>,
}

impl InitialLinks {
    /// The initial links of `surfaces`, or the error naming how many are needed when that is
    /// more than `max_links` (counted first, so a refused scene allocates nothing per link).
    pub(super) fn within(surfaces: &Surfaces, max_links: usize) -> Result<Self, BaselineError> {
        count_within(surfaces, max_links as u64)?;
        let rows: Vec<Vec<InitialLink>> = (0..surfaces.len())
            .into_par_iter()
            .map(|i| {
                (0..surfaces.len())
                    .filter_map(|j| {
                        initial(surfaces, i, j).map(|transfer| InitialLink {
                            sender: i as u32,
                            receiver: j as u32,
                            transfer,
                        })
                    })
                    .collect()
            })
            .collect();
        Ok(InitialLinks {
            links: rows.concat(),
        })
    }

    pub(super) fn len(&self) -> usize {
        self.links.len()
    }
}

/// Whether ordered pair (i, j) gets an initial link, and its unoccluded transfer.
fn initial(surfaces: &Surfaces, i: usize, j: usize) -> Option<f64> {
    if i == j || surfaces.source_weight[i] <= 0.0 || surfaces.reflectance[j] <= 0.0 {
        return None;
    }
    let (p, q) = (surfaces.whole(i), surfaces.whole(j));
    let transfer = surfaces.transfer(&p, &q);
    interacts(transfer, &p, &q).then_some(transfer)
}

fn row_count(surfaces: &Surfaces, i: usize) -> u64 {
    (0..surfaces.len())
        .filter(|&j| initial(surfaces, i, j).is_some())
        .count() as u64
}

/// Scenes up to this many surface edges (16 · 10⁶ pairs, under a second) are always counted to
/// the end, so a refusal names the exact need; larger ones stop once past the limit.
const EXACT_COUNT_SURFACES: usize = 4096;

/// The number of initial links when at most `max`; otherwise the error naming the count.
fn count_within(surfaces: &Surfaces, max: u64) -> Result<u64, BaselineError> {
    count_stopping(surfaces, max, surfaces.len() > EXACT_COUNT_SURFACES)
}

/// [`count_within`], in O(n²) time in parallel; with `stop_early`, rows not yet counted are
/// skipped once the count is past `max`, and the error then says "at least".
fn count_stopping(surfaces: &Surfaces, max: u64, stop_early: bool) -> Result<u64, BaselineError> {
    let counted = AtomicU64::new(0);
    let rows_done = AtomicU64::new(0);
    (0..surfaces.len()).into_par_iter().for_each(|i| {
        if !stop_early || counted.load(Ordering::Relaxed) <= max {
            counted.fetch_add(row_count(surfaces, i), Ordering::Relaxed);
            rows_done.fetch_add(1, Ordering::Relaxed);
        }
    });
    let counted = counted.into_inner();
    if counted > max {
        return Err(BaselineError::InitialLinkingTooLarge {
            needed: counted,
            complete: rows_done.into_inner() == surfaces.len() as u64,
            surfaces: surfaces.len(),
            max_links: max as usize,
        });
    }
    Ok(counted)
}

/// The ordered surface-edge pairs HR links initially (see the `hr` module docs for the rule).
///
/// O(n²) time over the n surface edges, in parallel, and no memory per link: on `fig3`
/// subdivided ×1000 this is the paper's "10⁶ default basis functions" (R3).
pub fn count_initial_links(kernel: &Kernel) -> u64 {
    let surfaces = Surfaces::new(kernel);
    (0..surfaces.len())
        .into_par_iter()
        .map(|i| row_count(&surfaces, i))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{box_edges, box_kernel, kernel, surface};
    use crate::{HierarchicalRadiosity, HrParams};

    #[test]
    fn closed_box_links_twelve_ordered_pairs() {
        // Each wall of a convex room sees the three others, never itself.
        let kernel = box_kernel();
        assert_eq!(count_initial_links(&kernel), 12);
        // F_ε above every form factor: the initial links are the final ones.
        let hr = HierarchicalRadiosity::build(
            &kernel,
            &HrParams {
                f_eps: 2.0,
                ..HrParams::default()
            },
            1,
        )
        .unwrap();
        assert_eq!(hr.stats().initial_links, 12);
        assert_eq!(hr.stats().links, 12);
        assert_eq!(hr.links().len(), 12);
    }

    #[test]
    fn black_receivers_and_back_faces_are_not_linked() {
        let mut edges = box_edges();
        edges[2].reflectance = 0.0; // nothing reflects at the ceiling: no link into it
        assert_eq!(count_initial_links(&kernel(edges)), 12 - 3);
        // Two segments back to back cannot interact; face to face they do, both ways.
        let back = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([0.0, 1.0], [1.0, 1.0], 0.5, 0.0),
        ]);
        assert_eq!(count_initial_links(&back), 0);
        let facing = kernel(vec![
            surface([0.0, 0.0], [1.0, 0.0], 0.5, 1.0),
            surface([1.0, 1.0], [0.0, 1.0], 0.5, 0.0),
        ]);
        assert_eq!(count_initial_links(&facing), 2);
        // Pieces of one straight wall never link, however they were cut.
        let wall = kernel(vec![
            surface([0.0, 0.0], [0.1, 0.0], 0.5, 1.0),
            surface([0.1, 0.0], [0.7, 0.0], 0.5, 0.0),
            surface([0.7, 0.0], [1.0, 0.0], 0.5, 0.0),
        ]);
        assert_eq!(count_initial_links(&wall), 0);
    }

    #[test]
    fn subdividing_multiplies_initial_links() {
        // 4 walls of m pieces: each piece sees the 3m pieces of the other walls.
        let scene = box_kernel().scene().subdivide(10).unwrap();
        assert_eq!(count_initial_links(&Kernel::new(scene)), 40 * 30);
    }

    #[test]
    fn fig3_initial_links_scale_with_the_square_of_the_subdivision() {
        // fig3: six surface edges; the three ceiling pieces are collinear (the light among them),
        // so of the 30 ordered pairs 6 cannot interact. Every other pair faces fully, so
        // subdividing by m multiplies the count by m² (R3: ×1000 gives 24 · 10⁶).
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/fig3.ron");
        let scene = flatland_geom::Scene::load(path).unwrap();
        assert_eq!(count_initial_links(&Kernel::new(scene.clone())), 24);
        let scene = scene.subdivide(20).unwrap();
        assert_eq!(count_initial_links(&Kernel::new(scene)), 24 * 400);
    }

    #[test]
    fn the_list_matches_the_count_and_a_refusal_names_the_need() {
        let kernel = Kernel::new(box_kernel().scene().subdivide(10).unwrap());
        let surfaces = Surfaces::new(&kernel);
        let list = InitialLinks::within(&surfaces, 1200).unwrap();
        assert_eq!(list.len() as u64, count_initial_links(&kernel));
        assert!(
            list.links
                .windows(2)
                .all(|w| { (w[0].sender, w[0].receiver) < (w[1].sender, w[1].receiver) })
        );
        let err = InitialLinks::within(&surfaces, 1199)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("needs 1 200 links") && err.contains("`max_links` = 1 199"),
            "{err}"
        );
    }
}
