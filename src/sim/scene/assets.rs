//! Where the scene files live, and the checks that the Fetch assets are there.
//!
//! The scene template (`models/scene.xml`, this project's file) is compiled in.
//! The Fetch robot's files (robot.xml, shared.xml, meshes, a texture) come from
//! gymnasium-robotics 1.4.2 and are looked up, in this order:
//! 1. `$BLOCKPUZZLE_MODELS_DIR`: a folder with a template `scene.xml` and the
//!    assets under `gymnasium_robotics/` (the layout of this checkout's `models/`);
//! 2. a folder registered at run time with [`use_fetch_assets`]: the Python
//!    package registers the `envs/assets` folder of the installed
//!    `gymnasium-robotics` wheel once, at import; its files are checked
//!    against their sha256 when it is registered;
//! 3. this checkout's `models/` (filled by `make setup`), except in builds for
//!    the Python wheel, which keep no path of the checkout they were built in.

use super::SceneError;
use sha2::{Digest, Sha256};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::RwLock;

/// Environment variable that overrides the models folder.
pub const MODELS_DIR_VAR: &str = "BLOCKPUZZLE_MODELS_DIR";

/// Relative path (under a models folder) of the git-ignored Fetch assets.
pub const FETCH_ASSETS: &str = "gymnasium_robotics";

/// The scene template, compiled in.
const TEMPLATE: &str = include_str!("../../../models/scene.xml");

/// The Fetch files a scene reads, relative to the assets folder (`fetch/`,
/// `stls/`, `textures/`), with their sha256 in gymnasium-robotics 1.4.2.
pub const FETCH_FILES: &[(&str, &str)] = &[
    ("fetch/robot.xml", "f5fd3395c3d9efea0293f80c5d214355826510c9472b5eb5ca570761255da167"),
    ("fetch/shared.xml", "23ff1c601587a022c46e1a91cf2a10579c5b5f124e1e40afe23b4a76bf560329"),
    ("stls/fetch/base_link_collision.stl", "ddbbecaa94eebb923a153935b9ff02893ca159361ce4fb40363fe64ee6733b81"),
    ("stls/fetch/bellows_link_collision.stl", "23b1ad0022edb12a65859bedf65dd6d018ee3769c1e48665c8ba2868c845306e"),
    ("stls/fetch/elbow_flex_link_collision.stl", "fa200b07d6ffe096eb7823b2c2154cc8ce8e22ea5516f557719b9fb308283cb1"),
    ("stls/fetch/estop_link.stl", "08ee8f343d047983477a5c57292ec6b4a4d317e9a999c8fbfd45b3249c8226fe"),
    ("stls/fetch/forearm_roll_link_collision.stl", "a74b8d891845f56c58cdc9c4fb115b5ad1a89893cf9d5902310ea5bd7c70c81e"),
    ("stls/fetch/gripper_link.stl", "d292a962df7d90eb13919ae8dd269e5ca55f2f54e2f6fa035c562684ff7ec26f"),
    ("stls/fetch/head_pan_link_collision.stl", "36362238ca8c68d5aec127130014aa5c7b0ae5613b52ebd82603f6d9b03cf426"),
    ("stls/fetch/head_tilt_link_collision.stl", "3444f186e3faa628654ba7c9ee096d422c34d07948fd5f502918ac4781238919"),
    ("stls/fetch/l_wheel_link_collision.stl", "0be83a03318e7f2d51b59c2b13e56a5ecdfeaa2ba465bbd841f3605334be6a63"),
    ("stls/fetch/laser_link.stl", "285e57045df959a58c14d0b26c1a24203bd213acd17554f5b07bc526dfbc0747"),
    ("stls/fetch/r_wheel_link_collision.stl", "1280da184382df0ab072c91024046fc82c70d4f46c8d6697245d328af97aeeac"),
    ("stls/fetch/shoulder_lift_link_collision.stl", "af0703cad45527a1e7e5c76e15a43a81600b8482e479e1ecceedff3624b381af"),
    ("stls/fetch/shoulder_pan_link_collision.stl", "7d6e74913589c3b7ee113c6b55170a40b3cc7d4095c7c1c520464655e6e2d301"),
    ("stls/fetch/torso_fixed_link.stl", "ee88311cd5ae20727c4ea7af579edea4da832b54a86b77d6804e4be30c638158"),
    ("stls/fetch/torso_lift_link_collision.stl", "4f24652be8a346b040ee199d3586af874ca0359460d91b86d893ff2a85afdfde"),
    ("stls/fetch/upperarm_roll_link_collision.stl", "b52550449cfa148390cbbcb3879ff3ee67a484e98bbd2ad91046c09d49dae9d1"),
    ("stls/fetch/wrist_flex_link_collision.stl", "435f181dea365137f63e74f718911b7dfd780af6fc92ce5c74908e7d0790413b"),
    ("stls/fetch/wrist_roll_link_collision.stl", "942ca8736eecefd12c6d5397292c5725546b70c0826d9daf67b68d69255011d5"),
    ("textures/block.png", "d39ffb85a87d00c346764191e38ecac3135f2d6f690f64a8ee5da4783ef18e76"),
];

/// The folder registered by [`use_fetch_assets`].
static REGISTERED: RwLock<Option<PathBuf>> = RwLock::new(None);

