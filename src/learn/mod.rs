//! Layer 9, learn (the `train` feature, the only layer that links libtorch): the algorithms and
//! the training loop.
//!
//! | module | what |
//! |---|---|
//! | [`agents`] | the algorithm interface, each algorithm (DDPG/TD3, SAC, PGGD, BC, DAgger), networks, replay |
//! | [`train`] | the training loop generic over the algorithm, run directories, checkpoints, MPI, starting from a trained policy and demonstrations |
//! | [`bench`] | the training benchmark (`blockpuzzle bench --ddpg`) |
//! | [`blas`] | libtorch's numeric libraries and thread counts |
//! | [`table`] | the paper's results table on BlocksChoose-v0 |

pub mod agents;
pub mod bench;
pub mod blas;
pub mod table;
pub mod train;
