//! `Transport`: the later bounces of one scene and mesh, built once, queried per move.

use std::time::Instant;

use flatland_geom::Kernel;
use flatland_solve::{Mesh, SparseOperator};

use crate::clusters::Clusters;
use crate::estimate::{estimate, validation_lights};
use crate::footprint::Watch;
use crate::lowrank::{BlockTolerance, LowRank, build_blocks};
use crate::{
    BlockFootprint, Columns, ErrorEstimate, LaterBounces, Move, QueryBuffers, Stop, TransportError,
    TransportParams,
};

/// The later bounces `M₂ = K² (I − K)⁻¹` of one scene on one mesh, in a form that answers
/// `M₂ B₀` for a light's direct light B₀ in a fraction of a millisecond.
#[derive(Clone, Debug, PartialEq)]
pub struct Transport {
    pub(crate) params: TransportParams,
    pub(crate) identity: MeshIdentity,
    pub(crate) form: LowRank,
    pub(crate) estimate: ErrorEstimate,
    /// Seconds the build took (kept in the model file).
    pub(crate) setup_s: f64,
    /// Seconds the load took, for a model read from a file.
    pub(crate) loaded_s: Option<f64>,
}

/// What a model belongs to: the scene (its fingerprint), the element count and a hash of the
/// elements' parameter intervals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct MeshIdentity {
    pub scene: u64,
    pub elements: usize,
    pub mesh: u64,
}

impl MeshIdentity {
    /// In words, for an error.
    pub fn describe(&self) -> String {
        format!(
            "scene {:016x} on {} elements (mesh {:016x})",
            self.scene, self.elements, self.mesh
        )
    }

