//! Clusters of elements: the leaves of a spatial tree of their midpoints, each at most a given
//! number of elements. In a floor plan a leaf is a room or a few walls of one, so the light a
//! cluster sends on (a block of columns of M₂) reaches only the rooms around it.

use flatland_solve::Mesh;

/// The elements split into clusters.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Clusters {
    /// Each cluster's elements, ascending.
    pub members: Vec<Vec<u32>>,
    /// Per element: its cluster and its place in that cluster's list.
    pub place: Vec<(u32, u32)>,
}

impl Clusters {
    /// The leaves of a k-d tree of `mesh`'s midpoints, halved at the median of the longer side
    /// of their box until each holds at most `largest` elements. Ties are broken by element
    /// index, so the clusters are the same on every machine.
    pub fn spatial(mesh: &Mesh, largest: usize) -> Clusters {
        let points: Vec<[f64; 2]> = (0..mesh.len())
            .map(|i| {
                let m = mesh.local(i)[2];
                [m.x, m.y]
            })
            .collect();
        let mut order: Vec<u32> = (0..mesh.len() as u32).collect();
        let mut members = Vec::new();
        split(&points, &mut order, largest.max(1), &mut members);
        Clusters::from_members(members, mesh.len())
    }

    /// Like [`Clusters::spatial`], but first by the way elements face (four quadrants of the
    /// normal's direction), so a cluster never holds both faces of a wall.
    pub fn facing(mesh: &Mesh, largest: usize) -> Clusters {
        let points: Vec<[f64; 2]> = (0..mesh.len())
            .map(|i| {
                let m = mesh.local(i)[2];
                [m.x, m.y]
            })
            .collect();
        let quadrant = |i: usize| {
            let n = mesh.edge_of(i).normal;
            let angle = n.y.atan2(n.x) + std::f64::consts::FRAC_PI_4;
            (angle.rem_euclid(std::f64::consts::TAU) / std::f64::consts::FRAC_PI_2) as usize % 4
        };
        let mut members = Vec::new();
        for side in 0..4 {
            let mut order: Vec<u32> = (0..mesh.len() as u32)
                .filter(|&i| quadrant(i as usize) == side)
                .collect();
            split(&points, &mut order, largest.max(1), &mut members);
        }
        Clusters::from_members(members, mesh.len())
    }

    /// Clusters with the given members (each element in exactly one).
    pub fn from_members(mut members: Vec<Vec<u32>>, n: usize) -> Clusters {
        let mut place = vec![(u32::MAX, u32::MAX); n];
        for (c, list) in members.iter_mut().enumerate() {
            list.sort_unstable();
            for (k, &e) in list.iter().enumerate() {
                place[e as usize] = (c as u32, k as u32);
            }
        }
        debug_assert!(place.iter().all(|p| p.0 != u32::MAX));
        Clusters { members, place }
    }
}

/// Splits `order` (element indices) recursively into leaves of at most `largest`.
fn split(points: &[[f64; 2]], order: &mut [u32], largest: usize, out: &mut Vec<Vec<u32>>) {
    if order.len() <= largest {
        if !order.is_empty() {
            out.push(order.to_vec());
        }
        return;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &e in order.iter() {
        for d in 0..2 {
            lo[d] = lo[d].min(points[e as usize][d]);
            hi[d] = hi[d].max(points[e as usize][d]);
        }
    }
    let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
    order.sort_unstable_by(|&a, &b| {
        points[a as usize][axis]
            .total_cmp(&points[b as usize][axis])
            .then(a.cmp(&b))
    });
    let (left, right) = order.split_at_mut(order.len() / 2);
    split(points, left, largest, out);
    split(points, right, largest, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::Kernel;

    #[test]
    fn every_element_is_in_one_cluster_of_at_most_the_size() {
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(400, 2).unwrap());
        let mesh = Mesh::new(&kernel, 1500).unwrap();
        let clusters = Clusters::spatial(&mesh, 40);
        let mut count = vec![0; mesh.len()];
        for (c, list) in clusters.members.iter().enumerate() {
            assert!(
                !list.is_empty() && list.len() <= 40,
                "cluster {c}: {}",
                list.len()
            );
            for (k, &e) in list.iter().enumerate() {
                count[e as usize] += 1;
                assert_eq!(clusters.place[e as usize], (c as u32, k as u32));
            }
        }
        assert!(count.iter().all(|&c| c == 1));
        assert!(clusters.members.len() >= mesh.len() / 40);
        assert_eq!(clusters, Clusters::spatial(&mesh, 40));
        // Facing clusters never mix opposite faces.
        let facing = Clusters::facing(&mesh, 40);
        for list in &facing.members {
            let first = mesh.edge_of(list[0] as usize).normal;
            assert!(
                list.iter()
                    .all(|&e| mesh.edge_of(e as usize).normal.dot(first) > 0.0)
            );
        }
    }
}
