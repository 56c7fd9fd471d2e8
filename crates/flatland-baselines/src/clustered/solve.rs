//! Clustered HR's transfer operator on a mesh, applied matrix-free by pull, gather and push
//! over its hierarchy: memory linear in the links, the nodes and the elements.

use super::clusters::{Hierarchy, Kind, NONE};
use flatland_solve::{Mesh, TransferOperator};

/// How a node reads and writes the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Access {
    /// A cluster: its children hold everything.
    Cluster { first_child: u32 },
    /// An element: `∫ B` over its interval from the prefix sums, `(element, arc length
    /// into it)` at both ends; and, if it has no children, the collocation points under it.
    Element {
        from: (u32, f64),
        to: (u32, f64),
        first_child: u32,
        points: (u32, u32),
    },
}

/// One link as the operator applies it: `H(q) += g · ∫_p B`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Gather {
    pub(super) p: u32,
    pub(super) q: u32,
    pub(super) g: f64,
}

/// `(K b)_i = ρ_i · Σ_{links (P, Q), Q ∋ y_i} g · ∫_P b`: for every node, its `∫ B` is pulled
/// up from the elements (prefix sums) through the clusters; each link gathers into its
/// receiver; what a node gathered is pushed down to the collocation points under it.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct ClusterOperator {
    access: Vec<Access>,
    links: Vec<Gather>,
    lengths: Vec<f64>,
    rho: Vec<f64>,
}

impl ClusterOperator {
    pub(super) fn new(h: &Hierarchy, links: Vec<Gather>, mesh: &Mesh) -> ClusterOperator {
        let els = mesh.elements();
        let l = mesh.total_length();
        let starts: Vec<f64> = els.iter().map(|e| e.s[0]).collect();
        let mids: Vec<f64> = els.iter().map(|e| e.s_mid).collect();
        let locate = |s: f64| {
            let e = starts.partition_point(|&s0| s0 <= s).saturating_sub(1);
            (e as u32, ((s - starts[e]) * l).clamp(0.0, els[e].length))
        };
        let access = h
            .nodes
            .iter()
            .map(|node| match node.kind {
                Kind::Cluster { .. } => Access::Cluster {
                    first_child: node.first_child,
                },
                Kind::Element(e) => Access::Element {
                    from: locate(e.s0),
                    to: locate(e.s1),
                    first_child: node.first_child,
                    points: (
                        mids.partition_point(|&m| m < e.s0) as u32,
                        mids.partition_point(|&m| m < e.s1) as u32,
                    ),
                },
            })
            .collect();
        ClusterOperator {
            access,
            links,
            lengths: els.iter().map(|e| e.length).collect(),
            rho: (0..mesh.len())
                .map(|i| mesh.edge_of(i).reflectance)
                .collect(),
        }
    }

    /// `∫ B` over every node: elements from the prefix sums, clusters from their children
    /// (which come after them).
    fn pull(&self, b: &[f64]) -> Vec<f64> {
        let mut prefix = Vec::with_capacity(b.len() + 1);
        prefix.push(0.0);
        for (bi, li) in b.iter().zip(&self.lengths) {
            prefix.push(prefix.last().copied().unwrap_or(0.0) + bi * li);
        }
        let integral = |(e, offset): (u32, f64)| prefix[e as usize] + b[e as usize] * offset;
        let mut pulled = vec![0.0; self.access.len()];
        for (i, access) in self.access.iter().enumerate().rev() {
            pulled[i] = match *access {
                Access::Element { from, to, .. } => integral(to) - integral(from),
                Access::Cluster { first_child } => {
                    pulled[first_child as usize] + pulled[first_child as usize + 1]
                }
            };
        }
        pulled
    }

    /// What the nodes gathered, carried down to the collocation points.
    fn push(&self, mut gathered: Vec<f64>, out: &mut [f64]) {
        let mut diff = vec![0.0; out.len() + 1];
        for i in 0..self.access.len() {
            let h = gathered[i];
            let first_child = match self.access[i] {
                Access::Cluster { first_child } => first_child,
                Access::Element {
                    first_child,
                    points,
                    ..
                } => {
                    if first_child == NONE {
                        diff[points.0 as usize] += h;
                        diff[points.1 as usize] -= h;
                    }
                    first_child
                }
            };
            if first_child != NONE && h != 0.0 {
                gathered[first_child as usize] += h;
                gathered[first_child as usize + 1] += h;
            }
        }
        let mut running = 0.0;
        for ((o, d), rho) in out.iter_mut().zip(&diff).zip(&self.rho) {
            running += d;
            *o = rho * running;
        }
    }
}

