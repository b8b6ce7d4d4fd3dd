//! Learning agents: DDPG (with its networks, optimiser, normaliser and
//! replay buffer).

pub mod ddpg;
pub mod mlp;
pub mod nets;
pub mod normalizer;
pub mod replay;
