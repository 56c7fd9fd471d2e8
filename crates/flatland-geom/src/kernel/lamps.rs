//! The light each parent edge sends when point lights light the scene: what `E'` weighs a
//! sender by (docs/ALGORITHM.md §2) besides its emission.
//!
//! A lamp of power `Φ` gives an edge of length `l` the mean irradiance `Φ Δφ / (2π l)`, `Δφ`
//! the angle its visible, front-facing part subtends at the lamp (docs/ALGORITHM.md §1a); the
//! edge reflects `ρ` of it. `Δφ` is measured by rays from the lamp in [`LAMP_RAYS`] directions
//! evenly spread, each closest hit on a surface's front adding `2π / LAMP_RAYS`: `log n` per
//! ray, so a lamp costs the same in any scene, and the rays see the occluders the solve sees.
//! The weight only decides where a representation spends its links or samples; the solve's
//! source is the exact direct light (`flatland_solve::DirectLight`), so an edge thinner than
//! a ray's step seen from a lamp and missed keeps the floor, not a wrong answer.

use std::f64::consts::TAU;

use glam::DVec2;
use rayon::prelude::*;

use super::Kernel;
use crate::visibility::orient;

/// Directions a lamp's rays stand for: a step of 0.09°, so an edge subtending a degree gets
/// ten rays (not all cast: see `rays_met`).
pub const LAMP_RAYS: usize = 4096;

impl Kernel {
    /// Per parent edge (group), the light it reflects of the scene's lamps' direct light:
    /// `ρ Σ Φ Δφ / (2π l)`; 0 for a blocker and an edge no lamp sees. Lamps in parallel,
    /// summed in their order, so the result is the same on any number of threads.
    pub(super) fn lamp_light(&self) -> Vec<f64> {
        let mut sent = vec![0.0; self.parents.len()];
        let lamps: Vec<_> = self
            .scene
            .lights()
            .iter()
            .filter(|l| l.power > 0.0)
            .collect();
        if lamps.is_empty() {
            return sent;
        }
        let seen: Vec<Vec<(usize, usize)>> = lamps
            .par_iter()
            .map(|lamp| self.rays_met(lamp.at))
            .collect();
        for (lamp, met) in lamps.iter().zip(&seen) {
            // Φ / (2π) per radian, 2π / LAMP_RAYS radians per ray.
            let per_ray = lamp.power / LAMP_RAYS as f64;
            for &(group, rays) in met {
                sent[group] += per_ray * rays as f64;
            }
        }
        for (s, p) in sent.iter_mut().zip(&self.parents) {
            *s *= p.reflectance / p.d.length();
        }
        sent
    }

    /// The surfaces whose front the rays from `at` meet first: `(group, rays)`, groups
    /// ascending. Every [`COARSE_STEP`]-th ray is cast; between two that meet the same surface
    /// the rays in between are taken to meet it too, and elsewhere the step is halved down to
    /// single rays. So a lamp costs its coarse rays plus a few per edge it sees end, not
    /// [`LAMP_RAYS`]: what is missed is only a surface narrower than a coarse step (0.7°)
    /// seen between two rays that meet one other surface.
    fn rays_met(&self, at: DVec2) -> Vec<(usize, usize)> {
        let met = |k: usize| -> Option<usize> {
            // Half a step off the axes: a ray never runs along an axis-parallel wall.
            let angle = TAU * (k as f64 + 0.5) / LAMP_RAYS as f64;
            let group = self.first_parent_hit(at, DVec2::from_angle(angle))?;
            let s = self.segments[group];
            let front = self.parents[group].rank.is_some() && orient(s.a, s.b, at) > 0.0;
            front.then_some(group)
        };
        let mut counted: Vec<(usize, usize)> = Vec::new();
        let first = met(0);
        let mut left = first;
        for start in (0..LAMP_RAYS).step_by(COARSE_STEP) {
            let end = start + COARSE_STEP;
            let right = if end == LAMP_RAYS { first } else { met(end) };
            span_rays(&met, (start, left), (end, right), &mut counted);
            left = right;
        }
        counted.sort_unstable();
        let mut merged: Vec<(usize, usize)> = Vec::new();
        for (group, rays) in counted {
            match merged.last_mut() {
                Some((g, n)) if *g == group => *n += rays,
                _ => merged.push((group, rays)),
            }
        }
        merged
    }
}

/// Rays between two cast ones: every [`COARSE_STEP`]-th of the [`LAMP_RAYS`] is cast first.
const COARSE_STEP: usize = 8;

