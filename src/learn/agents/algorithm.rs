//! What a learning algorithm is to the training loop: the [`Algorithm`]
//! trait a learner implements, and the [`Registration`] its file declares.
//!
//! An algorithm is one file (`ddpg.rs`, `pggd.rs`, `sac.rs`) that implements
//! [`Algorithm`] (its update as a gradient plus an optimiser step, so that the
//! loop can average shards' gradients, across MPI ranks too; how it explores;
//! the deterministic policy it exports; the parts of its state, which
//! checkpoints save and load by name) and declares a [`Registration`]: its
//! names, its own settings (a `clap` + `serde` type), the shared settings it
//! reads, its checks and its memory footprint. Adding one is that file and
//! its line in `registry.rs`; the trainer, checkpoints, `--algo`, the
//! settings checks and `bench --train` take it from there. This module knows
//! no algorithm.

use super::arch::Arch;
use super::nets::{Adam, Net};
use super::replay::Batch;
use super::shared::SharedConfig;
use crate::policy::actor::mlp::PlainNet;
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::AnyPolicy;
use crate::policy::actor::DeterministicPolicy;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::collections::BTreeMap;

/// What an algorithm's own settings are: flags (`clap`), a group of a run's
/// `config.json` (`serde`, missing keys taking their defaults) and defaults.
pub trait AlgorithmConfig:
    clap::Args
    + clap::FromArgMatches
    + Serialize
    + serde::de::DeserializeOwned
    + Default
    + Clone
    + PartialEq
    + std::fmt::Debug
    + Send
    + Sync
    + 'static
{
}

impl<T> AlgorithmConfig for T where
    T: clap::Args
        + clap::FromArgMatches
        + Serialize
        + serde::de::DeserializeOwned
        + Default
        + Clone
        + PartialEq
        + std::fmt::Debug
        + Send
        + Sync
        + 'static
{
}

/// An algorithm's names and the facts about its settings that callers ask for.
#[derive(Debug, Clone, Copy)]
pub struct Info {
    /// What policy files and zoo entries record as the algorithm that trained a policy (DDPG's
    /// `--td3` makes it TD3: [`crate::learn::train::TrainConfig::trainer`]); its name is the
    /// algorithm's ([`Info::name`]).
    pub trainer: crate::benchmark::saved::Trainer,
    /// How it is shown in titles and reports, e.g. "DDPG".
    pub title: &'static str,
    /// One line for `--help`.
    pub about: &'static str,
    /// Whether it learns from an AggreVaTeD expert (`--expert`).
    pub takes_expert: bool,
    /// Whether it imitates the solver ([`Algorithm::solver_share`]): the solver, which reads the
    /// entities observation, labels its exploration steps, so it trains `--net entity`.
    pub imitates: bool,
    /// The flags of the shared settings ([`SharedConfig`]) it reads; a run that
    /// gives any other is refused, naming the algorithms that read it.
    pub reads: &'static [&'static str],
    /// What its own settings' flags start with: the flag of field `f` is
    /// `--{flag_prefix}{f}` (underscores as dashes).
    pub flag_prefix: &'static str,
    /// Its own settings a branch (`train --branch-from`) may change, by field name.
    pub branchable: &'static [&'static str],
    /// Whether a run of it may start from a trained policy (`train --init-from`): its actor and
    /// normaliser taken from the policy ([`Algorithm::init_from`]), its critics (where it has any)
    /// fresh, which a critic warm-up ([`Algorithm::hold_actor`]) fits before the actor moves.
    pub starts_from_policy: bool,
}

impl Info {
    /// `--algo` value, checkpoint name and its settings' group in `config.json` (lowercase): the
    /// name policy files record for it.
    pub const fn name(&self) -> &'static str {
        self.trainer.name()
    }
}

