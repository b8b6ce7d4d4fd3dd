//! The settings learning algorithms share: the networks' shape, the
//! discount, the observation normaliser, and the actor-critics' learning
//! rates, target averaging, n-step returns, arithmetic and critics. Each
//! algorithm reads the ones its registration lists
//! ([`super::algorithm::Registration::reads`]); its own settings are its own
//! type, in its file.
//!
//! Every default is written once, in [`SharedConfig::DEFAULT`]: the flags,
//! the run files and `Default` take it from there.

use crate::support::limits::Bound;
use serde::{Deserialize, Serialize};

/// Hidden units per layer.
pub const HIDDEN: Bound = Bound::new("--hidden", 1, 8_192, "a layer of 8,192 units already holds 67 M weights");
/// Hidden layers.
pub const LAYERS: Bound = Bound::new("--layers", 1, 32, "");
/// Steps of an n-step return.
pub const N_STEP: Bound = Bound::new("--n-step", 1, 50, "an episode's length in the paper's tasks");

/// Settings several algorithms read (defaults: the paper's, i.e. Plappert et al. 2018).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "Settings the algorithms share")]
pub struct SharedConfig {
    /// Hidden layers of every network.
    #[arg(long, default_value_t = Self::DEFAULT.layers, value_parser = LAYERS.parser::<usize>())]
    pub layers: usize,
    /// Units per hidden layer.
    #[arg(long, default_value_t = Self::DEFAULT.hidden, value_parser = HIDDEN.parser::<usize>())]
    pub hidden: usize,
    /// Actor learning rate (Adam).
    #[arg(long, default_value_t = Self::DEFAULT.lr_actor)]
    pub lr_actor: f64,
    /// Critic learning rate (Adam).
    #[arg(long, default_value_t = Self::DEFAULT.lr_critic)]
    pub lr_critic: f64,
    /// Discount; the default 0.98 is 1 − 1/T for T = 50 steps.
    #[arg(long, default_value_t = Self::DEFAULT.gamma)]
    pub gamma: f64,
    /// Target networks keep this share of themselves at each update.
    #[arg(long, default_value_t = Self::DEFAULT.polyak)]
    pub polyak: f64,
    /// Floor of the normaliser's standard deviation.
    #[arg(long, default_value_t = Self::DEFAULT.norm_eps)]
    pub norm_eps: f64,
    /// Normalised observations are clipped to ±this.
    #[arg(long, default_value_t = Self::DEFAULT.norm_clip)]
    pub norm_clip: f32,
    /// Arithmetic of the update's hidden-layer products: `f32` (the paper's)
    /// or `bf16` (mixed precision; about 1.5× the update rate on CPUs with AMX,
    /// results/ddpg.md).
    #[arg(long, value_enum, default_value_t = Self::DEFAULT.precision)]
    pub precision: Precision,
    /// Steps of reward summed before bootstrapping (1: the paper's one-step target).
    #[arg(long, default_value_t = Self::DEFAULT.n_step, value_parser = N_STEP.parser::<usize>())]
    pub n_step: usize,
    /// With `--net set`: the critics are MLPs over the same `objects` observation (its rows in
    /// the environment's order), only the actor a set network (an asymmetric actor-critic: the
    /// critics serve training alone; the policy saved is the set actor).
    #[arg(long)]
    pub flat_critic: bool,
    /// Layer normalisation (no gain, no bias) of every hidden layer of the critics before its ReLU,
    /// as RLPD's critics (Ball et al. 2023): it bounds the values a critic extrapolates to actions
    /// its data never took.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub critic_norm: bool,
}

