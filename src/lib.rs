//! BlockPuzzle: a physical-reasoning benchmark for robot learning.
//!
//! Objects are coloured red (constraint), blue (manipulated), green (goal) or
//! grey (neutral); an episode fails when red touches blue and succeeds when
//! every blue object touches a green one. The environments put coloured blocks
//! in front of the OpenAI Fetch robot in MuJoCo.

pub mod env;
pub mod evaluate;
pub mod io;
pub mod math;
pub mod mj;
pub mod rules;
pub mod scene;
pub mod table;
pub mod task;

pub use env::{make, BlockEnv, EnvConfig, EnvError, Info, Step};
pub use rules::Colour;
pub mod agents;
pub mod bench;
pub mod blas;
pub mod check;
pub mod cli;
pub mod policy;
pub mod render;
pub mod rollout;
pub mod train;
pub mod zoo;