    pub fn of(mesh: &Mesh) -> MeshIdentity {
        // FNV-1a over the bits of every element's interval and reflectance.
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut write = |v: f64| {
            for byte in v.to_bits().to_le_bytes() {
                h ^= u64::from(byte);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for (i, e) in mesh.elements().iter().enumerate() {
            write(e.s[0]);
            write(e.s[1]);
            write(mesh.edge_of(i).reflectance);
        }
        MeshIdentity {
            scene: mesh.fingerprint(),
            elements: mesh.len(),
            mesh: h,
        }
    }
}

impl Transport {
    /// Builds the later bounces of `kernel`'s scene on `mesh` from its exact `operator` (the
    /// sweep's, [`flatland_solve::sweep_operator`]): clusters of elements, each cluster's block
    /// of `M₂` by local solves, compressed to `params.tolerance` (and `params.budget`), then
    /// its own error estimate from `params.validation_lights` lights. `stop` is polled per
    /// cluster, then per validation light. Errors: parameters out of range, an operator of
    /// another size, light that does not die out.
    pub fn build(
        kernel: &Kernel,
        mesh: &Mesh,
        operator: &SparseOperator,
        params: &TransportParams,
        stop: &Stop,
    ) -> Result<Transport, TransportError> {
        Transport::build_watched(kernel, mesh, operator, params, stop, &|_| {})
    }

    /// [`Transport::build`], each block's footprint handed to `watch` as soon as it is made
    /// (before a budget cuts ranks: [`Transport::footprints`] gives what is kept), so a viewer
    /// can draw the blocks as they grow.
    pub fn build_watched(
        kernel: &Kernel,
        mesh: &Mesh,
        operator: &SparseOperator,
        params: &TransportParams,
        stop: &Stop,
        watch: &Watch<'_>,
    ) -> Result<Transport, TransportError> {
        params.check()?;
        TransportError::check_inputs(kernel, mesh, operator)?;
        let started = Instant::now();
        let columns = Columns::of(operator);
        let mut built = Transport::build_unvalidated(kernel, mesh, &columns, params, stop, watch)?;
        built.validate(kernel, mesh, &columns, stop)?;
        built.setup_s = started.elapsed().as_secs_f64();
        Ok(built)
    }

    /// [`Transport::build_watched`] from the operator by columns, without its error estimate,
    /// which takes a few exact solves of its own: the model answers at once and
    /// [`Transport::estimated_error`] reads no lights (`lights == 0`) until
    /// [`Transport::validate`] measures it. For a viewer, whose moving light should not wait
    /// for the validation.
    pub fn build_unvalidated(
        kernel: &Kernel,
        mesh: &Mesh,
        columns: &Columns,
        params: &TransportParams,
        stop: &Stop,
        watch: &Watch<'_>,
    ) -> Result<Transport, TransportError> {
        params.check()?;
        TransportError::check_columns(kernel, mesh, columns)?;
        let started = Instant::now();
        let clusters = Clusters::spatial(mesh, params.cluster_elements);
        let tolerance = BlockTolerance {
            block: params.tolerance,
            solve: params.solve_tolerance,
        };
        let blocks = build_blocks(columns, &clusters, tolerance, stop, watch)?;
        let mut form = LowRank { clusters, blocks };
        if let Some(budget) = params.budget {
            form.fit_budget(budget);
        }
        Ok(Transport {
            params: *params,
            identity: MeshIdentity::of(mesh),
            form,
            estimate: ErrorEstimate::default(),
            setup_s: started.elapsed().as_secs_f64(),
            loaded_s: None,
        })
    }

    /// Measures the model's error estimate on its `validation_lights` (as
    /// [`Transport::build`] does), `stop` polled per light; its seconds are added to the
    /// set-up's. `kernel`, `mesh` and `columns` must be the ones it was built from.
    pub fn validate(
        &mut self,
        kernel: &Kernel,
        mesh: &Mesh,
        columns: &Columns,
        stop: &Stop,
    ) -> Result<(), TransportError> {
        self.check_mesh(mesh)?;
        TransportError::check_columns(kernel, mesh, columns)?;
        let started = Instant::now();
        let params = &self.params;
        let lights = validation_lights(kernel, mesh, params.validation_lights, params.seed);
        let form = &self.form;
        self.estimate = estimate(kernel, mesh, columns, &lights, stop, &|m, buffers| {
            form.accumulate(m.lit, buffers);
        })?;
        self.setup_s += started.elapsed().as_secs_f64();
        Ok(())
    }

    /// Adds `M₂ B₀` to `out` (length N) for B₀ given by its non-zero entries `(element,
    /// value)` — what a point light lights: one room and what it sees through doors. Where
    /// B₀ is nowhere negative the answer is raised to 0 where the truncation took it below
    /// (never further from the exact one). Elements past N are an error.
    pub fn add_later_bounces_of(
        &self,
        lit: &[(u32, f64)],
        out: &mut [f64],
        buffers: &mut QueryBuffers,
    ) -> Result<(), TransportError> {
        let n = self.identity.elements;
        TransportError::check_length("the output", out.len(), n)?;
        if let Some(&(j, _)) = lit.iter().find(|&&(j, _)| j as usize >= n) {
            return Err(TransportError::InvalidParameter {
                name: "B₀",
                value: format!("an entry for element {j}"),
                valid: "entries for elements of the mesh the model was built on",
            });
        }
        buffers.start(n);
        self.form.accumulate(lit, buffers);
        buffers.finish(out, lit.iter().all(|&(_, b)| b >= 0.0));
        Ok(())
    }

    /// `M₂ B₀` for a dense B₀ (length N).
    pub fn later_bounces(&self, b0: &[f64]) -> Result<Vec<f64>, TransportError> {
        let n = self.identity.elements;
        TransportError::check_length("B₀", b0.len(), n)?;
        let lit: Vec<(u32, f64)> = b0
            .iter()
            .enumerate()
            .filter(|&(_, &b)| b != 0.0)
            .map(|(j, &b)| (j as u32, b))
            .collect();
        let mut out = vec![0.0; n];
        self.add_later_bounces_of(&lit, &mut out, &mut QueryBuffers::default())?;
        Ok(out)
    }

    /// The model's own error estimate, from lights it drew itself (none, `lights == 0`, for a
    /// model from [`Transport::build_unvalidated`] not yet validated).
    #[must_use]
    pub fn estimated_error(&self) -> ErrorEstimate {
        self.estimate
    }

    /// Bytes the model holds (what a query reads; the file is about 4/3 of it).
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.form.bytes()
    }

    /// Seconds the set-up took in this process: the build, or the load of a saved model.
    #[must_use]
    pub fn setup_s(&self) -> f64 {
        self.loaded_s.unwrap_or(self.setup_s)
    }

    /// Seconds the build took, also for a model read from a file (which records it).
    #[must_use]
    pub fn build_s(&self) -> f64 {
        self.setup_s
    }

    /// The parameters it was built with.
    #[must_use]
    pub fn params(&self) -> &TransportParams {
        &self.params
    }

    /// How many times [`Transport::build`] polls its stop: once per block (cluster), then once
    /// per validation light of its estimate. A caller may count the polls as progress.
    #[must_use]
    pub fn set_up_steps(mesh: &Mesh, params: &TransportParams) -> usize {
        Transport::blocks_to_build(mesh, params) + params.validation_lights
    }

    /// The blocks a build on `mesh` makes: one per cluster of elements.
    #[must_use]
    pub fn blocks_to_build(mesh: &Mesh, params: &TransportParams) -> usize {
        Clusters::spatial(mesh, params.cluster_elements)
            .members
            .len()
    }

    /// Refuses `mesh` unless the model was built on it (its scene, its element count, its
    /// elements), with the one-line error [`Transport::load`] gives.
    pub fn check_mesh(&self, mesh: &Mesh) -> Result<(), TransportError> {
        let identity = MeshIdentity::of(mesh);
        if self.identity == identity {
            return Ok(());
        }
        Err(TransportError::ModelMismatch {
            model: self.identity.describe(),
            mesh: identity.describe(),
        })
    }

    /// Where each block lies: its senders and receivers as runs of elements, and its rank (in
    /// cluster order; one per cluster).
    #[must_use]
    pub fn footprints(&self) -> Vec<BlockFootprint> {
        self.form.footprints()
    }

    /// Visits every entry `(receiver, sender, M₂[receiver, sender])` the model holds — the
    /// learned kernel of the later bounces, for a picture of it (a query clamps what it sums
    /// at 0; an entry is as stored, and may dip below 0 by the truncation).
    pub fn entries(&self, mut visit: impl FnMut(u32, u32, f64)) {
        self.form.entries(&mut visit);
    }

    /// Clusters and the mean rank of their blocks.
    #[must_use]
    pub fn shape(&self) -> (usize, f64, f64) {
        let blocks = &self.form.blocks;
        let ranks: usize = blocks.iter().map(|b| b.rank()).sum();
        let rows: usize = blocks.iter().map(|b| b.rows.len()).sum();
        let count = blocks.len().max(1) as f64;
        (blocks.len(), ranks as f64 / count, rows as f64 / count)
    }
}

impl LaterBounces for Transport {
    fn add_later_bounces(
        &self,
        lights: Move<'_>,
        out: &mut [f64],
        buffers: &mut QueryBuffers,
    ) -> Result<(), TransportError> {
        self.add_later_bounces_of(lights.lit, out, buffers)
    }

