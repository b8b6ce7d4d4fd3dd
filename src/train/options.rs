//! Which training settings each algorithm, network and mode uses: one table
//! ([`RULES`]), checked in one place ([`check`]) for `train`, `train --config`
//! recipes and `bench --ddpg`. A setting given away from its default that the
//! run would not use is refused, naming it and what uses it, rather than
//! ignored: `--target-noise` without `--td3`, `--noise-eps` with `--algo sac`,
//! `--set-pooling` without `--net set`.
//!
//! A setting is "given" when it differs from its default (a recipe's key and a
//! flag are the same setting), so a value equal to the default passes: it
//! changes nothing either way.

use super::learner::AggrevatedConfig;
use crate::agents::algorithm::Algo;
use crate::agents::arch::{NetConfig, NetKind};
use crate::agents::ddpg::DdpgConfig;
use crate::agents::pggd::PggdConfig;

/// The choices that decide which settings a run uses, and the settings.
#[derive(Debug, Clone, Copy)]
pub struct Options<'a> {
    /// `--algo`.
    pub algo: Algo,
    /// `--net` and the set network's settings.
    pub net: &'a NetConfig,
    /// The off-policy settings (DDPG's, shared with SAC and, for the network's shape, PGGD).
    pub ddpg: &'a DdpgConfig,
    /// PGGD's settings.
    pub pggd: &'a PggdConfig,
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
    ddpg: DdpgConfig,
    pggd: PggdConfig,
    net: NetConfig,
    aggrevated: AggrevatedConfig,
}

fn is(o: &Options, name: &str) -> bool {
    o.algo.name() == name
}
fn ddpg(o: &Options) -> bool {
    is(o, "ddpg")
}
fn off_policy(o: &Options) -> bool {
    is(o, "ddpg") || is(o, "sac")
}
fn td3(o: &Options) -> bool {
    ddpg(o) && o.ddpg.td3
}
fn set(o: &Options) -> bool {
    o.net.net == NetKind::Set
}
fn expert(o: &Options) -> bool {
    o.aggrevated.expert.is_some()
}

const DDPG: &str = "--algo ddpg";
const OFF_POLICY: &str = "--algo ddpg or --algo sac";
const TD3: &str = "--algo ddpg --td3";
const PGGD: &str = "--algo pggd";
const SET: &str = "--net set";

