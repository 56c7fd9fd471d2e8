//! One trait for every kernel representation a solver can use, and its four implementations.

use flatland_geom::Kernel;

use super::TransferOperator;
use super::exact::exact_operator;
use super::quadrature::gauss_legendre;
use super::{DenseOperator, KernelRectangle, Mesh, RectangleOperator, SolveParams, Stop};
use crate::baselines::{BlockValue, HierarchicalRadiosity, UniformGrid};
use crate::{Approximation, FitError, LearnedKernel};

/// A kernel representation the radiosity solver can use: the exact kernel, the learned model,
/// hierarchical radiosity, the uniform grid, or anything else that approximates the learning
/// target `ζ(s, t) = E'(sender edge) · k(s, t)`.
///
/// The solver needs one thing of it: the discrete operator on a [`Mesh`]
/// ([`KernelRepresentation::operator`]). The default builds it from [`zeta`] alone: `E'` is
/// constant per edge, so `k̃ = ζ̃ / E'` is an exact division, and
/// `K_ij = ∫_{element j} k̃(s, t_i) L ds` by Gauss–Legendre quadrature
/// ([`quadrature_operator`]). A representation that knows more overrides `operator`:
///
/// - the exact kernel uses the closed-form point-to-segment transfer and exact visible
///   intervals ([`exact_operator`](super::exact_operator));
/// - HR and the uniform grid are constant on rectangles of `(s, t)` and apply their links
///   directly, gathering and pushing–pulling ([`RectangleOperator`]);
/// - the default learned model keeps the geometry exact and learns only the visibility `Ṽ`:
///   the closed form on each piece of an element between faces, times that face's `Ṽ`.
///
/// [`zeta`]: KernelRepresentation::zeta
pub trait KernelRepresentation: Sync {
    /// ζ̃(s, t), the approximated learning target (s = sender, t = receiver).
    fn zeta(&self, s: f64, t: f64) -> f64;

    /// Number of basis functions it holds (cells, links, blocks); `None` for the exact kernel.
    fn basis_functions(&self) -> Option<usize>;

    /// `Scene::fingerprint` of the scene it represents, when it knows it (so a mesh of another
    /// scene is refused).
    fn scene_fingerprint(&self) -> Option<u64> {
        None
    }

    /// The discrete operator on `mesh`. Default: [`quadrature_operator`] with
    /// `params.quadrature_points` points per element. Override it with anything faster or more
    /// exact; `stop` must be polled in long loops.
    fn operator(
        &self,
        mesh: &Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, FitError> {
        check_fingerprint(self.scene_fingerprint(), mesh)?;
        Ok(Box::new(quadrature_operator(
            self,
            mesh,
            params.quadrature_points,
            stop,
        )?))
    }
}

fn check_fingerprint(fingerprint: Option<u64>, mesh: &Mesh) -> Result<(), FitError> {
    match fingerprint {
        Some(f) if f != mesh.fingerprint() => Err(FitError::SceneMismatch {
            representation: format!("{f:016x}"),
            mesh: format!("{:016x}", mesh.fingerprint()),
        }),
        _ => Ok(()),
    }
}

/// Every edge's `1 / E'`, or the error naming the first edge whose `E'` is 0 (there `ζ ≡ 0`
/// and `k` cannot be recovered from an approximation of ζ).
pub fn inverse_source_weights(mesh: &Mesh) -> Result<Vec<f64>, FitError> {
    mesh.edges()
        .iter()
        .map(|e| {
            if e.source_weight > 0.0 && e.source_weight.is_finite() {
                Ok(1.0 / e.source_weight)
            } else {
                Err(FitError::ZeroSourceWeight {
                    edge: e.pieces.start,
                })
            }
        })
        .collect()
}

/// `K_ij = ∫_{element j} ζ̃(s, t_i) / E'_j · L ds` by `points`-point Gauss–Legendre per element,
/// `t_i` element i's midpoint: the generic operator of any representation of ζ. Rows in
/// parallel; `rep.zeta` is called `N² · points` times and no ray is cast.
pub fn quadrature_operator<R: KernelRepresentation + ?Sized>(
    rep: &R,
    mesh: &Mesh,
    points: usize,
    stop: &Stop,
) -> Result<DenseOperator, FitError> {
    if !(1..=16).contains(&points) {
        return Err(FitError::InvalidParameter {
            name: "quadrature_points",
            value: points.to_string(),
            valid: "in [1, 16]",
        });
    }
    let inverse = inverse_source_weights(mesh)?;
    let (nodes, weights) = gauss_legendre(points);
    let els = mesh.elements();
    DenseOperator::assemble(
        mesh.len(),
        |i, row| {
            let t = els[i].s_mid;
            for (j, (out, e)) in row.iter_mut().zip(els).enumerate() {
                let (half, mid) = (0.5 * (e.s[1] - e.s[0]), 0.5 * (e.s[0] + e.s[1]));
                let sum: f64 = nodes
                    .iter()
                    .zip(&weights)
                    .map(|(x, w)| w * rep.zeta(mid + half * x, t))
                    .sum();
                // ∫ over the element in arc length: (length / 2) Σ w ζ̃.
                *out = 0.5 * els[j].length * sum * inverse[e.mesh_edge];
            }
        },
        stop,
    )
}

impl KernelRepresentation for Kernel {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        Kernel::zeta(self, s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        None
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        Some(self.scene().fingerprint())
    }

