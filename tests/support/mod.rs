//! What the suites share and none of them is about: getting and running
//! outside programs, scratch directories, the HTTP client and a seeded
//! random source. Each thing has one way here, so that a suite that needs
//! it takes it from here rather than writing its own.

mod http;
mod node;
mod python;
mod rng;
mod scratch;
mod tools;

pub use http::client;
pub use node::NodePackages;
pub use python::PythonTools;
pub use rng::Rng;
pub use scratch::Scratch;
pub use tools::{
    InstallLock, apt_install, available, debian_program, loud, printed, repo, run, run_to_end,
    tools,
};
