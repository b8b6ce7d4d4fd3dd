//! Layer 1, support: what every layer above uses and nothing of BlockPuzzle itself.
//!
//! | module | what |
//! |---|---|
//! | [`io`] | the one writer (atomic, never clobbering what is not ours) and the one bounded reader |
//! | [`limits`] | the core's bounds (seeds, counts, episode and thread counts), the form of a content hash, and message cutting |
//! | [`diff`] | differences between two values of a configuration, in words |
//! | [`error`] | an error and its sources in one line |
//! | [`math`] | small geometry (quaternions, angles) |
//! | [`progress`] | progress bars on a terminal, plain lines elsewhere |

pub mod diff;
pub mod error;
pub mod io;
pub mod limits;
pub mod math;
pub mod progress;
