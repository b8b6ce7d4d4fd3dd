//! Layer 10, learn (the `train` feature, the only layer that links libtorch): the algorithms and
//! the training loop. What needs no libtorch lives below (the paper's table and the environment
//! throughput benchmark are in `benchmark/`).
//!
//! | module | what |
//! |---|---|
//! | [`agents`] | the algorithm interface, each algorithm (DDPG/TD3, SAC, PGGD, BC, DAgger), networks, replay |
//! | [`train`] | the training loop generic over the algorithm, run directories, checkpoints, MPI, starting from a trained policy and demonstrations |
//! | [`bench`] | the training benchmark (`blockpuzzle bench --train`) |
//! | [`blas`] | libtorch's numeric libraries and thread counts |

pub mod agents;
pub mod bench;
pub mod blas;
pub mod train;
