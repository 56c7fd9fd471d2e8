//! The crate's one error type.

use flatland_geom::EdgeId;

/// Everything that can go wrong while meshing, building an operator or solving.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// A parameter is outside its valid range.
    #[error("parameter `{name}` is {value}, but must be {valid}")]
    InvalidParameter {
        /// The parameter's name as the CLI and files spell it.
        name: &'static str,
        /// The rejected value, as text.
        value: String,
        /// The valid range in words.
        valid: &'static str,
    },
    /// A representation of ζ = E'·k cannot give k on an edge whose source weight E' is 0.
    #[error(
        "surface edge {edge} has source weight E' = 0, so k = ζ / E' cannot be recovered there \
         from an approximation of ζ; use an emission floor > 0 (or the exact kernel)"
    )]
    ZeroSourceWeight {
        /// The edge (the first piece of its parent).
        edge: EdgeId,
    },
    /// The linear solve did not reach its tolerance.
    #[error(
        "the radiosity solve did not converge: relative residual {residual:e} after {iterations} \
         iterations (tolerance {tolerance:e}); a closed room with reflectance 1 traps light \
         forever, and a kernel approximation can make I − K singular"
    )]
    NotConverged {
        /// Products with K made.
        iterations: usize,
        /// The relative residual reached.
        residual: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
    /// An operator entry is not a finite number.
    #[error("the transfer operator has a non-finite entry at row {row}, column {column}")]
    NonFiniteOperator {
        /// Receiver element.
        row: usize,
        /// Sender element.
        column: usize,
    },
    /// A representation or reference of one scene was used with a mesh of another.
    #[error(
        "the kernel representation belongs to the scene with fingerprint {representation}, \
         but the mesh to {mesh}: build both on the same scene (and subdivision)"
    )]
    SceneMismatch {
        /// The representation's scene fingerprint (16 hex digits).
        representation: String,
        /// The mesh's scene fingerprint.
        mesh: String,
    },
    /// A representation of `ζ = E' k` learned under other lamps than the mesh's: `E'` (the
    /// light a sender sends first, docs/ALGORITHM.md §2) differs, so `ζ̃ / E'` is not `k`.
    #[error(
        "the kernel representation learned ζ = E' k with {representation} lamp(s), but the mesh's \
         scene has {mesh} lamp(s) or lamps elsewhere, and E' (the light each wall sends first) \
         with them: learn it again on this scene, or put the lamps back"
    )]
    LightsMismatch {
        /// Lamps of the representation's scene.
        representation: usize,
        /// Lamps of the mesh's scene.
        mesh: usize,
    },
    /// A scene or its lights refused (a light on an edge, named by its index).
    #[error(transparent)]
    Geom(#[from] flatland_geom::GeomError),
    /// The caller's stop flag ended the work.
    #[error("interrupted")]
    Interrupted,
}
