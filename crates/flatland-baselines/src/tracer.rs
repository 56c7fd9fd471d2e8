//! A Monte Carlo light tracer: the lit scene a user without any kernel would compute.
//!
//! It learns and stores nothing about the kernel: photons leave the emitters, bounce, and are
//! counted where they land. Each lighting is traced from scratch, which is what the learned
//! kernel (one fit, any lighting) is measured against.
//!
//! # The method
//! - **Emission.** An emitter sends power `E × length`, a point light its power `Φ`. Photons of
//!   equal power are spread over the emitters in proportion, stratified: photon `k` of a batch
//!   of `S` sits at `(k + ξ)/S` along all emitters laid end to end (the edges, then the
//!   lights), so each emitter gets its share to within one photon, an edge's start points are
//!   uniform along it and a light's directions uniform in angle (`Φ / (2π)` per radian,
//!   docs/ALGORITHM.md §1a).
//! - **Directions.** From a surface, cosine-distributed about the front normal: in Flatland
//!   `sin θ` is uniform in `[−1, 1]` (the density `cos θ / 2` of the kernel's `1/(2r)`).
//! - **Transport.** The closest hit by the BVH ([`Kernel::first_hit`]; of a thin wall's two
//!   faces back to back, the one towards the photon). On the front of a surface the photon's
//!   power is added to the irradiance `H` of the element it lands in (per unit length), and it
//!   goes on with probability `ρ` (Russian roulette, power unchanged), re-emitted from the hit
//!   point. Blockers and the backs of surfaces absorb; a photon that leaves the scene is
//!   gone.
//! - **Radiosity.** `B_i = E_i + ρ_i H_i` per element of the [`Mesh`]: the mean over the
//!   element, where the solver's `B_i` is the value at its midpoint.
//! - **Noise.** Photons are traced in batches, each a full stratified sample with its own seed
//!   stream ([`flatland_solve::seeds::stream`]`(seed, batch)`), summed in batch order: the
//!   result of a seed is the same on any number of threads. The spread of the batch means
//!   gives each element's standard error ([`Traced::std_error`]).
//!
//! # Use
//! [`trace`] lights a scene as it is, its point lights included; a [`LightTracer`] traces any
//! [`Lighting`] (emission overrides per edge, with the scene's lights or others instead) of one
//! scene and mesh, one trace per lighting. A budget is a photon
//! count or a wall time ([`TraceBudget`]); `stop` is polled between batches and ends the trace
//! with what is done ([`Traced::stopped`]). The result has what a bench row needs: `B`
//! (compare it with [`solve_errors`](flatland_solve::solve_errors) against the exact
//! [`ExactReference::radiosity_on`](flatland_solve::ExactReference::radiosity_on), as for a
//! solved [`Solution`](flatland_solve::Solution)), the wall time, the rays cast (one per
//! [`Kernel::first_hit`]), the photons and the bytes the tracer held.
//!
//! ```
//! use flatland_baselines::{Lighting, LightTracer, TraceBudget, TraceParams, trace};
//! use flatland_geom::{EdgeId, Kernel, bundled};
//! use flatland_solve::{ExactReference, Mesh, SolveParams, never, solve_errors};
//!
//! let kernel = Kernel::new(bundled::scene("fig3")?);
//! let mesh = Mesh::new(&kernel, 64)?;
//! let params = TraceParams { budget: TraceBudget::Photons(50_000), seed: 1 };
//! let traced = trace(&kernel, &mesh, &params, &never)?;
//! let exact = ExactReference::new(&kernel, 512, &SolveParams::default(), &never)?
//!     .radiosity_on(&mesh, &never)?;
//! let errors = solve_errors(&mesh, &traced.radiosity, &exact);
//! assert!(errors.rel_l2_b < 0.1, "{errors:?}");
//!
//! // Another lighting of the same scene: the light off, the floor (edge 0) glowing.
//! let tracer = LightTracer::new(&kernel, &mesh)?;
//! let floor_lit = Lighting::default()
//!     .with_emission(EdgeId::new(3), 0.0)
//!     .with_emission(EdgeId::new(0), 0.5);
//! let relit = tracer.trace(&floor_lit, &params, &never)?;
//! assert!(relit.radiosity[0] >= 0.5 && relit.rays > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod emitters;
mod photons;
mod tally;