    fn bytes(&self) -> usize {
        self.form.bytes()
    }

    fn estimated_error(&self) -> ErrorEstimate {
        self.estimate
    }

    fn setup_s(&self) -> f64 {
        Transport::setup_s(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::free::free_points;
    use crate::lit_source;
    use flatland_geom::{DVec2, Edge, PointLight, Scene};
    use flatland_solve::TransferOperator;
    use flatland_solve::{
        DirectLight, LightBuffers, SolveParams, never, solve_linear, sweep_operator,
    };
    use flatland_testkit::assert_close;

    /// A generated plan of about `edges` edges, lamps removed, on 3 elements per section.
    fn plan(edges: usize, seed: u64) -> (Kernel, Mesh, SparseOperator) {
        let scene = flatland_geom::generate::floor_plan_lit(edges, seed)
            .unwrap()
            .with_lights(Vec::new())
            .unwrap();
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, 3 * Mesh::min_elements(kernel.scene())).unwrap();
        let k = sweep_operator(&kernel, &mesh, &never).unwrap();
        (kernel, mesh, k)
    }

    /// The exact `M₂ B₀ = (I − K)⁻¹ K² B₀` by GMRES.
    fn exact_later(k: &SparseOperator, b0: &[f64]) -> Vec<f64> {
        let (mut once, mut twice) = (vec![0.0; b0.len()], vec![0.0; b0.len()]);
        k.apply(b0, &mut once);
        k.apply(&once, &mut twice);
        solve_linear(k, &twice, twice.clone(), &SolveParams::default(), &never)
            .unwrap()
            .radiosity
    }

    fn relative(mesh: &Mesh, a: &[f64], b: &[f64]) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (i, e) in mesh.elements().iter().enumerate() {
            num += e.length * (a[i] - b[i]).powi(2);
            den += e.length * b[i] * b[i];
        }
        (num / den).sqrt()
    }

