//! The integration tests, one binary (one link per configuration instead of one per file): each
//! module is what was a file of tests/, run against the real MuJoCo. Modules that need the training
//! stack or the CLI say so at their top (`#![cfg(feature = "train")]`); `common` holds shared helpers.
//! One module: `cargo test --test it MODULE::`. tests/assets.rs stays a binary of its own: it registers
//! another Fetch assets folder for the whole process.

mod aggrevated;
mod align_mujoco3;
mod architecture;
mod cli;
mod collision_filter;
mod common;
mod counts;
mod curriculum;
mod demos;
mod docs;
mod entities;
mod env;
mod experiments;
mod families;
mod finetune;
mod golden;
mod hindsight;
mod learning;
mod limits;
mod mpi;
mod mujoco_wrapper;
mod obs_spec;
mod physics;
mod provenance;
mod render;
mod rules_in_simulation;
#[cfg(feature = "serve")]
mod serve;
mod set_network;
mod suites;
mod task_files;
mod tasks;
mod train;
mod vector;
mod zoo;
