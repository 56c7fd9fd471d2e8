//! Point lights: the exact direct light of every element by one view of the sweep per light,
//! the irradiance at any surface point, and the mesh whose source term holds them.
//!
//! A light of power `Φ` sends `Φ / (2π)` per radian (docs/ALGORITHM.md §1a), so a surface
//! point it sees at distance `r` and angle `θ` from its normal gets the irradiance
//! `H = Φ cos θ / (2π r)`, and since `cos θ dl / r = dφ`, the mean over an element of length
//! `l` is `Φ Δφ / (2π l)` with `Δφ` the angle its visible, front-facing part subtends. That
//! mean is what the solver's source takes: `B₀_i = E_i + ρ_i H̄_i`. It is exact, and right
//! across a shadow edge inside an element; the midpoint's value would put the whole element
//! in or out of the shadow. B is still collocated at midpoints for the reflected light, which
//! varies smoothly where the direct light jumps.

use flatland_geom::{DVec2, Kernel, PointLight};
use rayon::prelude::*;

use crate::sweep::{LitPiece, SweepBuffers, SweepScene, element_angles, holds};
use crate::{Mesh, SolveError, check_scene};

/// The sweep's hierarchy of one scene and mesh, kept to view any number of lights from
/// anywhere: built once, each light position is one view (two half-plane envelopes), which
/// costs about `log n` plus what the light sees.
#[derive(Clone, Debug)]
pub struct DirectLight {
    scene: SweepScene,
}

/// What one thread reuses from view to view, so a view allocates nothing once warm.
#[derive(Debug, Default)]
pub struct LightBuffers {
    sweep: SweepBuffers,
    pieces: Vec<LitPiece>,
    angles: Vec<(u32, f64)>,
}

impl DirectLight {
    /// The hierarchy of `kernel`'s scene on `mesh` (a mesh of that scene).
    pub fn new(kernel: &Kernel, mesh: &Mesh) -> Result<DirectLight, SolveError> {
        check_scene(kernel, mesh)?;
        Ok(DirectLight {
            scene: SweepScene::new(kernel.scene(), mesh),
        })
    }

    /// The hierarchy already built for the sweep's operator on the same mesh.
    pub(crate) fn of_sweep(scene: SweepScene) -> DirectLight {
        DirectLight { scene }
    }

    /// One view from scene point `at`: `(element, Δφ)` for every element whose front faces
    /// `at` and which `at` sees, `Δφ` the angle its visible part subtends (radians), elements
    /// ascending. The slice lives in `buffers` until the next view. A light of power `Φ` there
    /// gives element `j` the mean irradiance `Φ Δφ / (2π l_j)`.
    pub fn view<'b>(
        &self,
        mesh: &Mesh,
        at: DVec2,
        buffers: &'b mut LightBuffers,
    ) -> &'b [(u32, f64)] {
        let at = mesh.to_local(at);
        let LightBuffers {
            sweep,
            pieces,
            angles,
        } = buffers;
        pieces.clear();
        angles.clear();
        self.scene.light_view(mesh, at, sweep, pieces);
        for piece in pieces.iter() {
            element_angles(mesh, at, piece, angles);
        }
        // An element seen in several places (between occluders, or across the horizontal
        // line) sums.
        angles.sort_by_key(|&(j, _)| j);
        angles.dedup_by(|later, kept| {
            let same = later.0 == kept.0;
            if same {
                kept.1 += later.1;
            }
            same
        });
        angles
    }

    /// The mean irradiance `H̄_j = Σ_lights Φ Δφ_j / (2π l_j)` of every element of `mesh`:
    /// one view per light, in parallel; summed in the lights' order, so the result is the
    /// same on any number of threads.
    #[must_use]
    pub fn mean_irradiance(&self, mesh: &Mesh, lights: &[PointLight]) -> Vec<f64> {
        let seen: Vec<Vec<(u32, f64)>> = lights
            .par_iter()
            .map_init(LightBuffers::default, |buffers, light| {
                if light.power == 0.0 {
                    return Vec::new();
                }
                self.view(mesh, light.at, buffers).to_vec()
            })
            .collect();
        let mut flux = vec![0.0; mesh.len()];
        for (light, angles) in lights.iter().zip(&seen) {
            let per_radian = light.power / std::f64::consts::TAU;
            for &(j, angle) in angles {
                flux[j as usize] += per_radian * angle;
            }
        }
        for (f, element) in flux.iter_mut().zip(mesh.elements()) {
            *f /= element.length;
        }
        flux
    }

    /// What `lights` see of the surfaces, kept to give the irradiance at any point of them
    /// ([`LitSurfaces::irradiance_at`]): one view per light, in parallel.
    #[must_use]
    pub fn lit(&self, mesh: &Mesh, lights: &[PointLight]) -> LitSurfaces {
        lit_surfaces(&self.scene, mesh, lights)
    }
}

