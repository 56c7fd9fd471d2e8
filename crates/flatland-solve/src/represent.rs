//! The one trait every representation of the kernel implements (the exact kernel here; the
//! learned model and the baselines in their crates), and the generic operator of any of them.

use flatland_geom::{EdgeId, Kernel};

use crate::exact::exact_operator;
use crate::physical::make_physical;
use crate::quadrature::gauss_legendre;
use crate::{
    DenseOperator, ExactMethod, Mesh, SolveError, SolveParams, Stop, TransferOperator,
    sweep_operator,
};

/// A representation of the kernel: the exact kernel, the learned model, hierarchical
/// radiosity, the uniform grid, or anything else that approximates the learning target
/// `ζ(s, t) = E'(sender edge) · k(s, t)` over `[0, 1)²`. Errors ([`Reference::errors`]) and
/// solves ([`solve`]) take any of them.
///
/// The solver needs one thing of it: the discrete operator on a [`Mesh`]
/// ([`Representation::operator`]). The default builds it from [`zeta`] alone: `E'` is
/// constant per edge, so `k̃ = ζ̃ / E'` is an exact division, and
/// `K_ij = ∫_{element j} k̃(s, t_i) L ds` by Gauss–Legendre quadrature
/// ([`quadrature_operator`]). A representation that knows more overrides `operator`:
///
/// - the exact kernel uses the closed-form point-to-segment transfer and exact visible
///   intervals ([`exact_operator`], or [`sweep_operator`] on large scenes);
/// - HR and the uniform grid are constant on rectangles of `(s, t)` and apply their links
///   directly, gathering and pushing–pulling ([`RectangleOperator`](crate::RectangleOperator));
/// - the default learned model keeps the geometry exact and learns only the visibility `Ṽ`:
///   the closed form on each piece of an element between faces, times that face's `Ṽ`.
///
/// [`zeta`]: Representation::zeta
/// [`Reference::errors`]: crate::Reference::errors
/// [`solve`]: crate::solve
pub trait Representation: Sync {
    /// ζ̃(s, t), the approximated learning target (s = sender, t = receiver).
    fn zeta(&self, s: f64, t: f64) -> f64;

    /// Number of basis functions it holds (cells, links, blocks); `None` for the exact kernel.
    fn basis_functions(&self) -> Option<usize>;

    /// Bytes the representation needs in memory (its payload, not allocator slack).
    fn memory_bytes(&self) -> usize;

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
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        check_fingerprint(self.scene_fingerprint(), mesh)?;
        Ok(Box::new(quadrature_operator(
            self,
            mesh,
            params.quadrature_points,
            stop,
        )?))
    }
}

/// Refuses a mesh of another scene than the one a representation says it represents
/// ([`Representation::scene_fingerprint`]; `None` passes).
pub fn check_fingerprint(fingerprint: Option<u64>, mesh: &Mesh) -> Result<(), SolveError> {
    match fingerprint {
        Some(f) if f != mesh.fingerprint() => Err(SolveError::SceneMismatch {
            representation: format!("{f:016x}"),
            mesh: format!("{:016x}", mesh.fingerprint()),
        }),
        _ => Ok(()),
    }
}

/// Refuses a representation of `ζ = E' k` learned under `lights` on a mesh of other lamps:
/// `E'` depends on the lamps (docs/ALGORITHM.md §2), so `ζ̃ / E'` would not be `k`.
pub fn check_lights(lights: &[flatland_geom::PointLight], mesh: &Mesh) -> Result<(), SolveError> {
    if lights == mesh.lights() {
        return Ok(());
    }
    Err(SolveError::LightsMismatch {
        representation: lights.len(),
        mesh: mesh.lights().len(),
    })
}

/// Every edge's `1 / E'`, or the error naming the first edge whose `E'` is 0 (there `ζ ≡ 0`
/// and `k` cannot be recovered from an approximation of ζ).
pub fn inverse_source_weights(mesh: &Mesh) -> Result<Vec<f64>, SolveError> {
    mesh.edges()
        .iter()
        .map(|e| {
            if e.source_weight > 0.0 && e.source_weight.is_finite() {
                Ok(1.0 / e.source_weight)
            } else {
                Err(SolveError::ZeroSourceWeight {
                    edge: EdgeId::new(e.pieces.start),
                })
            }
        })
        .collect()
}

/// `K_ij = ∫_{element j} ζ̃(s, t_i) / E'_j · L ds` by `points`-point Gauss–Legendre per element,
/// `t_i` element i's midpoint: the generic operator of any representation of ζ. Rows in
/// parallel; `rep.zeta` is called `N² · points` times and no ray is cast. Each row is made
/// physical ([`make_physical`]: entries ≥ 0, sum at most `ρ_i`), whatever ζ̃ is: a network's
/// Gaussian sum can overshoot the kernel or go negative.
pub fn quadrature_operator<R: Representation + ?Sized>(
    rep: &R,
    mesh: &Mesh,
    points: usize,
    stop: &Stop,
) -> Result<DenseOperator, SolveError> {
    if !(1..=16).contains(&points) {
        return Err(SolveError::InvalidParameter {
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
            make_physical(row, mesh.edge_of(i).reflectance);
        },
        stop,
    )
}

/// A shared representation is the representation: what a command holds in an `Arc` (the
/// scene's kernel, a fit shared with a thread) is solved without a copy.
impl<T: Representation + Send + ?Sized> Representation for std::sync::Arc<T> {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        (**self).zeta(s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        (**self).basis_functions()
    }

    fn memory_bytes(&self) -> usize {
        (**self).memory_bytes()
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        (**self).scene_fingerprint()
    }

    fn operator(
        &self,
        mesh: &Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        (**self).operator(mesh, params, stop)
    }
}

impl Representation for Kernel {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        Kernel::zeta(self, s, t)
    }

    fn basis_functions(&self) -> Option<usize> {
        None
    }

    /// The exact kernel stores no approximation: no payload beyond the scene every
    /// representation shares.
    fn memory_bytes(&self) -> usize {
        0
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        Some(self.scene().fingerprint())
    }

    /// The exact operator: closed form and exact visible intervals, no rays; dense from the
    /// pair table on small scenes, sparse by the visibility sweep on large ones
    /// ([`ExactMethod`]).
    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        let method = ExactMethod::of(self);
        method.check(mesh.len())?;
        Ok(match method {
            ExactMethod::Dense => Box::new(exact_operator(self, mesh, stop)?),
            ExactMethod::Sweep => Box::new(sweep_operator(self, mesh, stop)?),
        })
    }
}
