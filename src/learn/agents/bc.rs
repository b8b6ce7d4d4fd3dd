//! Behaviour cloning of the solver (`--algo bc`): the imitation learner
//! ([`super::imitation`]) on episodes the solver plays itself, with
//! `--bc-noise` on its actions.

use super::algorithm::{Info, Registration};
use super::imitation::{Cloner, Schedule, READS};
use serde::{Deserialize, Serialize};

/// Behaviour cloning in the list of algorithms (`--algo bc`).
pub const REGISTRATION: Registration<BcConfig> = Registration {
    info: Info {
        trainer: crate::benchmark::saved::Trainer::Bc,
        title: "BC",
        about: "behaviour cloning of the solver, which plays every exploration episode (--net entity)",
        takes_expert: false,
        imitates: true,
        reads: READS,
        flag_prefix: "bc-",
        branchable: &[],
        starts_from_policy: true,
    },
    new: |spec, own, rng| Box::new(Cloner::new("bc", spec, Schedule::Solver, own.noise, rng)),
    validate: |c| {
        if c.noise.is_finite() && c.noise >= 0.0 {
            Ok(())
        } else {
            Err(format!("--bc-noise must be a standard deviation ≥ 0, not {}", c.noise))
        }
    },
    unused: |_| Vec::new(),
    // The actor with Adam's two moments.
    memory: |spec, _| spec.mlp_bytes(0, spec.act_dim, 3),
    take_branch: super::algorithm::no_branch,
    describe: |c| if c.noise > 0.0 { vec![format!("noise {} on the solver's actions", c.noise)] } else { Vec::new() },
};

/// Behaviour cloning's own settings.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "BC's settings (--algo bc)")]
pub struct BcConfig {
    /// BC: standard deviation of the Gaussian noise added to the solver's actions in the
    /// exploration episodes (its labels stay clean), so that they visit states off the solver's
    /// path and the learner sees how the solver recovers (DART, Laskey et al. 2017; 0: none).
    #[arg(id = "bc_noise", long = "bc-noise", value_name = "SIGMA", default_value_t = 0.0)]
    pub noise: f64,
}
