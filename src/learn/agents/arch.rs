//! Which network an algorithm learns with, and what it reads: a flat MLP
//! over the flat observation (the paper's), or a set network over the
//! `objects` observation: a per-object encoder shared by every
//! object row, optionally one masked self-attention block between the rows,
//! masked mean and max pooling, then a head over the robot features, the
//! pooled features and (a critic) the action. Every algorithm builds its
//! actor, critics and normaliser through [`Arch`], so `--net set` reaches
//! DDPG, TD3, SAC and PGGD without any of them knowing which it got.

use super::nets::{mlp_sizes, Net};
use crate::env::{ObsMode, ObsSpec};
use crate::policy::actor::mlp::SetLayout;
use crate::policy::actor::normalizer::Normalizer;
use crate::support::limits::Bound;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Why [`Arch::of`] builds no networks: the network settings, or an observation the network does not read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArchError {
    /// A network setting out of range ([`NetConfig::validate`]'s reason).
    #[error("{0}")]
    Settings(String),
    /// `--net` asked of an observation it does not read.
    #[error("--net {net} reads the `{reads}` observation, not the `{given}` one")]
    OtherMode {
        /// The network kind's flag value.
        net: &'static str,
        /// The observation it reads.
        reads: ObsMode,
        /// The one it was given.
        given: ObsMode,
    },
    /// The set layout does not fit the observation.
    #[error(transparent)]
    Fit(#[from] crate::policy::actor::FitError),
}

/// Layers of a set network's per-object encoder.
pub const SET_ENCODER_LAYERS: Bound = Bound::new("--set-encoder-layers", 1, 32, "");
/// Pre-LayerNorm transformer blocks of a set network's encoder.
pub const SET_TRANSFORMER: Bound = Bound::new("--set-transformer", 0, 8, "");
/// The width of a set network's per-row layers (0: `--hidden`).
pub const SET_WIDTH: Bound = Bound::new("--set-width", 0, 8_192, "a layer of 8,192 units already holds 67 M weights");

/// The network's kind (`--net`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum NetKind {
    /// An MLP over the flat observation (the paper's).
    #[default]
    Mlp,
    /// A permutation-invariant set network over the `objects` observation.
    Set,
    /// The same set network over the `entities` observation: the blocks' rows and the gripper's,
    /// table's and floor's, with their colours, so that every rule object is in view.
    Entity,
}

impl NetKind {
    /// As `--net` spells it.
    pub fn name(self) -> &'static str {
        match self {
            NetKind::Mlp => "mlp",
            NetKind::Set => "set",
            NetKind::Entity => "entity",
        }
    }

    /// The network that reads `mode` (`--net` for a policy of that observation).
    pub fn reading(mode: ObsMode) -> Self {
        match mode {
            ObsMode::Flat => NetKind::Mlp,
            ObsMode::Objects => NetKind::Set,
            ObsMode::Entities => NetKind::Entity,
        }
    }

    /// Whether it is a set network (`set` or `entity`).
    pub fn is_set(self) -> bool {
        match self {
            NetKind::Mlp => false,
            NetKind::Set | NetKind::Entity => true,
        }
    }
}

/// How a set network combines its object rows (`--set-pooling`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Pooling {
    /// Masked mean and max of the encoded rows (Deep Sets).
    #[default]
    MeanMax,
    /// One masked self-attention block between the encoded rows, then mean and max.
    Attention,
    /// Masked mean and max of the encoded rows of each colour apart (red, blue, green, grey).
    Colour,
    /// Attention pooling with a learned query: the rows weighted by a softmax of their scores.
    Query,
}