/// How an algorithm is named, configured and built: declared once in its
/// file, listed in `registry.rs`.
pub struct Registration<C: AlgorithmConfig> {
    /// Its names and settings facts.
    pub info: Info,
    /// A fresh learner; `rng` fixes the initial weights.
    pub new: fn(&Spec, &C, &mut ChaCha8Rng) -> Box<dyn Algorithm>,
    /// Whether its own settings are in range; the error names the flag.
    pub validate: fn(&C) -> Result<(), String>,
    /// Its own settings that these settings would ignore (e.g. TD3's without
    /// `--td3`), as (flag, the flags that use it).
    pub unused: fn(&C) -> Vec<(&'static str, &'static str)>,
    /// The bytes its networks and optimiser state take (the trainer's memory check).
    pub memory: fn(&Spec, &C) -> u64,
    /// Its own settings away from the paper's, in words for titles, e.g. "TD3", "no action penalty".
    pub describe: fn(&C) -> Vec<String>,
    /// Gives a learner of it (loaded from a checkpoint) the settings a branch may change,
    /// [`Info::branchable`], from the branch's own (`take_fields` copies the listed ones;
    /// `no_branch` for an algorithm with none).
    pub take_branch: fn(&mut dyn Algorithm, &C) -> Result<(), String>,
}

/// The `take_branch` of an algorithm with no branchable setting.
pub(crate) fn no_branch<C>(_: &mut dyn Algorithm, _: &C) -> Result<(), String> {
    Ok(())
}

/// `agent` as the learner type `T` of the algorithm `name` (a branch's settings go to their own
/// algorithm's learner).
///
/// # Errors
/// A learner of another type.
pub(crate) fn learner_mut<'a, T: 'static>(agent: &'a mut dyn Algorithm, name: &str) -> Result<&'a mut T, String> {
    agent.as_any_mut().downcast_mut::<T>().ok_or_else(|| {
        format!(
            "{name}: a branch's settings are for another algorithm's learner (the registry pairs each with its own)"
        )
    })
}

/// What an algorithm is built from besides its own settings: the networks'
/// inputs and the shared settings.
#[derive(Debug, Clone, Copy)]
pub struct Spec<'a> {
    /// What the networks read: the observation's length and, for a set network, its layout.
    pub arch: Arch,
    /// Action size.
    pub act_dim: usize,
    /// Network shape, discount, normaliser, the actor-critics' optimiser and targets, n-step, precision.
    pub shared: &'a SharedConfig,
}

impl Spec<'_> {
    /// The bytes of `copies` copies (a network, its target, Adam's two
    /// moments, …) of an MLP from the observation (and `extra` more inputs)
    /// to `out` outputs, with the shared shape: an estimate for set networks too.
    pub fn mlp_bytes(&self, extra: usize, out: usize, copies: u64) -> u64 {
        let (hidden, layers) = (self.shared.hidden as u64, self.shared.layers as u64);
        let inputs = (self.arch.obs_dim + extra) as u64;
        let params =
            (inputs + 1) * hidden + (hidden + 1) * hidden * layers.saturating_sub(1) + (hidden + 1) * out as u64;
        4 * copies * params
    }
}

/// Losses and statistics of one update (`progress.csv`'s `train/` columns).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct UpdateStats {
    /// Critic loss (mean squared TD error; NaN without a critic).
    pub critic_loss: f64,
    /// Actor (policy) loss.
    pub actor_loss: f64,
    /// Mean Q(s, a) over the batch (NaN without a critic).
    pub mean_q: f64,
}

