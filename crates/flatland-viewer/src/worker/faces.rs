//! Which of the network's edges join cells of one face: the only edges the overlay draws.
//!
//! The visibility network files every cell under one face of the visibility structure, and a cell
//! answers only rays of its own face; the network's other edges (its simplices span faces)
//! join cells that never answer the same ray, and drawn they are a web across the plot. The
//! face of a cell is asked at its re-projected `(s, t)` ([`LearnedKernel::face_cells`]), once
//! per face: the answer names every cell of that face. A network without faces (the paper's,
//! learning ζ) is grouped by the pair of surface edges its cells' `(s, t)` lie on instead.

use std::collections::HashMap;

use kernel_fit::{LearnedKernel, Target};

/// The group of each cell: cells of one face share a number; `None` where it is not known (a
/// cell that never won a sample, or whose mean `(s, t)` lies outside its own face).
#[must_use]
pub fn cell_groups(model: &LearnedKernel, st: &[Option<[f64; 2]>]) -> Vec<Option<u32>> {
    let mut groups = vec![None; st.len()];
    if model.target() == Target::Visibility {
        let mut next = 0;
        for (c, at) in st.iter().enumerate() {
            let (None, Some([s, t])) = (groups[c], at) else {
                continue;
            };
            let Some(cells) = model.face_cells(*s, *t) else {
                continue;
            };
            if !cells.contains(&c) {
                continue; // its mean lies in another face: that face's own cells will say
            }
            for other in cells {
                if let Some(g) = groups.get_mut(other) {
                    *g = Some(next);
                }
            }
            next += 1;
        }
    } else {
        let scene = model.scene();
        let mut pairs = HashMap::new();
        for (c, at) in st.iter().enumerate() {
            if let Some([s, t]) = at {
                let pair = (scene.point(*s).edge, scene.point(*t).edge);
                let next = pairs.len() as u32;
                groups[c] = Some(*pairs.entry(pair).or_insert(next));
            }
        }
    }
    groups
}

/// The edges whose two cells share a group.
#[must_use]
pub fn face_edges(edges: &[(usize, usize)], groups: &[Option<u32>]) -> Vec<[u32; 2]> {
    edges
        .iter()
        .filter(|&&(a, b)| {
            matches!((groups.get(a), groups.get(b)), (Some(Some(x)), Some(Some(y))) if x == y)
        })
        .map(|&(a, b)| [a as u32, b as u32])
        .collect()
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use flatland_geom::Kernel;
    use flatland_solve::Reference;
    use kernel_fit::{Fit, FitParams};

    use super::*;

    fn grown(params: FitParams, steps: usize) -> Fit {
        let kernel = Arc::new(Kernel::new(flatland_geom::bundled::scene("fig3").unwrap()));
        let reference = Arc::new(Reference::new(&kernel, 16, 64, 1));
        let mut fit = Fit::new(kernel, reference, params).unwrap();
        for _ in 0..steps {
            if fit.step().is_some() {
                break;
            }
        }
        fit
    }

    #[test]
    fn only_edges_within_one_face_are_kept_and_every_kept_pair_is_one_face() {
        // Grown to the end (exact after about 17 000 steps): early on every cell has a face of
        // its own, later some faces get more.
        let fit = grown(FitParams::default(), 30_000);
        let model = fit.model();
        let st = fit.cell_st();
        let groups = cell_groups(model, &st);
        let edges = fit.network().edges();
        let kept = face_edges(&edges, &groups);
        assert!(!kept.is_empty(), "some cells share a face");
        assert!(kept.len() < edges.len(), "edges across faces are dropped");
        for [a, b] in &kept {
            let [s, t] = st[*a as usize].unwrap();
            let face = model.face_cells(s, t).unwrap();
            assert!(
                face.contains(&(*a as usize)) && face.contains(&(*b as usize)),
                "{a} and {b} are cells of one face"
            );
        }
    }

    #[test]
    fn the_paper_network_is_grouped_by_pairs_of_surface_edges() {
        let fit = grown(FitParams::paper(), 3000);
        let model = fit.model();
        let st = fit.cell_st();
        let groups = cell_groups(model, &st);
        let scene = model.scene();
        for (a, ga) in groups.iter().enumerate() {
            for (b, gb) in groups.iter().enumerate() {
                if let (Some(x), Some(y)) = (ga, gb) {
                    let pair = |c: usize| {
                        let [s, t] = st[c].unwrap();
                        (scene.point(s).edge, scene.point(t).edge)
                    };
                    assert_eq!(x == y, pair(a) == pair(b));
                }
            }
        }
        assert_eq!(
            face_edges(&[(0, 1)], &[Some(3), None]),
            Vec::<[u32; 2]>::new()
        );
        assert_eq!(face_edges(&[(0, 1)], &[Some(3), Some(3)]), vec![[0, 1]]);
    }
}
