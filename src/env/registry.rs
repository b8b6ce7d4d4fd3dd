//! The registry of versioned environment ids.

use super::{BlockEnv, EnvConfig, EnvError};
use crate::curriculum::Layout;
use crate::rules::Colour::*;

/// A registered environment.
#[derive(Debug, Clone, Copy)]
pub struct Registration {
    /// Versioned id, e.g. "BlocksTouch-v0".
    pub id: &'static str,
    /// One-line description.
    pub summary: &'static str,
}

/// Every registered environment, in listing order.
pub const REGISTRY: &[Registration] = &[
    Registration {
        id: "BlocksTouch-v0",
        summary: "push the blue block against the green one (2 blocks, curriculum levels 0-5)",
    },
    Registration {
        id: "BlocksChoose-v0",
        summary: "blue to green with a grey distractor, grey last in the observation (levels 0-10, challenge mode)",
    },
    Registration {
        id: "GripperTouch-v0",
        summary: "touch the green block with the blue gripper (1 block, no curriculum): the quickest learning check",
    },
];

/// The registered ids.
pub fn ids() -> Vec<&'static str> {
    REGISTRY.iter().map(|r| r.id).collect()
}

/// The configuration registered under `id`.
///
/// # Errors
/// [`EnvError::UnknownId`] naming the known ids.
pub fn config(id: &str) -> Result<EnvConfig, EnvError> {
    let cfg = match id {
        "BlocksTouch-v0" => EnvConfig::custom(id, vec![Blue, Green], Layout::Touch),
        "BlocksChoose-v0" => EnvConfig::custom(id, vec![Blue, Green, Grey], Layout::Choose),
        "GripperTouch-v0" => EnvConfig {
            gripper: Blue,
            ..EnvConfig::custom(id, vec![Green], Layout::NearGripper { min: 0.1, max: 0.15 })
        },
        _ => {
            return Err(EnvError::UnknownId { id: id.to_owned(), known: ids().iter().map(|s| s.to_string()).collect() })
        }
    };
    Ok(cfg)
}

/// Builds the environment registered under `id`.
///
/// # Errors
/// [`EnvError::UnknownId`], or whatever building the scene reports.
pub fn make(id: &str) -> Result<BlockEnv, EnvError> {
    BlockEnv::new(config(id)?)
}
