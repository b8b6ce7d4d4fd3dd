//! The run directory: its files, saved policies, `progress.csv`.

use super::{EpochRow, TrainConfig};
use crate::agents::mlp::TanhMlp;
use crate::agents::AnyPolicy;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Files of a run directory.
pub struct RunDir {
    /// The folder.
    pub dir: PathBuf,
}

impl RunDir {
    /// `config.json`.
    pub fn config(&self) -> PathBuf {
        self.dir.join("config.json")
    }
    /// `progress.csv`.
    pub fn progress(&self) -> PathBuf {
        self.dir.join("progress.csv")
    }
    /// `checkpoint.bin`.
    pub fn checkpoint(&self) -> PathBuf {
        self.dir.join("checkpoint.bin")
    }
    /// `policy.json`.
    pub fn policy(&self) -> PathBuf {
        self.dir.join("policy.json")
    }
    /// `success.png`.
    pub fn plot(&self) -> PathBuf {
        self.dir.join("success.png")
    }
    /// `best_policy.json`.
    pub fn best_policy(&self) -> PathBuf {
        self.dir.join("best_policy.json")
    }
    /// `snapshots/`: policies kept with `--snapshot-every`.
    pub fn snapshots(&self) -> PathBuf {
        self.dir.join("snapshots")
    }
    /// `snapshots/epoch-NNNN.json`: the policy after `epoch` epochs.
    pub fn snapshot(&self, epoch: usize) -> PathBuf {
        self.snapshots().join(format!("epoch-{epoch:04}.json"))
    }
    /// The run's `config.json`.
    ///
    /// # Errors
    /// A missing or malformed file, named.
    pub fn read_config(&self) -> Result<TrainConfig> {
        let path = self.config();
        let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("{} is not a training config", path.display()))
    }
    /// `expert_policy.json`: AggreVaTeD's expert as the run first loaded it
    /// (a resumed run uses this copy, so the expert cannot change under it).
    pub fn expert_policy(&self) -> PathBuf {
        self.dir.join("expert_policy.json")
    }
}

/// A saved policy: the actor, its normaliser and what it was trained on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedPolicy {
    /// Environment id it was trained on.
    pub env_id: String,
    /// The task it was trained on, by content (absent in policies saved before tasks were files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<crate::task::TaskSource>,
    /// Epochs of training behind it.
    pub epoch: usize,
    /// Environment steps of training behind it (absent in policies saved before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub env_steps: Option<u64>,
    /// Its finals success when saved.
    pub finals_success: f64,
    /// The policy.
    pub policy: AnyPolicy,
    /// DDPG's critic Q(s, a) of the same epoch (input: the normalised
    /// observation, then the action), so that the policy can be an AggreVaTeD
    /// expert with `--pg-weight expert-advantage`. Absent for PGGD and in
    /// policies saved before the critic was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub critic: Option<TanhMlp>,
}

impl SavedPolicy {
    /// Whether the policy (and critic, if kept) can act: see
    /// [`AnyPolicy::check`]; the critic maps observation and action to one value.
    ///
    /// # Errors
    /// The first problem, named.
    pub fn check(&self) -> Result<(), String> {
        self.policy.check()?;
        if let Some(c) = &self.critic {
            let n_in = self.policy.obs_dim() + crate::env::ACTION_DIM;
            c.check(n_in, 1, crate::agents::MAX_ABS_WEIGHT).map_err(|e| format!("critic: {e}"))?;
        }
        Ok(())
    }
}

/// Writes `bytes` to `path` through a temporary file `path.EXT.tmp`.
///
/// # Errors
/// I/O errors with the path.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    crate::io::write_atomic(path, |f| f.write_all(bytes)).with_context(|| format!("writing {}", path.display()))
}

/// Writes `value` as JSON to `path` through a temporary file.
///
/// # Errors
/// I/O errors with the path.
pub fn write_json_atomic(path: &Path, value: &impl Serialize) -> Result<()> {
    write_atomic(path, &serde_json::to_vec_pretty(value)?)
}

/// Loads a policy from a file (`policy.json` of a run, or a zoo entry's
/// `.safetensors`/`.json`), a run directory (`best_policy.json`, else
/// `policy.json`), or a zoo entry by name (see [`crate::zoo`]). The policy is
/// checked before it is returned: non-finite or absurd weights, or layers
/// that do not fit together, are an error naming the file.
///
/// # Errors
/// A clear message for a missing, malformed or damaged file.
pub fn load_policy(path: &Path) -> Result<SavedPolicy> {
    if crate::zoo::is_name(path) {
        let file = crate::zoo::find(&crate::zoo::dir(), &path.to_string_lossy())?;
        return Ok(crate::zoo::load(&file)?.1);
    }
    if crate::zoo::is_zoo_file(path) {
        return Ok(crate::zoo::load(path)?.1);
    }
    let file = if path.is_dir() {
        let run = RunDir { dir: path.to_owned() };
        if run.best_policy().exists() {
            run.best_policy()
        } else {
            run.policy()
        }
    } else {
        path.to_owned()
    };
    let text = std::fs::read_to_string(&file)
        .with_context(|| format!("cannot read policy {} (train one with `blockpuzzle train`)", file.display()))?;
    let saved: SavedPolicy =
        serde_json::from_str(&text).with_context(|| format!("{} is not a blockpuzzle policy file", file.display()))?;
    saved.check().map_err(|e| anyhow::anyhow!("policy {} is not usable: {e}", file.display()))?;
    Ok(saved)
}

pub(super) fn write_progress(path: &Path, rows: &[EpochRow]) -> Result<()> {
    crate::io::write_atomic_via(path, |tmp| {
        let mut w = csv::Writer::from_path(tmp)?;
        for r in rows {
            w.serialize(r)?;
        }
        w.flush()?;
        Ok(())
    })
}

/// Reads `progress.csv`.
///
/// # Errors
/// A message naming the file for a missing or malformed file.
pub fn read_progress(path: &Path) -> Result<Vec<EpochRow>> {
    let mut r = csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
    r.deserialize().collect::<Result<Vec<EpochRow>, _>>().with_context(|| format!("{} is malformed", path.display()))
}