    #[test]
    fn a_closed_uniform_room_gives_rho_squared_over_one_minus_rho() {
        // Rows of K sum to ρ in a closed room, so for B₀ = 1 everywhere K B₀ = ρ and
        // M₂ B₀ = ρ² / (1 − ρ), whatever the room hides from itself.
        let rho = 0.6;
        let corners = [
            (0.0, 0.0),
            (4.0, 0.0),
            (4.0, 1.5),
            (2.5, 1.5),
            (2.5, 3.0),
            (0.0, 3.0),
        ];
        let points: Vec<DVec2> = corners.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
        let kernel = Kernel::new(Scene::new(Edge::polygon(&points, rho)).unwrap());
        let mesh = Mesh::new(&kernel, 240).unwrap();
        let k = sweep_operator(&kernel, &mesh, &never).unwrap();
        let params = TransportParams {
            tolerance: 0.01,
            cluster_elements: 24,
            solve_tolerance: 1e-6,
            ..TransportParams::default()
        };
        let transport = Transport::build(&kernel, &mesh, &k, &params, &never).unwrap();
        let later = transport.later_bounces(&vec![1.0; mesh.len()]).unwrap();
        let expected = rho * rho / (1.0 - rho);
        let error = relative(&mesh, &later, &vec![expected; mesh.len()]);
        assert!(
            error <= 0.01,
            "relative error {error} against ρ²/(1 − ρ) = {expected}"
        );
    }

    #[test]
    fn later_bounces_are_the_exact_ones_within_the_models_own_estimate() {
        let (kernel, mesh, k) = plan(300, 21);
        let transport =
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never).unwrap();
        let estimate = transport.estimated_error();
        assert_eq!(estimate.lights, 32);
        let direct = DirectLight::new(&kernel, &mesh).unwrap();
        // Lights the set-up never saw: another seed's free points.
        let mut rng = flatland_testkit::rng(77);
        let lights = free_points(&kernel, &mesh, 24, 0.05, &mut rng);
        assert_eq!(lights.len(), 24);
        let mut errors = Vec::new();
        for at in lights {
            let light = PointLight { at, power: 5.0 };
            let lit = lit_source(&direct, &mesh, &[light], &mut LightBuffers::default());
            let mut b0 = vec![0.0; mesh.len()];
            for &(j, b) in &lit {
                b0[j as usize] = b;
            }
            let exact = exact_later(&k, &b0);
            let later = transport.later_bounces(&b0).unwrap();
            assert!(later.iter().all(|&v| v >= 0.0), "a negative later bounce");
            let error = relative(&mesh, &later, &exact);
            // Stated factor: each light within twice the largest estimated error.
            assert!(error <= 2.0 * estimate.later_max, "{error} vs {estimate:?}");
            errors.push(error);
        }
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        // The estimate is neither far below the measured mean nor far above it.
        assert!(
            mean <= 2.0 * estimate.later_mean,
            "mean {mean} vs {estimate:?}"
        );
        assert!(
            mean >= 0.25 * estimate.later_mean,
            "mean {mean} vs {estimate:?}"
        );
        assert!(estimate.later_mean <= 2.0 * transport.params().tolerance);
    }

