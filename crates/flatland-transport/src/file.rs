//! The transport's model file: the versioned JSON the project's other models use (read through
//! [`flatland_geom::versioned`]), with the blocks' numbers packed as base64 of their
//! little-endian bytes — a model of 10⁴ edges holds tens of megabytes of numbers, and decimal
//! text would be 2.5 times that and slow to parse. Every field is checked on load, and a model
//! is only ever loaded against a mesh: one of another scene or mesh is refused.

use std::path::Path;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use flatland_solve::Mesh;
use serde::{Deserialize, Serialize};

use crate::clusters::Clusters;
use crate::lowrank::{ClusterBlock, LowRank};
use crate::transport::MeshIdentity;
use crate::{ErrorEstimate, Transport, TransportError, TransportParams};

/// The `format` of a transport model file.
pub const TRANSPORT_FORMAT: &str = "flatland-transport";
/// The version this build writes and reads.
pub const TRANSPORT_VERSION: u32 = 1;

/// The file: header first, then what the model is of, then the model.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TransportFile {
    format: String,
    version: u32,
    /// The scene's fingerprint (16 hex digits), the element count and the mesh's hash.
    scene_fingerprint: String,
    elements: usize,
    mesh_hash: String,
    params: TransportParams,
    estimate: ErrorEstimate,
    setup_s: f64,
    /// Each cluster's elements.
    clusters: Vec<Packed>,
    blocks: Vec<PackedBlock>,
}

/// A block as stored.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PackedBlock {
    rows: Packed,
    u: Packed,
    v: Packed,
    sigma: Packed,
    norm: f64,
    dropped: f64,
}

/// Numbers as base64 of their little-endian bytes.
#[derive(Serialize, Deserialize)]
#[serde(transparent)]
struct Packed(String);

impl Packed {
    fn words<T: Copy, const W: usize>(values: &[T], bytes: impl Fn(T) -> [u8; W]) -> Packed {
        let raw: Vec<u8> = values.iter().flat_map(|&v| bytes(v)).collect();
        Packed(STANDARD.encode(raw))
    }

    fn u32s(values: &[u32]) -> Packed {
        Packed::words(values, u32::to_le_bytes)
    }

    fn f32s(values: &[f32]) -> Packed {
        Packed::words(values, f32::to_le_bytes)
    }

    fn f64s(values: &[f64]) -> Packed {
        Packed::words(values, f64::to_le_bytes)
    }

    fn unpack<T, const W: usize>(
        &self,
        what: &str,
        from: impl Fn([u8; W]) -> T,
    ) -> Result<Vec<T>, String> {
        let raw = STANDARD
            .decode(&self.0)
            .map_err(|e| format!("{what}: not base64 ({e})"))?;
        if raw.len() % W != 0 {
            return Err(format!(
                "{what}: {} bytes, not a multiple of {W}",
                raw.len()
            ));
        }
        Ok(raw
            .chunks_exact(W)
            .map(|c| from(c.try_into().expect("chunks of W bytes")))
            .collect())
    }
}

impl Transport {
    /// Writes the model to `path` (atomically: a reader sees the old file or the new one).
    pub fn save(&self, path: &Path) -> Result<(), TransportError> {
        let file = TransportFile {
            format: TRANSPORT_FORMAT.to_owned(),
            version: TRANSPORT_VERSION,
            scene_fingerprint: format!("{:016x}", self.identity.scene),
            elements: self.identity.elements,
            mesh_hash: format!("{:016x}", self.identity.mesh),
            params: self.params,
            estimate: self.estimate,
            setup_s: self.setup_s,
            clusters: self
                .form
                .clusters
                .members
                .iter()
                .map(|m| Packed::u32s(m))
                .collect(),
            blocks: self
                .form
                .blocks
                .iter()
                .map(|b| PackedBlock {
                    rows: Packed::u32s(&b.rows),
                    u: Packed::f32s(&b.u),
                    v: Packed::f32s(&b.v),
                    sigma: Packed::f64s(&b.sigma),
                    norm: b.norm,
                    dropped: b.dropped,
                })
                .collect(),
        };
        let text = serde_json::to_vec(&file).map_err(|e| TransportError::File {
            path: path.display().to_string(),
            message: format!("cannot write: {e}"),
        })?;
        flatland_geom::write_atomic(path, &text).map_err(|e| TransportError::File {
            path: path.display().to_string(),
            message: e.to_string(),
        })
    }

