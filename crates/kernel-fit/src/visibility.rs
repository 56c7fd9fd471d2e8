//! The visibility learner's geometry: which face of a pair's visibility structure a ray or a
//! cell lies in, and where its samples are drawn.
//!
//! With [`Target::Visibility`](crate::Target::Visibility) the network learns only `V` on the
//! pairs of surface edges where it varies ([`PairClass::Varies`]); everywhere else the geometry
//! gives it exactly. On such a pair `V` is constant on the faces cut out by the curves of the
//! pair's event points ([`flatland_geom::PairEvents`]). A cell belongs to the face of its centre
//! ray, and a [`FaceGate`] lets only the cells of a query ray's face respond: no cell straddles
//! a known discontinuity, and a face with one cell anywhere in it has that cell's value.

use foldhash::HashMap;

use flatland_geom::{DVec2, Kernel, PairClass, PairEvents, Unoccluded};
use flatland_solve::InputFrame;
use rand::{Rng, RngExt};
use sgcs::{CellId, Gate};

use crate::Gating;

/// One face of a pair's visibility structure: the ordered pair of surface edges (sender rank,
/// receiver rank), the sub-pair, and the side of each of the sub-pair's event points (bits).
/// Visibility is the same for every ray of one face.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct FaceKey {
    pair: (u32, u32),
    sub: u8,
    sides: Box<[u64]>,
}

impl FaceKey {
    /// The face of the ray from `x` (on the surface of rank `a`) to `y` (rank `b`); `None`
    /// unless visibility varies on that pair.
    pub(crate) fn of(kernel: &Kernel, a: usize, b: usize, x: DVec2, y: DVec2) -> Option<FaceKey> {
        if a == b || kernel.pair_class(a, b) != PairClass::Varies {
            return None;
        }
        let events = kernel.visibility_events(a, b)?;
        let sub = events.sub_pair(x, y);
        let points = events.points(sub);
        let mut sides = vec![0u64; points.len().div_ceil(64)];
        for (i, &v) in points.iter().enumerate() {
            if PairEvents::side(x, y, v) {
                sides[i / 64] |= 1 << (i % 64);
            }
        }
        Some(FaceKey {
            pair: (a as u32, b as u32),
            sub: sub as u8,
            sides: sides.into(),
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
    pair_ids: HashMap<(u32, u32), u32>,
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
    parents: Vec<(DVec2, DVec2)>,
}

impl Labeller {
    pub(crate) fn new(kernel: &Kernel, frame: InputFrame) -> Labeller {
        Labeller {
            frame,
            parents: (0..kernel.surface_parents())
                .map(|r| kernel.surface_parent(r))
                .collect(),
        }
    }

    /// The face of the centre ray of a cell at `pos` (frame coordinates, `x₁ y₁ x₂ y₂`): its
    /// ends are put on the nearest surface edges.
    pub(crate) fn face(&self, kernel: &Kernel, pos: &[f64]) -> Option<FaceKey> {
        let x = self.frame.unmap([pos[0], pos[1]]);
        let y = self.frame.unmap([pos[2], pos[3]]);
        FaceKey::of(kernel, self.nearest_parent(x), self.nearest_parent(y), x, y)
    }

    fn nearest_parent(&self, p: DVec2) -> usize {
        let mut best = (f64::INFINITY, 0);
        for (r, &(a, b)) in self.parents.iter().enumerate() {
            let d = distance_to_segment(p, a, b);
            if d < best.0 {
                best = (d, r);
            }
        }
        best.1
    }
}

fn distance_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len2 = d.length_squared();
    let u = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + d * u)
}

/// Draws `(s, t)` where visibility varies: a share `importance` from a proposal that follows
/// the clipped square of the unoccluded target `g = min(ζ_unoccluded / c, 1)²`, the rest
/// uniformly, each with the importance weight `w ∝ g / q` that makes weighted sums estimate
/// `∫∫ g (·) ds dt` over those pairs (so errors count where the target is bright).
///
/// The pairs of surface edges where visibility varies are listed with the area of their
/// rectangle of `(s, t)`; a uniform draw picks one in proportion to its area, then a point in
/// it (no draw is wasted on pairs geometry decides). The importance proposal cuts each pair's
/// rectangle into [`TILES`]² tiles, estimates `g` on each from a few points (geometry only, no
/// ray) and draws tiles in proportion to area × estimate. A scene with more than
/// [`MAX_LISTED_PARENTS`] surface edges draws from the whole square instead, keeps what lands on
/// such a pair, and draws in proportion to `g` by rejection.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Sampler {
    importance: f64,
    /// The clip level `c` of the unoccluded ζ (a high quantile of it).
    clip: f64,
    /// The mean of `g` over uniform draws.
    mean_g: f64,
    /// The pairs where visibility varies: (sender rank, receiver rank, cumulative area).
    pairs: Vec<(u32, u32, f64)>,
    /// Parameter ranges of the surface edges, by rank.
    ranges: Vec<(f64, f64)>,
    /// Per tile (pair-major, [`TILES`]² per pair): the estimate of `g`, and the cumulative
    /// area × estimate the importance proposal draws by.
    tile_g: Vec<f64>,
    tile_cumulative: Vec<f64>,
    /// The area-weighted mean of `tile_g`.
    mean_tile_g: f64,
}

