//! Learning algorithms (DDPG, PGGD, SAC, and BC and DAgger, which imitate
//! the solver: one file each, listed in `registry.rs`) behind one interface
//! (`algorithm.rs`), the settings they share (`shared.rs`), their networks,
//! optimiser, normaliser and replay buffer, AggreVaTeD's expert view and
//! mixture, and the imitation learner (`imitation.rs`). The trained policies
//! they produce, and their plain-Rust networks and normaliser, are the
//! core's [`crate::policy::actor`] (re-exported here).

pub mod algorithm;
pub mod arch;
pub mod bc;
pub mod dagger;
pub mod ddpg;
pub mod expert;
pub mod imitation;
pub mod nets;
pub mod pggd;
pub mod registry;
pub mod replay;
pub mod sac;
pub mod shared;
