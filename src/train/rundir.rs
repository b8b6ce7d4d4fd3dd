//! The run directory: its files and `progress.csv`.

use super::{EpochRow, TrainConfig};
use anyhow::{Context, Result};
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
        self.dir.join(crate::saved::POLICY_FILE)
    }
    /// `success.png`.
    pub fn plot(&self) -> PathBuf {
        self.dir.join("success.png")
    }
    /// `best_policy.json`.
    pub fn best_policy(&self) -> PathBuf {
        self.dir.join(crate::saved::BEST_POLICY_FILE)
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
