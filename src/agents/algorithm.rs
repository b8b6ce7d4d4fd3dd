//! What a learning algorithm is to the training loop, and the list of them.
//!
//! An algorithm is one file (`ddpg.rs`, `pggd.rs`, `sac.rs`) that implements
//! [`Algorithm`]: its update as a gradient plus an optimiser step (so the
//! loop can average shards' gradients, across MPI ranks too), how it
//! explores, the deterministic policy it exports, and its state as named
//! tensors and counters ([`StateDict`]), which checkpoints store by name.
//! Adding one is that file and a line in [`ALGORITHMS`]; the trainer,
//! checkpoints, `--algo` and the run's files take it from there.

use super::ddpg::{DdpgConfig, UpdateStats};
use super::mlp::TanhMlp;
use super::nets::{Adam, Net};
use super::normalizer::Normalizer;
use super::pggd::PggdConfig;
use super::replay::Batch;
use super::AnyPolicy;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// Every algorithm `--algo` accepts: its registration (name, summary,
/// constructor, settings check). The first is the default.
pub const ALGORITHMS: &[Registration] =
    &[super::ddpg::REGISTRATION, super::pggd::REGISTRATION, super::sac::REGISTRATION];

/// How an algorithm is named and built.
pub struct Registration {
    /// `--algo` value and checkpoint name (lowercase).
    pub name: &'static str,
    /// How it is shown in titles and reports, e.g. "DDPG".
    pub title: &'static str,
    /// One line for `--help`.
    pub about: &'static str,
    /// Whether it learns from an AggreVaTeD expert (`--expert`).
    pub takes_expert: bool,
    /// A fresh learner; `rng` fixes the initial weights.
    pub new: fn(&Spec, &mut ChaCha8Rng) -> Box<dyn Algorithm>,
    /// Whether the run's settings suit it; the error names the flag.
    pub check: fn(&DdpgConfig, &PggdConfig) -> Result<(), String>,
}

/// What an algorithm is built from: the networks' inputs and the run's settings (the
/// off-policy settings in [`DdpgConfig`] are shared by DDPG and SAC, and
/// give PGGD its network shape and normaliser).
#[derive(Debug, Clone, Copy)]
pub struct Spec<'a> {
    /// What the networks read: the observation's length and, for a set network, its layout.
    pub arch: super::arch::Arch,
    /// Action size.
    pub act_dim: usize,
    /// Network shape, optimiser, discount, normaliser, exploration, n-step, TD3.
    pub ddpg: &'a DdpgConfig,
    /// PGGD's settings.
    pub pggd: &'a PggdConfig,
}

/// An algorithm by name (`--algo`, a run's `config.json`, a checkpoint):
/// one of [`ALGORITHMS`].
#[derive(Clone, Copy)]
pub struct Algo(&'static Registration);

impl Algo {
    /// DDPG (the default; the paper's).
    pub const DDPG: Self = Self(&ALGORITHMS[0]);
    /// PGGD (the paper's; with `--expert`, AggreVaTeD).
    pub const PGGD: Self = Self(&ALGORITHMS[1]);

    /// The algorithm of a registration (an algorithm's file names itself this way).
    pub const fn of(registration: &'static Registration) -> Self {
        Self(registration)
    }

    /// The registered algorithm called `name`.
    ///
    /// # Errors
    /// An unknown name, with the known ones.
    pub fn named(name: &str) -> Result<Self, String> {
        ALGORITHMS.iter().find(|r| r.name == name).map(Self).ok_or_else(|| {
            let known: Vec<&str> = ALGORITHMS.iter().map(|r| r.name).collect();
            format!("unknown algorithm {name:?}; known: {}", known.join(", "))
        })
    }

    /// Its registration.
    pub fn registration(self) -> &'static Registration {
        self.0
    }

    /// Whether the run's settings suit it: [`Registration::check`], and
    /// `--expert` only for algorithms that take one.
    ///
    /// # Errors
    /// The first setting that does not suit it, naming the flag.
    pub fn check(self, ddpg: &DdpgConfig, pggd: &PggdConfig, expert: bool) -> Result<(), String> {
        if expert && !self.0.takes_expert {
            let takers: Vec<&str> = ALGORITHMS.iter().filter(|r| r.takes_expert).map(|r| r.name).collect();
            return Err(format!(
                "--expert is for AggreVaTeD (--algo {}); {} trains without an expert",
                takers.join(" or --algo "),
                self.0.title
            ));
        }
        (self.0.check)(ddpg, pggd)
    }

    /// Its name, e.g. "ddpg".
    pub fn name(self) -> &'static str {
        self.0.name
    }

    /// A fresh learner of this algorithm, after its settings check.
    ///
    /// # Errors
    /// [`Registration::check`]'s message.
    pub fn build(self, spec: &Spec, rng: &mut ChaCha8Rng) -> Result<Box<dyn Algorithm>, String> {
        (self.0.check)(spec.ddpg, spec.pggd)?;
        Ok((self.0.new)(spec, rng))
    }

    /// clap's parser for `--algo`: the registered names, each with its summary.
    pub fn parser() -> impl clap::builder::TypedValueParser<Value = Self> {
        use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
        PossibleValuesParser::new(ALGORITHMS.iter().map(|r| PossibleValue::new(r.name).help(r.about)))
            .map(|name| Self::named(&name).unwrap_or_default())
    }
}