    /// The exact operator: closed form and exact visible intervals, no rays.
    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, FitError> {
        Ok(Box::new(exact_operator(self, mesh, stop)?))
    }
}

/// The learned model. A visibility model (the default learner) integrates its own `Ṽ` exactly
/// against the closed-form transfer, asking `Ṽ` once per face (the `learned` module); the paper's
/// network, which learns ζ itself, uses the quadrature default.
impl KernelRepresentation for LearnedKernel {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        Approximation::zeta(self, s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(Approximation::basis_functions(self))
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        Some(self.scene().fingerprint())
    }

    fn operator(
        &self,
        mesh: &Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, FitError> {
        check_fingerprint(self.scene_fingerprint(), mesh)?;
        match self.geometry_kernel() {
            Some(kernel) => Ok(Box::new(super::learned::visibility_operator(
                self, kernel, mesh, stop,
            )?)),
            None => Ok(Box::new(quadrature_operator(
                self,
                mesh,
                params.quadrature_points,
                stop,
            )?)),
        }
    }
}

/// HR: its own links, each a rectangle of constant `ζ̃ / E'(sender edge)` (links never straddle
/// an edge), applied by gather and push–pull ([`RectangleOperator`]).
impl KernelRepresentation for HierarchicalRadiosity {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        Approximation::zeta(self, s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(Approximation::basis_functions(self))
    }

    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, FitError> {
        let inverse = inverse_source_weights(mesh)?;
        if stop() {
            return Err(FitError::Interrupted);
        }
        let rectangles = self.links().into_iter().map(|link| {
            let sender = mesh.elements()[mesh.element_at(0.5 * (link.s[0] + link.s[1]))];
            KernelRectangle {
                s: link.s,
                t: link.t,
                k: link.value * inverse[sender.mesh_edge],
            }
        });
        Ok(Box::new(RectangleOperator::new(mesh, rectangles)))
    }
}

/// The uniform grid: each block is a rectangle. Blocks of ζ are split where they straddle a
/// sender edge (each part divided by its own E'); blocks of k ([`BlockValue::ExactKernelMean`])
/// are used as they are.
impl KernelRepresentation for UniformGrid {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        Approximation::zeta(self, s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(Approximation::basis_functions(self))
    }

    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, FitError> {
        let g = self.g();
        let of_k = self.block_value() == BlockValue::ExactKernelMean;
        let inverse = if of_k {
            vec![1.0; mesh.edges().len()]
        } else {
            inverse_source_weights(mesh)?
        };
        if stop() {
            return Err(FitError::Interrupted);
        }
        let mut rectangles = Vec::with_capacity(g * g * 2);
        for i in 0..g {
            let s = [i as f64 / g as f64, (i + 1) as f64 / g as f64];
            for (k, edge) in mesh.edges().iter().enumerate() {
                let part = [s[0].max(edge.s[0]), s[1].min(edge.s[1])];
                if part[1] <= part[0] {
                    continue;
                }
                for j in 0..g {
                    rectangles.push(KernelRectangle {
                        s: part,
                        t: [j as f64 / g as f64, (j + 1) as f64 / g as f64],
                        k: self.values()[i * g + j] * inverse[k],
                    });
                }
            }
        }
        Ok(Box::new(RectangleOperator::new(mesh, rectangles)))
    }
}
