//! Layer 6, episode: playing a policy in an environment, and what follows from episodes.
//!
//! | module | what |
//! |---|---|
//! | [`rollout`] | the one episode loop and the trajectory dump it records |
//! | [`outcome`] | what an episode that did not succeed did (failure, no contact, fell, ...) |
//! | [`generate`] | generated tasks: a family's seed to its first candidate the solver plays |
//! | [`check`] | `task check`: a task validated and its layouts sampled |
//! | [`align`] | replaying gymnasium-robotics FetchPush-v4 episodes in the FetchPush-like task |

pub mod align;
pub mod check;
pub mod generate;
pub mod outcome;
pub mod rollout;
