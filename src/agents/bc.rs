//! Behaviour cloning of the solver (`--algo bc`): the imitation learner
//! ([`super::imitation`]) on episodes the solver plays itself.

use super::algorithm::{Info, Registration};
use super::imitation::{Cloner, Schedule, READS};
use serde::{Deserialize, Serialize};

/// Behaviour cloning in the list of algorithms (`--algo bc`).
pub const REGISTRATION: Registration<BcConfig> = Registration {
    info: Info {
        name: "bc",
        title: "BC",
        about: "behaviour cloning of the solver, which plays every exploration episode (--net entity)",
        takes_expert: false,
        imitates: true,
        reads: READS,
        flag_prefix: "bc-",
        branchable: &[],
    },
    new: |spec, _, rng| Box::new(Cloner::new("bc", spec, Schedule::Solver, rng)),
    validate: |_| Ok(()),
    unused: |_| Vec::new(),
    // The actor with Adam's two moments.
    memory: |spec, _| spec.mlp_bytes(0, spec.act_dim, 3),
    describe: |_| Vec::new(),
};

/// Behaviour cloning's own settings: none beyond the shared ones it reads.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct BcConfig {}