    /// Reads the model at `path` for `mesh`: the file's format and version first, then every
    /// field, then that it was built on `mesh`'s scene and on `mesh` itself. Errors are one
    /// line naming the file and what is wrong.
    pub fn load(path: &Path, mesh: &Mesh) -> Result<Transport, TransportError> {
        let fail = |message: String| TransportError::File {
            path: path.display().to_string(),
            message,
        };
        let started = std::time::Instant::now();
        let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read: {e}")))?;
        let file: TransportFile = flatland_geom::versioned::read(
            &bytes,
            &flatland_geom::versioned::Kind {
                format: TRANSPORT_FORMAT,
                version: TRANSPORT_VERSION,
                noun: "transport model",
                remedy: "build it again with this build",
            },
        )
        .map_err(fail)?;
        let mut transport = file.into_transport().map_err(fail)?;
        transport.check_mesh(mesh)?;
        transport.loaded_s = Some(started.elapsed().as_secs_f64());
        Ok(transport)
    }
}

impl TransportFile {
    /// The model, every field checked against the others.
    fn into_transport(self) -> Result<Transport, String> {
        self.params.check().map_err(|e| format!("params: {e}"))?;
        let hex = |name: &str, text: &str| {
            u64::from_str_radix(text, 16)
                .ok()
                .filter(|_| text.len() == 16)
                .ok_or_else(|| format!("`{name}` must be 16 hex digits, not {text:?}"))
        };
        let identity = MeshIdentity {
            scene: hex("scene_fingerprint", &self.scene_fingerprint)?,
            elements: self.elements,
            mesh: hex("mesh_hash", &self.mesh_hash)?,
        };
        let n = self.elements;
        let members = self
            .clusters
            .iter()
            .enumerate()
            .map(|(c, m)| m.unpack(&format!("cluster {c}"), u32::from_le_bytes))
            .collect::<Result<Vec<Vec<u32>>, String>>()?;
        check_partition(&members, n)?;
        if self.blocks.len() != members.len() {
            return Err(format!(
                "{} blocks for {} clusters: one block per cluster",
                self.blocks.len(),
                members.len()
            ));
        }
        let blocks = self
            .blocks
            .iter()
            .zip(&members)
            .enumerate()
            .map(|(c, (b, m))| unpack_block(c, b, m.len(), n))
            .collect::<Result<Vec<ClusterBlock>, String>>()?;
        let figures = [self.setup_s, self.estimate.later_mean, self.estimate.b_mean];
        if figures.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err("`setup_s` and the estimate must be finite and not negative".to_owned());
        }
        Ok(Transport {
            params: self.params,
            identity,
            form: LowRank {
                clusters: Clusters::from_members(members, n),
                blocks,
            },
            estimate: self.estimate,
            setup_s: self.setup_s,
            loaded_s: None,
        })
    }
}

/// Every element of `0..n` in exactly one cluster, each cluster ascending.
fn check_partition(members: &[Vec<u32>], n: usize) -> Result<(), String> {
    let mut seen = vec![false; n];
    for (c, list) in members.iter().enumerate() {
        if list.is_empty() || list.windows(2).any(|w| w[0] >= w[1]) {
            return Err(format!(
                "cluster {c}: elements must be ascending, at least one"
            ));
        }
        for &e in list {
            let slot = seen
                .get_mut(e as usize)
                .ok_or_else(|| format!("cluster {c}: element {e} of a mesh of {n}"))?;
            if *slot {
                return Err(format!("element {e} is in two clusters"));
            }
            *slot = true;
        }
    }
    match seen.iter().position(|s| !s) {
        Some(e) => Err(format!("element {e} is in no cluster")),
        None => Ok(()),
    }
}