/// [`DirectLight::lit`] through a hierarchy already made for `mesh`'s scene.
pub(crate) fn lit_surfaces(scene: &SweepScene, mesh: &Mesh, lights: &[PointLight]) -> LitSurfaces {
    let views: Vec<Vec<LitPiece>> = lights
        .par_iter()
        .map_init(SweepBuffers::default, |buffers, light| {
            let mut pieces = Vec::new();
            scene.light_view(mesh, mesh.to_local(light.at), buffers, &mut pieces);
            pieces
        })
        .collect();
    let mut pieces: Vec<(u32, LitPiece)> = views
        .into_iter()
        .enumerate()
        .flat_map(|(l, v)| v.into_iter().map(move |p| (l as u32, p)))
        .collect();
    pieces.sort_by_key(|&(l, p)| (p.edge, l));
    let mut starts = vec![0; mesh.edges().len() + 1];
    for &(_, p) in &pieces {
        starts[p.edge as usize + 1] += 1;
    }
    for k in 0..mesh.edges().len() {
        starts[k + 1] += starts[k];
    }
    LitSurfaces {
        lights: lights.iter().map(|l| (mesh.to_local(l.at), *l)).collect(),
        pieces,
        starts,
    }
}

/// What the scene's lights see of `mesh`'s surfaces, `None` without lights.
pub(crate) fn lit_mesh(scene: &SweepScene, mesh: &Mesh) -> Option<LitSurfaces> {
    (!mesh.lights().is_empty()).then(|| lit_surfaces(scene, mesh, mesh.lights()))
}

/// The stretches of surfaces that a set of lights sees, by mesh edge: the irradiance at any
/// point of a surface from them ([`DirectLight::lit`]).
#[derive(Clone, Debug)]
pub struct LitSurfaces {
    /// Each light, in the frame and as given.
    lights: Vec<(DVec2, PointLight)>,
    /// `(light, piece)`, by mesh edge then light.
    pieces: Vec<(u32, LitPiece)>,
    /// `starts[k]..starts[k + 1]`: the pieces on mesh edge `k`.
    starts: Vec<usize>,
}

impl LitSurfaces {
    /// The irradiance `H(p) = Σ Φ cos θ V / (2π r)` at scene point `p` on mesh edge `k` of
    /// `mesh` (any mesh of the scene the lights were viewed on: mesh edges are the scene's
    /// surface edges, whatever the elements), over the lights that see it. 0 for `k` out of
    /// range.
    #[must_use]
    pub fn irradiance_at(&self, mesh: &Mesh, k: usize, p: DVec2) -> f64 {
        let Some(range) = self.starts.get(k..k + 2) else {
            return 0.0;
        };
        let normal = mesh.edges()[k].normal;
        let y = mesh.to_local(p);
        let mut h = 0.0;
        for &(l, piece) in &self.pieces[range[0]..range[1]] {
            let (at, light) = self.lights[l as usize];
            if holds(at, &piece, y) {
                let d = light.at - p;
                h += light.power * normal.dot(d) / (std::f64::consts::TAU * d.length_squared());
            }
        }
        h
    }
}

