//! Trained policies without the training stack: the deterministic actors
//! that DDPG, TD3, SAC and PGGD produce ([`AnyPolicy`]), their networks'
//! forward pass in plain Rust ([`mlp`]) and the observation normaliser they
//! were trained with ([`normalizer`]), and the grey-blind view through which a
//! policy trained without grey blocks plays a scene with them. Saved policy
//! files, the zoo and evaluation read these; training (`crate::learn::agents`) builds
//! them, so the Python package acts with the command line's arithmetic.

pub mod mlp;
pub mod normalizer;

use crate::env::{obs_dim, ObsSpec, BLOCK_OBS, ROBOT_OBS};
use crate::sim::rules::Colour;
use mlp::PlainNet;
use normalizer::Normalizer;
use serde::{Deserialize, Serialize};

/// The largest weight, bias or normaliser statistic a loaded policy may hold
/// (trained ones stay far below; larger values mean a damaged or diverged
/// file, which would act on overflowed numbers).
pub const MAX_ABS_WEIGHT: f32 = 1e6;

/// A trained policy, as saved in `policy.json`: a deterministic tanh actor
/// (DDPG, TD3, and SAC's mean action) or PGGD's Gaussian.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum AnyPolicy {
    /// PGGD (tried first: a DDPG policy lacks its `act_dim` and `sigma_min`).
    Pggd(PggdPolicy),
    /// A deterministic tanh actor (DDPG, TD3, SAC).
    Deterministic(DeterministicPolicy),
}

/// A trained policy in the episode loop: its deterministic action, padded with zeros to the
/// environment's [`crate::env::ACTION_DIM`] components where its network has fewer.
impl crate::policy::Policy for AnyPolicy {
    fn act(&mut self, obs: &[f32]) -> [f32; crate::env::ACTION_DIM] {
        let a = AnyPolicy::act(self, obs);
        std::array::from_fn(|k| a.get(k).copied().unwrap_or(0.0))
    }
}

impl AnyPolicy {
    /// The deterministic action (DDPG: π(s); PGGD: clip(μ(s), ±1)).
    pub fn act(&self, obs: &[f32]) -> Vec<f32> {
        match self {
            Self::Pggd(p) => p.act(obs),
            Self::Deterministic(p) => p.act(obs),
        }
    }

    /// The policy's network.
    pub fn net(&self) -> &mlp::PlainNet {
        match self {
            Self::Pggd(p) => &p.net,
            Self::Deterministic(p) => &p.net,
        }
    }

    /// Whether its network reads observations of `mode`: an MLP reads the flat one, a set network
    /// the set mode whose rows have its rows' width. A check of a recorded mode, not a guess.
    pub fn reads(&self, mode: crate::env::ObsMode) -> bool {
        use crate::env::ObsSpec;
        match self.net().set {
            None => !mode.is_set(),
            Some(l) => mode.is_set() && l.object == ObsSpec::new(mode, 0).object_dim(),
        }
    }

    /// The observation of a file written before policies recorded it (`policy.json` without
    /// `obs_mode`, zoo formats 1–6): the one mode of [`crate::env::ObsMode::ALL`] its network
    /// [reads](Self::reads). Only readers of such files call this; everything else reads the record.
    ///
    /// # Errors
    /// No mode, or more than one, fits the network.
    pub fn legacy_obs_mode(&self) -> Result<crate::env::ObsMode, FitError> {
        let fits: Vec<_> = crate::env::ObsMode::ALL.into_iter().filter(|&m| self.reads(m)).collect();
        match fits[..] {
            [m] => Ok(m),
            _ => Err(FitError::NoRecordedMode { several: !fits.is_empty() }),
        }
    }

    /// The block slots of the layout it was saved with ([`crate::env::EnvConfig::slots`]) when it
    /// reads `mode`: a set network's rows less the mode's fixtures' (a multi-task policy's are its
    /// tasks' most blocks); 0 for an MLP (its task's own).
    pub fn block_slots(&self, mode: crate::env::ObsMode) -> usize {
        self.net().set.map_or(0, |s| s.slots.saturating_sub(mode.fixtures().len()))
    }

    /// A set network's policy on observations with `slots` object slots: the
    /// same weights, the normaliser's shared row statistics in every slot
    /// (a set network's weights do not depend on the number of objects). An
    /// MLP's policy is returned as it is.
    pub fn with_slots(&self, slots: usize) -> Self {
        let Some(layout) = self.net().set else { return self.clone() };
        let layout = layout.with_slots(slots);
        let mut out = self.clone();
        let (net, norm) = match &mut out {
            Self::Pggd(p) => (&mut p.net, &mut p.norm),
            Self::Deterministic(p) => (&mut p.net, &mut p.norm),
        };
        net.set = Some(layout);
        *norm = norm.with_slots(layout);
        out
    }

    /// Observation size the policy expects.
    pub fn obs_dim(&self) -> usize {
        match self {
            Self::Pggd(p) => p.norm.dim(),
            Self::Deterministic(p) => p.norm.dim(),
        }
    }

