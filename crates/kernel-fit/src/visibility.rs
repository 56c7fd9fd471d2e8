//! The visibility learner's geometry: which face of a pair's visibility structure a ray or a
//! cell lies in, and the gates that let only a face's cells respond (its samples are drawn by
//! `sampler`).
//!
//! With [`Target::Visibility`](crate::Target::Visibility) the network learns only `V` on the
//! pairs of surface edges where it varies ([`PairClass::Varies`]); everywhere else the geometry
//! gives it exactly. On such a pair `V` is constant on the faces cut out by the curves of the
//! pair's event points ([`flatland_geom::PairEvents`]). A cell belongs to the face of its centre
//! ray, and a [`FaceGate`] lets only the cells of a query ray's face respond: no cell straddles
//! a known discontinuity, and a face with one cell anywhere in it has that cell's value.

use foldhash::HashMap;

use flatland_geom::{DVec2, Kernel, PairClass, RayFace, SurfaceRank, Unoccluded};
use flatland_solve::InputFrame;
use sgcs::{CellId, Gate};

use crate::Gating;

mod nearest;
mod sampler;

use nearest::NearestEdges;
pub(crate) use sampler::Sampler;

/// One face of a pair's visibility structure: the ordered pair of surface edges (sender rank,
/// receiver rank) and the ray's [`RayFace`] (sub-pair, the side of each of the sub-pair's
/// event points as bits, the event points it meets). Visibility is the same for every ray of
/// one face.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct FaceKey {
    pair: (SurfaceRank, SurfaceRank),
    face: RayFace,
}

impl FaceKey {
    /// The face of the ray from `x` (on the surface of rank `a`) to `y` (rank `b`); `None`
    /// unless visibility varies on that pair.
    pub(crate) fn of(
        kernel: &Kernel,
        a: SurfaceRank,
        b: SurfaceRank,
        x: DVec2,
        y: DVec2,
    ) -> Option<FaceKey> {
        if a == b || kernel.pair_class(a, b) != PairClass::Varies {
            return None;
        }
        let events = kernel.visibility_events(a, b)?;
        Some(FaceKey {
            pair: (a, b),
            face: events.face(x, y),
        })
    }

    /// The face of the ray at `(s, t)`.
    pub(crate) fn at(kernel: &Kernel, u: &Unoccluded) -> Option<FaceKey> {
        FaceKey::of(kernel, u.sender, u.receiver, u.x, u.y)
    }
}

/// A face of the visibility structure as [`Faces`] numbers it: the face and its pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FaceId {
    face: u32,
    pair: u32,
}

/// Which face and pair every cell is in, and the cells of each face and each pair (ascending).
/// Faces and pairs are numbered as they are first met ([`Faces::intern`]), so a caller can
/// look a ray's face up once and gate every later step on it without hashing. Derived from the
/// cells' positions: rebuilt, never saved.
#[derive(Clone, Debug, Default)]
pub(crate) struct Faces {
    ids: HashMap<FaceKey, FaceId>,
    pair_ids: HashMap<(SurfaceRank, SurfaceRank), u32>,
    face_cells: Vec<Vec<CellId>>,
    pair_cells: Vec<Vec<CellId>>,
    /// Per cell: its face, `None` when its centre ray is on no varying pair.
    of_cell: Vec<Option<FaceId>>,
}

impl Faces {
    /// The number of `key`, numbering it (and its pair) if it is new.
    pub(crate) fn intern(&mut self, key: FaceKey) -> FaceId {
        if let Some(&id) = self.ids.get(&key) {
            return id;
        }
        let next_pair = self.pair_cells.len() as u32;
        let pair = *self.pair_ids.entry(key.pair).or_insert(next_pair);
        if pair == next_pair {
            self.pair_cells.push(Vec::new());
        }
        let id = FaceId {
            face: self.face_cells.len() as u32,
            pair,
        };
        self.face_cells.push(Vec::new());
        self.ids.insert(key, id);
        id
    }

    /// The number of `key`, if it has one.
    fn find(&self, key: &FaceKey) -> Option<FaceId> {
        self.ids.get(key).copied()
    }

