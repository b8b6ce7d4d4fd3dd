//! The alignment check against gymnasium-robotics (the way envpool checks its
//! Fetch against the original): FetchPush-v4 episodes recorded by
//! `bench/align_fetchpush.py` (state after reset, actions, gripper and block
//! positions after every step) are replayed in a FetchPush-like BlockPuzzle
//! environment ([`fetchpush_like`]) from the same states with the same
//! actions, and the per-step distance between the two trajectories is
//! reported. On the same engine (the `mujoco3` feature and the reference's
//! MuJoCo 3.11.0) they agree to 1e-4 m (`tests/it/align_mujoco3.rs`); on Debian's
//! 2.2.2 the figure is the engines' own difference (`blockpuzzle align`).

use crate::env::{BlockEnv, EnvConfig, EnvError};
use crate::sim::mj::ObjType;
use crate::task::Task;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use thiserror::Error;

/// How far (m) the FetchPush-like trajectories may drift from FetchPush-v4's
/// on the same engine: the bound of `tests/it/align_mujoco3.rs`, marked in the figure.
pub const TOLERANCE: f64 = 1e-4;

/// The task file of the FetchPush-like environment.
pub const FETCHPUSH_TASK: &str = include_str!("fetchpush.toml");

/// What can go wrong in the alignment check.
#[derive(Debug, Error)]
pub enum AlignError {
    /// The reference file is missing or unreadable.
    #[error("cannot read the alignment reference {path}: {source}; make it with `bash bench/align_fetchpush.sh`")]
    Read { path: String, source: std::io::Error },
    /// The reference file is not what `bench/align_fetchpush.py` writes.
    #[error("{path} is not an alignment reference (as bench/align_fetchpush.py writes): {reason}")]
    Format { path: String, reason: String },
    /// A joint of the reference that our model lacks.
    #[error("the reference's joint {name:?} has no counterpart in the FetchPush-like scene")]
    UnknownJoint { name: String },
    /// A joint of the reference with another number of values than ours.
    #[error("the reference's joint {name:?} has {qpos} position and {qvel} velocity values, the scene's has {want_qpos} and {want_qvel} (a free joint: 7 and 6); record the reference again with `bash bench/align_fetchpush.sh`")]
    JointSize { name: String, qpos: usize, qvel: usize, want_qpos: usize, want_qvel: usize },
    /// The environment failed.
    #[error(transparent)]
    Env(#[from] EnvError),
}

/// One joint's state in the reference.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointState {
    pub qpos: Vec<f64>,
    pub qvel: Vec<f64>,
}

/// One recorded FetchPush-v4 episode.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefEpisode {
    /// "random" or "scripted".
    pub kind: String,
    pub seed: u64,
    /// State after reset, by joint name.
    pub joints: BTreeMap<String, JointState>,
    pub actions: Vec<[f32; 4]>,
    /// Gripper position after reset and after each step.
    pub grip: Vec<[f64; 3]>,
    /// Block position after reset and after each step.
    pub object: Vec<[f64; 3]>,
}

/// A file of recorded episodes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    pub env: String,
    /// The MuJoCo version the reference ran on.
    pub mujoco: String,
    pub gymnasium_robotics: String,
    pub episodes: Vec<RefEpisode>,
}

impl Reference {
    /// Reads a reference file.
    ///
    /// # Errors
    /// [`AlignError::Read`] / [`AlignError::Format`].
    pub fn load(path: &Path) -> Result<Self, AlignError> {
        let p = path.display().to_string();
        let text =
            crate::support::io::read_text(path, "alignment reference", crate::support::limits::RESULT_FILE_BYTES)
                .map_err(|source| AlignError::Read { path: p.clone(), source })?;
        let r: Reference =
            serde_json::from_str(&text).map_err(|e| AlignError::Format { path: p.clone(), reason: e.to_string() })?;
        if r.episodes.is_empty() {
            return Err(AlignError::Format { path: p, reason: "it holds no episodes".into() });
        }
        for (i, e) in r.episodes.iter().enumerate() {
            let n = e.actions.len() + 1;
            if e.grip.len() != n || e.object.len() != n {
                let reason =
                    format!("episode {i} has {} actions but {} / {} positions", n - 1, e.grip.len(), e.object.len());
                return Err(AlignError::Format { path: p, reason });
            }
        }
        Ok(r)
    }
}

/// How far one replayed episode drifted from its reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Deviation {
    pub kind: String,
    pub seed: u64,
    /// Steps compared (reset state included).
    pub steps: usize,
    /// Largest distance between the gripper positions (m).
    pub grip_max: f64,
    /// Largest distance between the block positions (m).
    pub object_max: f64,
    /// The step of the largest deviation of either (0: the reset state).
    pub worst_step: usize,
    /// Per step (reset state first): gripper and block distance (m).
    pub per_step: Vec<[f64; 2]>,
}