use std::time::{Duration, Instant};

use flatland_geom::{EdgeId, Kernel, LightCheck, PointLight};
use flatland_solve::{Mesh, Stop};
use rayon::prelude::*;

use crate::BaselineError;
use emitters::Emitters;
use photons::Batch;
use tally::{BatchTally, Tallies};

/// How long a trace runs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TraceBudget {
    /// About this many photons, in equal batches of at most 1024 and at least 32 batches
    /// (fewer only for fewer photons): the count is rounded up to a multiple of the batch
    /// count. Valid: `1..=10¹²`.
    Photons(u64),
    /// Batches of 1024 photons until this many seconds of wall time have passed (checked
    /// after each round of batches, one round a few per thread). Valid: `(0, 10⁶]`.
    Seconds(f64),
}

/// Settings of a trace.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TraceParams {
    /// How long it runs (default: a million photons).
    pub budget: TraceBudget,
    /// The seed of every batch's stream.
    pub seed: u64,
}

impl Default for TraceParams {
    fn default() -> Self {
        TraceParams {
            budget: TraceBudget::Photons(1_000_000),
            seed: 1,
        }
    }
}

/// Most photons a budget may ask for.
const MAX_PHOTONS: u64 = 1_000_000_000_000;
/// Longest time a budget may ask for.
const MAX_SECONDS: f64 = 1e6;
/// Photons per batch for a time budget, and the least for a photon budget.
const PHOTONS_PER_BATCH: u64 = 1024;
/// Fewest batches a photon budget is split into (the standard error needs a few).
const MIN_BATCHES: u64 = 32;

impl TraceParams {
    /// The one place these values are checked.
    pub fn check(&self) -> Result<(), BaselineError> {
        match self.budget {
            TraceBudget::Photons(n) if !(1..=MAX_PHOTONS).contains(&n) => {
                Err(BaselineError::InvalidParameter {
                    name: "photons",
                    value: n.to_string(),
                    valid: "in 1..=1000000000000",
                })
            }
            TraceBudget::Seconds(t) if !(t > 0.0 && t <= MAX_SECONDS) => {
                Err(BaselineError::InvalidParameter {
                    name: "seconds",
                    value: t.to_string(),
                    valid: "in (0, 1000000]",
                })
            }
            _ => Ok(()),
        }
    }
}

/// A lighting of a scene: the scene's own emissions, with some edges' overridden, and its own
/// point lights or others instead.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lighting {
    overrides: Vec<(EdgeId, f64)>,
    lights: Option<Vec<PointLight>>,
}

impl Lighting {
    /// The same lighting with surface edge `edge` emitting `emission`; for a piece of a
    /// subdivided edge, the whole edge. A later override of the same edge wins. Checked when
    /// traced: a surface edge of the scene, `emission` finite and ≥ 0.
    #[must_use]
    pub fn with_emission(mut self, edge: EdgeId, emission: f64) -> Lighting {
        self.overrides.push((edge, emission));
        self
    }

    /// The same lighting with `lights` instead of the scene's point lights (none: every light
    /// off). Checked when traced by the rule of
    /// [`Scene::with_lights`](flatland_geom::Scene::with_lights): finite, power ≥ 0, off every
    /// edge.
    #[must_use]
    pub fn with_lights(mut self, lights: Vec<PointLight>) -> Lighting {
        self.lights = Some(lights);
        self
    }

    /// The overrides, in the order given.
    #[must_use]
    pub fn overrides(&self) -> &[(EdgeId, f64)] {
        &self.overrides
    }

    /// The point lights instead of the scene's, if the lighting replaces them.
    #[must_use]
    pub fn lights(&self) -> Option<&[PointLight]> {
        self.lights.as_deref()
    }
}

/// What a trace found: `B` per element and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Traced {
    /// `B_i = E_i + ρ_i H_i` per element (emission included), in the mesh's order.
    pub radiosity: Vec<f64>,
    /// The standard error of each `B_i`, from the spread of the batch means (NaN with fewer
    /// than two batches).
    pub std_error: Vec<f64>,
    /// Photons traced.
    pub photons: u64,
    /// Rays cast (closest-hit queries).
    pub rays: u64,
    /// Wall time of the trace.
    pub wall: Duration,
    /// Bytes the tracer held: its tables, the tallies of the batches in flight, the result.
    pub memory_bytes: usize,
    /// Where the emitted power went.
    pub power: PowerBalance,
    /// Whether `stop` ended the trace before its budget (what was traced is kept).
    pub stopped: bool,
}