impl SharedConfig {
    /// Every shared setting's flag (what an algorithm that reads them all lists as it reads).
    pub const FLAGS: &'static [&'static str] = &[
        "--layers",
        "--hidden",
        "--lr-actor",
        "--lr-critic",
        "--gamma",
        "--polyak",
        "--norm-eps",
        "--norm-clip",
        "--precision",
        "--n-step",
        "--flat-critic",
        "--critic-norm",
    ];

    /// The defaults.
    pub const DEFAULT: Self = Self {
        layers: 3,
        hidden: 256,
        lr_actor: 1e-3,
        lr_critic: 1e-3,
        gamma: 0.98,
        polyak: 0.95,
        norm_eps: 0.01,
        norm_clip: 5.0,
        precision: Precision::F32,
        n_step: 1,
        flat_critic: false,
        critic_norm: false,
    };

    /// The defaults with every setting a `config.json` omits at its default turned on, so that it
    /// serialises every field (tests enumerate the fields from it).
    #[cfg(test)]
    pub(crate) const ALL_WRITTEN: Self = Self { critic_norm: true, ..Self::DEFAULT };

    /// Whether every setting is in range; the error names the flag.
    ///
    /// # Errors
    /// The first setting out of range.
    pub fn validate(&self) -> Result<(), String> {
        for (bound, v) in [(LAYERS, self.layers), (HIDDEN, self.hidden), (N_STEP, self.n_step)] {
            bound.check_usize(v)?;
        }
        let finite_pos = |v: f64| v.is_finite() && v > 0.0;
        let checks: [(bool, &str); 5] = [
            (finite_pos(self.lr_actor), "--lr-actor must be a positive number"),
            (finite_pos(self.lr_critic), "--lr-critic must be a positive number"),
            ((0.0..1.0).contains(&self.gamma), "--gamma must be in [0, 1)"),
            ((0.0..=1.0).contains(&self.polyak), "--polyak must be in [0, 1]"),
            (
                finite_pos(self.norm_eps) && self.norm_clip.is_finite() && self.norm_clip > 0.0,
                "--norm-eps and --norm-clip must be positive numbers",
            ),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, msg)) => Err((*msg).to_owned()),
            None => self.precision.check(),
        }
    }

    /// Whether the update's products are bfloat16.
    pub fn bf16(&self) -> bool {
        self.precision == Precision::Bf16
    }
}

impl Default for SharedConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Arithmetic of the networks' hidden-layer products during updates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Float32 throughout.
    #[default]
    F32,
    /// Bfloat16 products with float accumulation and float parameters.
    Bf16,
}

impl std::fmt::Display for Precision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::F32 => "f32",
            Self::Bf16 => "bf16",
        })
    }
}

impl Precision {
    /// Whether this CPU computes bfloat16 products natively (AMX or AVX512-BF16).
    pub fn bf16_supported() -> bool {
        std::fs::read_to_string("/proc/cpuinfo")
            .map(|c| c.split_whitespace().any(|f| f == "amx_bf16" || f == "avx512_bf16"))
            .unwrap_or(false)
    }

    /// Whether this CPU can run this precision.
    ///
    /// # Errors
    /// bf16 on a CPU without AMX or AVX512-BF16, naming the fix.
    pub fn check(self) -> Result<(), String> {
        if self == Self::Bf16 && !Self::bf16_supported() {
            return Err(
                "--precision bf16 needs a CPU with AMX or AVX512-BF16 (this one has neither); use --precision f32"
                    .into(),
            );
        }
        Ok(())
    }
}

/// The settings of a run's files written before the algorithms had settings
/// of their own held every shared setting in the `ddpg` group: the shared
/// group is taken from there when a file has none (every other key of that
/// group is DDPG's own, which the DDPG group reads).
pub fn upgrade_legacy(value: &mut serde_json::Value) {
    if let serde_json::Value::Object(map) = value {
        if !map.contains_key(SHARED_KEY) {
            if let Some(old) = map.get("ddpg").cloned() {
                map.insert(SHARED_KEY.to_owned(), old);
            }
        }
    }
}

/// The key of the shared group in a run's files.
pub const SHARED_KEY: &str = "shared";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_flags_and_the_files_defaults() {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            shared: SharedConfig,
        }
        use clap::Parser;
        assert_eq!(Cli::parse_from(["x"]).shared, SharedConfig::default());
        assert_eq!(serde_json::from_str::<SharedConfig>("{}").unwrap(), SharedConfig::default());
        // Every field: those the files leave out at their default (critic_norm) set.
        let fields = serde_json::to_value(SharedConfig::ALL_WRITTEN).unwrap();
        let flags: Vec<String> =
            fields.as_object().unwrap().keys().map(|k| format!("--{}", k.replace('_', "-"))).collect();
        let mut listed: Vec<String> = SharedConfig::FLAGS.iter().map(|f| f.to_string()).collect();
        listed.sort();
        assert_eq!(listed, flags, "FLAGS lists every field");
        let mut old = serde_json::json!({"ddpg": {"layers": 2, "hidden": 64, "td3": true}});
        upgrade_legacy(&mut old);
        let shared: SharedConfig = serde_json::from_value(old[SHARED_KEY].clone()).unwrap();
        assert_eq!((shared.layers, shared.hidden, shared.gamma), (2, 64, 0.98));
    }
}