    /// Built without its estimate, the model is the whole build's and answers the same; once
    /// validated its estimate is the build's too. Validating on another mesh is refused and a
    /// stop is obeyed.
    #[test]
    fn a_model_validated_later_is_the_one_built_at_once() {
        let (kernel, mesh, k) = plan(150, 5);
        let params = TransportParams::default();
        let whole = Transport::build(&kernel, &mesh, &k, &params, &never).unwrap();
        let columns = Columns::of(&k);
        let mut early =
            Transport::build_unvalidated(&kernel, &mesh, &columns, &params, &never, &|_| {})
                .unwrap();
        assert_eq!(early.form, whole.form);
        assert_eq!(early.estimated_error().lights, 0);
        let b0: Vec<f64> = (0..mesh.len()).map(|i| (i % 7) as f64 / 7.0).collect();
        assert_eq!(
            early.later_bounces(&b0).unwrap(),
            whole.later_bounces(&b0).unwrap()
        );
        let stopped = || true;
        assert!(matches!(
            early.validate(&kernel, &mesh, &columns, &stopped),
            Err(TransportError::Interrupted)
        ));
        let (other_kernel, other_mesh, other_k) = plan(150, 6);
        assert!(matches!(
            early.validate(&other_kernel, &other_mesh, &Columns::of(&other_k), &never),
            Err(TransportError::ModelMismatch { .. })
        ));
        early.validate(&kernel, &mesh, &columns, &never).unwrap();
        assert_eq!(early.estimated_error(), whole.estimated_error());
        assert!(early.estimated_error().lights > 0);
    }