impl Default for Algo {
    fn default() -> Self {
        Self::DDPG
    }
}

/// Two algorithms are the same when their names are (a registration's
/// address is not unique: `const` items may be copied).
impl PartialEq for Algo {
    fn eq(&self, other: &Self) -> bool {
        self.0.name == other.0.name
    }
}

impl Eq for Algo {}

impl std::fmt::Debug for Algo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.title)
    }
}

impl std::fmt::Display for Algo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.name)
    }
}

impl serde::Serialize for Algo {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0.name)
    }
}

impl<'de> serde::Deserialize<'de> for Algo {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Self::named(&name).map_err(serde::de::Error::custom)
    }
}

/// A learner as the training loop sees it.
pub trait Algorithm: Send {
    /// Which algorithm.
    fn algo(&self) -> Algo;

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

    /// A critic Q(s̄, a) of the policy as a plain network, saved beside it
    /// (for AggreVaTeD's `expert-advantage`); None where there is none.
    fn critic(&self) -> Option<TanhMlp> {
        None
    }

    /// Takes the settings a branch may change (`train --branch-from`).
    fn take_branch_settings(&mut self, _ddpg: &DdpgConfig) {}

    /// Everything a checkpoint must hold to continue bit for bit, by name
    /// (the normaliser apart).
    fn state(&self) -> StateDict;

    /// Restores [`Algorithm::state`]'s output into a learner built with the same settings.
    ///
    /// # Errors
    /// A missing or mis-sized entry, named.
    fn load_state(&mut self, state: &StateDict) -> Result<(), String>;

    /// This learner as `Any`, for callers that need one algorithm's internals (tests, experts).
    fn as_any(&self) -> &dyn std::any::Any;
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
    pub fn load_net(&self, name: &str, net: &mut Net) -> Result<(), String> {
        net.load_vecs(&self.arrays(name)).map_err(|e| format!("{name}: {e}"))
    }

    /// Loads `adam` from `name.*` and `name.t`.
    ///
    /// # Errors
    /// Missing or mis-sized moments or step count, naming `name`.
    pub fn load_adam(&self, name: &str, adam: &mut Adam) -> Result<(), String> {
        let t = self.counter(&format!("{name}.t"))?;
        adam.load_vecs(&self.arrays(name), t).map_err(|e| format!("{name}: {e}"))
    }

    /// The counter `name`.
    ///
    /// # Errors
    /// When it is missing.
    pub fn counter(&self, name: &str) -> Result<u64, String> {
        self.counters.get(name).copied().ok_or_else(|| format!("the counter {name} is missing"))
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_lowercase_and_round_trip() {
        for (i, r) in ALGORITHMS.iter().enumerate() {
            assert_eq!(r.name, r.name.to_lowercase());
            assert!(ALGORITHMS[..i].iter().all(|o| o.name != r.name), "{} twice", r.name);
            let a = Algo::named(r.name).unwrap();
            assert_eq!(serde_json::to_string(&a).unwrap(), format!("\"{}\"", r.name));
            assert_eq!(serde_json::from_str::<Algo>(&format!("\"{}\"", r.name)).unwrap(), a);
        }
        let e = Algo::named("ppo").unwrap_err();
        assert!(e.contains("unknown algorithm \"ppo\"") && e.contains("ddpg, pggd"), "{e}");
        assert_eq!((Algo::DDPG.name(), Algo::PGGD.name()), ("ddpg", "pggd"));
        assert_eq!(Algo::of(&super::super::sac::REGISTRATION), Algo::named("sac").unwrap());
    }
}
