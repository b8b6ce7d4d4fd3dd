//! Which training settings each algorithm, network and mode uses, checked in
//! one place ([`check`]) for `train`, `train --config` recipes and `bench
//! --train`: the registry says which shared and own settings an algorithm
//! uses ([`Algo::unused`]), a table ([`RULES`]) the networks', AggreVaTeD's
//! and hindsight's. A setting given away from its default that the
//! run would not use is refused, naming it and what uses it, rather than
//! ignored: `--target-noise` without `--td3`, `--noise-eps` with `--algo sac`,
//! `--set-pooling` without `--net set`. It also refuses what an imitation
//! learner cannot learn from (another network than `--net entity`, hindsight colours).
//!
//! A setting is "given" when it differs from its default (a recipe's key and a
//! flag are the same setting), so a value equal to the default passes: it
//! changes nothing either way.

use super::learner::AggrevatedConfig;
use crate::learn::agents::arch::{NetConfig, NetKind};
use crate::learn::agents::registry::{Algo, AlgoConfigs};
use crate::learn::agents::shared::SharedConfig;

/// The choices that decide which settings a run uses, and the settings.
#[derive(Debug, Clone, Copy)]
pub struct Options<'a> {
    /// `--algo`.
    pub algo: Algo,
    /// `--net` and the set network's settings.
    pub net: &'a NetConfig,
    /// The settings the algorithms share.
    pub shared: &'a SharedConfig,
    /// Each algorithm's own settings.
    pub algos: &'a AlgoConfigs,
    /// AggreVaTeD's settings (`--expert` and the rest).
    pub aggrevated: &'a AggrevatedConfig,
    /// `--hindsight-colours`.
    pub hindsight_colours: usize,
    /// Whether `--hindsight-strategy` differs from its default.
    pub hindsight_strategy_given: bool,
}

/// One setting and who uses it.
struct Rule {
    /// The flag (a recipe's key is the flag without its dashes).
    flag: &'static str,
    /// Whether the run gives it (a value other than the default).
    given: fn(&Options, &Defaults) -> bool,
    /// Whether the run uses it.
    used: fn(&Options) -> bool,
    /// Who uses it, as the flags that ask for it.
    by: &'static str,
}

/// Every setting's default, written once where the setting is defined.
struct Defaults {
    net: NetConfig,
    aggrevated: AggrevatedConfig,
}

fn set(o: &Options) -> bool {
    o.net.net.is_set()
}
fn expert(o: &Options) -> bool {
    o.aggrevated.expert.is_some()
}
fn actor_critic(o: &Options) -> bool {
    o.algo.info().reads.contains(&"--flat-critic")
}

const SET: &str = "--net set";

/// The table: each setting outside the algorithms' own that only some runs
/// use (which algorithm uses which of its and the shared settings, the
/// registry says: [`Algo::unused`]).
const RULES: &[Rule] = &[
    // The critics of a set network's run (an algorithm that has critics reads --flat-critic).
    Rule {
        flag: "--flat-critic",
        given: |o, _| o.shared.flat_critic,
        used: |o| set(o) || !actor_critic(o),
        by: "--net set with an algorithm that has critics",
    },
    // AggreVaTeD's (whether the algorithm takes `--expert` at all is its registration's to say).
    Rule {
        flag: "--beta0",
        given: |o, d| o.aggrevated.beta0 != d.aggrevated.beta0,
        used: expert,
        by: "--expert POLICY (AggreVaTeD)",
    },
    Rule {
        flag: "--t0",
        given: |o, d| o.aggrevated.t0 != d.aggrevated.t0,
        used: expert,
        by: "--expert POLICY (AggreVaTeD)",
    },
    Rule {
        flag: "--pg-weight",
        given: |o, d| o.aggrevated.pg_weight != d.aggrevated.pg_weight,
        used: |o| expert(o) && o.algo.info().takes_expert,
        by: "--algo pggd --expert POLICY (AggreVaTeD)",
    },
    // The set network's.
    Rule {
        flag: "--set-encoder-layers",
        given: |o, d| o.net.set_encoder_layers != d.net.set_encoder_layers,
        used: set,
        by: SET,
    },
    Rule { flag: "--set-pooling", given: |o, d| o.net.set_pooling != d.net.set_pooling, used: set, by: SET },
    Rule { flag: "--set-norm", given: |o, _| o.net.set_norm, used: set, by: SET },
    Rule { flag: "--set-robot-tokens", given: |o, _| o.net.set_robot_tokens, used: set, by: SET },
    Rule { flag: "--set-transformer", given: |o, _| o.net.set_transformer > 0, used: set, by: SET },
    Rule { flag: "--set-width", given: |o, _| o.net.set_width > 0, used: set, by: SET },
    Rule {
        flag: "--set-type-norm",
        given: |o, _| o.net.set_type_norm,
        used: |o| o.net.net == NetKind::Entity,
        by: "--net entity (the rows of the gripper, table and floor)",
    },
    // Hindsight colours'.
    Rule {
        flag: "--hindsight-strategy",
        given: |o, _| o.hindsight_strategy_given,
        used: |o| o.hindsight_colours > 0,
        by: "--hindsight-colours N (N ≥ 1)",
    },
];

