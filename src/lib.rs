//! BlockPuzzle: a physical-reasoning benchmark for robot learning.
//!
//! Objects are coloured red (constraint), blue (manipulated), green (goal) or
//! grey (neutral); an episode fails when red touches blue and succeeds when
//! every blue object touches a green one. The environments put coloured blocks
//! in front of the OpenAI Fetch robot in MuJoCo.
//!
//! Without cargo features the crate is the environment core, trained
//! policies and their evaluation (no libtorch, EGL or plotting); `render` adds headless rendering, `train` the training
//! stack and command line, `mpi` training under `mpirun`.

// The environment core.
pub mod actor;
pub mod align;
pub mod check;
pub mod demos;
pub mod diff;
pub mod env;
pub mod evaluate;
pub mod generate;
pub mod hindsight;
pub mod io;
pub mod limits;
pub mod load;
pub mod math;
pub mod mj;
pub mod outcome;
pub mod policy;
pub mod progress;
pub mod provenance;
pub mod results;
pub mod rollout;
pub mod rules;
pub mod saved;
pub mod scene;
pub mod stream;
pub mod suite;
pub mod task;
pub mod zoo;

pub use env::{make, BlockEnv, EnvConfig, EnvError, Info, Step};
pub use rules::Colour;

#[cfg(feature = "cli")]
pub mod cli;
#[cfg(feature = "render")]
pub mod render;

// The training stack.
#[cfg(feature = "train")]
pub mod agents;
#[cfg(feature = "train")]
pub mod bench;
#[cfg(feature = "train")]
pub mod blas;
#[cfg(feature = "train")]
pub mod table;
#[cfg(feature = "train")]
pub mod train;

/// The README's Rust example, compiled and run by `cargo test` (a doctest).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctest;
