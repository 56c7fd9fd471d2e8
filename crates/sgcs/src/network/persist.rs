//! Saving and loading: the versioned JSON form (primary state only), validated on load.

use serde::{Deserialize, Serialize};

use super::cells::{SavedCells, WorstSamples};
use super::{CellId, Network, check_values};
use crate::{Insertion, Params, SgcsError};

/// Version of the JSON format written by [`Network::to_json`].
pub const FORMAT_VERSION: u32 = 1;

const FORMAT_NAME: &str = "sgcs-network";

impl Network {
    /// The network as versioned JSON (format version [`FORMAT_VERSION`]).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| panic!("sgcs: serialising failed: {e}"))
    }

    /// Reads [`Network::to_json`]'s output; refuses other format versions with a message and
    /// validates the whole network (parameters, values, topology).
    pub fn from_json(text: &str) -> Result<Network, SgcsError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| SgcsError::Format(e.to_string()))?;
        if value.get("format").and_then(|f| f.as_str()) != Some(FORMAT_NAME) {
            return Err(SgcsError::Format(format!(
                "not an {FORMAT_NAME} document (missing \"format\": \"{FORMAT_NAME}\")"
            )));
        }
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == u64::from(FORMAT_VERSION) => {}
            Some(found) => {
                return Err(SgcsError::UnsupportedVersion {
                    found,
                    supported: FORMAT_VERSION,
                });
            }
            None => return Err(SgcsError::Format("missing \"version\"".into())),
        }
        serde_json::from_value(value).map_err(|e| SgcsError::Corrupt(e.to_string()))
    }
}

/// The saved form: primary state only; everything derived is rebuilt and checked on load.
#[derive(Serialize, Deserialize)]
pub(super) struct NetworkData {
    format: String,
    version: u32,
    params: Params,
    input_dim: usize,
    output_dim: usize,
    steps: u64,
    positions: Vec<f64>,
    outputs: Vec<f64>,
    triangles: Vec<[CellId; 3]>,
    error_mean: Vec<f64>,
    count: Vec<f64>,
    stamp: Vec<u64>,
    /// Only with [`Insertion::WorstSample`] (absent: all zero).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    worst: Option<WorstSamples>,
}

impl From<Network> for NetworkData {
    fn from(net: Network) -> Self {
        let keep_worst = net.params.insertion == Insertion::WorstSample;
        let cells = net.cells.into_saved();
        NetworkData {
            format: FORMAT_NAME.to_string(),
            version: FORMAT_VERSION,
            params: net.params,
            input_dim: net.n,
            output_dim: net.m,
            steps: net.steps,
            positions: cells.pos,
            outputs: cells.out,
            triangles: net.tris,
            error_mean: cells.err_mean,
            count: cells.cnt,
            stamp: cells.stamp,
            worst: cells.worst.filter(|_| keep_worst),
        }
    }
}

impl TryFrom<NetworkData> for Network {
    type Error = SgcsError;

    fn try_from(d: NetworkData) -> Result<Self, SgcsError> {
        if d.format != FORMAT_NAME {
            return Err(SgcsError::Format(format!("format is {:?}", d.format)));
        }
        if d.version != FORMAT_VERSION {
            return Err(SgcsError::UnsupportedVersion {
                found: u64::from(d.version),
                supported: FORMAT_VERSION,
            });
        }
        d.params.validate()?;
        let len = d.error_mean.len();
        if d.input_dim == 0
            || d.output_dim == 0
            || len < 3
            || len.checked_mul(d.input_dim) != Some(d.positions.len())
            || len.checked_mul(d.output_dim) != Some(d.outputs.len())
            || d.count.len() != len
            || d.stamp.len() != len
        {
            return Err(SgcsError::Corrupt("array lengths disagree".into()));
        }
        check_values("positions", &d.positions, d.positions.len())?;
        let cells = SavedCells {
            pos: d.positions,
            out: d.outputs,
            err_mean: d.error_mean,
            cnt: d.count,
            stamp: d.stamp,
            worst: d.worst,
        };
        let net = Network::assemble(
            d.params,
            d.input_dim,
            d.output_dim,
            cells,
            d.triangles,
            d.steps,
        )?;
        net.check_invariants().map_err(SgcsError::Corrupt)?;
        Ok(net)
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::test_support::{gated_params, grown, rng, unit_triangle};

    #[test]
    fn save_load_gives_identical_predictions_and_training() {
        let f = |x: f64, y: f64| (3.0 * x).cos() + y * y;
        let p = Params {
            lambda: 50,
            ..Params::default()
        };
        let mut a = grown(p, 10_000, 3, f);
        let mut b = Network::from_json(&a.to_json()).unwrap();
        b.check_invariants().unwrap();
        let mut r = rng(99);
        for _ in 0..200 {
            let xi = [r.random::<f64>() * 1.2 - 0.1, r.random::<f64>() * 1.2 - 0.1];
            assert_eq!(a.predict1(&xi).to_bits(), b.predict1(&xi).to_bits());
            assert_eq!(a.bmu(&xi), b.bmu(&xi));
        }
        // Training on after loading stays bit-identical (the index is rebuilt, results are not).
        for _ in 0..3_000 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            a.step(&[x, y], &[f(x, y)]);
            b.step(&[x, y], &[f(x, y)]);
        }
        assert_eq!(a.to_json(), b.to_json());
    }

    #[test]
    fn load_refuses_other_versions_and_garbage() {
        let net = Network::new(Params::default(), 2, 1, &unit_triangle()).unwrap();
        let text = net.to_json().replace("\"version\":1", "\"version\":2");
        let err = Network::from_json(&text).unwrap_err().to_string();
        assert!(
            err.contains("version 2") && err.contains("version 1"),
            "{err}"
        );
        assert!(Network::from_json("{}").is_err());
        assert!(Network::from_json("not json").is_err());
        let broken = net.to_json().replace("[0,1,2]", "[0,1,7]");
        assert!(Network::from_json(&broken).is_err());
    }

    /// Worst samples are saved: a reloaded network trains on exactly like the original.
    #[test]
    fn worst_samples_survive_save_and_load() {
        let f = |x: f64, y: f64| if x + y > 1.0 { 1.0 } else { 0.0 };
        let mut a = grown(gated_params(), 3_000, 5, f);
        let mut b = Network::from_json(&a.to_json()).unwrap();
        let mut r = rng(6);
        for _ in 0..2_000 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            a.step(&[x, y], &[f(x, y)]);
            b.step(&[x, y], &[f(x, y)]);
        }
        assert_eq!(a.to_json(), b.to_json());
    }
}