    #[test]
    fn the_sparse_and_dense_queries_agree_and_bad_input_is_refused() {
        let (kernel, mesh, k) = plan(150, 3);
        let transport =
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never).unwrap();
        let lit = [(3u32, 0.5), (4, 0.25), (mesh.len() as u32 - 1, 1.0)];
        let mut b0 = vec![0.0; mesh.len()];
        for &(j, b) in &lit {
            b0[j as usize] = b;
        }
        let mut sparse = vec![0.0; mesh.len()];
        transport
            .add_later_bounces_of(&lit, &mut sparse, &mut QueryBuffers::default())
            .unwrap();
        assert_eq!(sparse, transport.later_bounces(&b0).unwrap());
        assert!(sparse.iter().any(|&v| v > 0.0));
        let past = [(mesh.len() as u32, 1.0)];
        let message = transport
            .add_later_bounces_of(&past, &mut sparse, &mut QueryBuffers::default())
            .unwrap_err()
            .to_string();
        assert!(
            message.contains(&format!("element {}", mesh.len())),
            "{message}"
        );
        assert!(transport.later_bounces(&b0[1..]).is_err());
        let short = sweep_operator(
            &kernel,
            &Mesh::new(&kernel, mesh.len() + 7).unwrap(),
            &never,
        )
        .unwrap();
        let message = Transport::build(&kernel, &mesh, &short, &TransportParams::default(), &never)
            .unwrap_err()
            .to_string();
        assert!(message.contains("the operator has"), "{message}");
        assert!(matches!(
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &|| true),
            Err(TransportError::Interrupted)
        ));
        // The polls a progress bar counts.
        let polls = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let counted = std::sync::Arc::clone(&polls);
        let counting = move || {
            counted.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            false
        };
        Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &counting).unwrap();
        let steps = Transport::set_up_steps(&mesh, &TransportParams::default());
        assert_eq!(polls.load(std::sync::atomic::Ordering::Relaxed), steps);
    }

    #[test]
    fn the_watched_blocks_are_the_stored_ones_and_cover_what_the_model_holds() {
        let (kernel, mesh, k) = plan(200, 5);
        let seen = std::sync::Mutex::new(Vec::new());
        let watch = |f: BlockFootprint| seen.lock().unwrap().push(f);
        let params = TransportParams::default();
        let transport =
            Transport::build_watched(&kernel, &mesh, &k, &params, &never, &watch).unwrap();
        let mut seen = seen.into_inner().unwrap();
        seen.sort_by_key(|f| f.cluster);
        let stored = transport.footprints();
        assert_eq!(seen, stored, "no budget: what was watched is what is kept");
        assert_eq!(stored.len(), Transport::blocks_to_build(&mesh, &params));
        // Every element sends from exactly one block; each block's runs are its rows.
        let mut sends = vec![0; mesh.len()];
        for (f, block) in stored.iter().zip(&transport.form.blocks) {
            f.senders
                .iter()
                .cloned()
                .flatten()
                .for_each(|e| sends[e as usize] += 1);
            let rows: Vec<u32> = f.receivers.iter().cloned().flatten().collect();
            assert_eq!(rows, block.rows);
            assert_eq!(f.rank, block.rank());
            assert!(f.pairs() <= block.rows.len() * mesh.len());
        }
        assert!(sends.iter().all(|&n| n == 1));
        assert!(stored.iter().any(|f| f.rank > 0 && f.pairs() > 0));
        // A budget cuts ranks after the build: the stored footprints say so.
        let tight = TransportParams {
            budget: Some(transport.bytes() / 4),
            ..params
        };
        let cut = Transport::build(&kernel, &mesh, &k, &tight, &never).unwrap();
        let ranks = |t: &Transport| t.footprints().iter().map(|f| f.rank).sum::<usize>();
        assert!(ranks(&cut) < ranks(&transport));
    }

    #[test]
    fn the_entries_are_the_columns_a_query_gives() {
        let (kernel, mesh, k) = plan(150, 6);
        let transport =
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never).unwrap();
        let n = mesh.len();
        let mut columns = vec![vec![0.0; n]; n];
        let mut count = 0;
        transport.entries(|row, column, value| {
            columns[column as usize][row as usize] += value;
            count += 1;
        });
        let kept: usize = transport
            .footprints()
            .iter()
            .filter(|f| f.rank > 0)
            .map(|f| {
                let len =
                    |runs: &[std::ops::Range<u32>]| runs.iter().map(|r| r.len()).sum::<usize>();
                len(&f.senders) * len(&f.receivers)
            })
            .sum();
        assert_eq!(count, kept, "one visit per pair of a block");
        for j in (0..n).step_by(7) {
            let mut unit = vec![0.0; n];
            unit[j] = 1.0;
            let column = transport.later_bounces(&unit).unwrap();
            for (i, (&queried, &entry)) in column.iter().zip(&columns[j]).enumerate() {
                assert_close!(
                    queried,
                    entry.max(0.0),
                    rel = 1e-9,
                    abs = 1e-15,
                    "M₂[{i}, {j}]"
                );
            }
        }
    }

    #[test]
    fn a_seed_gives_the_same_model_on_any_number_of_threads() {
        let (kernel, mesh, k) = plan(200, 8);
        let params = TransportParams {
            seed: 5,
            ..TransportParams::default()
        };
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| Transport::build(&kernel, &mesh, &k, &params, &never).unwrap())
        };
        let (one, two) = (on(1), on(2));
        assert_eq!(one.form, two.form);
        assert_eq!(one.estimate, two.estimate);
        assert_eq!(one.identity, two.identity);
    }

    #[test]
    fn a_budget_is_kept_by_dropping_the_least_light_per_byte() {
        let (kernel, mesh, k) = plan(300, 4);
        let free =
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never).unwrap();
        let budget = free.bytes() / 3;
        let params = TransportParams {
            budget: Some(budget),
            ..TransportParams::default()
        };
        let tight = Transport::build(&kernel, &mesh, &k, &params, &never).unwrap();
        assert!(tight.bytes() <= budget, "{} > {budget}", tight.bytes());
        let (e_free, e_tight) = (free.estimated_error(), tight.estimated_error());
        assert!(
            e_tight.later_mean > e_free.later_mean,
            "{e_tight:?} vs {e_free:?}"
        );
        assert_close!(
            tight.form.blocks.len() as f64,
            free.form.blocks.len() as f64,
            0.0
        );
    }
}
