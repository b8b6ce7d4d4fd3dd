//! Branching a run: a new run directory that starts from another run's
//! latest checkpoint (weights, optimiser state, normaliser, replay buffers,
//! curriculum level, epoch and step counts) and continues with a few
//! settings changed, e.g. a larger challenge share from a strong policy.
//!
//! A branch is the parent's state copied (replay segments hard-linked where
//! the file system allows: they are written once and never changed) plus a
//! `config.json` that records the change; training then
//! resumes it like any run. The parent is untouched and may keep training.
//! Only settings the trainer reads each epoch, and those an algorithm's
//! registration lists as branchable (DDPG's exploration noise and action
//! penalties), may change; the agent's other hyperparameters (network shape,
//! learning rates, TD3, n-step, precision) live in its checkpoint and stay the parent's.

use super::{checkpoint, differing_fields, Context, Result, RunDir, TrainConfig, TrainError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Settings of the trainer a branch may change besides those a resume may
/// change: how episodes are drawn, the curriculum's threshold, updates per
/// cycle, and what a fine-tuning learner does with the policy it started from
/// (`--anchor-alpha`, `--ibrl`: not in the checkpoint, given to the learner
/// again on every resume), e.g. a weaker anchor once the critic has learned.
/// Each algorithm adds its own that the learner takes over from
/// the branch's settings ([`crate::learn::agents::algorithm::Registration::branchable`]:
/// DDPG's exploration noise and action penalties).
pub const BRANCHABLE_CHANGES: &[&str] =
    &["level_replay", "challenge_share", "success_threshold", "batches", "anchor_alpha", "ibrl"];

/// Every setting a branch may change, as flags.
fn branchable() -> Vec<String> {
    BRANCHABLE_CHANGES
        .iter()
        .map(|f| crate::learn::agents::registry::flag("", f))
        .chain(crate::learn::agents::registry::branchable_flags())
        .collect()
}

/// Where a branched run came from (recorded in its `config.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BranchedFrom {
    /// The parent run directory, as given.
    pub run: PathBuf,
    /// Epochs the parent had completed at the branch point.
    pub epoch: usize,
    /// The parent's environment steps at the branch point.
    pub env_steps: u64,
    /// The settings changed, by flag name (e.g. `--challenge-share`).
    pub changed: Vec<String>,
    /// The seal of the parent's configuration ([`super::config_seal`]), which the copied checkpoint
    /// records: the branch's first resume takes it (absent in branches made before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent_seal: Option<String>,
}

