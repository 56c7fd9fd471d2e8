//! The lit elements of a scene as the pieces drawn: consecutive elements of one edge merged
//! until a piece is a couple of points long on screen (a plan of ten thousand edges costs what
//! its pixels show), and B at each piece's ends, so B is drawn as a function, not as flat
//! steps: the line through the neighbouring pieces' midpoints (each piece's mean B at its
//! midpoint, linear between midpoints along an edge), flat over the last half piece at an
//! edge's ends.

use egui::Pos2;
use flatland_solve::Mesh;

use super::widgets::View;

/// The shortest piece drawn, in points: shorter elements of one edge are merged (their B
/// averaged by length) until a piece is this long on screen, so a plan of ten thousand edges
/// costs what its pixels show, not its elements.
pub(super) const MIN_PIECE: f32 = 2.0;

/// Consecutive elements of one mesh edge, merged to at least [`MIN_PIECE`] on screen.
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece {
    /// Its ends on screen.
    pub a: Pos2,
    pub b: Pos2,
    /// B averaged over it by length.
    pub value: f64,
    /// Its length in scene units.
    pub length: f64,
    /// Whether it continues the piece before it along one edge.
    pub joined: bool,
    /// Its first element (for the tests' exact values).
    #[cfg(test)]
    pub first: usize,
}

/// The lit elements of `mesh` as pieces at least `min` points long on `view` (elements are
/// merged only along one mesh edge, where they are contiguous).
#[must_use]
pub(super) fn pieces(view: &View, mesh: &Mesh, b: &[f64], min: f32) -> Vec<Piece> {
    let elements = mesh.elements();
    let mut out: Vec<Piece> = Vec::new();
    for (i, (el, &value)) in elements.iter().zip(b).enumerate() {
        let contiguous =
            i > 0 && elements[i - 1].mesh_edge == el.mesh_edge && elements[i - 1].s[1] == el.s[0];
        let (a, z) = (view.screen(el.a), view.screen(el.b));
        match out.last_mut() {
            Some(p) if contiguous && p.a.distance(p.b) < min => {
                let length = p.length + el.length;
                p.value = (p.value * p.length + value * el.length) / length;
                (p.length, p.b) = (length, z);
            }
            _ => out.push(Piece {
                a,
                b: z,
                value,
                length: el.length,
                joined: contiguous,
                #[cfg(test)]
                first: i,
            }),
        }
    }
    out
}

/// B at each piece's start and end: where two pieces of one edge meet, the value of the line
/// through their midpoints (weighted by their lengths); at an edge's ends, the piece's own B.
#[must_use]
pub(super) fn end_values(pieces: &[Piece]) -> Vec<[f64; 2]> {
    let mut ends: Vec<[f64; 2]> = pieces.iter().map(|p| [p.value, p.value]).collect();
    for i in 1..pieces.len() {
        let (left, right) = (&pieces[i - 1], &pieces[i]);
        if !right.joined {
            continue;
        }
        let w = left.length / (left.length + right.length);
        let at_joint = left.value + (right.value - left.value) * w;
        ends[i - 1][1] = at_joint;
        ends[i][0] = at_joint;
    }
    ends
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::Kernel;
    use flatland_testkit::assert_close;

    fn floorplan() -> (Mesh, View) {
        let kernel = Kernel::new(flatland_geom::bundled::scene("floorplan").unwrap());
        let mesh = Mesh::new(&kernel, 3000).unwrap();
        let rect = egui::Rect::from_min_size(Pos2::ZERO, egui::vec2(400.0, 300.0));
        (mesh, View::of(kernel.scene(), rect))
    }

    #[test]
    fn a_linear_b_along_an_edge_is_drawn_exactly_merged_or_not() {
        // B linear in the parameter: a piece's mean is B at its middle and the line through
        // the middles is B itself, so every joint gets B at the joint, however merged.
        let (mesh, view) = floorplan();
        let b: Vec<f64> = mesh
            .elements()
            .iter()
            .map(|e| 1.0 + 3.0 * e.s_mid)
            .collect();
        for min in [0.0, 12.0] {
            let pieces = pieces(&view, &mesh, &b, min);
            let ends = end_values(&pieces);
            let mut joints = 0;
            for i in 1..pieces.len() {
                if pieces[i].joined {
                    let exact = 1.0 + 3.0 * mesh.elements()[pieces[i].first].s[0];
                    assert_close!(ends[i][0], exact, rel = 1e-9, abs = 1e-12);
                    assert_close!(ends[i - 1][1], exact, rel = 1e-9, abs = 1e-12);
                    joints += 1;
                }
            }
            assert!(
                joints > pieces.len() / 3,
                "{joints} joints of {}",
                pieces.len()
            );
        }
        let all = pieces(&view, &mesh, &b, 0.0).len();
        assert_eq!(all, mesh.len(), "nothing merged below a length of 0");
        assert!(pieces(&view, &mesh, &b, 12.0).len() < all / 2, "merged");
    }

    #[test]
    fn pieces_tile_the_elements_and_keep_their_mean() {
        let (mesh, view) = floorplan();
        let b: Vec<f64> = (0..mesh.len()).map(|i| (i % 7) as f64).collect();
        let pieces = pieces(&view, &mesh, &b, 6.0);
        // Merged pieces carry the elements' length and their length-weighted B.
        let length: f64 = pieces.iter().map(|p| p.length).sum();
        let light: f64 = pieces.iter().map(|p| p.value * p.length).sum();
        let elements = mesh.elements();
        assert_close!(
            length,
            elements.iter().map(|e| e.length).sum::<f64>(),
            rel = 1e-9,
            abs = 1e-12
        );
        let exact: f64 = elements.iter().zip(&b).map(|(e, v)| v * e.length).sum();
        assert_close!(light, exact, rel = 1e-9, abs = 1e-12);
        assert!(pieces.len() < mesh.len());
    }
}
