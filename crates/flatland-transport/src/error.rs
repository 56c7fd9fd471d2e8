//! The crate's one error type.

/// Everything that can go wrong while building, querying, saving or loading a transport.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TransportError {
    /// A parameter is outside its valid range.
    #[error("parameter `{name}` is {value}, but must be {valid}")]
    InvalidParameter {
        /// The parameter's name as files and the CLI spell it.
        name: &'static str,
        /// The rejected value, as text.
        value: String,
        /// The valid range in words.
        valid: &'static str,
    },
    /// The mesh, the operator or a source vector do not belong together.
    #[error("{what} has {found} elements, but the mesh has {expected}")]
    LengthMismatch {
        /// What was given ("the operator", "B₀").
        what: &'static str,
        /// Its length.
        found: usize,
        /// The mesh's element count.
        expected: usize,
    },
    /// A model of another scene or mesh.
    #[error(
        "the transport model was built for {model}, but the mesh is {mesh}: build the model again \
         on this scene and mesh (`--save-model`)"
    )]
    ModelMismatch {
        /// The model's scene and mesh, in words.
        model: String,
        /// The mesh's, in words.
        mesh: String,
    },
    /// Light that does not die out: a local solve pushed more than its limit.
    #[error(
        "the later bounces from element {element} did not die out after {pushes} pushes; every \
         reflectance must be below 1 where light can be trapped"
    )]
    NotConverged {
        /// An element the light started from.
        element: usize,
        /// Pushes made.
        pushes: usize,
    },
    /// A model file that cannot be read (one line: what and where).
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: String,
        /// What is wrong with it.
        message: String,
    },
    /// The solver (or its visibility sweep) refused something (its message, unchanged).
    #[error(transparent)]
    Solve(#[from] flatland_solve::SolveError),
    /// The caller's stop flag ended the work.
    #[error("interrupted")]
    Interrupted,
}

impl TransportError {
    /// `Ok` when `what` has the mesh's `expected` elements, else [`TransportError::LengthMismatch`].
    pub(crate) fn check_length(
        what: &'static str,
        found: usize,
        expected: usize,
    ) -> Result<(), TransportError> {
        if found == expected {
            Ok(())
        } else {
            Err(TransportError::LengthMismatch {
                what,
                found,
                expected,
            })
        }
    }

    /// What every form's build checks first: `mesh` is a mesh of `kernel`'s scene and
    /// `operator` is its operator.
    pub(crate) fn check_inputs(
        kernel: &flatland_geom::Kernel,
        mesh: &flatland_solve::Mesh,
        operator: &flatland_solve::SparseOperator,
    ) -> Result<(), TransportError> {
        use flatland_solve::TransferOperator as _;
        TransportError::check_size(kernel, mesh, operator.len())
    }

    /// [`TransportError::check_inputs`] for the operator by columns.
    pub(crate) fn check_columns(
        kernel: &flatland_geom::Kernel,
        mesh: &flatland_solve::Mesh,
        columns: &crate::Columns,
    ) -> Result<(), TransportError> {
        TransportError::check_size(kernel, mesh, columns.len())
    }

    fn check_size(
        kernel: &flatland_geom::Kernel,
        mesh: &flatland_solve::Mesh,
        operator_len: usize,
    ) -> Result<(), TransportError> {
        flatland_solve::check_scene(kernel, mesh)?;
        TransportError::check_length("the operator", operator_len, mesh.len())
    }
}