/// Where a scene's files come from: the folder the generated model is loaded
/// from (includes resolve against it), the template, and the prefix of the
/// Fetch files relative to that folder.
#[derive(Debug, Clone)]
pub struct Assets {
    /// The folder the generated model is loaded from.
    pub base: PathBuf,
    /// The scene template's text.
    pub template: Cow<'static, str>,
    /// The Fetch assets' path relative to `base`, ending in `/` (or empty).
    pub fetch_prefix: &'static str,
}

/// The models folder of `$BLOCKPUZZLE_MODELS_DIR`, else of this checkout (none in wheel builds).
pub fn models_dir() -> Option<PathBuf> {
    std::env::var_os(MODELS_DIR_VAR).map(PathBuf::from).or_else(|| {
        let built = env!("BLOCKPUZZLE_DEFAULT_MODELS_DIR");
        (!built.is_empty()).then(|| PathBuf::from(built))
    })
}

/// Uses the Fetch assets in `root` (a folder with `fetch/`, `stls/` and
/// `textures/`, such as gymnasium-robotics' `envs/assets`) for the scenes
/// built from now on, unless `$BLOCKPUZZLE_MODELS_DIR` is set. Every file is
/// checked against its sha256 first.
///
/// # Errors
/// [`SceneError::MissingAssets`] or [`SceneError::AssetChecksum`] naming the file.
pub fn use_fetch_assets(root: &Path) -> Result<(), SceneError> {
    verify_fetch_files(root)?;
    *REGISTERED.write().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(root.to_path_buf());
    Ok(())
}

/// The folder registered by [`use_fetch_assets`], if any.
pub fn registered_fetch_assets() -> Option<PathBuf> {
    REGISTERED.read().unwrap_or_else(std::sync::PoisonError::into_inner).clone()
}

/// Checks each of [`FETCH_FILES`] under `root` against its sha256.
///
/// # Errors
/// The first file missing or differing.
pub fn verify_fetch_files(root: &Path) -> Result<(), SceneError> {
    for (rel, want) in FETCH_FILES {
        let path = root.join(rel);
        let bytes = std::fs::read(&path).map_err(|_| SceneError::MissingAssets { missing: path.clone() })?;
        let got: String = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
        if got != *want {
            return Err(SceneError::AssetChecksum { path, expected: (*want).to_owned(), found: got });
        }
    }
    Ok(())
}

/// Where the next scene's files come from (see the module's order).
///
/// # Errors
/// [`SceneError::MissingAssets`] naming the first missing file, or
/// [`SceneError::NoAssets`] when no folder is known.
pub fn assets() -> Result<Assets, SceneError> {
    let from_env = std::env::var_os(MODELS_DIR_VAR).is_some();
    if !from_env {
        if let Some(root) = registered_fetch_assets() {
            return Ok(Assets { base: root, template: Cow::Borrowed(TEMPLATE), fetch_prefix: "" });
        }
    }
    let dir = models_dir().ok_or(SceneError::NoAssets)?;
    check_assets(&dir)?;
    let template = if from_env {
        let path = dir.join(super::xml::TEMPLATE_FILE);
        Cow::Owned(std::fs::read_to_string(&path).map_err(|source| SceneError::Io { path, source })?)
    } else {
        Cow::Borrowed(TEMPLATE)
    };
    Ok(Assets { base: dir, template, fetch_prefix: "gymnasium_robotics/" })
}

/// Checks that a models folder holds the scene template and the Fetch assets.
///
/// # Errors
/// [`SceneError::MissingAssets`] naming the first missing file and the set-up command.
pub fn check_assets(dir: &Path) -> Result<(), SceneError> {
    let template = dir.join(super::xml::TEMPLATE_FILE);
    if !template.exists() {
        return Err(SceneError::MissingAssets { missing: template });
    }
    for (rel, _) in FETCH_FILES {
        let p = dir.join(FETCH_ASSETS).join(rel);
        if !p.exists() {
            return Err(SceneError::MissingAssets { missing: p });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_checkout_assets_match_the_pinned_checksums_and_a_changed_byte_is_named() {
        let Some(dir) = models_dir() else { return };
        let root = dir.join(FETCH_ASSETS);
        verify_fetch_files(&root).expect("models/gymnasium_robotics is gymnasium-robotics 1.4.2's (make setup)");
        let copy = tempfile::tempdir().expect("temp dir");
        for (rel, _) in FETCH_FILES {
            let to = copy.path().join(rel);
            std::fs::create_dir_all(to.parent().expect("a parent")).expect("mkdir");
            std::fs::copy(root.join(rel), &to).expect("copy");
        }
        let shared = copy.path().join("fetch/shared.xml");
        let mut text = std::fs::read(&shared).expect("read");
        text.push(b'\n');
        std::fs::write(&shared, text).expect("write");
        match verify_fetch_files(copy.path()) {
            Err(SceneError::AssetChecksum { path, .. }) => assert_eq!(path, shared),
            other => panic!("a changed shared.xml passed: {other:?}"),
        }
        std::fs::remove_file(copy.path().join("textures/block.png")).expect("rm");
        std::fs::write(&shared, std::fs::read(root.join("fetch/shared.xml")).expect("read")).expect("write");
        assert!(matches!(verify_fetch_files(copy.path()), Err(SceneError::MissingAssets { .. })));
    }
}