/// The network settings of a run (shared by every algorithm).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::Args)]
pub struct NetConfig {
    /// Network: `mlp` (the flat observation; the paper's), `set` (the `objects`
    /// observation: a per-object encoder shared across objects, masked pooling, a head;
    /// its output does not depend on the order or the number of objects) or `entity` (that
    /// set network over the `entities` observation: the gripper, table and floor as rows too).
    #[arg(long = "net", value_enum, default_value = "mlp")]
    #[serde(default)]
    pub net: NetKind,
    /// Set network: layers of the per-object encoder (of `--hidden` units; the head has `--layers`).
    #[arg(long, default_value_t = 2, value_parser = SET_ENCODER_LAYERS.parser::<usize>())]
    #[serde(default = "two")]
    pub set_encoder_layers: usize,
    /// Set network: `mean-max` pooling (Deep Sets), `attention` (one masked
    /// self-attention block between the encoded objects first), `colour`
    /// (mean and max of each colour's objects apart) or `query` (attention
    /// pooling with a learned query instead of the mean and max).
    #[arg(long, value_enum, default_value = "mean-max")]
    #[serde(default)]
    pub set_pooling: Pooling,
    /// Set network: layer-normalise the pooled features (no gain or bias) before the head, so
    /// that the head's inputs stay of unit scale however large the encoder's outputs grow.
    #[arg(long)]
    #[serde(default)]
    pub set_norm: bool,
    /// Set network: the encoder reads robot tokens, each row with the robot features before it and
    /// (a critic's) the action after it, instead of the row alone (Zhou et al. 2022): every row is
    /// seen relative to the gripper, and a set critic's action reaches every row.
    #[arg(long)]
    #[serde(default)]
    pub set_robot_tokens: bool,
    /// Entity set network: normalise by type of row, the gripper's, the table's and the floor's each
    /// with statistics of its own and the blocks' with theirs, instead of one set for every row.
    #[arg(long)]
    #[serde(default)]
    pub set_type_norm: bool,
    /// Set network: pre-LayerNorm transformer blocks after the encoder (0: none; the issue's
    /// recipe: 2), each masked multi-head self-attention (4 heads; `--hidden` a multiple of 4)
    /// and a feed-forward pair, with residual connections.
    #[arg(long, default_value_t = 0, value_parser = SET_TRANSFORMER.parser::<usize>())]
    #[serde(default, skip_serializing_if = "crate::policy::actor::mlp::is_zero")]
    pub set_transformer: usize,
    /// Set network: the width of the per-row layers (encoder, attention or transformer blocks,
    /// query pooling; 0: `--hidden`). They run once per row, the head once per sample, so a
    /// narrower row width (the published entity transformers use 64–128) cuts most of the cost.
    #[arg(long, default_value_t = 0, value_parser = SET_WIDTH.parser::<usize>())]
    #[serde(default, skip_serializing_if = "crate::policy::actor::mlp::is_zero")]
    pub set_width: usize,
}

fn two() -> usize {
    2
}

impl Default for NetConfig {
    fn default() -> Self {
        Self {
            net: NetKind::Mlp,
            set_encoder_layers: two(),
            set_pooling: Pooling::MeanMax,
            set_norm: false,
            set_robot_tokens: false,
            set_type_norm: false,
            set_transformer: 0,
            set_width: 0,
        }
    }
}

impl NetConfig {
    /// The observation mode the network reads.
    pub fn obs_mode(&self) -> ObsMode {
        match self.net {
            NetKind::Mlp => ObsMode::Flat,
            NetKind::Set => ObsMode::Objects,
            NetKind::Entity => ObsMode::Entities,
        }
    }

    /// Whether every setting is in range; the error names the flag.
    ///
    /// # Errors
    /// The first setting out of range.
    pub fn validate(&self) -> Result<(), String> {
        SET_ENCODER_LAYERS.check_usize(self.set_encoder_layers)?;
        SET_TRANSFORMER.check_usize(self.set_transformer)?;
        SET_WIDTH.check_usize(self.set_width)?;
        if self.set_transformer > 0 && self.set_pooling == Pooling::Attention {
            return Err(
                "--set-transformer replaces --set-pooling attention's block; pool with mean-max or query".into()
            );
        }
        Ok(())
    }

