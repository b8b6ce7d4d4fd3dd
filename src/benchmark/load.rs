//! The one way a policy named by a user is found: a policy file (`policy.json`
//! of a run, a snapshot, or a zoo entry's `.safetensors`/`.json`), a run
//! directory (its `best_policy.json`, else `policy.json`), or a zoo entry by
//! name. Above both [`crate::benchmark::saved`] and [`crate::benchmark::zoo`], so neither needs the other's caller.

use crate::benchmark::saved::{SavedPolicy, BEST_POLICY_FILE, POLICY_FILE};
use anyhow::Result;
use std::path::Path;

/// Loads the policy `path` names (see the module). The policy is checked
/// before it is returned: non-finite or absurd weights, or layers that do not
/// fit together, are an error naming the file.
///
/// # Errors
/// A clear message for a missing, malformed or damaged file, or an unknown zoo name.
pub fn load_policy(path: &Path) -> Result<SavedPolicy> {
    if crate::benchmark::zoo::is_name(path) {
        let file = crate::benchmark::zoo::find(&crate::benchmark::zoo::dir(), &path.to_string_lossy())?;
        return Ok(crate::benchmark::zoo::load(&file)?.1);
    }
    if crate::benchmark::zoo::is_zoo_file(path) {
        return Ok(crate::benchmark::zoo::load(path)?.1);
    }
    if crate::benchmark::zoo::is_lone_metadata(path) {
        return Err(crate::benchmark::zoo::ZooError::NoTensors {
            json: path.to_owned(),
            tensors: path.with_extension("safetensors"),
        }
        .into());
    }
    if path.is_dir() {
        let best = path.join(BEST_POLICY_FILE);
        return crate::benchmark::saved::read(&if best.exists() { best } else { path.join(POLICY_FILE) });
    }
    crate::benchmark::saved::read(path)
}
