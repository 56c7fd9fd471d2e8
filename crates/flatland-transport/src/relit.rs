//! The learned transport in a relighter: B of a move of point lights as the exact static
//! solution, the lights' exact direct light B₀ and first bounce K B₀ (the exact relighter's
//! view and columns), and the transport's later bounces M₂ B₀ — no linear solve per move.

use flatland_geom::{LightCheck, PointLight};
use flatland_solve::{LightBuffers, Relighter, Stop};

use crate::{LaterBounces, Move, QueryBuffers, Transport, TransportError, lit_source};

/// The exact relighter's first two terms and a [`Transport`]'s later bounces, per move (see the
/// module docs). Built from a relighter (its operator, columns and view hierarchy) and a
/// transport of the same mesh; any other form of the later bounces ([`LaterBounces`]: the
/// probe grid) plugs in the same way ([`TransportRelighter::with_form`]).
#[derive(Debug)]
pub struct TransportRelighter<T = Transport> {
    relighter: Relighter,
    transport: T,
    lights: LightCheck,
    /// The exact solution of the static emission alone (`E + K E + M₂ E`): the moving lights
    /// add to it, the equation being linear.
    still: Vec<f64>,
    radiosity: Vec<f64>,
    views: LightBuffers,
    query: QueryBuffers,
    setup_s: f64,
}

impl TransportRelighter {
    /// Joins `relighter` and `transport` (refused when the transport was built on another
    /// mesh or scene), solving the static emission once, exactly, with the relighter. `stop`
    /// ends that solve.
    pub fn new(
        kernel: &flatland_geom::Kernel,
        relighter: Relighter,
        transport: Transport,
        stop: &Stop,
    ) -> Result<TransportRelighter, TransportError> {
        transport.check_mesh(relighter.mesh())?;
        TransportRelighter::with_form(kernel, relighter, transport, stop)
    }
}

impl<T: LaterBounces> TransportRelighter<T> {
    /// Joins `relighter` and `form`, a form of the later bounces built on the relighter's
    /// mesh (a query checks its length only), solving the static emission once, exactly.
    pub fn with_form(
        kernel: &flatland_geom::Kernel,
        mut relighter: Relighter,
        transport: T,
        stop: &Stop,
    ) -> Result<TransportRelighter<T>, TransportError> {
        let started = std::time::Instant::now();
        let still = if relighter.emission().iter().any(|&e| e != 0.0) {
            let solved = relighter.relight(&[], stop).map_err(|e| match e {
                flatland_solve::SolveError::Interrupted => TransportError::Interrupted,
                e => TransportError::Solve(e),
            })?;
            solved.radiosity.to_vec()
        } else {
            vec![0.0; relighter.mesh().len()]
        };
        relighter.forget();
        let setup_s = relighter.setup_s() + transport.setup_s() + started.elapsed().as_secs_f64();
        Ok(TransportRelighter {
            lights: LightCheck::new(kernel.scene()),
            radiosity: still.clone(),
            still,
            relighter,
            transport,
            views: LightBuffers::default(),
            query: QueryBuffers::default(),
            setup_s,
        })
    }

    /// B under `lights` (the scene's emitting edges on): the static solution, plus per light
    /// the exact `B₀ + K B₀` and the transport's `M₂ B₀`. Errors: a light that is not
    /// finite, of negative power or on an edge (named by its index).
    pub fn relight(&mut self, lights: &[PointLight]) -> Result<&[f64], TransportError> {
        self.lights
            .check(lights)
            .map_err(flatland_solve::SolveError::from)?;
        let lit = lit_source(
            self.relighter.direct(),
            self.relighter.mesh(),
            lights,
            &mut self.views,
        );
        self.radiosity.clone_from(&self.still);
        for &(j, b) in &lit {
            self.radiosity[j as usize] += b;
        }
        self.relighter
            .columns()
            .gather_columns(&lit, &mut self.radiosity);
        let lights = Move { lights, lit: &lit };
        self.transport
            .add_later_bounces(lights, &mut self.radiosity, &mut self.query)?;
        Ok(&self.radiosity)
    }

    /// The transport (or the form of the later bounces).
    #[must_use]
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// The exact relighter it reads the operator from.
    #[must_use]
    pub fn relighter(&self) -> &Relighter {
        &self.relighter
    }

    /// Seconds of the whole set-up: the relighter's operator, the transport, the static solve.
    #[must_use]
    pub fn setup_s(&self) -> f64 {
        self.setup_s
    }

    /// Bytes held: the transport, the relighter (operator by rows and columns) and the
    /// vectors of a move.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.transport.bytes()
            + self.relighter.memory_bytes()
            + 8 * (self.still.capacity() + self.radiosity.capacity())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TransportParams;
    use crate::test_support::relative;
    use flatland_geom::Kernel;
    use flatland_solve::{Mesh, RelightParams, never};

    #[test]
    fn a_move_is_the_exact_relighters_within_the_transports_estimate() {
        // A plan whose lamps are lights that move, and one edge that emits (static light).
        let plan = flatland_geom::generate::floor_plan_lit(200, 9).unwrap();
        let lamps = plan.lights().to_vec();
        let mut edges = plan.edges().to_vec();
        edges[0].emission = 0.5;
        let scene = flatland_geom::Scene::new(edges).unwrap();
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, 3 * Mesh::min_elements(kernel.scene())).unwrap();
        let params = RelightParams {
            tolerance: 1e-10,
            ..RelightParams::default()
        };
        let mut exact = Relighter::new(&kernel, &mesh, params, &never).unwrap();
        let transport = Transport::build(
            &kernel,
            &mesh,
            exact.rows(),
            &TransportParams::default(),
            &never,
        )
        .unwrap();
        let estimate = transport.estimated_error();
        let copy = exact.with_params(params).unwrap();
        let mut relit = TransportRelighter::new(&kernel, copy, transport, &never).unwrap();
        for lamp in lamps.iter().take(6) {
            let lights = [*lamp];
            let b = relit.relight(&lights).unwrap().to_vec();
            let solved = exact.relight(&lights, &never).unwrap();
            assert!(b.iter().all(|&v| v >= 0.0));
            let error = relative(&mesh, &b, solved.radiosity);
            // Stated factor: within three times the largest estimated error of B.
            assert!(error <= 3.0 * estimate.b_max, "{error} vs {estimate:?}");
        }
        // No light: the static solution, exactly.
        let still = relit.relight(&[]).unwrap().to_vec();
        let solved = exact.relight(&[], &never).unwrap();
        assert!(relative(&mesh, &still, solved.radiosity) < 1e-8);
        // A light on an edge is refused, named.
        let edge = kernel.scene().edges()[3];
        let on_edge = flatland_geom::PointLight::new((edge.a + edge.b) * 0.5, 1.0);
        let message = relit.relight(&[on_edge]).unwrap_err().to_string();
        assert!(message.contains("edge"), "{message}");
    }
}