/// Makes `child` a branch of `parent` with the settings of `config`: checks
/// that only [`BRANCHABLE_CHANGES`] (and what a resume may change) differ
/// from the parent's, copies the parent's checkpoint state into `child`
/// (which must not exist) and writes `child`'s configuration. The caller
/// then trains `child` with `resume`.
///
/// # Errors
/// A missing or unfinished parent, an existing `child`, a setting a branch
/// may not change, or an I/O error; `child` is then not created.
pub fn branch(parent: &Path, child: &Path, config: &TrainConfig) -> Result<BranchedFrom> {
    let from = RunDir { dir: parent.to_owned() };
    if !from.config().exists() || !from.checkpoint().exists() {
        refuse!(
            "--branch-from {}: not a run directory with a checkpoint (needs config.json and checkpoint.bin); \
             give a run directory that has finished at least one epoch",
            parent.display()
        );
    }
    if child.exists() {
        refuse!(
            "--run-dir {} already exists; a branch starts a new run directory (choose another --run-dir, \
             or continue that run with --resume)",
            child.display()
        );
    }
    // The parent's checkpoints must load before anything is created.
    for path in checkpoints(&from)? {
        if path.exists() {
            checkpoint::verify(&path).map_err(|e| {
                TrainError::Refused(format!(
                    "--branch-from {}: nothing was created: the parent's {e}, or branch from another run",
                    parent.display()
                ))
            })?;
        }
    }
    let saved = from.read_config()?;
    let mut wanted = config.clone();
    wanted.task = saved.task.clone();
    wanted.tasks = saved.tasks.clone();
    // What the parent recorded when it started (the policy it started from, its demonstrations' hash).
    wanted.finetune.init_policy = saved.finetune.init_policy.clone();
    wanted.finetune.demos_sha256 = saved.finetune.demos_sha256.clone();
    wanted.replay = Some(config.replay.unwrap_or(saved.replay_layout()));
    let mut base = saved.clone();
    base.replay = Some(saved.replay_layout());
    base.branched_from = None;
    let mut changed = Vec::new();
    differing_fields(&base, &wanted, &mut changed);
    let branchable = branchable();
    let (allowed, refused): (Vec<String>, Vec<String>) = changed.into_iter().partition(|f| branchable.contains(f));
    if !refused.is_empty() {
        refuse!(
            "--branch-from {}: a branch may change only {} (and what --resume may); {} differ from {}; \
             pass the parent's values for those, or start a new run",
            parent.display(),
            branchable.join(", "),
            refused.join(", "),
            from.config().display()
        );
    }
    if saved.env != config.env && saved.task_id() != config.task_id() {
        refuse!(
            "--branch-from {}: the parent trained {}, this run asks for {}; pass --env {}",
            parent.display(),
            saved.task_id(),
            config.task_id(),
            saved.env
        );
    }

    // Copy into a temporary folder beside the child, check that the copy is
    // whole (a parent that is training may write a checkpoint meanwhile), then
    // rename it into place.
    let name = child.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "branch".into());
    let tmp = child.with_file_name(format!(".{name}.branching-{}", std::process::id()));
    let result = (|| -> Result<BranchedFrom> {
        for _attempt in 0..3 {
            if tmp.exists() {
                std::fs::remove_dir_all(&tmp).with_context(|| format!("cannot remove {}", tmp.display()))?;
            }
            copy_state(parent, &tmp)?;
            let copy = RunDir { dir: tmp.clone() };
            if whole(&copy)? {
                let state = checkpoint::peek_state(&copy.checkpoint())?;
                let record = BranchedFrom {
                    run: parent.to_owned(),
                    epoch: state.epoch,
                    env_steps: state.env_steps,
                    changed: allowed.clone(),
                    parent_seal: state.config_seal.clone(),
                };
                wanted.branched_from = Some(record.clone());
                crate::support::io::write_json(&copy.config(), &wanted)?;
                return Ok(record);
            }
        }
        refuse!(
            "--branch-from {}: the parent wrote new checkpoints while it was being copied (three tries); \
             branch it between two epochs or after stopping it",
            parent.display()
        )
    })();
    // The temporary folder sits beside the child, so its parent exists by now.
    let placed = result.and_then(|record| {
        std::fs::rename(&tmp, child)
            .with_context(|| format!("cannot move {} to {}", tmp.display(), child.display()))?;
        Ok(record)
    });
    if placed.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    placed
}

/// Copies `from`'s files into `to` (new), hard-linking replay segments
/// where possible, but not its snapshots (they belong to the parent's
/// history and stay there).
fn copy_state(from: &Path, to: &Path) -> Result<()> {
    let link = from.file_name().is_some_and(|n| n == "replay");
    std::fs::create_dir_all(to).with_context(|| format!("cannot create {}", to.display()))?;
    let entries = std::fs::read_dir(from).with_context(|| format!("cannot read {}", from.display()))?;
    for entry in entries {
        let entry = entry.with_context(|| format!("cannot read {}", from.display()))?;
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        let kind = entry.file_type().with_context(|| format!("cannot read {}", src.display()))?;
        if kind.is_dir() {
            if entry.file_name() != "snapshots" {
                copy_state(&src, &dst)?;
            }
        } else if kind.is_file() {
            // A file the parent removes meanwhile (a pruned replay segment) is
            // caught by the completeness check.
            if !(link && std::fs::hard_link(&src, &dst).is_ok()) && src.exists() {
                std::fs::copy(&src, &dst)
                    .with_context(|| format!("cannot copy {} to {}", src.display(), dst.display()))?;
            }
        }
    }
    Ok(())
}

/// The checkpoint files of a run, one per rank (rank 0's first; they may not exist).
fn checkpoints(run: &RunDir) -> Result<Vec<PathBuf>> {
    let mut dirs = vec![run.dir.clone()];
    for entry in std::fs::read_dir(&run.dir).with_context(|| format!("cannot read {}", run.dir.display()))? {
        let path = entry?.path();
        if path.is_dir() && path.file_name().is_some_and(|n| n.to_string_lossy().starts_with("rank-")) {
            dirs.push(path);
        }
    }
    Ok(dirs.into_iter().map(|d| d.join("checkpoint.bin")).collect())
}

/// Whether every checkpoint of a copied run (one per rank) finds the replay
/// segments it needs.
fn whole(run: &RunDir) -> Result<bool> {
    for path in checkpoints(run)? {
        if !path.exists() {
            return Ok(false);
        }
        let dir = path.parent().unwrap_or(&run.dir);
        for segment in checkpoint::segment_files(&path)? {
            if !dir.join(segment).exists() {
                return Ok(false);
            }
        }
    }
    Ok(true)
}