/// The FetchPush-like environment: [`FETCHPUSH_TASK`] without the collision
/// filter's exclusions (gymnasium's scene has none).
///
/// # Errors
/// Missing assets, or a model MuJoCo refuses.
pub fn fetchpush_like() -> Result<BlockEnv, EnvError> {
    let task = Task::from_toml(FETCHPUSH_TASK, None)?;
    BlockEnv::new(EnvConfig { collision_filter: false, ..EnvConfig::new(task) })
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The full MuJoCo state (qpos, qvel) of `env`'s model for the state `ep`
/// starts from, set joint by joint (FetchPush's `object0:joint` is the
/// block's); a joint the reference does not list keeps `env`'s current value
/// (FetchPush-v4 references list every joint the FetchPush-like scene has).
///
/// # Errors
/// A joint of the reference without counterpart.
pub fn start_state(env: &BlockEnv, ep: &RefEpisode) -> Result<(Vec<f64>, Vec<f64>), AlignError> {
    let model = env.data().model().clone();
    let (mut qpos, mut qvel) = (env.data().qpos().to_vec(), env.data().qvel().to_vec());
    for (name, s) in &ep.joints {
        let ours = if name == "object0:joint" {
            format!("{}:joint", crate::sim::scene::xml::block_name(0))
        } else {
            name.clone()
        };
        let j = env.model_id(ObjType::Joint, &ours).map_err(|_| AlignError::UnknownJoint { name: name.clone() })?;
        // A joint's values run up to the next joint's (or the end).
        let span = |adr: &[i32], total: usize| {
            (adr[j] as usize, adr.get(j + 1).map_or(total, |&next| next as usize) - adr[j] as usize)
        };
        let ((qa, nq), (va, nv)) = (span(model.jnt_qposadr(), qpos.len()), span(model.jnt_dofadr(), qvel.len()));
        if (s.qpos.len(), s.qvel.len()) != (nq, nv) {
            return Err(AlignError::JointSize {
                name: name.clone(),
                qpos: s.qpos.len(),
                qvel: s.qvel.len(),
                want_qpos: nq,
                want_qvel: nv,
            });
        }
        qpos[qa..qa + s.qpos.len()].copy_from_slice(&s.qpos);
        qvel[va..va + s.qvel.len()].copy_from_slice(&s.qvel);
    }
    Ok((qpos, qvel))
}

/// Replays `ep` in `env` (made by [`fetchpush_like`]): the episode starts
/// from the recorded state ([`start_state`]), the recorded actions applied;
/// positions compared after reset and each step.
///
/// # Errors
/// A joint without counterpart, or an environment error.
pub fn replay(env: &mut BlockEnv, ep: &RefEpisode) -> Result<Deviation, AlignError> {
    let (qpos, qvel) = start_state(env, ep)?;
    env.set_state(&qpos, &qvel)?;
    let mut d = Deviation {
        kind: ep.kind.clone(),
        seed: ep.seed,
        steps: 0,
        grip_max: 0.0,
        object_max: 0.0,
        worst_step: 0,
        per_step: Vec::with_capacity(ep.actions.len() + 1),
    };
    let mut worst = -1.0;
    for t in 0..=ep.actions.len() {
        let over = t > 0 && {
            let s = env.step(&ep.actions[t - 1])?;
            s.terminated || s.truncated
        };
        let (g, o) = (dist(env.gripper_position(), ep.grip[t]), dist(env.block_positions()[0], ep.object[t]));
        d.per_step.push([g, o]);
        d.grip_max = d.grip_max.max(g);
        d.object_max = d.object_max.max(o);
        if g.max(o) > worst {
            worst = g.max(o);
            d.worst_step = t;
        }
        d.steps = t + 1;
        if over {
            // The episode ended here (time limit, or the rules: the block
            // reached the floor); the recorded one may go on: compare what both ran.
            break;
        }
    }
    Ok(d)
}

/// Replays every episode of `reference`.
///
/// # Errors
/// As [`replay`].
pub fn replay_all(reference: &Reference) -> Result<Vec<Deviation>, AlignError> {
    let mut env = fetchpush_like()?;
    reference.episodes.iter().map(|ep| replay(&mut env, ep)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_reference_files_are_clear_errors() {
        let dir = tempfile::tempdir().unwrap();
        let missing = Reference::load(&dir.path().join("none.json")).unwrap_err().to_string();
        assert!(missing.contains("bench/align_fetchpush.sh"), "{missing}");
        let p = dir.path().join("r.json");
        std::fs::write(&p, r#"{"env": "FetchPush-v4"}"#).unwrap();
        let e = Reference::load(&p).unwrap_err().to_string();
        assert!(e.contains("not an alignment reference") && e.contains("missing field"), "{e}");
        let ep = r#"{"kind": "random", "seed": 0, "joints": {}, "actions": [[0, 0, 0, 0]], "grip": [[0, 0, 0]], "object": [[0, 0, 0]]}"#;
        let text = format!(
            r#"{{"env": "FetchPush-v4", "mujoco": "3.11.0", "gymnasium_robotics": "1.4.2", "episodes": [{ep}]}}"#
        );
        std::fs::write(&p, text).unwrap();
        let e = Reference::load(&p).unwrap_err().to_string();
        assert!(e.contains("episode 0 has 1 actions but 1 / 1 positions"), "{e}");
    }
}