/// One named part of a learner's state: what a checkpoint saves and loads.
pub enum Part<'a> {
    /// A network's parameters, saved as `name.0`, `name.1`, ….
    Net(&'a mut Net),
    /// An optimiser's moments (`name.0`, …) and step count (`name.t`).
    Adam(&'a mut Adam),
    /// A tensor's values, saved as `name.0`.
    Tensor(&'a mut tch::Tensor),
    /// A counter (e.g. a noise seed), saved as `name`.
    Counter(&'a mut u64),
}

/// A learner as `Any`, for callers that need one algorithm's internals (tests, experts, a branch's
/// settings, [`Registration::take_branch`]); every learner has it. Only learners: a
/// `Box<dyn Algorithm>` is none, so `boxed.as_any()` is always the learner inside.
pub trait AsAny {
    /// As `Any`.
    fn as_any(&self) -> &dyn std::any::Any;
    /// As `Any`, mutable.
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
}

impl<T: Algorithm + 'static> AsAny for T {
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// A learner as the training loop sees it.
pub trait Algorithm: AsAny + Send {
    /// Its registration's name, e.g. "ddpg".
    fn name(&self) -> &'static str;

    /// The observation normaliser.
    fn norm(&self) -> &Normalizer;

    /// The observation normaliser, to feed.
    fn norm_mut(&mut self) -> &mut Normalizer;

    /// The flattened gradient of the next update on `batch` and its
    /// statistics; nothing changes. `shard` (0, 1, …) keys any noise the
    /// update draws, so that averaged shards draw independent streams and a
    /// resumed run draws the same ones; `weights` are per-transition weights
    /// from an AggreVaTeD expert (algorithms that take one).
    fn gradient(&mut self, batch: &Batch, shard: u64, weights: Option<&[f32]>) -> (Vec<f32>, UpdateStats);

    /// One optimiser step with a gradient laid out as [`Algorithm::gradient`]'s
    /// (e.g. the mean of several shards').
    fn apply_gradient(&mut self, gradient: &[f32]);

    /// The length of the longest gradient [`Algorithm::gradient`] returns.
    fn gradient_len(&self) -> usize;

    /// End of a cycle of updates (e.g. target networks follow).
    fn end_cycle(&mut self) {}

    /// The deterministic policy, frozen (tests, finals, evaluation, the zoo).
    fn policy(&self) -> AnyPolicy;

    /// The exploring policy, frozen, for this cycle's episodes.
    fn explorer(&self) -> Box<dyn Explorer>;

    /// An imitation learner's probability that the solver acts at a step of
    /// `epoch`'s exploration episodes (the learner's explorer acts otherwise);
    /// the solver then labels every step, and the replay buffer holds its label
    /// as the action. None for the others.
    fn solver_share(&self, _epoch: usize) -> Option<f64> {
        None
    }

    /// An imitation learner's standard deviation of the Gaussian noise added to
    /// the solver's actions where the solver acts (its labels stay clean), so that
    /// the episodes visit states off the solver's path (DART, Laskey et al. 2017).
    fn solver_noise(&self) -> f64 {
        0.0
    }

    /// A critic Q(s̄, a) of the policy as a plain network, saved beside it
    /// (for AggreVaTeD's `expert-advantage`); None where there is none.
    fn critic(&self) -> Option<PlainNet> {
        None
    }

    /// The parts of its state, by name: everything a checkpoint must hold to
    /// continue bit for bit (the normaliser apart). [`Algorithm::state`] and
    /// [`Algorithm::load_state`] follow from this one list.
    fn parts(&mut self) -> Vec<(&'static str, Part<'_>)>;

    /// Takes the actor (its target too) and the observation normaliser from a trained deterministic
    /// policy (`train --init-from`), already fitted to this learner's layout ([`fit_actor`]); the
    /// critics stay as drawn. Only algorithms whose registration says [`Info::starts_from_policy`].
    ///
    /// # Errors
    /// An algorithm that cannot, or a policy whose network does not fit.
    fn init_from(&mut self, _policy: &DeterministicPolicy) -> Result<(), StartError> {
        // The interface names no algorithm: `FinetuneConfig::validate` lists those that can, from the registry.
        Err(StartError::CannotStart { algo: self.name() })
    }

    /// Keeps `policy` (the one the run started from) beside the learner, frozen, for `uses`: the
    /// anchor of `train --anchor-alpha` (the actor's loss becomes TD3+BC's, Fujimoto & Gu 2021, with
    /// the policy's action as the target, −α·Q(s, π(s))/mean|Q| + mean ‖π(s) − π₀(s)‖²) and IBRL's
    /// action proposal of `train --ibrl` (Hu et al. 2023: exploration takes whichever of its action
    /// and the actor's the critic values more, and the critic's target bootstraps from the better of
    /// the two at the next state; the saved policy stays the actor). Not checkpointed: a resumed
    /// run calls it again.
    ///
    /// # Errors
    /// An algorithm that cannot, or a policy that does not fit.
    fn keep_start(&mut self, _policy: &DeterministicPolicy, uses: StartUses) -> Result<(), StartError> {
        Err(StartError::CannotKeep { flags: uses.flags(), algo: self.name() })
    }

    /// Holds the actor still (`held`), or lets it learn again: while held, updates step the
    /// critics alone (the critic warm-up of `train --critic-warmup`).
    fn hold_actor(&mut self, _held: bool) {}

    /// Its state by name, from [`Algorithm::parts`].
    fn state(&mut self) -> StateDict {
        let mut s = StateDict::default();
        for (name, part) in self.parts() {
            match part {
                Part::Net(net) => s.put_net(name, net),
                Part::Adam(adam) => s.put_adam(name, adam),
                Part::Tensor(t) => s.put_arrays(name, vec![super::nets::tensor_to_vec(t)]),
                Part::Counter(c) => {
                    s.counters.insert(name.to_owned(), *c);
                }
            }
        }
        s
    }

    /// Restores [`Algorithm::state`]'s output into a learner built with the
    /// same settings.
    ///
    /// # Errors
    /// A missing or mis-sized part, or one these settings do not have (e.g.
    /// TD3's second critic without `--td3`), named.
    fn load_state(&mut self, state: &StateDict) -> Result<(), StateError> {
        let mut known = Vec::new();
        for (name, part) in self.parts() {
            known.push(name);
            match part {
                Part::Net(net) => state.load_net(name, net)?,
                Part::Adam(adam) => state.load_adam(name, adam)?,
                Part::Tensor(t) => match state.arrays(name).as_slice() {
                    [v] if v.len() as i64 == t.numel() as i64 => {
                        let values = tch::Tensor::of_slice(v).view_as(t);
                        tch::no_grad(|| t.copy_(&values));
                    }
                    _ => return Err(StateError::Tensor { part: name, values: t.numel() }),
                },
                Part::Counter(c) => *c = state.counter(name)?,
            }
        }
        // Arrays of a part these settings lack (counters of older checkpoints may be spare).
        let foreign = state
            .tensors
            .keys()
            .map(|k| k.rsplit_once('.').map_or(k.as_str(), |(part, _)| part))
            .find(|p| !known.contains(p));
        match foreign {
            Some(p) => Err(StateError::Foreign(p.to_owned())),
            None => Ok(()),
        }
    }
}

/// How a frozen policy explores: one action per step (stored as produced;
/// the environment gets it clipped to [−1, 1]). `noise` is the episode's
/// noise state (empty at its start).
pub trait Explorer: Send + Sync {
    /// The exploring action for `obs`.
    fn explore(&self, obs: &[f32], noise: &mut Vec<f32>, rng: &mut ChaCha8Rng) -> Vec<f32>;
}

/// An algorithm's state by name: parameter arrays (`actor.0`, `actor.1`, …,
/// `actor_adam.0`, …) and integer counters (`actor_adam.t`, noise seeds).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateDict {
    /// Arrays by name.
    pub tensors: BTreeMap<String, Vec<f32>>,
    /// Counters by name.
    pub counters: BTreeMap<String, u64>,
}

impl StateDict {
    /// Adds a network's parameters as `name.0`, `name.1`, ….
    pub fn put_net(&mut self, name: &str, net: &Net) {
        self.put_arrays(name, net.to_vecs());
    }

    /// Adds an optimiser's moments as `name.0`, … and its step count as `name.t`.
    pub fn put_adam(&mut self, name: &str, adam: &Adam) {
        self.put_arrays(name, adam.to_vecs());
        self.counters.insert(format!("{name}.t"), adam.t);
    }

    /// Adds arrays as `name.0`, `name.1`, ….
    pub fn put_arrays(&mut self, name: &str, arrays: Vec<Vec<f32>>) {
        for (i, v) in arrays.into_iter().enumerate() {
            self.tensors.insert(format!("{name}.{i}"), v);
        }
    }

    /// The arrays `name.0`, `name.1`, … in order.
    pub fn arrays(&self, name: &str) -> Vec<Vec<f32>> {
        (0..).map_while(|i| self.tensors.get(&format!("{name}.{i}")).cloned()).collect()
    }

    /// Loads `net` from `name.*`.
    ///
    /// # Errors
    /// Missing or mis-sized parameters, naming `name`.
    pub(crate) fn load_net(&self, name: &str, net: &mut Net) -> Result<(), StateError> {
        net.load_vecs(&self.arrays(name)).map_err(|shape| StateError::Shape { part: name.to_owned(), shape })
    }

    /// Loads `adam` from `name.*` and `name.t`.
    ///
    /// # Errors
    /// Missing or mis-sized moments or step count, naming `name`.
    pub(crate) fn load_adam(&self, name: &str, adam: &mut Adam) -> Result<(), StateError> {
        let t = self.counter(&format!("{name}.t"))?;
        adam.load_vecs(&self.arrays(name), t).map_err(|shape| StateError::Shape { part: name.to_owned(), shape })
    }

    /// The counter `name`.
    ///
    /// # Errors
    /// When it is missing.
    pub(crate) fn counter(&self, name: &str) -> Result<u64, StateError> {
        self.counters.get(name).copied().ok_or_else(|| StateError::MissingCounter(name.to_owned()))
    }
}

/// What a learner does with the policy it started from ([`Algorithm::keep_start`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StartUses {
    /// TD3+BC's α: the actor is kept near the policy (`--anchor-alpha`; 0: not).
    pub anchor_alpha: f64,
    /// The policy proposes actions beside the actor's (IBRL, `--ibrl`).
    pub propose: bool,
}

impl StartUses {
    /// Whether it is used at all.
    pub fn any(self) -> bool {
        self.anchor_alpha > 0.0 || self.propose
    }

    /// The flags that ask for these uses, for messages.
    pub fn flags(self) -> String {
        let on = [(self.anchor_alpha > 0.0, "--anchor-alpha"), (self.propose, "--ibrl")];
        on.iter().filter(|(set, _)| *set).map(|(_, f)| *f).collect::<Vec<_>>().join(" and ")
    }
}

/// Why a learner cannot start from, or keep, a trained policy.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StartError {
    /// An algorithm that does not start from a trained policy (`train --init-from`).
    #[error("{algo} cannot start from a trained policy (its registration says so)")]
    CannotStart {
        /// The algorithm.
        algo: &'static str,
    },
    /// An algorithm that keeps no starting policy beside it (`--anchor-alpha`, `--ibrl`).
    #[error(
        "{flags} keeps a deterministic actor's starting policy beside it (ddpg, with --td3 or not); {algo} cannot"
    )]
    CannotKeep {
        /// The flags that asked for it.
        flags: String,
        /// The algorithm.
        algo: &'static str,
    },
    /// A policy whose actor is another network than the learner's.
    #[error("the policy's actor is {theirs}, and this run's is {ours}: {fix}")]
    OtherActor {
        /// The policy's actor, described.
        theirs: String,
        /// The learner's actor, described.
        ours: String,
        /// What to do.
        fix: &'static str,
    },
    /// A policy whose normaliser reads another observation.
    #[error("the policy's normaliser reads {theirs} features, and this run's observation has {ours}")]
    OtherNormalizer {
        /// The policy's normaliser's features.
        theirs: usize,
        /// The run's observation's.
        ours: usize,
    },
    /// The fitted policy's values do not fit the learner's network.
    #[error("the policy's actor: {0}")]
    Shape(#[from] super::nets::Shape),
}

