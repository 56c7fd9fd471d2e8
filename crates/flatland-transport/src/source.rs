//! What a move gives the transport: the direct light of point lights as B₀'s non-zero
//! entries, from one view of the sweep per light.

use flatland_geom::PointLight;
use flatland_solve::{DirectLight, LightBuffers, Mesh};

/// `B₀`'s entries lit by `lights` (ascending elements): `ρ_j Φ Δφ_j / (2π l_j)` summed over
/// the lights, `Δφ_j` the angle element `j`'s visible front subtends from a light
/// (docs/ALGORITHM.md §1a). The static emission E is not included: what a moving light adds.
#[must_use]
pub fn lit_source(
    direct: &DirectLight,
    mesh: &Mesh,
    lights: &[PointLight],
    buffers: &mut LightBuffers,
) -> Vec<(u32, f64)> {
    let mut lit: Vec<(u32, f64)> = Vec::new();
    for light in lights.iter().filter(|l| l.power > 0.0) {
        let per_radian = light.power / std::f64::consts::TAU;
        for &(j, angle) in direct.view(mesh, light.at, buffers) {
            let element = mesh.elements()[j as usize];
            let rho = mesh.edge_of(j as usize).reflectance;
            lit.push((j, rho * per_radian * angle / element.length));
        }
    }
    lit.sort_by_key(|&(j, _)| j);
    lit.dedup_by(|later, kept| {
        let same = later.0 == kept.0;
        if same {
            kept.1 += later.1;
        }
        same
    });
    lit.retain(|&(_, b)| b != 0.0);
    lit
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::{DVec2, Kernel};

    #[test]
    fn the_lit_source_is_the_meshs_source_of_the_same_lights() {
        let scene = flatland_geom::generate::floor_plan_lit(300, 4).unwrap();
        let lights = scene.lights()[..3].to_vec();
        let lit_kernel = Kernel::new(scene.clone().with_lights(lights.clone()).unwrap());
        let kernel = Kernel::new(scene.with_lights(Vec::new()).unwrap());
        let mesh = Mesh::new(&kernel, 900).unwrap();
        let lit_mesh = Mesh::new(&lit_kernel, 900).unwrap();
        let direct = DirectLight::new(&kernel, &mesh).unwrap();
        let lit = lit_source(&direct, &mesh, &lights, &mut LightBuffers::default());
        let mut dense = mesh.emission();
        for &(j, b) in &lit {
            dense[j as usize] += b;
        }
        for (i, (a, b)) in dense.iter().zip(lit_mesh.emission()).enumerate() {
            flatland_testkit::assert_close!(*a, b, rel = 1e-12, abs = 1e-15, "element {i}");
        }
        assert!(lit.len() > 20);
        let none = lit_source(
            &direct,
            &mesh,
            &[PointLight {
                at: DVec2::new(1.0, 1.0),
                power: 0.0,
            }],
            &mut LightBuffers::default(),
        );
        assert!(none.is_empty());
    }
}