impl Mesh {
    /// `elements` elements over the surfaces of `kernel`'s scene, spread so that their lengths
    /// are as equal as the sections allow (each section gets at least one, apportioned by
    /// length), with the direct light of the scene's point lights in its source term
    /// ([`Mesh::emission`]). Sections are the parts of a surface edge between its ends and
    /// the junctions where other edges touch or cross it
    /// ([`MeshEdge::junctions`](crate::MeshEdge::junctions)). Errors name the valid range: at
    /// least [`Mesh::min_elements`], at most [`MAX_MESH_ELEMENTS`](crate::MAX_MESH_ELEMENTS).
    /// A dense operator refuses more than [`MAX_ELEMENTS`](crate::MAX_ELEMENTS) when it is
    /// built.
    ///
    /// Linear in the edges up to a logarithm: junctions are found through a spatial index,
    /// and each light is one view of the sweep's hierarchy.
    pub fn new(kernel: &Kernel, elements: usize) -> Result<Mesh, SolveError> {
        Mesh::unlit(kernel, elements)?.lit(kernel)
    }

    /// One element per section of a surface edge: the coarsest mesh (no limit on the count),
    /// lit as [`Mesh::new`]'s.
    pub fn coarsest(kernel: &Kernel) -> Result<Mesh, SolveError> {
        Mesh::coarsest_unlit(kernel).lit(kernel)
    }

    /// This mesh with element `i` split into `parts[i]` equal elements (1 keeps it), lit as
    /// [`Mesh::new`]'s (`kernel` the scene it was made for). Errors: `parts` not one count
    /// ≥ 1 per element, or more than [`MAX_MESH_ELEMENTS`](crate::MAX_MESH_ELEMENTS) in all.
    pub fn split(&self, kernel: &Kernel, parts: &[usize]) -> Result<Mesh, SolveError> {
        check_scene(kernel, self)?;
        self.split_unlit(parts)?.lit(kernel)
    }

    /// This mesh with every element cut at the fractions `cuts` of it (ascending, inside
    /// `(0, 1)`), each new element's midpoint at `mids` (one per new element, inside it), lit
    /// as [`Mesh::new`]'s: a nested mesh whose collocation points lie where its parent wants
    /// them. Errors: cuts or midpoints out of order or range, or more than
    /// [`MAX_MESH_ELEMENTS`](crate::MAX_MESH_ELEMENTS) elements.
    pub fn cut(&self, kernel: &Kernel, cuts: &[f64], mids: &[f64]) -> Result<Mesh, SolveError> {
        check_scene(kernel, self)?;
        self.cut_unlit(cuts, mids)?.lit(kernel)
    }

    /// This mesh lit through a hierarchy already made for its scene.
    pub(crate) fn lit_by(mut self, scene: &SweepScene, lights: &[PointLight]) -> Mesh {
        if !lights.is_empty() {
            let direct = DirectLight {
                scene: scene.clone(),
            }
            .mean_irradiance(&self, lights);
            self.set_lights(lights.to_vec(), direct);
        }
        self
    }