    /// How the run's title names the network (empty: the paper's MLP).
    pub fn describe(&self) -> String {
        let rows = match self.net {
            NetKind::Mlp => return String::new(),
            NetKind::Set => "set network",
            NetKind::Entity => "entity set network",
        };
        let kind = match self.set_pooling {
            Pooling::MeanMax => rows.to_owned(),
            Pooling::Attention => format!("{rows} + attention"),
            Pooling::Colour => format!("{rows}, pooled by colour"),
            Pooling::Query => format!("{rows}, pooled by a learned query"),
        };
        let kind = if self.set_robot_tokens { format!("{kind}, robot tokens") } else { kind };
        let kind = if self.set_type_norm { format!("{kind}, statistics per row type") } else { kind };
        let kind = match self.set_transformer {
            0 => kind,
            n => format!("{kind}, {n} transformer block{}", if n == 1 { "" } else { "s" }),
        };
        let kind = match self.set_width {
            0 => kind,
            w => format!("{kind}, rows {w} wide"),
        };
        if self.set_norm {
            format!("{kind}, layer-normalised")
        } else {
            kind
        }
    }
}

/// What an algorithm's networks read and how they are laid out: the
/// observation's length and, for a set network, its layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Arch {
    /// The observation's length.
    pub obs_dim: usize,
    /// A set network's layout (None: MLPs).
    pub set: Option<SetLayout>,
}

impl Arch {
    /// MLPs over `obs_dim`-long observations.
    pub fn mlp(obs_dim: usize) -> Self {
        Self { obs_dim, set: None }
    }

    /// The networks `net` asks for on observations laid out as `obs`.
    ///
    /// # Errors
    /// Settings out of range, a set network on a flat observation, or the reverse.
    pub fn of(obs: &ObsSpec, net: &NetConfig) -> Result<Self, ArchError> {
        net.validate().map_err(ArchError::Settings)?;
        if obs.mode != net.obs_mode() {
            return Err(ArchError::OtherMode { net: net.net.name(), reads: net.obs_mode(), given: obs.mode });
        }
        match net.net {
            NetKind::Mlp => Ok(Self::mlp(obs.dim())),
            NetKind::Set | NetKind::Entity => {
                let mut layout = SetLayout::of(obs, net.set_encoder_layers)?;
                layout.attention = net.set_pooling == Pooling::Attention;
                layout.by_colour = net.set_pooling == Pooling::Colour;
                layout.query = net.set_pooling == Pooling::Query;
                layout.norm = net.set_norm;
                layout.robot_tokens = net.set_robot_tokens;
                layout.fixtures = if net.set_type_norm { obs.mode.fixtures().len() } else { 0 };
                layout.transformer = net.set_transformer;
                layout.width = net.set_width;
                Ok(Self { obs_dim: obs.dim(), set: Some(layout) })
            }
        }
    }

    /// A network of `layers` hidden layers of `hidden` units (a set network:
    /// the encoder's layers, then a head of that many) from the observation
    /// and `extra` further inputs (a critic's action) to `out` outputs,
    /// through tanh if `tanh_out`; initialised from `rng`.
    pub fn net(
        &self,
        (hidden, layers): (usize, usize),
        extra: usize,
        out: usize,
        tanh_out: bool,
        rng: &mut impl Rng,
    ) -> Net {
        match self.set {
            None => Net::new(&mlp_sizes(self.obs_dim + extra, hidden, layers, out), tanh_out, rng),
            Some(s) => Net::new_set(s, extra, (hidden, s.encoder_layers, layers), out, tanh_out, rng),
        }
    }

    /// What the critics are: these networks, or with `flat` MLPs over the
    /// same observation (a set actor's asymmetric critics; `--flat-critic`).
    pub fn critics(&self, flat: bool) -> Self {
        if flat {
            Self::mlp(self.obs_dim)
        } else {
            *self
        }
    }

    /// The observation normaliser: per component, or for a set network per
    /// feature shared by every object row (the mask passes unchanged).
    pub fn normalizer(&self, eps: f64, clip: f32) -> Normalizer {
        match self.set {
            None => Normalizer::new(self.obs_dim, eps, clip),
            Some(s) => Normalizer::for_set(s, eps, clip),
        }
    }
}