/// A drawn place: `(s, t)` and its importance weight.
pub(crate) struct Draw {
    pub st: [f64; 2],
    pub weight: f64,
}

/// Uniform draws tried before concluding that no pair has varying visibility.
const MAX_TRIES: usize = 1 << 20;
/// Uniform draws that set the clip level.
const PILOT: usize = 4096;
/// The clip level is this quantile of the unoccluded ζ: the 1/r corners of a light must not
/// take every sample.
const CLIP_QUANTILE: f64 = 0.99;
/// Up to this many surface edges the pairs are listed (n² entries).
pub(crate) const MAX_LISTED_PARENTS: usize = 512;
/// Tiles per side of a pair's rectangle in the importance proposal.
const TILES: usize = 8;
/// Points per tile estimating `g` (a jittered 2 × 2 grid).
const TILE_POINTS: usize = 2;

impl Sampler {
    /// Lists the pairs, sets the clip level from a pilot of uniform draws and builds the
    /// importance proposal; `None` when visibility varies nowhere.
    pub(crate) fn new(kernel: &Kernel, importance: f64, rng: &mut impl Rng) -> Option<Sampler> {
        let n = kernel.surface_parents();
        let mut sampler = Sampler {
            importance,
            clip: 1.0,
            mean_g: 1.0,
            pairs: Vec::new(),
            ranges: Vec::new(),
            tile_g: Vec::new(),
            tile_cumulative: Vec::new(),
            mean_tile_g: 1.0,
        };
        if n <= MAX_LISTED_PARENTS {
            let scene = kernel.scene();
            sampler.ranges = (0..n)
                .map(|r| scene.parent_param_range(r).unwrap_or((0.0, 0.0)))
                .collect();
            let mut total = 0.0;
            for a in 0..n {
                for b in 0..n {
                    if kernel.pair_class(a, b) == PairClass::Varies {
                        let (ra, rb) = (sampler.ranges[a], sampler.ranges[b]);
                        total += (ra.1 - ra.0) * (rb.1 - rb.0);
                        sampler.pairs.push((a as u32, b as u32, total));
                    }
                }
            }
            if sampler.pairs.is_empty() {
                return None;
            }
        }
        let mut values: Vec<f64> = Vec::with_capacity(PILOT);
        for _ in 0..PILOT {
            values.push(sampler.uniform(kernel, rng)?.1.zeta);
        }
        values.sort_by(f64::total_cmp);
        let clip = values[((values.len() - 1) as f64 * CLIP_QUANTILE) as usize];
        sampler.clip = if clip > 0.0 { clip } else { 1.0 };
        let mean_g = values.iter().map(|&z| g(z, sampler.clip)).sum::<f64>() / values.len() as f64;
        sampler.mean_g = mean_g.max(f64::MIN_POSITIVE);
        sampler.build_tiles(kernel, rng);
        Some(sampler)
    }

    /// Estimates `g` on every tile of every listed pair.
    fn build_tiles(&mut self, kernel: &Kernel, rng: &mut impl Rng) {
        let (mut cumulative, mut weighted) = (0.0, 0.0);
        let mut previous = 0.0;
        for k in 0..self.pairs.len() {
            let (a, b, end) = self.pairs[k];
            let pair_area = end - previous;
            previous = end;
            let (ra, rb) = (self.ranges[a as usize], self.ranges[b as usize]);
            let (ws, wt) = ((ra.1 - ra.0) / TILES as f64, (rb.1 - rb.0) / TILES as f64);
            for i in 0..TILES {
                for j in 0..TILES {
                    let mut sum = 0.0;
                    for p in 0..TILE_POINTS * TILE_POINTS {
                        let u =
                            ((p / TILE_POINTS) as f64 + rng.random::<f64>()) / TILE_POINTS as f64;
                        let v =
                            ((p % TILE_POINTS) as f64 + rng.random::<f64>()) / TILE_POINTS as f64;
                        let z = kernel
                            .unoccluded(ra.0 + ws * (i as f64 + u), rb.0 + wt * (j as f64 + v))
                            .zeta;
                        sum += g(z, self.clip);
                    }
                    let estimate = sum / (TILE_POINTS * TILE_POINTS) as f64;
                    let area = pair_area / (TILES * TILES) as f64;
                    cumulative += area * estimate;
                    weighted += area * estimate;
                    self.tile_g.push(estimate);
                    self.tile_cumulative.push(cumulative);
                }
            }
        }
        let total_area = self.pairs.last().map_or(0.0, |p| p.2);
        self.mean_tile_g = if total_area > 0.0 && weighted > 0.0 {
            weighted / total_area
        } else {
            1.0
        };
    }