/// Why a checkpoint's state does not load into a learner ([`Algorithm::load_state`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StateError {
    /// A network's or an optimiser's arrays that do not fit it.
    #[error("{part}: {shape}")]
    Shape {
        /// The part.
        part: String,
        /// What does not fit.
        shape: super::nets::Shape,
    },
    /// A tensor part that is not one array of its size.
    #[error("{part}: expected one array of {values} values")]
    Tensor {
        /// The part.
        part: &'static str,
        /// Its values.
        values: usize,
    },
    /// A counter the learner needs.
    #[error("the counter {0} is missing")]
    MissingCounter(String),
    /// A part the learner with these settings does not have (e.g. TD3's second critic without `--td3`).
    #[error("the checkpoint holds {0}, which a learner with these settings does not have")]
    Foreign(String),
}

/// The three [`Algorithm`] methods every learner answers alike, from its registration and its
/// `norm` field: `learner_basics!(REGISTRATION.info.name())` in the `impl Algorithm`, or
/// `learner_basics!(field name)` for a learner that keeps its name in a field.
macro_rules! learner_basics {
    (@norm) => {
        fn norm(&self) -> &$crate::policy::actor::normalizer::Normalizer {
            &self.norm
        }

        fn norm_mut(&mut self) -> &mut $crate::policy::actor::normalizer::Normalizer {
            &mut self.norm
        }
    };
    (field $name:ident) => {
        fn name(&self) -> &'static str {
            self.$name
        }
        $crate::learn::agents::algorithm::learner_basics!(@norm);
    };
    ($name:expr) => {
        fn name(&self) -> &'static str {
            $name
        }
        $crate::learn::agents::algorithm::learner_basics!(@norm);
    };
}
pub(crate) use learner_basics;

