//! The light-driven fit as a kernel representation: its own rows on its own mesh, a pointwise
//! ζ̃ from its probes' views anywhere else.

use flatland_solve::{Mesh, Representation, SolveError, SolveParams, Stop, TransferOperator};

use super::LightFit;
use super::probes::Bracket;

impl LightFit {
    /// `Ṽ(s, t)`: whether the probe bracketing `t` sees the sender point `s`, blended between
    /// the two probes of a gap as the rows are. `None` before the first round.
    fn visibility(&self, s: f64, t: f64) -> Option<f64> {
        if self.probes.len() == 0 {
            return None;
        }
        let i = self.mesh.element_at(t);
        let sender = &self.mesh.elements()[self.mesh.element_at(s)];
        let edge = &self.mesh.edges()[sender.mesh_edge];
        let u = (s - edge.s[0]) / (edge.s[1] - edge.s[0]);
        let m = sender.mesh_edge as u32;
        let sees = |p: usize| f64::from(u8::from(self.probes.sees(p, m, u)));
        Some(match self.probes.bracket(&self.mesh, i) {
            Bracket::Probed(p) => sees(p),
            Bracket::Between { left, right, f } => (1.0 - f) * sees(left) + f * sees(right),
        })
    }
}

/// As a kernel: the unoccluded kernel (exact, closed form) times the probes' `Ṽ`; the exact
/// kernel before its first round, when the fit has no view to lend.
impl Representation for LightFit {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        let u = self.kernel.unoccluded(s, t);
        if u.zeta == 0.0 {
            return 0.0;
        }
        match self.visibility(s, t) {
            Some(v) => v * u.zeta,
            None => self.kernel.eval(s, t).zeta,
        }
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(self.probes.len())
    }

    fn memory_bytes(&self) -> usize {
        self.probes.memory_bytes() + self.rows.memory_bytes()
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        Some(self.kernel.scene().fingerprint())
    }

    /// Its own rows on the mesh it learned on; on any other mesh, the quadrature of its
    /// pointwise ζ̃.
    fn operator(
        &self,
        mesh: &Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        flatland_solve::check_fingerprint(self.scene_fingerprint(), mesh)?;
        if mesh.elements() == self.mesh.elements() {
            return Ok(self.own_operator());
        }
        Ok(Box::new(flatland_solve::quadrature_operator(
            self,
            mesh,
            params.quadrature_points,
            stop,
        )?))
    }
}