    /// One draw (no ray is cast).
    pub(crate) fn draw(&self, kernel: &Kernel, rng: &mut impl Rng) -> Draw {
        let by_importance = rng.random::<f64>() < self.importance;
        let (st, u) = match (by_importance, self.tile_cumulative.last()) {
            (true, Some(&total)) if total > 0.0 => loop {
                let x = rng.random::<f64>() * total;
                let tile = self
                    .tile_cumulative
                    .partition_point(|&c| c <= x)
                    .min(self.tile_cumulative.len() - 1);
                let (s, t) = self.point_in_tile(tile, rng);
                let u = kernel.unoccluded(s, t);
                if u.zeta > 0.0 {
                    break ([s, t], u);
                }
            },
            (true, _) => loop {
                let (st, u) = self.uniform(kernel, rng).expect("checked by Sampler::new");
                if rng.random::<f64>() < g(u.zeta, self.clip) {
                    break (st, u);
                }
            },
            (false, _) => self.uniform(kernel, rng).expect("checked by Sampler::new"),
        };
        Draw {
            weight: self.weight(st, u.zeta),
            st,
        }
    }

    /// The importance weight `p / q` of a sample at `st` with unoccluded ζ `zeta`, relative to
    /// uniform draws (`p ∝ g`, `q` the mixture of uniform and importance draws).
    pub(crate) fn weight(&self, st: [f64; 2], zeta: f64) -> f64 {
        let relative = g(zeta, self.clip) / self.mean_g;
        let proposal = match self.tile_of(st) {
            Some(tile) => self.tile_g[tile] / self.mean_tile_g,
            None => relative,
        };
        relative / ((1.0 - self.importance) + self.importance * proposal)
    }

    /// The tile holding `st`, if the pairs are listed.
    fn tile_of(&self, [s, t]: [f64; 2]) -> Option<usize> {
        if self.tile_g.is_empty() {
            return None;
        }
        let rank = |x: f64| {
            self.ranges
                .partition_point(|r| r.1 <= x)
                .min(self.ranges.len() - 1)
        };
        let (a, b) = (rank(s) as u32, rank(t) as u32);
        // Pairs are listed in (sender, receiver) order.
        let k = self
            .pairs
            .binary_search_by_key(&(a, b), |p| (p.0, p.1))
            .ok()?;
        let (ra, rb) = (self.ranges[a as usize], self.ranges[b as usize]);
        let cell = |x: f64, r: (f64, f64)| {
            (((x - r.0) / (r.1 - r.0) * TILES as f64) as usize).min(TILES - 1)
        };
        Some(k * TILES * TILES + cell(s, ra) * TILES + cell(t, rb))
    }

    /// A uniform point in tile `tile`.
    fn point_in_tile(&self, tile: usize, rng: &mut impl Rng) -> (f64, f64) {
        let (k, rest) = (tile / (TILES * TILES), tile % (TILES * TILES));
        let (i, j) = (rest / TILES, rest % TILES);
        let (a, b, _) = self.pairs[k];
        let (ra, rb) = (self.ranges[a as usize], self.ranges[b as usize]);
        let (ws, wt) = ((ra.1 - ra.0) / TILES as f64, (rb.1 - rb.0) / TILES as f64);
        (
            ra.0 + ws * (i as f64 + rng.random::<f64>()),
            rb.0 + wt * (j as f64 + rng.random::<f64>()),
        )
    }

    /// A uniform `(s, t)` on a pair where visibility varies and the unoccluded ζ is positive.
    fn uniform(&self, kernel: &Kernel, rng: &mut impl Rng) -> Option<([f64; 2], Unoccluded)> {
        for _ in 0..MAX_TRIES {
            let (s, t) = match self.pairs.last() {
                Some(&(_, _, total)) => {
                    let x = rng.random::<f64>() * total;
                    let k = self
                        .pairs
                        .partition_point(|p| p.2 <= x)
                        .min(self.pairs.len() - 1);
                    let (a, b, _) = self.pairs[k];
                    let (ra, rb) = (self.ranges[a as usize], self.ranges[b as usize]);
                    (
                        ra.0 + (ra.1 - ra.0) * rng.random::<f64>(),
                        rb.0 + (rb.1 - rb.0) * rng.random::<f64>(),
                    )
                }
                None => (rng.random::<f64>(), rng.random::<f64>()),
            };
            let u = kernel.unoccluded(s, t);
            if u.zeta > 0.0 && kernel.pair_class(u.sender, u.receiver) == PairClass::Varies {
                return Some(([s, t], u));
            }
        }
        None
    }
}

/// `min(z / c, 1)²`.
fn g(z: f64, c: f64) -> f64 {
    (z / c).min(1.0).powi(2)
}
