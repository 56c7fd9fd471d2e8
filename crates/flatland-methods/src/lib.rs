//! Every way flatland lights a scene, by one name each, and the one place each is built.
//!
//! A [`Method`] is a representation of the kernel — exact, learned (the light-driven learner,
//! the visibility network, the paper's network) or a baseline's (hierarchical radiosity,
//! clustered HR, the uniform grid) — or the Monte Carlo tracer, which needs none. Its name is
//! the same on the command line (`solve --kernel`, `bench --methods`, `view --learner`), in the
//! bench's CSV files, in the docs and in the viewer; clap's `ValueEnum` derives the parser,
//! the help and the list of valid names, and a name the project used before
//! ([`Retired`]) is refused with the one to write instead.
//!
//! [`Recipes::build`] builds any of them from an [`Ask`] (the method, its basis functions or
//! tolerance, its seed): the one place a method's parameters become a representation, so
//! `flatland solve`, the bench, the experiments and the viewer all build the same thing under
//! the same name. [`Recipes::light`] lights a [`flatland_solve::LitScene`] with a method or a
//! model file ([`KernelArg`]) and scores it: the exact solve the lit scene already made is
//! reused, the tracer traces, everything else is built and solved on the lit scene's mesh.
//!
//! ```
//! use std::sync::Arc;
//! use flatland_geom::{Kernel, bundled};
//! use flatland_methods::{Ask, Method, Recipes};
//! use flatland_solve::{Mesh, never};
//!
//! let method = Method::parse("hr")?;
//! assert_eq!(method.name(), "hr");
//! assert!(Method::parse("first-shot").unwrap_err().to_string().contains("`visibility`"));
//!
//! let kernel = Arc::new(Kernel::new(bundled::scene("fig3")?));
//! let mesh = Mesh::new(&kernel, 64)?;
//! let ask = Ask { basis: Some(200), ..Ask::new(method) };
//! let built = Recipes::default().build(ask, &kernel, &mesh, None, &never, &mut |_| {})?;
//! assert!(built.rep.basis_functions().unwrap() > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

mod build;
mod error;
mod light;
mod method;

pub use build::{
    Account, Ask, Built, DEFAULT_BASIS, LightAccount, NetworkAccount, Progress, Recipes,
};
pub use error::MethodError;
pub use light::{KernelArg, Lit, TRACER_PHOTONS};
pub use method::{Family, Knob, Method, Retired};