    /// Puts `cell` in the face `key` (moving it out of its old face and pair).
    pub(crate) fn place(&mut self, cell: CellId, key: Option<FaceKey>) {
        if self.of_cell.len() <= cell {
            self.of_cell.resize(cell + 1, None);
        }
        let new = key.map(|key| self.intern(key));
        let old = self.of_cell[cell];
        if old == new {
            return;
        }
        if let Some(FaceId { face, pair }) = old {
            remove_sorted(&mut self.face_cells[face as usize], cell);
            remove_sorted(&mut self.pair_cells[pair as usize], cell);
        }
        if let Some(FaceId { face, pair }) = new {
            insert_sorted(&mut self.face_cells[face as usize], cell);
            insert_sorted(&mut self.pair_cells[pair as usize], cell);
        }
        self.of_cell[cell] = new;
    }

    /// The gate of a query ray in face `key` (see [`Gating`]).
    pub(crate) fn gate<'a>(&'a self, key: &FaceKey, gating: Gating) -> FaceGate<'a> {
        match self.find(key) {
            Some(id) => self.gate_of(id, gating),
            // A face no cell has been in: its region is empty; its pair may have cells.
            None => {
                let pair = self.pair_ids.get(&key.pair).copied();
                let pair_cells = pair.map_or(&[][..], |p| self.pair_cells[p as usize].as_slice());
                let (region, fallback) = match gating {
                    Gating::Faces => (&[][..], Some(pair_cells)),
                    _ => (pair_cells, None),
                };
                FaceGate {
                    of_cell: &self.of_cell,
                    face: None,
                    pair,
                    gating,
                    region,
                    fallback,
                }
            }
        }
    }

    /// The gate of a query ray in the face numbered `id` (see [`Gating`]).
    pub(crate) fn gate_of(&self, id: FaceId, gating: Gating) -> FaceGate<'_> {
        let pair = self.pair_cells[id.pair as usize].as_slice();
        let (region, fallback) = match gating {
            Gating::Faces => (self.face_cells[id.face as usize].as_slice(), Some(pair)),
            _ => (pair, None),
        };
        FaceGate {
            of_cell: &self.of_cell,
            face: Some(id.face),
            pair: Some(id.pair),
            gating,
            region,
            fallback,
        }
    }

    /// Number of distinct faces holding at least one cell.
    pub(crate) fn occupied(&self) -> usize {
        self.face_cells.iter().filter(|c| !c.is_empty()).count()
    }

    /// Checks that the face and pair lists hold exactly the cells `of_cell` says, ascending, and
    /// that cell `c`'s face is `expected(c)`.
    pub(crate) fn check(
        &self,
        cells: usize,
        expected: impl Fn(CellId) -> Option<FaceKey>,
    ) -> Result<(), String> {
        if self.of_cell.len() != cells {
            return Err(format!(
                "faces known for {} of {cells} cells",
                self.of_cell.len()
            ));
        }
        for c in 0..cells {
            let want =
                expected(c).map(|key| (self.find(&key), self.pair_ids.get(&key.pair).copied()));
            let have = self.of_cell[c].map(|id| (Some(id), Some(id.pair)));
            if want != have {
                return Err(format!(
                    "cell {c} is filed under {have:?}, its centre is in {want:?}"
                ));
            }
        }
        for (face, list) in self.face_cells.iter().enumerate() {
            let sorted = list.windows(2).all(|w| w[0] < w[1]);
            if !sorted
                || list
                    .iter()
                    .any(|&c| self.of_cell[c].map(|f| f.face) != Some(face as u32))
            {
                return Err(format!("face {face} lists {list:?}"));
            }
        }
        for (pair, list) in self.pair_cells.iter().enumerate() {
            let sorted = list.windows(2).all(|w| w[0] < w[1]);
            if !sorted
                || list
                    .iter()
                    .any(|&c| self.of_cell[c].map(|f| f.pair) != Some(pair as u32))
            {
                return Err(format!("pair {pair} lists {list:?}"));
            }
        }
        let filed: usize = self.face_cells.iter().map(Vec::len).sum();
        if filed != self.of_cell.iter().flatten().count() {
            return Err("a cell is filed twice or not at all".into());
        }
        Ok(())
    }
}

fn insert_sorted(list: &mut Vec<CellId>, cell: CellId) {
    if let Err(at) = list.binary_search(&cell) {
        list.insert(at, cell);
    }
}

fn remove_sorted(list: &mut Vec<CellId>, cell: CellId) {
    if let Ok(at) = list.binary_search(&cell) {
        list.remove(at);
    }
}