impl Traced {
    /// Seconds of wall time, as [`Solution::wall_s`](flatland_solve::Solution::wall_s) gives a
    /// solve's.
    #[must_use]
    pub fn wall_s(&self) -> f64 {
        self.wall.as_secs_f64()
    }
}

/// Where the emitted power went (scene power units: `E × length` summed, and each light's `Φ`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PowerBalance {
    /// Sent by the emitters and the point lights.
    pub emitted: f64,
    /// Absorbed by surfaces, blockers and the backs of one-sided surfaces (and the rare photon
    /// still going after 1000 bounces).
    pub absorbed: f64,
    /// Left the scene.
    pub escaped: f64,
}

/// Lights `kernel`'s scene as it is, on `mesh` (see [`LightTracer::trace`]).
pub fn trace(
    kernel: &Kernel,
    mesh: &Mesh,
    params: &TraceParams,
    stop: &Stop,
) -> Result<Traced, BaselineError> {
    LightTracer::new(kernel, mesh)?.trace(&Lighting::default(), params, stop)
}

/// The tracer of one scene and mesh: traces any lighting of it, from scratch each time. The
/// method, its accounting and how a benchmark calls it: the docs of
/// `crates/flatland-baselines/src/tracer.rs`.
#[derive(Clone, Debug)]
pub struct LightTracer<'a> {
    kernel: &'a Kernel,
    mesh: &'a Mesh,
    /// The mesh edge of each scene edge (`None` for a blocker).
    surface_of: Vec<Option<u32>>,
    /// The edges filed to check a lighting's own lights.
    light_check: LightCheck,
}

impl<'a> LightTracer<'a> {
    /// A tracer of `kernel`'s scene on `mesh`, which must be a mesh of that scene.
    pub fn new(kernel: &'a Kernel, mesh: &'a Mesh) -> Result<LightTracer<'a>, BaselineError> {
        if mesh.fingerprint() != kernel.scene().fingerprint() {
            return Err(BaselineError::InvalidParameter {
                name: "mesh",
                value: format!("a mesh of scene {:016x}", mesh.fingerprint()),
                valid: "a mesh of the kernel's scene",
            });
        }
        let mut surface_of = vec![None; kernel.scene().edges().len()];
        for (m, edge) in mesh.edges().iter().enumerate() {
            for piece in edge.pieces.clone() {
                surface_of[piece] = Some(m as u32);
            }
        }
        Ok(LightTracer {
            kernel,
            mesh,
            surface_of,
            light_check: LightCheck::new(kernel.scene()),
        })
    }

    /// Traces `lighting` to `params.budget`: in rounds of a few batches per thread, each
    /// round's batches in parallel, their tallies summed in batch order.
    pub fn trace(
        &self,
        lighting: &Lighting,
        params: &TraceParams,
        stop: &Stop,
    ) -> Result<Traced, BaselineError> {
        params.check()?;
        let started = Instant::now();
        let lights = match lighting.lights() {
            Some(lights) => {
                self.light_check.check(lights)?;
                lights
            }
            None => self.kernel.scene().lights(),
        };
        let emitters = Emitters::new(self.mesh, &self.surface_of, lighting, lights)?;
        let (batches, size) = plan(params.budget, emitters.power());
        let round = 4 * rayon::current_num_threads().max(1) as u64;
        let mut tallies = Tallies::new(self.mesh.len(), size);
        let mut stopped = false;
        let mut next = 0;
        while next < batches && !stopped {
            if let TraceBudget::Seconds(t) = params.budget
                && next > 0
                && started.elapsed().as_secs_f64() >= t
            {
                break;
            }
            let end = batches.min(next + round);
            let done: Vec<Option<BatchTally>> = (next..end)
                .into_par_iter()
                .map(|b| (!stop()).then(|| self.batch(&emitters, params.seed, b, size).trace()))
                .collect();
            for tally in done {
                match tally {
                    Some(t) => tallies.add(&t),
                    None => stopped = true,
                }
            }
            next = end;
        }
        let table_bytes = self.surface_of.len() * size_of::<Option<u32>>() + emitters.bytes();
        let in_flight = round as usize * self.mesh.len() * size_of::<f64>();
        let (radiosity, std_error, power) = tallies.estimate(self.mesh, &emitters);
        Ok(Traced {
            photons: tallies.batches() * size,
            rays: tallies.rays(),
            wall: started.elapsed(),
            memory_bytes: table_bytes + in_flight + tallies.bytes() + 2 * radiosity.len() * 8,
            radiosity,
            std_error,
            power,
            stopped,
        })
    }

    fn batch<'t>(&'t self, emitters: &'t Emitters, seed: u64, index: u64, size: u64) -> Batch<'t> {
        Batch {
            kernel: self.kernel,
            mesh: self.mesh,
            surface_of: &self.surface_of,
            emitters,
            rng: flatland_solve::seeds::stream(seed, index),
            size,
        }
    }
}