/// Block `c` of a cluster of `width` elements on a mesh of `n`.
fn unpack_block(c: usize, b: &PackedBlock, width: usize, n: usize) -> Result<ClusterBlock, String> {
    let what = |part: &str| format!("block {c} {part}");
    let rows = b.rows.unpack(&what("rows"), u32::from_le_bytes)?;
    let u = b.u.unpack(&what("u"), f32::from_le_bytes)?;
    let v = b.v.unpack(&what("v"), f32::from_le_bytes)?;
    let sigma = b.sigma.unpack(&what("sigma"), f64::from_le_bytes)?;
    let rank = sigma.len();
    if rows.windows(2).any(|w| w[0] >= w[1]) || rows.last().is_some_and(|&r| r as usize >= n) {
        return Err(format!("block {c}: rows must ascend and be below {n}"));
    }
    if u.len() != rows.len() * rank || v.len() != width * rank || rank > width {
        return Err(format!(
            "block {c}: rank {rank} needs {} numbers in u and {} in v, not {} and {}",
            rows.len() * rank,
            width * rank,
            u.len(),
            v.len()
        ));
    }
    let finite = u.iter().chain(&v).all(|x| x.is_finite())
        && sigma
            .iter()
            .chain([&b.norm, &b.dropped])
            .all(|x| x.is_finite() && *x >= 0.0);
    if !finite {
        return Err(format!(
            "block {c}: every number must be finite (singular values and norms not negative)"
        ));
    }
    Ok(ClusterBlock {
        rows,
        u,
        v,
        sigma,
        norm: b.norm,
        dropped: b.dropped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::QueryBuffers;
    use flatland_geom::Kernel;
    use flatland_solve::{SparseOperator, never, sweep_operator};

    fn plan(seed: u64, per: usize) -> (Kernel, Mesh, SparseOperator) {
        let scene = flatland_geom::generate::floor_plan(200, seed).unwrap();
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, per * Mesh::min_elements(kernel.scene())).unwrap();
        let k = sweep_operator(&kernel, &mesh, &never).unwrap();
        (kernel, mesh, k)
    }

    fn dir(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("flatland-transport-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn save_then_load_gives_the_same_answers_bit_for_bit() {
        let (kernel, mesh, k) = plan(6, 2);
        let built =
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never).unwrap();
        let path = dir("roundtrip").join("model.json");
        built.save(&path).unwrap();
        let loaded = Transport::load(&path, &mesh).unwrap();
        // The same model; its set-up is now the load's, its build's seconds kept.
        assert_eq!(loaded.build_s(), built.build_s());
        assert!(loaded.loaded_s.is_some());
        assert_eq!(
            Transport {
                loaded_s: None,
                ..loaded.clone()
            },
            built
        );
        let lit: Vec<(u32, f64)> = (0..mesh.len() as u32)
            .step_by(7)
            .map(|j| (j, 0.1 + f64::from(j % 5)))
            .collect();
        let (mut a, mut b) = (vec![0.0; mesh.len()], vec![0.0; mesh.len()]);
        built
            .add_later_bounces_of(&lit, &mut a, &mut QueryBuffers::default())
            .unwrap();
        loaded
            .add_later_bounces_of(&lit, &mut b, &mut QueryBuffers::default())
            .unwrap();
        assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
        // The file is about 4/3 of the bytes held, not the 2.5 times of decimal text.
        let size = std::fs::metadata(&path).unwrap().len() as f64;
        assert!(
            size < 1.6 * built.bytes() as f64,
            "{size} bytes for {}",
            built.bytes()
        );
    }

    #[test]
    fn a_model_of_another_scene_or_mesh_is_refused() {
        let (kernel, mesh, k) = plan(6, 2);
        let built =
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never).unwrap();
        let path = dir("mismatch").join("model.json");
        built.save(&path).unwrap();
        let (_, other_scene, _) = plan(7, 2);
        let finer = Mesh::new(&kernel, mesh.len() + 1).unwrap();
        assert!(built.check_mesh(&mesh).is_ok());
        for other in [&other_scene, &finer] {
            assert!(built.check_mesh(other).is_err());
            let message = Transport::load(&path, other).unwrap_err().to_string();
            assert!(
                message.contains("was built for scene") && !message.contains('\n'),
                "{message}"
            );
        }
    }

    #[test]
    fn a_damaged_file_is_one_line_naming_what_is_wrong() {
        let (kernel, mesh, k) = plan(6, 2);
        let built =
            Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never).unwrap();
        let dir = dir("damaged");
        let path = dir.join("model.json");
        built.save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let first_rows = {
            let at = text.find("\"rows\":\"").unwrap() + 8;
            &text[at..at + text[at..].find('"').unwrap()]
        };
        let far = STANDARD.encode(u32::MAX.to_le_bytes());
        let cases = [
            (
                text[..text.len() / 2].to_owned(),
                "not a flatland transport model",
            ),
            (
                text.replacen("flatland-transport", "flatland-model", 1),
                "`format` must be",
            ),
            (
                text.replacen("\"version\":1", "\"version\":9", 1),
                "version 9, but this build reads version 1",
            ),
            (
                text.replacen(first_rows, &far, 1),
                "rows must ascend and be below",
            ),
            (text.replacen(first_rows, "%%%", 1), "not base64"),
            (
                text.replacen("\"tolerance\":0.05", "\"tolerance\":2.0", 1),
                "`tolerance` is 2",
            ),
        ];
        for (k, (damaged, expected)) in cases.iter().enumerate() {
            let bad = dir.join(format!("bad{k}.json"));
            std::fs::write(&bad, damaged).unwrap();
            let message = Transport::load(&bad, &mesh).unwrap_err().to_string();
            assert!(
                message.contains(expected) && !message.contains('\n'),
                "case {k}: {message}"
            );
            assert!(message.starts_with(&bad.display().to_string()), "{message}");
        }
    }
}