/// Admits the cells of the query's face ([`Gating::Faces`]) or pair ([`Gating::Pairs`]), and
/// names them, so every one of them responds however far it is (see [`sgcs::Gate::region`]).
pub(crate) struct FaceGate<'a> {
    of_cell: &'a [Option<FaceId>],
    face: Option<u32>,
    pair: Option<u32>,
    gating: Gating,
    region: &'a [CellId],
    fallback: Option<&'a [CellId]>,
}

impl Gate for FaceGate<'_> {
    #[inline]
    fn admits(&self, cell: CellId) -> bool {
        match self.of_cell.get(cell).copied().flatten() {
            Some(id) => match self.gating {
                Gating::Faces => Some(id.face) == self.face,
                _ => Some(id.pair) == self.pair,
            },
            None => false,
        }
    }
    fn region(&self) -> Option<&[CellId]> {
        Some(self.region)
    }
    fn fallback(&self) -> Option<&[CellId]> {
        self.fallback
    }
}

/// Computes the face of a cell from its position.
#[derive(Clone, Debug)]
pub(crate) struct Labeller {
    frame: InputFrame,
    /// The parent surface edges, by rank.
    parents: NearestEdges,
    /// Distances closer than this are a tie (rounding of the frame's unmap).
    tie: f64,
}

impl Labeller {
    pub(crate) fn new(kernel: &Kernel, frame: InputFrame) -> Labeller {
        Labeller {
            frame,
            parents: NearestEdges::new(
                kernel
                    .surface_ranks()
                    .map(|r| kernel.surface_parent(r))
                    .collect(),
            ),
            tie: TIE / frame.inv_scale,
        }
    }

    /// The face of the centre ray of a cell at `pos` (frame coordinates, `x₁ y₁ x₂ y₂`): its
    /// ends are put on the nearest surface edges.
    pub(crate) fn face(&self, kernel: &Kernel, pos: &[f64]) -> Option<FaceKey> {
        let x = self.frame.unmap([pos[0], pos[1]]);
        let y = self.frame.unmap([pos[2], pos[3]]);
        FaceKey::of(
            kernel,
            self.nearest_parent(x, y),
            self.nearest_parent(y, x),
            x,
            y,
        )
    }

    /// The surface edge nearest `p`, the lowest rank of several. Of edges equally near (within
    /// rounding) one whose front faces `other`, the ray's other end, comes first: where a box
    /// stands on a floor or against a wall, its bottom lies on the floor, back to back, and a
    /// ray from the room to a point there ends on the floor, not on the box.
    fn nearest_parent(&self, p: DVec2, other: DVec2) -> SurfaceRank {
        let faces = |r: usize| {
            let (a, b) = self.parents.edge(r);
            (b - a).perp_dot(other - a) > 0.0
        };
        SurfaceRank::new(self.parents.nearest(p, self.tie, faces).unwrap_or(0))
    }
}