/// Batches and photons per batch for `budget`; none if nothing emits.
fn plan(budget: TraceBudget, power: f64) -> (u64, u64) {
    if power <= 0.0 {
        return (0, PHOTONS_PER_BATCH);
    }
    match budget {
        TraceBudget::Photons(n) => {
            let batches = n.div_ceil(PHOTONS_PER_BATCH).max(MIN_BATCHES.min(n));
            (batches, n.div_ceil(batches))
        }
        TraceBudget::Seconds(_) => (u64::MAX, PHOTONS_PER_BATCH),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{box_edges, kernel};
    use flatland_geom::{DVec2, Edge, bundled};
    use flatland_solve::{ExactReference, SolveParams, never};
    use flatland_testkit::assert_close;
    use std::sync::atomic::{AtomicU64, Ordering};

    fn photons(n: u64, seed: u64) -> TraceParams {
        TraceParams {
            budget: TraceBudget::Photons(n),
            seed,
        }
    }

    /// The length-weighted L2 norm of `f(i)` over the mesh's elements.
    fn norm(mesh: &Mesh, f: impl Fn(usize) -> f64) -> f64 {
        let elements = mesh.elements().iter().enumerate();
        elements
            .map(|(i, e)| e.length * f(i).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// The exact mean of B over each element (what the tracer estimates): a fine exact solve
    /// averaged over the overlaps of its elements with each.
    fn exact_means(kernel: &Kernel, mesh: &Mesh) -> Vec<f64> {
        let reference = ExactReference::new(kernel, 1024, &SolveParams::default(), &never).unwrap();
        let (fine, b) = (reference.mesh(), &reference.solution().radiosity);
        let means = mesh.elements().iter().map(|e| {
            let overlaps = fine.elements().iter().zip(b);
            let sum: f64 = overlaps
                .map(|(f, bf)| (e.s[1].min(f.s[1]) - e.s[0].max(f.s[0])).max(0.0) * bf)
                .sum();
            sum / (e.s[1] - e.s[0])
        });
        means.collect()
    }

    /// An L-shaped closed room, counter-clockwise (facing in), every wall alike.
    fn l_room(reflectance: f64, emission: f64) -> Kernel {
        let p = [
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (0.0, 2.0),
        ];
        let points: Vec<DVec2> = p.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
        let edges = Edge::polygon(&points, reflectance);
        kernel(
            edges
                .into_iter()
                .map(|e| e.with_emission(emission))
                .collect(),
        )
    }

    /// With point lights the exact solve and the tracer are two independent computations of
    /// the same light: on a generated plan with a lamp per room and nothing emitting, the
    /// exact element means agree with the trace within 1 % plus three times its noise, and
    /// every watt the lamps send is absorbed (the plan is closed).
    #[test]
    fn a_plan_lit_by_lamps_is_lit_alike_by_the_solve_and_the_tracer() {
        let scene = flatland_geom::generate::floor_plan_lit(120, 3).unwrap();
        assert!(scene.max_emission() == 0.0 && scene.lights().len() >= 8);
        let phi: f64 = scene.lights().iter().map(|l| l.power).sum();
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, 300).unwrap();
        let traced = trace(&kernel, &mesh, &photons(1_500_000, 5), &never).unwrap();
        assert_close!(traced.power.emitted, phi, 1e-12);
        assert_close!(traced.power.absorbed, phi, 1e-9);
        let exact = exact_means(&kernel, &mesh);
        let diff = norm(&mesh, |i| traced.radiosity[i] - exact[i]);
        let (size, noise) = (
            norm(&mesh, |i| exact[i]),
            norm(&mesh, |i| traced.std_error[i]),
        );
        assert!(noise < 0.01 * size, "noise {noise} of {size}");
        assert!(
            diff <= 0.01 * size + 3.0 * noise,
            "|traced − exact| = {diff}, |B| = {size}, noise {noise}"
        );
    }

    /// The same on scenes drawn by hand: each bundled floor plan and maze with its emitters
    /// turned off and a lamp 0.05 in front of the middle of each.
    #[test]
    fn hand_drawn_levels_lit_by_lamps_are_lit_alike_by_the_solve_and_the_tracer() {
        for name in ["floorplan", "maze"] {
            let scene = bundled::scene(name).unwrap();
            let mut edges = scene.edges().to_vec();
            let mut lamps = Vec::new();
            for e in &mut edges {
                if e.emission > 0.0 {
                    let at = e.a.midpoint(e.b) + e.normal() * 0.05;
                    lamps.push(flatland_geom::PointLight::new(at, e.emission * e.length()));
                    e.emission = 0.0;
                }
            }
            let scene = flatland_geom::Scene::new(edges)
                .unwrap()
                .with_lights(lamps)
                .unwrap();
            let kernel = Kernel::new(scene);
            let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene()).min(600)).unwrap();
            let traced = trace(&kernel, &mesh, &photons(1_000_000, 7), &never).unwrap();
            let exact = exact_means(&kernel, &mesh);
            let diff = norm(&mesh, |i| traced.radiosity[i] - exact[i]);
            let (size, noise) = (
                norm(&mesh, |i| exact[i]),
                norm(&mesh, |i| traced.std_error[i]),
            );
            assert!(noise < 0.01 * size, "{name}: noise {noise} of {size}");
            assert!(
                diff <= 0.01 * size + 3.0 * noise,
                "{name}: |traced − exact| = {diff}, |B| = {size}, noise {noise}"
            );
        }
    }

    #[test]
    fn a_closed_uniform_room_gives_e_over_one_minus_rho() {
        // Every direction from a wall of a closed room meets a wall, so H = B and
        // B = E / (1 − ρ) = 2 everywhere, also where the room occludes itself.
        let kernel = l_room(0.5, 1.0);
        let mesh = Mesh::new(&kernel, 24).unwrap();
        let traced = trace(&kernel, &mesh, &photons(100_000, 3), &never).unwrap();
        for (i, (&b, &se)) in traced.radiosity.iter().zip(&traced.std_error).enumerate() {
            assert!(se < 0.02, "element {i}: standard error {se}");
            assert_close!(b, 2.0, 5.0 * se, "element {i}: B {b} ± {se}");
        }
        assert_eq!(traced.power.escaped, 0.0);
    }

    #[test]
    fn in_a_closed_room_the_power_absorbed_is_the_power_emitted() {
        let kernel = kernel(box_edges());
        let mesh = Mesh::new(&kernel, 32).unwrap();
        let traced = trace(&kernel, &mesh, &photons(60_000, 4), &never).unwrap();
        // Every photon ends on a wall: the bookkeeping is exact.
        let power = traced.power;
        assert_eq!(
            (power.emitted, power.absorbed, power.escaped),
            (1.0, 1.0, 0.0)
        );
        // And the estimate agrees: ∫ (1 − ρ) H dl = Φ, within the noise. The bound on the
        // noise adds the elements' errors as if fully correlated, so it can only be too wide.
        let (mut absorbed, mut noise) = (0.0, 0.0);
        for (i, e) in mesh.elements().iter().enumerate() {
            let edge = mesh.edge_of(i);
            let h = (traced.radiosity[i] - edge.emission) / edge.reflectance;
            absorbed += (1.0 - edge.reflectance) * h * e.length;
            noise += (1.0 - edge.reflectance) / edge.reflectance * traced.std_error[i] * e.length;
        }
        assert!(noise < 0.02, "too noisy to judge: {noise}");
        assert!(
            (absorbed - 1.0).abs() <= 4.0 * noise,
            "{absorbed} ± {noise}"
        );
    }

    #[test]
    fn the_tracer_agrees_with_the_exact_solve_on_every_bundled_scene() {
        for name in bundled::names() {
            let kernel = Kernel::new(bundled::scene(name).unwrap());
            let mesh = Mesh::new(&kernel, Mesh::min_elements(kernel.scene()).max(48)).unwrap();
            let exact = exact_means(&kernel, &mesh);
            let traced = trace(&kernel, &mesh, &photons(300_000, 5), &never).unwrap();
            let error = norm(&mesh, |i| traced.radiosity[i] - exact[i]);
            let noise = norm(&mesh, |i| traced.std_error[i]);
            let reflected = norm(&mesh, |i| exact[i] - mesh.edge_of(i).emission);
            println!("{name}: |B − exact| {error:.5}, noise {noise:.5}, |B − E| {reflected:.4}");
            assert!(noise < 0.03 * reflected, "{name}: too noisy to judge");
            // Beyond the noise only the fine reference's own error, far below it.
            assert!(
                error <= 3.0 * noise + 1e-3 * reflected,
                "{name}: {error} vs {noise}"
            );
        }
    }

    #[test]
    fn the_error_falls_like_one_over_the_root_of_the_photons() {
        let kernel = Kernel::new(bundled::scene("fig3").unwrap());
        let mesh = Mesh::new(&kernel, 32).unwrap();
        let exact = exact_means(&kernel, &mesh);
        let reflected = norm(&mesh, |i| exact[i] - mesh.edge_of(i).emission);
        let points: Vec<(f64, f64)> = (0..4)
            .map(|k| {
                let n = 10_000 * 4u64.pow(k);
                let traced = trace(&kernel, &mesh, &photons(n, 6), &never).unwrap();
                let error = norm(&mesh, |i| traced.radiosity[i] - exact[i]) / reflected;
                ((n as f64).ln(), error.ln())
            })
            .collect();
        // Least-squares slope of ln error against ln photons. Each error is a norm over 32
        // elements, good to about 1/√64 ≈ 13 %, so the slope is good to about ±0.04.
        let (mx, my) = points
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0 / 4.0, b + p.1 / 4.0));
        let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let slope = sxy / sxx;
        println!(
            "errors {:?}, slope {slope:.3}",
            points.iter().map(|p| p.1.exp()).collect::<Vec<_>>()
        );
        assert!((slope + 0.5).abs() <= 0.15, "slope {slope}");
    }

    #[test]
    fn a_seed_gives_the_same_result_on_any_number_of_threads() {
        let kernel = Kernel::new(bundled::scene("maze").unwrap());
        let mesh = Mesh::new(&kernel, 64).unwrap();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let t = pool.install(|| trace(&kernel, &mesh, &photons(40_000, 7), &never).unwrap());
            (t.radiosity, t.std_error, t.photons, t.rays, t.power)
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
        assert_ne!(one.0, {
            let other = trace(&kernel, &mesh, &photons(40_000, 8), &never).unwrap();
            other.radiosity
        });
    }

    #[test]
    fn a_lighting_traces_as_the_scene_edited_to_it_would() {
        let scene = bundled::scene("fig3").unwrap();
        let kernel = Kernel::new(scene.clone());
        let mesh = Mesh::new(&kernel, 32).unwrap();
        let lighting = Lighting::default()
            .with_emission(EdgeId::new(3), 0.0)
            .with_emission(EdgeId::new(0), 0.5);
        let relit = LightTracer::new(&kernel, &mesh)
            .unwrap()
            .trace(&lighting, &photons(20_000, 9), &never)
            .unwrap();
        let edited = scene
            .with_edge(EdgeId::new(3), scene.edges()[3].with_emission(0.0))
            .and_then(|s| s.with_edge(EdgeId::new(0), s.edges()[0].with_emission(0.5)))
            .unwrap();
        let edited_kernel = Kernel::new(edited);
        let edited_mesh = Mesh::new(&edited_kernel, 32).unwrap();
        let direct = trace(&edited_kernel, &edited_mesh, &photons(20_000, 9), &never).unwrap();
        assert_eq!(
            (&relit.radiosity, relit.rays),
            (&direct.radiosity, direct.rays)
        );
        assert!(relit.radiosity[0] >= 0.5);
    }

    #[test]
    fn a_lighting_with_its_own_lights_traces_as_the_scene_lit_by_them() {
        let scene = flatland_geom::generate::floor_plan_lit(120, 3).unwrap();
        let lamp = PointLight::new(scene.lights()[1].at, 5.0);
        let kernel = Kernel::new(scene.clone());
        let mesh = Mesh::new(&kernel, 300).unwrap();
        let tracer = LightTracer::new(&kernel, &mesh).unwrap();
        let lighting = Lighting::default().with_lights(vec![lamp]);
        let relit = tracer
            .trace(&lighting, &photons(20_000, 4), &never)
            .unwrap();
        let moved = Kernel::new(scene.with_lights(vec![lamp]).unwrap());
        let moved_mesh = Mesh::new(&moved, 300).unwrap();
        let direct = trace(&moved, &moved_mesh, &photons(20_000, 4), &never).unwrap();
        assert_eq!(
            (&relit.radiosity, relit.rays),
            (&direct.radiosity, direct.rays)
        );
        assert_close!(relit.power.emitted, 5.0, 1e-12);
        // No lights: nothing emits, nothing is traced.
        let dark = Lighting::default().with_lights(Vec::new());
        let none = tracer.trace(&dark, &photons(1_000, 4), &never).unwrap();
        assert_eq!((none.photons, none.rays), (0, 0));
        // A light on a wall is refused by its index and the edge.
        let wall = kernel.scene().edges()[0];
        let on_wall = Lighting::default().with_lights(vec![lamp, PointLight::new(wall.a, 1.0)]);
        let err = tracer
            .trace(&on_wall, &photons(1_000, 4), &never)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("light 1: at (") && err.contains("lies on edge"),
            "{err}"
        );
    }

    #[test]
    fn time_budgets_and_stops_end_the_trace_with_what_is_done() {
        let kernel = Kernel::new(bundled::scene("fig3").unwrap());
        let mesh = Mesh::new(&kernel, 32).unwrap();
        let timed = TraceParams {
            budget: TraceBudget::Seconds(0.05),
            seed: 1,
        };
        let traced = trace(&kernel, &mesh, &timed, &never).unwrap();
        assert!(traced.wall_s() >= 0.05 && !traced.stopped);
        assert!(traced.photons >= 2 * PHOTONS_PER_BATCH);
        assert!(traced.photons.is_multiple_of(PHOTONS_PER_BATCH));
        assert!(traced.std_error.iter().all(|e| e.is_finite()));
        // A stop after a few batches keeps them.
        static POLLS: AtomicU64 = AtomicU64::new(0);
        let stop = || POLLS.fetch_add(1, Ordering::Relaxed) >= 5;
        let stopped = trace(&kernel, &mesh, &photons(1_000_000, 1), &stop).unwrap();
        assert!(stopped.stopped && stopped.photons > 0 && stopped.photons < 1_000_000);
        // Stopped at once: nothing traced, B = E.
        let none = trace(&kernel, &mesh, &photons(1_000, 1), &|| true).unwrap();
        assert_eq!((none.photons, none.rays, none.stopped), (0, 0, true));
        assert_eq!(none.radiosity, mesh.emission());
    }

    #[test]
    fn bad_budgets_meshes_and_dark_scenes() {
        let kernel = Kernel::new(bundled::scene("fig3").unwrap());
        let mesh = Mesh::new(&kernel, 32).unwrap();
        for (budget, says) in [
            (TraceBudget::Photons(0), "photons"),
            (TraceBudget::Seconds(0.0), "seconds"),
            (TraceBudget::Seconds(f64::NAN), "seconds"),
        ] {
            let params = TraceParams { budget, seed: 1 };
            let err = trace(&kernel, &mesh, &params, &never)
                .unwrap_err()
                .to_string();
            assert!(err.contains(says), "{err}");
        }
        let other = Kernel::new(bundled::scene("box").unwrap());
        let err = LightTracer::new(&other, &mesh).unwrap_err().to_string();
        assert!(err.contains("mesh of the kernel's scene"), "{err}");
        // Nothing emits: no photon, B = 0.
        let dark = LightTracer::new(&kernel, &mesh)
            .unwrap()
            .trace(
                &Lighting::default().with_emission(EdgeId::new(3), 0.0),
                &photons(1_000, 1),
                &never,
            )
            .unwrap();
        assert_eq!(
            (dark.photons, dark.rays, dark.power),
            (0, 0, PowerBalance::default())
        );
        assert!(dark.radiosity.iter().all(|&b| b == 0.0));
    }
}