impl TransferOperator for ClusterOperator {
    fn len(&self) -> usize {
        self.lengths.len()
    }

    fn apply(&self, b: &[f64], out: &mut [f64]) {
        let pulled = self.pull(b);
        let mut gathered = vec![0.0; self.access.len()];
        for link in &self.links {
            gathered[link.q as usize] += link.g * pulled[link.p as usize];
        }
        self.push(gathered, out);
    }
}

#[cfg(test)]
mod tests {
    use crate::test_support::{blocker_kernel, kernel};
    use crate::{ClusteredParams, ClusteredRadiosity};
    use flatland_geom::{DVec2, Edge, Kernel};
    use flatland_solve::{
        DenseOperator, ExactReference, Mesh, Representation, SolveParams, never, solve,
        solve_errors, solve_operator,
    };

    fn build(kernel: &Kernel, budget: usize, seed: u64) -> ClusteredRadiosity {
        ClusteredRadiosity::build(kernel, budget, &ClusteredParams::default(), seed).unwrap()
    }

    #[test]
    fn push_pull_equals_brute_force_integration_of_its_own_zeta() {
        // K_ij = ∫_{element j} ζ̃(s, t_i) / E' L ds by dense midpoint sampling of ζ̃ (which jumps
        // where a link ends inside an element: sampling error below jump / samples).
        let kernel = Kernel::new(flatland_geom::bundled::scene("fig3").unwrap());
        let mesh = Mesh::new(&kernel, 60).unwrap();
        let params = SolveParams::default();
        for budget in [5, 60, 600] {
            let rep = build(&kernel, budget, 2);
            let fast = solve(&rep, &mesh, &params, &never).unwrap();
            let els = mesh.elements();
            let samples = 2000;
            let brute = DenseOperator::assemble(
                mesh.len(),
                |i, row| {
                    for (j, e) in els.iter().enumerate() {
                        let sum: f64 = (0..samples)
                            .map(|q| {
                                let s =
                                    e.s[0] + (e.s[1] - e.s[0]) * (q as f64 + 0.5) / samples as f64;
                                rep.zeta(s, els[i].s_mid)
                            })
                            .sum();
                        row[j] = sum / samples as f64 * e.length / mesh.edge_of(j).source_weight;
                    }
                },
                &never,
            )
            .unwrap();
            let slow = solve_operator(&brute, &mesh, &params, &never).unwrap();
            let e = solve_errors(&mesh, &fast.radiosity, &slow.radiosity);
            assert!(e.rel_l2_reflected < 2e-3, "budget {budget}: {e:?}");
        }
    }