/// Distances within this share of the scene's size are a tie in [`Labeller::nearest_parent`].
const TIE: f64 = 1e-12;

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;

    /// A face of one of `pairs` pairs, with one of four side patterns.
    fn random_key(rng: &mut impl rand::Rng, pairs: u32) -> FaceKey {
        let mut rank = || SurfaceRank::new(rng.random_range(0..pairs) as usize);
        FaceKey {
            pair: (rank(), rank()),
            face: RayFace {
                sub: rng.random_range(0..2),
                sides: vec![rng.random_range(0..4u64)].into(),
                on_ray: Box::default(),
            },
        }
    }

    /// Cells placed, moved between faces, moved off every face and inserted at random, with
    /// faces of rays interned in between: after every change the face and pair lists hold
    /// exactly the cells filed there, ascending, and every gate names exactly those cells.
    #[test]
    fn face_filing_survives_random_moves_and_insertions() {
        let mut rng = crate::seeds::stream(11, 0);
        let mut faces = Faces::default();
        let mut filed: Vec<Option<FaceKey>> = Vec::new();
        for step in 0..3000 {
            let key = (rng.random::<f64>() < 0.85).then(|| random_key(&mut rng, 4));
            match rng.random_range(0..10) {
                // A new cell (ids are dense, as the network's are).
                0..=2 => {
                    faces.place(filed.len(), key.clone());
                    filed.push(key);
                }
                // A ray's face, numbered before any cell is in it.
                3 => {
                    if let Some(key) = key {
                        faces.intern(key);
                    }
                }
                // A cell moves (possibly within its face, or off every face).
                _ if !filed.is_empty() => {
                    let c = rng.random_range(0..filed.len());
                    faces.place(c, key.clone());
                    filed[c] = key;
                }
                _ => {}
            }
            faces
                .check(filed.len(), |c| filed[c].clone())
                .unwrap_or_else(|e| panic!("after change {step}: {e}"));
            let probe = random_key(&mut rng, 4);
            let in_face: Vec<CellId> = (0..filed.len())
                .filter(|&c| filed[c].as_ref() == Some(&probe))
                .collect();
            let in_pair: Vec<CellId> = (0..filed.len())
                .filter(|&c| filed[c].as_ref().is_some_and(|k| k.pair == probe.pair))
                .collect();
            let by_face = faces.gate(&probe, Gating::Faces);
            assert_eq!(by_face.region(), Some(&in_face[..]), "after change {step}");
            assert_eq!(
                by_face.fallback(),
                Some(&in_pair[..]),
                "after change {step}"
            );
            let by_pair = faces.gate(&probe, Gating::Pairs);
            assert_eq!(by_pair.region(), Some(&in_pair[..]), "after change {step}");
            for c in 0..filed.len() {
                assert_eq!(by_face.admits(c), in_face.contains(&c), "cell {c}");
                assert_eq!(by_pair.admits(c), in_pair.contains(&c), "cell {c}");
            }
        }
        assert!(faces.occupied() > 0 && filed.len() > 500, "{}", filed.len());
    }

    /// A room with boxes standing on its floor, against a wall and in a corner: the bottom of
    /// each lies on the room's wall, back to back with it.
    fn boxes_against_walls() -> Kernel {
        let v = DVec2::new;
        let mut edges = flatland_geom::Edge::polygon(
            &[
                v(0.0, 0.0),
                v(4.0, 0.0),
                v(4.0, 3.0),
                v(2.5, 3.0),
                v(1.5, 3.0),
                v(0.0, 3.0),
            ],
            0.5,
        );
        edges[3].emission = 1.0;
        for [x0, y0, x1, y1] in [
            [1.0, 0.0, 1.5, 0.5],
            [3.5, 1.0, 4.0, 1.5],
            [0.0, 0.0, 0.5, 0.5],
            [3.5, 2.5, 4.0, 3.0],
        ] {
            // Clockwise: the box's walls face outwards.
            let corners = [v(x0, y0), v(x0, y1), v(x1, y1), v(x1, y0)];
            edges.extend(flatland_geom::Edge::polygon(&corners, 0.6));
        }
        Kernel::new(flatland_geom::Scene::new(edges).unwrap())
    }

    /// Regression: a cell centred on the ray of `(s, t)` is filed under that ray's face. Where
    /// a box stands on the floor or against a wall, the box's edge on it was as near to a point
    /// there as the floor, and rounding in the frame's unmap made it the nearer: cells of rays
    /// from the room to the floor or wall behind a box were filed under a pair that never faces,
    /// their faces stayed empty, and the default preset's error on such scenes grew with the
    /// cells (0.13 at 400 cells, 0.17 at 4000, on a room with boxes in its corners).
    #[test]
    fn a_cell_on_a_ray_is_filed_under_its_face_where_boxes_touch_walls() {
        let kernel = boxes_against_walls();
        let frame = InputFrame::of(kernel.scene());
        let labeller = Labeller::new(&kernel, frame);
        let mut rng = crate::seeds::stream(12, 0);
        let (mut faces, mut wrong) = (0, Vec::new());
        for _ in 0..100_000 {
            let (s, t) = (rng.random::<f64>(), rng.random::<f64>());
            let u = kernel.unoccluded(s, t);
            let Some(key) = FaceKey::at(&kernel, &u).filter(|_| u.k > 0.0) else {
                continue;
            };
            faces += 1;
            let filed = labeller.face(&kernel, &frame.gamma(kernel.scene(), s, t));
            if filed.as_ref() != Some(&key) {
                wrong.push((s, t, u.x, u.y));
            }
        }
        assert!(faces > 10_000, "{faces} rays on varying pairs");
        assert!(
            wrong.is_empty(),
            "{} of {faces} filed elsewhere, e.g. {:?}",
            wrong.len(),
            wrong[0]
        );
    }
}