    /// Whether the policy can act: [`MAX_ABS_WEIGHT`] bounds every weight and
    /// normaliser statistic, the network maps the normaliser's size to the
    /// action size (PGGD: twice that, for μ and σ), σ's floor is sane.
    ///
    /// # Errors
    /// The first problem, named.
    pub fn check(&self) -> Result<(), String> {
        let (net, norm, outputs) = match self {
            Self::Deterministic(p) => (&p.net, &p.norm, crate::env::ACTION_DIM),
            Self::Pggd(p) => {
                if p.act_dim != crate::env::ACTION_DIM {
                    return Err(format!(
                        "the policy has {} actions, the environments {}",
                        p.act_dim,
                        crate::env::ACTION_DIM
                    ));
                }
                if !p.sigma_min.is_finite() || p.sigma_min < 0.0 || p.sigma_min > 1e3 {
                    return Err(format!("sigma_min is {}", p.sigma_min));
                }
                (&p.net, &p.norm, 2 * p.act_dim)
            }
        };
        norm.check(MAX_ABS_WEIGHT)?;
        net.check(norm.dim(), outputs, MAX_ABS_WEIGHT).map_err(|e| format!("actor: {e}"))
    }

    /// The canonical form of what acts, hashed by [`crate::benchmark::saved::SavedPolicy::policy_id`]:
    /// the network (weights, layout, output), the normaliser's mean, std and
    /// clip (not its running sums, which a zoo entry does not keep), and
    /// PGGD's action size and σ floor. A policy file and its zoo entry give the same text.
    pub fn canonical(&self) -> String {
        let (net, norm) = (self.net(), self.norm());
        let (act_dim, sigma_min) = match self {
            Self::Pggd(p) => (Some(p.act_dim), Some(p.sigma_min)),
            Self::Deterministic(_) => (None, None),
        };
        serde_json::json!({
            "algo": self.algo(), "net": net, "mean": norm.mean(), "std": norm.std(), "clip": norm.clip(),
            "act_dim": act_dim, "sigma_min": sigma_min,
        })
        .to_string()
    }

    /// The observation normaliser it was trained with.
    pub fn norm(&self) -> &Normalizer {
        match self {
            Self::Pggd(p) => &p.norm,
            Self::Deterministic(p) => &p.norm,
        }
    }

    /// The policy's kind as files record it: "ddpg" (a deterministic tanh
    /// actor, whichever algorithm trained it) or "pggd".
    pub fn algo(&self) -> &'static str {
        match self {
            Self::Pggd(_) => "pggd",
            Self::Deterministic(_) => "ddpg",
        }
    }

    /// What acts (zoo format 7's `kind`).
    pub fn kind(&self) -> PolicyKind {
        match self {
            Self::Deterministic(_) => PolicyKind::Deterministic,
            Self::Pggd(_) => PolicyKind::Gaussian,
        }
    }
}

/// Why a network does not fit what it is asked to read or be blended with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    /// A set network asked to read a flat observation.
    #[error("a set network reads the `objects` or `entities` observation, not the `{0}` one")]
    SetOnFlat(crate::env::ObsMode),
    /// A file that does not record its observation, whose network reads none or several.
    #[error(
        "the file does not record its obs_mode, and its network reads {} of the observations ({}); export it \
         again from its run with `blockpuzzle zoo export`",
        if *.several { "several" } else { "none" },
        crate::env::ObsMode::ALL.map(|m| m.name()).join(", ")
    )]
    NoRecordedMode {
        /// Several modes fit (else none).
        several: bool,
    },
    /// A blend weight outside [0, 1].
    #[error("the weight {0} is outside [0, 1] (0: the base policy, 1: the tuned one)")]
    BlendWeight(f64),
    /// Two networks of different layouts asked to blend.
    #[error(
        "the base policy's actor is {base}, and the tuned one's is {tuned}: only a policy and the one it was \
         fine-tuned from (one network) can be blended"
    )]
    OtherNetwork {
        /// The base policy's network, described.
        base: String,
        /// The tuned policy's.
        tuned: String,
    },
}

/// Validators that return their reason as text take a [`FitError`] with `?`.
impl From<FitError> for String {
    fn from(e: FitError) -> Self {
        e.to_string()
    }
}

/// What acts, as zoo format 7's `kind` records it: `deterministic` (a tanh actor: DDPG, TD3, SAC's
/// mean action, BC, DAgger) or `gaussian` (PGGD's μ and σ).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PolicyKind {
    /// A tanh actor.
    Deterministic,
    /// A Gaussian policy (PGGD).
    Gaussian,
}

impl PolicyKind {
    /// The recorded word.
    pub fn name(self) -> &'static str {
        match self {
            Self::Deterministic => "deterministic",
            Self::Gaussian => "gaussian",
        }
    }
}

impl std::fmt::Display for PolicyKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A frozen deterministic tanh actor (DDPG, TD3, SAC's mean action) for
/// rollouts: plain Rust, `Send + Sync`, cheap to clone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeterministicPolicy {
    /// The actor.
    pub net: PlainNet,
    /// The observation normaliser it was trained with.
    pub norm: Normalizer,
}