/// `policy` fitted to a learner whose actor is `ours` and normaliser `norm`: a set network's rows
/// set to this layout's slots (its weights do not depend on them), and checked to be the same
/// network (kind, layers, options) reading an observation of the same length.
///
/// # Errors
/// A network or normaliser of another shape, both sides named.
pub fn fit_actor(
    ours: &PlainNet,
    norm: &Normalizer,
    policy: &DeterministicPolicy,
) -> Result<DeterministicPolicy, StartError> {
    let fitted = match (ours.set, policy.net.set) {
        (Some(s), Some(_)) => match AnyPolicy::Deterministic(policy.clone()).with_slots(s.slots) {
            AnyPolicy::Deterministic(p) => p,
            AnyPolicy::Pggd(_) => unreachable!("with_slots keeps the kind"),
        },
        _ => policy.clone(),
    };
    let inputs = |n: &PlainNet| n.layers.first().map_or(0, |l| l.n_in);
    let other = |fix| StartError::OtherActor { theirs: fitted.net.describe(), ours: ours.describe(), fix };
    if ours.set.is_none() && fitted.net.set.is_none() && inputs(&fitted.net) != inputs(ours) {
        return Err(other(
            "a flat policy reads its own task's layout (its blocks' rows in order), so it starts only a run of a \
             task with that layout; start from a policy of this task, or from a set network's (--net set or \
             entity), which reads any number of blocks",
        ));
    }
    if !fitted.net.same_network(ours) {
        return Err(other(
            "train with the policy's network settings (--net, --set-width, --hidden, --layers and the set options \
             it was trained with)",
        ));
    }
    if fitted.norm.dim() != norm.dim() || fitted.norm.set_layout() != norm.set_layout() {
        return Err(StartError::OtherNormalizer { theirs: fitted.norm.dim(), ours: norm.dim() });
    }
    Ok(fitted)
}