    /// The mesh with the direct light of the scene's lights, if it has any.
    fn lit(mut self, kernel: &Kernel) -> Result<Mesh, SolveError> {
        let lights = kernel.scene().lights();
        if !lights.is_empty() {
            let direct = DirectLight::new(kernel, &self)?.mean_irradiance(&self, lights);
            self.set_lights(lights.to_vec(), direct);
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{power_balance, room};
    use crate::{ExactReference, SolveParams, exact_operator, never, solve, sweep_operator};
    use flatland_geom::{Edge, Scene};
    use flatland_testkit::assert_close;
    use std::f64::consts::TAU;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// A convex hexagon (counter-clockwise, facing in), ρ = 0.5, nothing emitting.
    fn hexagon() -> Vec<Edge> {
        let pts = [
            v(0.0, 0.0),
            v(3.0, -0.4),
            v(4.2, 1.1),
            v(3.6, 2.9),
            v(0.9, 3.3),
            v(-0.7, 1.6),
        ];
        Edge::polygon(&pts, 0.5)
    }

    /// The direction of `p` from `light`, in radians.
    fn bearing(light: DVec2, p: DVec2) -> f64 {
        (p - light).y.atan2((p - light).x)
    }

    /// The length of the part of `[lo, hi]` (radians, `hi − lo < 2π`) that `[c, d]` covers
    /// on the circle.
    fn circular_overlap([lo, hi]: [f64; 2], [c, d]: [f64; 2]) -> f64 {
        (-2..=2)
            .map(|k| {
                let shift = TAU * f64::from(k);
                (hi.min(d + shift) - lo.max(c + shift)).max(0.0)
            })
            .sum()
    }

    /// The counter-clockwise arc of directions from `light` to the segment `[a, b]`.
    fn arc(light: DVec2, a: DVec2, b: DVec2) -> [f64; 2] {
        let (ta, tb) = (bearing(light, a), bearing(light, b));
        let sweep = (a - light)
            .perp_dot(b - light)
            .atan2((a - light).dot(b - light));
        if sweep >= 0.0 {
            [ta, ta + sweep]
        } else {
            [tb, tb - sweep]
        }
    }

    /// The closed form, computed without the sweep: in a convex room every element's whole
    /// arc is seen, but for the directions a blocker (inside the room, so nearer than any
    /// wall) covers.
    fn expected_angles(mesh: &Mesh, light: DVec2, blocker: Option<(DVec2, DVec2)>) -> Vec<f64> {
        mesh.elements()
            .iter()
            .map(|el| {
                let whole = arc(light, el.a, el.b);
                let hidden =
                    blocker.map_or(0.0, |(p, q)| circular_overlap(whole, arc(light, p, q)));
                whole[1] - whole[0] - hidden
            })
            .collect()
    }

    fn view_angles(kernel: &Kernel, mesh: &Mesh, light: DVec2) -> Vec<f64> {
        let direct = DirectLight::new(kernel, mesh).unwrap();
        let mut dense = vec![0.0; mesh.len()];
        for &(j, a) in direct.view(mesh, light, &mut LightBuffers::default()) {
            dense[j as usize] = a;
        }
        dense
    }

    #[test]
    fn in_a_convex_room_each_element_gets_the_angle_it_subtends_even_across_a_shadow_edge() {
        let blocker = (v(1.2, 1.9), v(2.3, 2.4));
        for (with_blocker, light) in [
            (false, v(1.7, 1.3)),
            (true, v(1.7, 1.3)),
            (true, v(0.3, 0.6)),
        ] {
            let mut edges = hexagon();
            if with_blocker {
                edges.push(Edge::blocker(blocker.0, blocker.1));
            }
            let kernel = Kernel::new(Scene::new(edges).unwrap());
            let mesh = Mesh::new(&kernel, 97).unwrap();
            let got = view_angles(&kernel, &mesh, light);
            let want = expected_angles(&mesh, light, with_blocker.then_some(blocker));
            let mut split = 0;
            for (j, (g, w)) in got.iter().zip(&want).enumerate() {
                assert!(
                    (g - w).abs() <= 1e-9 * w.abs().max(1e-3),
                    "element {j}: {g} vs {w}"
                );
                let whole = arc(light, mesh.elements()[j].a, mesh.elements()[j].b);
                split += usize::from(*w > 1e-6 && *w < whole[1] - whole[0] - 1e-6);
            }
            assert_close!(
                got.iter().sum::<f64>()
                    + if with_blocker {
                        circular_overlap([0.0, TAU], arc(light, blocker.0, blocker.1))
                    } else {
                        0.0
                    },
                TAU,
                1e-12
            );
            if with_blocker {
                assert_eq!(split, 2, "both shadow edges fall inside an element");
            }
            // The mesh's source: ρ Φ Δφ / (2π l) per element.
            let lit = kernel
                .scene()
                .clone()
                .with_lights(vec![PointLight::new(light, 3.0)])
                .unwrap();
            let lit_kernel = Kernel::new(lit);
            let lit_mesh = Mesh::new(&lit_kernel, 97).unwrap();
            for (j, el) in lit_mesh.elements().iter().enumerate() {
                let want = 0.5 * 3.0 * want[j] / (TAU * el.length);
                assert!(
                    (lit_mesh.emission()[j] - want).abs() <= 1e-9 * want.max(1e-6),
                    "{j}"
                );
            }
        }
    }

    /// The irradiance at a point is `Φ cos θ / (2π r)` where the light sees it, 0 in shadow.
    #[test]
    fn the_irradiance_at_a_point_is_the_closed_form_or_zero_in_shadow() {
        let blocker = (v(1.2, 1.9), v(2.3, 2.4));
        let mut edges = hexagon();
        edges.push(Edge::blocker(blocker.0, blocker.1));
        let light = PointLight::new(v(1.7, 1.3), 2.5);
        let kernel = Kernel::new(Scene::new(edges).unwrap().with_lights(vec![light]).unwrap());
        let mesh = Mesh::new(&kernel, 60).unwrap();
        let lit = DirectLight::new(&kernel, &mesh)
            .unwrap()
            .lit(&mesh, &[light]);
        let mut shadowed = 0;
        for (k, edge) in mesh.edges().iter().enumerate() {
            for step in 0..200 {
                let p = edge.a + (edge.b - edge.a) * ((step as f64 + 0.5) / 200.0);
                let d = light.at - p;
                let (o1, o2) = (d.perp_dot(blocker.0 - p), d.perp_dot(blocker.1 - p));
                let q = blocker.1 - blocker.0;
                let crosses = o1 * o2 < 0.0
                    && q.perp_dot(p - blocker.0) * q.perp_dot(light.at - blocker.0) < 0.0;
                let want = if crosses {
                    0.0
                } else {
                    light.power * edge.normal.dot(d) / (TAU * d.length_squared())
                };
                shadowed += usize::from(crosses);
                assert_close!(lit.irradiance_at(&mesh, k, p), want, 1e-12);
            }
        }
        assert!(shadowed > 50, "{shadowed} points in shadow");
        // A point level with the light, on a wall: seen once, not twice (the two half-views
        // meet there).
        let square = room(
            &[v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)],
            0.5,
            0.0,
        );
        let light = PointLight::new(v(0.5, 1.0), 1.0);
        let kernel = Kernel::new(square.with_lights(vec![light]).unwrap());
        let mesh = Mesh::new(&kernel, 40).unwrap();
        let lit = DirectLight::new(&kernel, &mesh)
            .unwrap()
            .lit(&mesh, &[light]);
        assert_close!(
            lit.irradiance_at(&mesh, 1, v(2.0, 1.0)),
            1.0 / (TAU * 1.5),
            1e-14
        );
        assert_close!(
            lit.irradiance_at(&mesh, 3, v(0.0, 1.0)),
            1.0 / (TAU * 0.5),
            1e-14
        );
    }

    /// A closed room of uniform ρ lit by a light alone: the direct light leaving the walls is
    /// `ρ Φ` exactly (every direction lands on a wall), and all that leaves them is
    /// `P = ρ Φ + ρ P`, `P = ρ Φ / (1 − ρ)`, up to the collocation's quadrature.
    #[test]
    fn a_closed_room_lit_by_a_light_reflects_rho_phi_over_one_minus_rho() {
        let (rho, phi) = (0.6, 5.0);
        let pts: Vec<DVec2> = hexagon().iter().map(|e| e.a).collect();
        let scene = Scene::new(Edge::polygon(&pts, rho)).unwrap();
        let kernel = Kernel::new(
            scene
                .with_lights(vec![PointLight::new(v(2.9, 0.8), phi)])
                .unwrap(),
        );
        let mesh = Mesh::new(&kernel, 600).unwrap();
        let b0 = mesh.emission();
        let leaving = |b: &[f64]| -> f64 {
            b.iter()
                .zip(mesh.elements())
                .map(|(b, el)| b * el.length)
                .sum()
        };
        assert_close!(leaving(&b0), rho * phi, 1e-12);
        let solution = solve(&kernel, &mesh, &SolveParams::default(), &never).unwrap();
        let p = leaving(&solution.radiosity);
        assert!(
            (p / (rho * phi / (1.0 - rho)) - 1.0).abs() < 2e-3,
            "P = {p}"
        );
    }

    /// Energy: what the surfaces absorb is what the light and the emitting walls send.
    #[test]
    fn a_closed_room_absorbs_the_lights_power_and_the_emission() {
        let mut edges = crate::test_support::l_room(0.5).edges().to_vec();
        for (k, e) in edges.iter_mut().enumerate() {
            e.reflectance = 0.3 + 0.1 * k as f64;
        }
        let lights = vec![
            PointLight::new(v(0.4, 2.2), 3.0),
            PointLight::new(v(2.5, 0.5), 1.0),
        ];
        let kernel = Kernel::new(Scene::new(edges).unwrap().with_lights(lights).unwrap());
        let mesh = Mesh::new(&kernel, 512).unwrap();
        for op in [
            Box::new(exact_operator(&kernel, &mesh, &never).unwrap())
                as Box<dyn crate::TransferOperator>,
            Box::new(sweep_operator(&kernel, &mesh, &never).unwrap()),
        ] {
            let (emitted, absorbed) = power_balance(op.as_ref(), &mesh);
            assert!(
                emitted > 4.0 && (absorbed / emitted - 1.0).abs() < 3e-3,
                "{emitted} vs {absorbed}"
            );
        }
    }

    /// Mirror symmetry: a light on a rectangle's axis lights mirrored elements alike. (A
    /// light has no receiving side, so the kernel's reciprocity has no counterpart here.)
    #[test]
    fn a_light_on_the_axis_of_a_symmetric_room_lights_it_symmetrically() {
        let scene = room(
            &[v(0.0, 0.0), v(4.0, 0.0), v(4.0, 2.0), v(0.0, 2.0)],
            0.5,
            0.0,
        );
        let kernel = Kernel::new(
            scene
                .with_lights(vec![PointLight::new(v(2.0, 0.7), 1.0)])
                .unwrap(),
        );
        let mesh = Mesh::new(&kernel, 64).unwrap();
        let h = mesh.direct_irradiance();
        let mirror = |p: DVec2| v(4.0 - p.x, p.y);
        for (i, el) in mesh.elements().iter().enumerate() {
            let j = mesh
                .elements()
                .iter()
                .position(|o| (o.midpoint - mirror(el.midpoint)).length() < 1e-9)
                .unwrap();
            assert_close!(h[i], h[j], 1e-13);
        }
    }

    /// A light of power 0 (switched off) changes nothing: bit for bit the unlit solve; and
    /// the exact reference adds the light at other meshes' points.
    #[test]
    fn an_unlit_solve_is_untouched_and_the_reference_carries_the_lights() {
        let scene = crate::test_support::l_room(0.5);
        let kernel = Kernel::new(scene.clone());
        let off = Kernel::new(
            scene
                .clone()
                .with_lights(vec![PointLight::new(v(0.5, 0.5), 0.0)])
                .unwrap(),
        );
        let params = SolveParams::default();
        let (mesh, mesh_off) = (
            Mesh::new(&kernel, 120).unwrap(),
            Mesh::new(&off, 120).unwrap(),
        );
        assert_eq!(mesh.emission(), mesh_off.emission());
        assert!(mesh.direct_irradiance().is_empty());
        let a = solve(&kernel, &mesh, &params, &never).unwrap();
        let b = solve(&off, &mesh_off, &params, &never).unwrap();
        assert_eq!(a.radiosity, b.radiosity);
        // Lit: the reference at a coarse mesh's midpoints agrees with the coarse solve.
        let lit = Kernel::new(
            scene
                .with_lights(vec![PointLight::new(v(0.5, 2.5), 4.0)])
                .unwrap(),
        );
        let reference = ExactReference::new(&lit, 2048, &params, &never).unwrap();
        let coarse = Mesh::new(&lit, 256).unwrap();
        let exact = reference.radiosity_on(&coarse, &never).unwrap();
        let solved = solve(&lit, &coarse, &params, &never).unwrap();
        let errors = crate::solve_errors(&coarse, &solved.radiosity, &exact);
        assert!(errors.rel_l2_b < 0.02, "{errors:?}");
        // Another lighting of the same scene is refused.
        let err = reference
            .radiosity_on(&mesh, &never)
            .unwrap_err()
            .to_string();
        assert!(err.contains("same point lights"), "{err}");
    }
}