/// Counts the rays `a..b` (`a` met `hit_a`, `b` met `hit_b`, `b` not counted here): all to
/// `hit_a` when both ends met the same surface, else the middle ray is cast and each half
/// counted alike, down to single rays.
fn span_rays(
    met: &impl Fn(usize) -> Option<usize>,
    (a, hit_a): (usize, Option<usize>),
    (b, hit_b): (usize, Option<usize>),
    counted: &mut Vec<(usize, usize)>,
) {
    if hit_a == hit_b || b - a == 1 {
        if let Some(group) = hit_a {
            let rays = if hit_a == hit_b { b - a } else { 1 };
            counted.push((group, rays));
        }
        return;
    }
    let m = a + (b - a) / 2;
    let hit_m = met(m);
    span_rays(met, (a, hit_a), (m, hit_m), counted);
    span_rays(met, (m, hit_m), (b, hit_b), counted);
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use flatland_testkit::assert_close;

    use crate::{Edge, EdgeId, Kernel, PointLight, Scene};

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }
    use glam::DVec2;

    /// A square room of side 2 facing in, reflectance `rho`, nothing emitting.
    fn room(rho: f64) -> Vec<Edge> {
        let corners = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        (0..4)
            .map(|i| Edge::surface(corners[i], corners[(i + 1) % 4], rho))
            .collect()
    }

    #[test]
    fn a_lamp_at_a_rooms_centre_gives_each_wall_its_closed_form_share() {
        // Each wall subtends π/2 at the centre: H̄ = Φ (π/2) / (2π · 2) = Φ / 8, and the wall
        // sends ρ H̄. Φ = 4, ρ = 0.5: E' = 0.25 on every wall.
        let scene = Scene::new(room(0.5))
            .unwrap()
            .with_lights(vec![PointLight::new(v(1.0, 1.0), 4.0)])
            .unwrap();
        let kernel = Kernel::new(scene);
        for e in 0..4 {
            assert_close!(kernel.source_weight(EdgeId::new(e)), 0.25, 1e-12);
        }
    }

    #[test]
    fn an_occluded_wall_keeps_the_floor_and_emitters_add_the_lamps_light() {
        // A blocker just above the lamp hides the ceiling from it; the side walls lose the
        // part above the rays past its ends. The floor emits 1 and is lit too.
        let mut edges = room(0.5);
        edges[0].emission = 1.0;
        edges.push(Edge::blocker(v(0.2, 1.2), v(1.8, 1.2)));
        let lamp = PointLight::new(v(1.0, 1.0), 4.0);
        let scene = Scene::new(edges).unwrap().with_lights(vec![lamp]).unwrap();
        let kernel = Kernel::new(scene);
        let weight = |e| kernel.source_weight(EdgeId::new(e));
        // The floor: E + ρ Φ (π/2) / (2π · 2) = 1 + 0.25.
        assert_close!(weight(0), 1.25, 1e-12);
        // The right wall (2,0)→(2,2) sees the lamp from y = 0 up to the ray past the
        // blocker's end (1.8, 1.2), which meets it at y = 1.25: the angle from atan(-1) to
        // atan(0.25), within a ray's step.
        let angle = 0.25f64.atan() + PI / 4.0;
        let step = std::f64::consts::TAU / super::LAMP_RAYS as f64;
        let wall = 0.5 * 4.0 * angle / (std::f64::consts::TAU * 2.0);
        let per_step = 0.5 * 4.0 * step / (std::f64::consts::TAU * 2.0);
        assert!(
            (weight(1) - wall).abs() <= per_step,
            "{} vs {wall}",
            weight(1)
        );
        // The ceiling is hidden: the floor of 1 % of the largest E' (the floor's 1.25).
        assert_close!(weight(2), 0.0125, 1e-12);
    }

    #[test]
    fn scenes_lit_by_emitters_alone_weigh_senders_as_before() {
        // The rule before lamps counted: E for an emitter, the floor of 1 % of the largest E
        // elsewhere, bit for bit, on every bundled scene without lamps.
        for name in crate::bundled::names() {
            let scene = crate::bundled::scene(name).unwrap();
            if !scene.lights().is_empty() {
                continue;
            }
            let floor = 0.01 * scene.max_emission();
            let kernel = Kernel::new(scene.clone());
            for (e, edge) in scene.edges().iter().enumerate() {
                let before = if edge.emission > 0.0 {
                    edge.emission
                } else {
                    floor
                };
                assert_eq!(
                    kernel.source_weight(EdgeId::new(e)),
                    before,
                    "{name} edge {e}"
                );
            }
        }
    }

    #[test]
    fn the_rays_cast_count_what_casting_every_ray_counts_up_to_what_falls_between() {
        // A lit floor plan: furniture, doors and walls seen from many lamps. Casting every
        // ray of LAMP_RAYS is the reference; the coarse rays refined where the surface met
        // changes may only miss what fits between two coarse rays.
        let params = crate::generate::GenerateParams {
            kind: crate::generate::SceneKind::FloorPlan,
            edges: 400,
            seed: 5,
        };
        let kernel = Kernel::new(crate::generate::generate_lit(&params).unwrap());
        let (mut all, mut missed) = (0usize, 0usize);
        for lamp in kernel.scene().lights() {
            let cast = kernel.rays_met(lamp.at);
            let mut every: Vec<(usize, usize)> = Vec::new();
            for k in 0..super::LAMP_RAYS {
                let angle = std::f64::consts::TAU * (k as f64 + 0.5) / super::LAMP_RAYS as f64;
                let Some(g) = kernel.first_parent_hit(lamp.at, DVec2::from_angle(angle)) else {
                    continue;
                };
                let s = kernel.segments[g];
                if kernel.parents[g].rank.is_none()
                    || crate::visibility::orient(s.a, s.b, lamp.at) <= 0.0
                {
                    continue;
                }
                match every.iter_mut().find(|(h, _)| *h == g) {
                    Some((_, n)) => *n += 1,
                    None => every.push((g, 1)),
                }
            }
            for (g, n) in every {
                let got = cast.iter().find(|(h, _)| *h == g).map_or(0, |c| c.1);
                all += n;
                missed += n.abs_diff(got);
            }
        }
        assert!(all > 0);
        // Off by no more than a coarse step's rays per surface where it is, rarely.
        assert!(
            missed * 100 <= all,
            "{missed} of {all} rays counted elsewhere"
        );
    }
}
