//! DAgger (Ross, Gordon and Bagnell 2011; `--algo dagger`): the imitation
//! learner ([`super::imitation`]) on episodes where the solver acts with a
//! probability β that decays epoch by epoch and the learner acts otherwise;
//! the solver labels every step, the learner's included.

use super::algorithm::{Info, Registration};
use super::imitation::{Cloner, Schedule, READS};
use serde::{Deserialize, Serialize};

/// DAgger in the list of algorithms (`--algo dagger`).
pub const REGISTRATION: Registration<DaggerConfig> = Registration {
    info: Info {
        trainer: crate::benchmark::saved::Trainer::Dagger,
        title: "DAgger",
        about: "DAgger: the solver labels the learner's own states (--net entity)",
        takes_expert: false,
        imitates: true,
        reads: READS,
        flag_prefix: "dagger-",
        branchable: &["beta0", "t0"],
        starts_from_policy: true,
    },
    new: |spec, own, rng| Box::new(Cloner::new("dagger", spec, own.schedule(), 0.0, rng)),
    validate: DaggerConfig::validate,
    unused: |_| Vec::new(),
    // The actor with Adam's two moments.
    memory: |spec, _| spec.mlp_bytes(0, spec.act_dim, 3),
    // β0 and t0, the schedule of the solver's share.
    take_branch: |agent, own| {
        super::algorithm::learner_mut::<super::imitation::Cloner>(agent, "dagger")?.schedule = own.schedule();
        Ok(())
    },
    describe: |c| {
        let d = DaggerConfig::DEFAULT;
        if (c.beta0, c.t0) == (d.beta0, d.t0) {
            Vec::new()
        } else {
            vec![format!("β = {} + {}·exp(−epoch / {})", c.beta0, 1.0 - c.beta0, c.t0)]
        }
    },
};

/// DAgger's own settings: the schedule of the solver's share of the steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "DAgger's settings (--algo dagger)")]
pub struct DaggerConfig {
    /// DAgger: the share β0 of the steps the solver keeps acting on in the end; the share is
    /// β = β0 + (1 − β0)·exp(−epoch / t0), 1 in the first epoch.
    #[arg(id = "dagger_beta0", long = "dagger-beta0", value_name = "BETA0", default_value_t = Self::DEFAULT.beta0)]
    pub beta0: f64,
    /// DAgger: t0 of the solver's share, in epochs (0: β0 from the first epoch).
    #[arg(id = "dagger_t0", long = "dagger-t0", value_name = "EPOCHS", default_value_t = Self::DEFAULT.t0)]
    pub t0: f64,
}

impl DaggerConfig {
    /// The defaults: the solver acts on every step of the first epoch, on about a third of the
    /// fourth epoch's and on none in the end.
    pub const DEFAULT: Self = Self { beta0: 0.0, t0: 3.0 };

    /// The schedule these settings give.
    pub fn schedule(&self) -> Schedule {
        Schedule::Decay { beta0: self.beta0, t0: self.t0 }
    }

    /// Whether every setting is in range; the error names the flag.
    ///
    /// # Errors
    /// The first setting out of range.
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.beta0) {
            return Err(format!("--dagger-beta0 must be in [0, 1], not {}", self.beta0));
        }
        if !self.t0.is_finite() || self.t0 < 0.0 {
            return Err(format!("--dagger-t0 must be a number of epochs ≥ 0, not {}", self.t0));
        }
        Ok(())
    }
}

impl Default for DaggerConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
