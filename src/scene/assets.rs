//! Where the scene files live, and the check that the Fetch assets are there.

use super::SceneError;
use std::path::{Path, PathBuf};

/// Environment variable that overrides the models folder.
pub const MODELS_DIR_VAR: &str = "BLOCKPUZZLE_MODELS_DIR";

/// Relative path (under the models folder) of the git-ignored Fetch assets.
pub const FETCH_ASSETS: &str = "gymnasium_robotics";

/// The files of the Fetch robot that the scene needs.
const REQUIRED: &[&str] = &[
    "gymnasium_robotics/fetch/robot.xml",
    "gymnasium_robotics/fetch/shared.xml",
    "gymnasium_robotics/stls/fetch/gripper_link.stl",
    "gymnasium_robotics/textures/block.png",
];

/// The models folder: `$BLOCKPUZZLE_MODELS_DIR`, else this checkout's `models/`.
pub fn models_dir() -> PathBuf {
    std::env::var_os(MODELS_DIR_VAR)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("BLOCKPUZZLE_DEFAULT_MODELS_DIR")))
}

/// Checks that `dir` holds the scene template and the Fetch assets.
///
/// # Errors
/// [`SceneError::MissingAssets`] naming the first missing file and the set-up command.
pub fn check_assets(dir: &Path) -> Result<(), SceneError> {
    let template = dir.join(super::xml::TEMPLATE_FILE);
    if !template.exists() {
        return Err(SceneError::MissingAssets { missing: template });
    }
    for rel in REQUIRED {
        let p = dir.join(rel);
        if !p.exists() {
            return Err(SceneError::MissingAssets { missing: p });
        }
    }
    Ok(())
}