/// The table: each setting that only some runs use.
const RULES: &[Rule] = &[
    // DDPG's own: its deterministic actor's penalties and exploration noise.
    Rule { flag: "--action-l2", given: |o, d| o.ddpg.action_l2 != d.ddpg.action_l2, used: ddpg, by: DDPG },
    Rule { flag: "--preact-l2", given: |o, d| o.ddpg.preact_l2 != d.ddpg.preact_l2, used: ddpg, by: DDPG },
    Rule { flag: "--preact-margin", given: |o, d| o.ddpg.preact_margin != d.ddpg.preact_margin, used: ddpg, by: DDPG },
    Rule { flag: "--random-eps", given: |o, d| o.ddpg.random_eps != d.ddpg.random_eps, used: ddpg, by: DDPG },
    Rule { flag: "--noise-eps", given: |o, d| o.ddpg.noise_eps != d.ddpg.noise_eps, used: ddpg, by: DDPG },
    Rule {
        flag: "--noise-correlation",
        given: |o, d| o.ddpg.noise_correlation != d.ddpg.noise_correlation,
        used: ddpg,
        by: DDPG,
    },
    Rule { flag: "--td3", given: |o, _| o.ddpg.td3, used: ddpg, by: DDPG },
    Rule { flag: "--target-noise", given: |o, d| o.ddpg.target_noise != d.ddpg.target_noise, used: td3, by: TD3 },
    Rule {
        flag: "--target-noise-clip",
        given: |o, d| o.ddpg.target_noise_clip != d.ddpg.target_noise_clip,
        used: td3,
        by: TD3,
    },
    Rule { flag: "--policy-delay", given: |o, d| o.ddpg.policy_delay != d.ddpg.policy_delay, used: td3, by: TD3 },
    // The actor-critics' (PGGD has one network and no critic).
    Rule { flag: "--lr-actor", given: |o, d| o.ddpg.lr_actor != d.ddpg.lr_actor, used: off_policy, by: OFF_POLICY },
    Rule { flag: "--lr-critic", given: |o, d| o.ddpg.lr_critic != d.ddpg.lr_critic, used: off_policy, by: OFF_POLICY },
    Rule { flag: "--polyak", given: |o, d| o.ddpg.polyak != d.ddpg.polyak, used: off_policy, by: OFF_POLICY },
    Rule { flag: "--n-step", given: |o, d| o.ddpg.n_step != d.ddpg.n_step, used: off_policy, by: OFF_POLICY },
    Rule { flag: "--precision", given: |o, d| o.ddpg.precision != d.ddpg.precision, used: off_policy, by: OFF_POLICY },
    Rule {
        flag: "--flat-critic",
        given: |o, _| o.ddpg.flat_critic,
        used: |o| off_policy(o) && set(o),
        by: "--net set with --algo ddpg or --algo sac",
    },
    // PGGD's.
    Rule { flag: "--pg-lr", given: |o, d| o.pggd.lr != d.pggd.lr, used: |o| is(o, "pggd"), by: PGGD },
    Rule {
        flag: "--pg-sigma-min",
        given: |o, d| o.pggd.sigma_min != d.pggd.sigma_min,
        used: |o| is(o, "pggd"),
        by: PGGD,
    },
    Rule {
        flag: "--pg-normalize",
        given: |o, d| o.pggd.normalize != d.pggd.normalize,
        used: |o| is(o, "pggd"),
        by: PGGD,
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
        used: |o| expert(o) && o.algo.registration().takes_expert,
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
    // Hindsight colours'.
    Rule {
        flag: "--hindsight-strategy",
        given: |o, _| o.hindsight_strategy_given,
        used: |o| o.hindsight_colours > 0,
        by: "--hindsight-colours N (N ≥ 1)",
    },
];

/// Refuses settings the run would not use (see the module), all of them in one message.
///
/// # Errors
/// Each setting given and unused, with what uses it and the fix.
pub fn check(o: &Options) -> Result<(), String> {
    let d = Defaults {
        ddpg: DdpgConfig::default(),
        pggd: PggdConfig::default(),
        net: NetConfig::default(),
        aggrevated: AggrevatedConfig::default(),
    };
    let unused: Vec<String> = RULES
        .iter()
        .filter(|r| (r.given)(o, &d) && !(r.used)(o))
        .map(|r| format!("{} is only used with {}", r.flag, r.by))
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
    let mut s = format!("{}: --algo {}", o.algo.registration().title, o.algo.name());
    if o.ddpg.td3 {
        s += " --td3";
    }
    if set(o) {
        s += " --net set";
    }
    if expert(o) {
        s += " --expert";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(algo: &str, ddpg: DdpgConfig, net: NetConfig, aggrevated: AggrevatedConfig) -> Result<(), String> {
        let pggd = PggdConfig::default();
        check(&Options {
            algo: Algo::named(algo).unwrap(),
            net: &net,
            ddpg: &ddpg,
            pggd: &pggd,
            aggrevated: &aggrevated,
            hindsight_colours: 0,
            hindsight_strategy_given: false,
        })
    }

    #[test]
    fn every_default_run_passes_and_an_unused_setting_is_named() {
        for algo in ["ddpg", "sac", "pggd"] {
            with(algo, DdpgConfig::default(), NetConfig::default(), AggrevatedConfig::default()).unwrap();
        }
        let noisy = DdpgConfig { noise_eps: 0.1, ..DdpgConfig::default() };
        let e = with("sac", noisy.clone(), NetConfig::default(), AggrevatedConfig::default()).unwrap_err();
        assert!(e.contains("--noise-eps is only used with --algo ddpg") && e.contains("(SAC: --algo sac)"), "{e}");
        with("ddpg", noisy, NetConfig::default(), AggrevatedConfig::default()).unwrap();
        let smoothing = DdpgConfig { target_noise: 0.3, policy_delay: 3, ..DdpgConfig::default() };
        let e = with("ddpg", smoothing.clone(), NetConfig::default(), AggrevatedConfig::default()).unwrap_err();
        assert!(e.contains("--target-noise") && e.contains("--policy-delay") && e.contains("--td3"), "{e}");
        with("ddpg", DdpgConfig { td3: true, ..smoothing }, NetConfig::default(), AggrevatedConfig::default()).unwrap();
        let beta = AggrevatedConfig { beta0: 0.5, ..AggrevatedConfig::default() };
        let e = with("pggd", DdpgConfig::default(), NetConfig::default(), beta).unwrap_err();
        assert!(e.contains("--beta0 is only used with --expert"), "{e}");
        let pooling = NetConfig { set_pooling: crate::agents::arch::Pooling::Attention, ..NetConfig::default() };
        let e = with("ddpg", DdpgConfig::default(), pooling, AggrevatedConfig::default()).unwrap_err();
        assert!(e.contains("--set-pooling is only used with --net set"), "{e}");
    }
}