impl DeterministicPolicy {
    /// The deterministic action π(s).
    pub fn act(&self, obs: &[f32]) -> Vec<f32> {
        let mut x = obs.to_vec();
        self.norm.normalize_in_place(&mut x);
        self.net.forward(&x)
    }

    /// This policy's network interpolated towards `base`'s, weight by weight: (1 − `weight`)·base +
    /// `weight`·self (WiSE-FT, Wortsman et al. 2022, for a policy fine-tuned from `base`). It keeps
    /// this policy's normaliser and layout: a fine-tuned run's normaliser began as its starting
    /// policy's and went on counting the run's observations. Each weight is computed in f64, so that
    /// `weight` 0 gives `base`'s weights and 1 this policy's, exactly.
    ///
    /// # Errors
    /// A `weight` outside [0, 1], or `base` another network (both named).
    pub fn blend(&self, base: &DeterministicPolicy, weight: f64) -> Result<DeterministicPolicy, FitError> {
        if !(0.0..=1.0).contains(&weight) {
            return Err(FitError::BlendWeight(weight));
        }
        if !self.net.same_network(&base.net) {
            return Err(FitError::OtherNetwork { base: base.net.describe(), tuned: self.net.describe() });
        }
        let mix = |b: &[f32], t: &[f32]| -> Vec<f32> {
            b.iter().zip(t).map(|(&b, &t)| ((1.0 - weight) * f64::from(b) + weight * f64::from(t)) as f32).collect()
        };
        let mut out = self.clone();
        for ((o, b), t) in out.net.layers.iter_mut().zip(&base.net.layers).zip(&self.net.layers) {
            o.w = mix(&b.w, &t.w);
            o.b = mix(&b.b, &t.b);
        }
        Ok(out)
    }
}

/// A frozen PGGD policy: plain Rust, `Send + Sync`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PggdPolicy {
    /// The network, outputs `[μ | σ pre-activation]`.
    pub net: PlainNet,
    /// The observation normaliser it was trained with.
    pub norm: Normalizer,
    /// Action size.
    pub act_dim: usize,
    /// Floor of σ.
    pub sigma_min: f64,
}

impl PggdPolicy {
    /// μ(s) and σ(s).
    pub fn distribution(&self, obs: &[f32]) -> (Vec<f32>, Vec<f32>) {
        let mut x = obs.to_vec();
        self.norm.normalize_in_place(&mut x);
        let out = self.net.forward(&x);
        let (mean, pre) = out.split_at(self.act_dim);
        let std = pre.iter().map(|&v| (v.max(0.0) + (-v.abs()).exp().ln_1p()) + self.sigma_min as f32).collect();
        (mean.to_vec(), std)
    }

    /// The deterministic action clip(μ(s), ±1) (testing, finals, evaluation).
    pub fn act(&self, obs: &[f32]) -> Vec<f32> {
        let (mean, _) = self.distribution(obs);
        mean.iter().map(|m| m.clamp(-1.0, 1.0)).collect()
    }
}

/// Whether an object row of the observation is a grey block's (its colour one-hot says grey).
fn is_grey(row: &[f32]) -> bool {
    ObsSpec::colour(row).get(Colour::Grey as usize).is_some_and(|&v| v > 0.5)
}

/// The flat observation with every grey block's features removed: a
/// BlocksChoose observation becomes a BlocksTouch one (robot, blue, green).
/// Rows of absent objects (no colour: a grey copy a task with counts left
/// out) go too, so the view has the same size whatever the count.
pub fn without_grey(obs: &[f32]) -> Vec<f32> {
    let spec = ObsSpec::flat(obs.len().saturating_sub(ROBOT_OBS) / BLOCK_OBS);
    spec.keep_objects(obs, |row| !is_grey(row) && ObsSpec::colour(row).iter().any(|&v| v > 0.5))
}

/// Size of [`without_grey`]'s output for a scene with blocks of `colours`.
pub fn obs_dim_without_grey(colours: &[Colour]) -> usize {
    obs_dim(colours.iter().filter(|&&c| c != Colour::Grey).count())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_blocks_are_cut_out_whole() {
        let mut obs: Vec<f32> = (0..ROBOT_OBS).map(|k| k as f32).collect();
        for (tag, one_hot) in
            [(100.0, [0.0, 1.0, 0.0, 0.0]), (200.0, [0.0, 0.0, 0.0, 1.0]), (300.0, [0.0, 0.0, 1.0, 0.0])]
        {
            obs.extend((0..BLOCK_OBS - 4).map(|k| tag + k as f32));
            obs.extend(one_hot);
        }
        let v = without_grey(&obs);
        assert_eq!(v.len(), ROBOT_OBS + 2 * BLOCK_OBS);
        assert_eq!(&v[..ROBOT_OBS + BLOCK_OBS], &obs[..ROBOT_OBS + BLOCK_OBS]);
        assert_eq!(&v[ROBOT_OBS + BLOCK_OBS..], &obs[ROBOT_OBS + 2 * BLOCK_OBS..]);
    }
}