/// A plain network's parameters in a [`Net`]'s order (each layer's weights, then its biases).
pub fn plain_vecs(net: &PlainNet) -> Vec<Vec<f32>> {
    net.layers.iter().flat_map(|l| [l.w.clone(), l.b.clone()]).collect()
}

/// The number of values in `nets`' parameters (a gradient's length).
pub fn param_count(nets: &[&Net]) -> usize {
    nets.iter().flat_map(|n| &n.params).map(tch::Tensor::numel).sum()
}

/// Splits a flattened gradient into one slice per network, in order.
///
/// # Panics
/// If `gradient` is not exactly as long as the networks' parameters.
pub fn split_gradient<'g>(gradient: &'g [f32], nets: &[&Net]) -> Vec<&'g [f32]> {
    let mut rest = gradient;
    let parts = nets
        .iter()
        .map(|n| {
            let (g, r) = rest.split_at(param_count(&[n]).min(rest.len()));
            rest = r;
            g
        })
        .collect();
    assert!(rest.is_empty(), "a gradient of another layout");
    parts
}

/// `into` with the fields named in `fields` taken from `from` (a branch's settings: the one list,
/// [`Info::branchable`], says which), through their serde form.
///
/// # Errors
/// A name that is no field of the settings, or a value that does not read back.
pub(crate) fn take_fields<C>(into: &C, from: &C, fields: &[&str]) -> Result<C, String>
where
    C: serde::Serialize + serde::de::DeserializeOwned,
{
    let (mut to, from) = (serde_json::to_value(into), serde_json::to_value(from));
    let (Ok(serde_json::Value::Object(to)), Ok(serde_json::Value::Object(from))) = (&mut to, from) else {
        return Err("settings that are not a table of fields".into());
    };
    for f in fields {
        let v = from.get(*f).ok_or_else(|| format!("branchable setting {f:?} is no field of the settings"))?;
        to.insert((*f).to_owned(), v.clone());
    }
    serde_json::from_value(serde_json::Value::Object(to.clone())).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mlp_bytes_count_weights_and_biases() {
        let shared = SharedConfig { hidden: 4, layers: 2, ..SharedConfig::default() };
        let spec = Spec { arch: Arch::mlp(3), act_dim: 2, shared: &shared };
        // 3 -> 4 -> 4 -> 2: 16 + 20 + 10 parameters.
        assert_eq!(spec.mlp_bytes(0, 2, 1), 4 * 46);
        assert_eq!(spec.mlp_bytes(2, 1, 2), 4 * 2 * (24 + 20 + 5));
    }
}
