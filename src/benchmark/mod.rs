//! Layer 7, benchmark: suites, saved policies and the numbers published about them.
//!
//! | module | what |
//! |---|---|
//! | [`facts`] | what readers of the project's files need from the core, as one JSON document |
//! | [`suite`] | evaluation suites: splits of rows (tasks or families' generator seeds) |
//! | [`stream`] | task streams: families over a generator-seed range, their record and cache |
//! | [`provenance`] | what made a number: build, engine, policy and task hashes |
//! | [`saved`] | a run's policy file (`policy.json`) |
//! | [`zoo`] | the model zoo: safetensors + sealed JSON metadata |
//! | [`load`] | the one resolver from a name a user gives to a saved policy |
//! | [`evaluate`] | evaluation of a policy on a task or a suite |
//! | [`results`] | suite results compared and ranked, every derived number recomputed |
//! | [`demos`] | the solver's episodes on a suite split, for imitation and offline RL |
//! | [`table`] | the paper's results table on BlocksChoose-v0, from saved policies |
//! | [`throughput`] | environment steps/s and `mj_step`/s (`blockpuzzle bench`) |

pub mod demos;
pub mod evaluate;
pub mod facts;
pub mod load;
pub mod provenance;
pub mod results;
pub mod saved;
pub mod stream;
pub mod suite;
pub mod table;
pub mod throughput;
pub mod zoo;