/// Refuses what an imitation learner (`--algo bc|dagger`) cannot learn from: a network over
/// another observation than the solver's, and hindsight colours.
fn check_imitation(o: &Options) -> Result<(), String> {
    let info = o.algo.info();
    if info.imitates && o.net.net != NetKind::Entity {
        return Err(format!(
            "--algo {} imitates the solver, which reads the entities observation (the gripper's, table's and \
             floor's rows too): train with --net entity",
            info.name()
        ));
    }
    if info.imitates && o.hindsight_colours > 0 {
        return Err(format!(
            "--hindsight-colours: the solver's labels are its actions under the colours it saw, not under others; \
             --algo {} takes none",
            info.name()
        ));
    }
    Ok(())
}

/// Refuses settings the run would not use (see the module), all of them in one message.
///
/// # Errors
/// Each setting given and unused, with what uses it and the fix.
pub fn check(o: &Options) -> Result<(), String> {
    check_imitation(o)?;
    let d = Defaults { net: NetConfig::default(), aggrevated: AggrevatedConfig::default() };
    let unused: Vec<String> = o
        .algo
        .unused(o.shared, o.algos)
        .into_iter()
        .chain(RULES.iter().filter(|r| (r.given)(o, &d) && !(r.used)(o)).map(|r| (r.flag.to_owned(), r.by.to_owned())))
        .map(|(flag, by)| format!("{flag} is only used with {by}"))
        .collect();
    match unused.as_slice() {
        [] => Ok(()),
        [one] => Err(format!(
            "{one}, and this run ({}) would ignore it: drop it (a recipe's key is the flag without its dashes)",
            describe(o)
        )),
        many => Err(format!(
            "settings this run ({}) would ignore: {}; drop them (a recipe's key is the flag without its dashes)",
            describe(o),
            many.join("; ")
        )),
    }
}

/// The run's choices as flags, e.g. "SAC: --algo sac --net set".
fn describe(o: &Options) -> String {
    let mut s = format!("{}: --algo {}", o.algo.title(), o.algo.name());
    if set(o) {
        s += &format!(" --net {}", o.net.net.name());
    }
    if expert(o) {
        s += " --expert";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learn::agents::ddpg::DdpgConfig;

    fn with(
        algo: &str,
        shared: SharedConfig,
        ddpg: DdpgConfig,
        net: NetConfig,
        aggrevated: AggrevatedConfig,
    ) -> Result<(), String> {
        let algos = AlgoConfigs { ddpg, ..AlgoConfigs::default() };
        check(&Options {
            algo: Algo::named(algo).unwrap(),
            net: &net,
            shared: &shared,
            algos: &algos,
            aggrevated: &aggrevated,
            hindsight_colours: 0,
            hindsight_strategy_given: false,
        })
    }

    #[test]
    fn every_default_run_passes_and_an_unused_setting_is_named() {
        let (s, d, n, a) =
            (SharedConfig::default(), DdpgConfig::default(), NetConfig::default(), AggrevatedConfig::default());
        for algo in ["ddpg", "sac", "pggd"] {
            with(algo, s.clone(), d.clone(), n, a.clone()).unwrap();
        }
        let noisy = DdpgConfig { noise_eps: 0.1, ..d.clone() };
        let e = with("sac", s.clone(), noisy.clone(), n, a.clone()).unwrap_err();
        assert!(e.contains("--noise-eps is only used with --algo ddpg") && e.contains("(SAC: --algo sac)"), "{e}");
        with("ddpg", s.clone(), noisy, n, a.clone()).unwrap();
        let smoothing = DdpgConfig { target_noise: 0.3, policy_delay: 3, ..d.clone() };
        let e = with("ddpg", s.clone(), smoothing.clone(), n, a.clone()).unwrap_err();
        assert!(e.contains("--target-noise") && e.contains("--policy-delay") && e.contains("--td3"), "{e}");
        with("ddpg", s.clone(), DdpgConfig { td3: true, ..smoothing }, n, a.clone()).unwrap();
        let beta = AggrevatedConfig { beta0: 0.5, ..a.clone() };
        let e = with("pggd", s.clone(), d.clone(), n, beta).unwrap_err();
        assert!(e.contains("--beta0 is only used with --expert"), "{e}");
        let pooling = NetConfig { set_pooling: crate::learn::agents::arch::Pooling::Attention, ..n };
        let e = with("ddpg", s.clone(), d.clone(), pooling, a.clone()).unwrap_err();
        assert!(e.contains("--set-pooling is only used with --net set"), "{e}");
        let n_step = SharedConfig { n_step: 3, ..s.clone() };
        let e = with("pggd", n_step, d.clone(), n, a.clone()).unwrap_err();
        assert!(e.contains("--n-step is only used with --algo ddpg or --algo sac"), "{e}");
        let flat = SharedConfig { flat_critic: true, ..s };
        let e = with("sac", flat, d, n, a).unwrap_err();
        assert!(e.contains("--flat-critic is only used with --net set"), "{e}");
    }
}
