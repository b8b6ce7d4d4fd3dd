//! A run's policy from its checkpoint alone. Run state carried between machines
//! (`experiments/generalist/state/`) holds the checkpoint, `config.json` and `progress.csv`; the
//! policy file the run wrote at that epoch is made from them again, field for field, so that a
//! carried run can be evaluated or exported to the zoo without training on.

use super::checkpoint;
use super::rundir::{read_progress, RunDir};
use super::trainer::saved_policy;
use super::{check_config_seal, Result};
use crate::benchmark::saved::SavedPolicy;
use std::path::Path;

/// The policy file (`policy.json`) the run in `run_dir` wrote after the epoch of its checkpoint:
/// its config, checkpoint and the epoch's `progress.csv` row. The replay log is not read.
///
/// # Errors
/// A folder that holds no run, a missing or damaged checkpoint, a `config.json` the checkpoint was
/// not written with, or a `progress.csv` without the checkpoint's last epoch.
pub fn policy_from_checkpoint(run_dir: &Path) -> Result<SavedPolicy> {
    let run = RunDir { dir: run_dir.to_owned() };
    let config = run.read_config()?;
    let path = run.checkpoint();
    if !path.is_file() {
        refuse!(
            "{} has no checkpoint.bin, so no policy can be made from it; give a run directory that `blockpuzzle \
             train --run-dir` wrote (or its carried state: checkpoint.bin, config.json and progress.csv)",
            run.dir.display()
        );
    }
    let state = checkpoint::peek_state(&path)?;
    check_config_seal(&run, &config, &path, &state, &run.dir.display().to_string())?;
    // Checkpoints from before replay logs hold their buffers inline: those are read with it.
    let loaded = match checkpoint::load_without_replay(&path, &state.env_id, state.obs_dim, state.act_dim) {
        Ok(loaded) => loaded,
        Err(checkpoint::CheckpointError::Mismatch { .. }) => {
            checkpoint::load(&path, &state.env_id, state.obs_dim, state.act_dim)?
        }
        Err(e) => return Err(e.into()),
    };
    let last = state.epoch.checked_sub(1);
    let rows = read_progress(&run.progress())?;
    let Some(row) = rows.iter().rev().find(|r| Some(r.epoch) == last) else {
        refuse!(
            "{} has no row for epoch {} of {}'s checkpoint (it records {} epochs): restore the run's own progress.csv \
             with its checkpoint",
            run.progress().display(),
            state.epoch,
            run.dir.display(),
            rows.len()
        );
    };
    // The solver version that labelled its last epoch (`provenance.json`); unknown where the run
    // directory does not record its builds.
    let solver = run.read_provenance()?.pop().map(|s| s.build.solver_version());
    let agent = &*loaded.agent;
    Ok(saved_policy(&config, &loaded.state, row.finals_success, agent.policy(), agent.critic(), solver))
}
