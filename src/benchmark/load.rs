//! The one resolver: what a policy name a user gives (`--policy`, `--checkpoint`, `--from`,
//! `--expert`, Python's `evaluate`) stands for. In order: `random` (uniform random actions), a
//! baseline that needs no training (`scripted`, the solver; `obs-hash`), a zoo entry's file
//! (`.safetensors`/`.json`), a run directory (its `best_policy.json`, else `policy.json`), a policy
//! file, a zoo entry by name. Above both [`crate::benchmark::saved`] and [`crate::benchmark::zoo`],
//! so neither needs the other's caller.

use crate::benchmark::evaluate::{Baseline, Subject};
use crate::benchmark::saved::{SavedPolicy, BEST_POLICY_FILE, POLICY_FILE};
use std::path::{Path, PathBuf};

/// Why a policy name stands for no usable trained policy.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// A zoo entry (by name or file) that is missing or not usable.
    #[error(transparent)]
    Zoo(#[from] crate::benchmark::zoo::ZooError),
    /// A policy file (or a run directory's) that is missing or not usable.
    #[error(transparent)]
    Saved(#[from] crate::benchmark::saved::SavedError),
    /// `random` where a trained policy is needed.
    #[error("`random` is random actions, not a trained policy; give a policy file, run directory or zoo name")]
    Random,
    /// A baseline where a trained policy is needed.
    #[error(
        "`{name}` is a baseline that needs no training, not a trained policy; give a policy file, run directory or \
         zoo name (suites evaluate baselines: `eval --suite S --baseline {name}`)"
    )]
    Baseline {
        /// The baseline's name.
        name: String,
    },
    /// A folder that holds no policy file: not a run directory.
    #[error(
        "{} is a folder with neither {BEST_POLICY_FILE} nor {POLICY_FILE}, so not a run directory; give a run \
         directory (one `blockpuzzle train --run-dir` wrote), a policy file or a zoo name (a run carried with \
         only its checkpoint.bin: `blockpuzzle zoo export --from RUN` makes its policy)",
        path.display()
    )]
    NotARun {
        /// The folder.
        path: PathBuf,
    },
}

/// What a policy name stands for (resolved once per name: its size does not matter).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
pub enum Named {
    /// Uniform random actions (seeded by the command that plays them).
    Random,
    /// A policy that needs no training.
    Baseline(Baseline),
    /// A trained policy, with the name it was given (results name it so).
    Saved(PathBuf, SavedPolicy),
}

impl Named {
    /// Fits `config` to what the policy reads: a trained policy's observation mode and block slots
    /// (random actions and the baselines play any layout, and leave it as it is).
    ///
    /// # Errors
    /// A policy file whose recorded tasks do not compile.
    pub fn fit(&self, config: &mut crate::env::EnvConfig) -> Result<(), crate::task::TaskError> {
        if let Named::Saved(_, saved) = self {
            config.obs_mode = saved.obs_mode();
            config.slots = saved.slots()?;
        }
        Ok(())
    }

    /// The policy that plays `env` (made from a config [`Named::fit`] fitted): random actions seeded
    /// with `seed`, a baseline, or the trained policy fitted to `env`'s observation.
    ///
    /// # Errors
    /// A trained policy whose observation fits `env` neither directly nor with grey blocks removed.
    pub fn into_player(
        self,
        env: &crate::env::BlockEnv,
        seed: u64,
    ) -> Result<Box<dyn crate::policy::Policy>, crate::benchmark::evaluate::EvalError> {
        Ok(match self {
            Named::Random => Box::new(crate::policy::RandomPolicy::new(seed)),
            Named::Baseline(baseline) => baseline.policy(env),
            Named::Saved(path, saved) => Box::new(crate::benchmark::evaluate::trained_policy(&path, saved, env)?),
        })
    }

    /// What suites and evaluations play: a trained policy or a baseline (random actions are no
    /// subject of an evaluation: None).
    pub fn subject(&self) -> Option<Subject<'_>> {
        match self {
            Named::Random => None,
            Named::Baseline(b) => Some(Subject::Baseline(*b)),
            Named::Saved(path, saved) => Some(Subject::Saved(path, saved)),
        }
    }
}

/// The policy `name` stands for (see the module). A trained policy is checked before it is
/// returned: non-finite or absurd weights, or layers that do not fit together, are an error naming
/// the file.
///
/// # Errors
/// A clear message for a missing, malformed or damaged file, or an unknown zoo name.
pub fn resolve(path: &Path) -> Result<Named, LoadError> {
    if path.to_str() == Some("random") {
        return Ok(Named::Random);
    }
    if let Some(b) = path.to_str().and_then(Baseline::named) {
        return Ok(Named::Baseline(b));
    }
    let saved = if crate::benchmark::zoo::is_name(path) {
        let file = crate::benchmark::zoo::find(&crate::benchmark::zoo::dir(), &path.to_string_lossy())?;
        crate::benchmark::zoo::load(&file)?.1
    } else if crate::benchmark::zoo::is_zoo_file(path) {
        crate::benchmark::zoo::load(path)?.1
    } else if crate::benchmark::zoo::is_lone_metadata(path) {
        let tensors = path.with_extension("safetensors");
        return Err(crate::benchmark::zoo::ZooError::NoTensors { json: path.to_owned(), tensors }.into());
    } else if path.is_dir() {
        let (best, last) = (path.join(BEST_POLICY_FILE), path.join(POLICY_FILE));
        if !best.exists() && !last.exists() {
            return Err(LoadError::NotARun { path: path.to_owned() });
        }
        crate::benchmark::saved::read(&if best.exists() { best } else { last })?
    } else {
        crate::benchmark::saved::read(path)?
    };
    Ok(Named::Saved(path.to_owned(), saved))
}

/// The trained policy `path` names ([`resolve`]); `random` and the baselines are refused, naming
/// what they are.
///
/// # Errors
/// As [`resolve`], and a name that is no trained policy.
pub fn load_policy(path: &Path) -> Result<SavedPolicy, LoadError> {
    match resolve(path)? {
        Named::Saved(_, saved) => Ok(saved),
        Named::Random => Err(LoadError::Random),
        Named::Baseline(b) => Err(LoadError::Baseline { name: b.name().to_owned() }),
    }
}