    /// A closed square room, every wall of reflectance `rho` and emission 1, cut into `m`
    /// pieces per wall.
    fn uniform_room(rho: f64, m: usize) -> Kernel {
        let p = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(x, y)| DVec2::new(x, y));
        let mut edges = Vec::new();
        for k in 0..4 {
            let (a, b) = (p[k], p[(k + 1) % 4]);
            for piece in 0..m {
                let u = |i: usize| a + (b - a) * (i as f64 / m as f64);
                edges.push(Edge::surface(u(piece), u(piece + 1), rho).with_emission(1.0));
            }
        }
        kernel(edges)
    }

    #[test]
    fn a_closed_uniform_room_reaches_e_over_one_minus_rho() {
        // Every point of the closed room gathers ρ of what the room sends: B = E / (1 − ρ) = 2.
        // A link gives each receiver its receiver element's mean irradiance, so where links
        // of one point end in elements of unequal sizes B spreads around 2, and its mean moves
        // only as far as that spread weighs senders unequally (within 1 %). Refined as far as
        // it goes, every link joins two elements of the minimum length with their exact
        // unoccluded mean, and B is 2 everywhere.
        let kernel = uniform_room(0.5, 3);
        let mesh = Mesh::new(&kernel, 96).unwrap();
        let total: f64 = mesh.elements().iter().map(|e| e.length).sum();
        let coarse = ClusteredParams {
            min_length: 0.25,
            ..ClusteredParams::default()
        };
        for (budget, params) in [
            (30, ClusteredParams::default()),
            (300, coarse),
            (100_000, coarse),
        ] {
            let rep = ClusteredRadiosity::build(&kernel, budget, &params, 1).unwrap();
            let b = solve(&rep, &mesh, &SolveParams::default(), &never)
                .unwrap()
                .radiosity;
            let mean: f64 = b
                .iter()
                .zip(mesh.elements())
                .map(|(v, e)| v * e.length)
                .sum::<f64>()
                / total;
            assert!((mean - 2.0).abs() < 0.02, "budget {budget}: mean {mean}");
            let spread = b.iter().map(|v| (v - 2.0).abs()).fold(0.0, f64::max);
            if rep.stats().finest {
                assert!(spread < 1e-8, "{spread}, {:?}", rep.stats());
                assert_eq!(rep.stats().cluster_links, 0, "{:?}", rep.stats());
            } else {
                assert!(
                    budget < 1000 && spread > 1e-3,
                    "{spread}, {:?}",
                    rep.stats()
                );
            }
        }
    }

    #[test]
    fn emitted_power_is_absorbed_and_radiosity_is_never_negative() {
        // The closed box with one light: the power its walls absorb, ∫ (1 − ρ)(B − E)/ρ, is the
        // power emitted, ∫ E, within what the cluster links' sampling leaves.
        let kernel = kernel(crate::test_support::box_edges());
        let mesh = Mesh::new(&kernel, 128).unwrap();
        for (budget, tolerance) in [(50, 0.1), (500, 0.02), (5000, 0.005)] {
            let rep = build(&kernel, budget, 3);
            let b = solve(&rep, &mesh, &SolveParams::default(), &never)
                .unwrap()
                .radiosity;
            assert!(b.iter().all(|&v| v >= 0.0), "budget {budget}");
            let (mut emitted, mut absorbed) = (0.0, 0.0);
            for (i, e) in mesh.elements().iter().enumerate() {
                let edge = mesh.edge_of(i);
                emitted += edge.emission * e.length;
                absorbed +=
                    (1.0 - edge.reflectance) * (b[i] - edge.emission) / edge.reflectance * e.length;
            }
            let off = (absorbed - emitted).abs() / emitted;
            assert!(off < tolerance, "budget {budget}: {absorbed} vs {emitted}");
        }
        // With a blocker in the room (which absorbs too), B stays non-negative at every budget.
        let kernel = blocker_kernel();
        for budget in [1, 7, 70, 700] {
            let b = solve(
                &build(&kernel, budget, 5),
                &mesh_of(&kernel),
                &SolveParams::default(),
                &never,
            )
            .unwrap()
            .radiosity;
            assert!(b.iter().all(|&v| v >= 0.0), "budget {budget}");
        }
    }

    fn mesh_of(kernel: &Kernel) -> Mesh {
        Mesh::new(kernel, 128).unwrap()
    }

    #[test]
    fn the_error_falls_towards_the_exact_solve_as_the_budget_grows() {
        let params = SolveParams::default();
        for name in ["fig3", "maze"] {
            let kernel = Kernel::new(flatland_geom::bundled::scene(name).unwrap());
            let mesh = Mesh::new(&kernel, 256).unwrap();
            let truth = ExactReference::new(&kernel, 1024, &params, &never)
                .unwrap()
                .radiosity_on(&mesh, &never)
                .unwrap();
            let mut errors = Vec::new();
            for budget in [300, 3_000, 30_000] {
                let b = solve(&build(&kernel, budget, 1), &mesh, &params, &never)
                    .unwrap()
                    .radiosity;
                errors.push(solve_errors(&mesh, &b, &truth).rel_l2_reflected);
            }
            println!("{name}: {errors:?}");
            assert!(errors.windows(2).all(|w| w[1] < w[0]), "{name}: {errors:?}");
            assert!(errors[2] < 0.05, "{name}: {errors:?}");
        }
    }
}
