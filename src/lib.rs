//! BlockPuzzle: a physical-reasoning benchmark for robot learning.
//!
//! Objects are coloured red (constraint), blue (manipulated), green (goal) or
//! grey (neutral); an episode fails when red touches blue and succeeds when
//! every blue object touches a green one. The environments put coloured blocks
//! in front of the OpenAI Fetch robot in MuJoCo.
//!
//! Without cargo features the crate is the environment core, trained
//! policies and their evaluation (no libtorch, EGL or plotting); `render` adds headless rendering, `train` the training
//! stack and command line, `mpi` training under `mpirun`, `serve` the browser app.

// The layers, bottom to top: a module uses only its own layer and the ones listed before it
// (tests/it/architecture.rs checks it). Each layer's mod.rs opens with its part of the map;
// ARCHITECTURE.md has the whole.
pub mod support;
pub mod sim;
pub mod task;
pub mod env;
pub mod policy;
pub mod episode;
pub mod benchmark;
#[cfg(feature = "render")]
pub mod render;
#[cfg(feature = "serve")]
pub mod serve;
#[cfg(feature = "train")]
pub mod learn;
#[cfg(feature = "cli")]
pub mod cli;

// The crate's public face: what the README's example and a first script need, at the top.
pub use env::registry::make;
pub use env::{BlockEnv, EnvConfig, EnvError, Info, Step};
pub use sim::rules::Colour;

/// The README's Rust example, compiled and run by `cargo test` (a doctest).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctest;
