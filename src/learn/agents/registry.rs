//! The list of algorithms: one line per algorithm file names it, its module and
//! its settings type, and from it come [`Algo`] (an algorithm by name: what `--algo`
//! accepts, [`Algo::ALL`]) and [`AlgoConfigs`] (every algorithm's own settings, as flags and
//! as groups of a run's `config.json`).
//! The trainer, checkpoints, `bench --train` and the settings checks ask
//! these and name no algorithm.

use super::algorithm::{Algorithm, AlgorithmConfig, Info, Spec};
use super::shared::SharedConfig;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Lists the algorithms: `Variant: module: SettingsType`, the first the default. From the list come
/// [`AlgoConfigs`] and [`Algo`], whose methods call the algorithm's [`super::algorithm::Registration`]
/// with its own settings. Each method takes the one field it uses as a constant of its own: a read
/// of the registration's field would keep the whole registration, every function in it and with
/// them libtorch, in a binary that only names or describes an algorithm (`blockpuzzle`, whose
/// argument parser and `report` do: src/cli/halves.rs).
macro_rules! algorithms {
    ($($variant:ident: $module:ident: $config:ty),+ $(,)?) => {
        /// Every algorithm's own settings, one group each (flags; `config.json` keys by algorithm name).
        #[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, clap::Args)]
        pub struct AlgoConfigs {
            $(
                #[allow(missing_docs)]
                #[command(flatten)]
                #[serde(default)]
                pub $module: $config,
            )+
        }

        /// An algorithm by name (`--algo`, a run's `config.json`, a checkpoint).
        #[derive(Clone, Copy, PartialEq, Eq)]
        pub enum Algo {
            $(
                #[allow(missing_docs)]
                $variant,
            )+
        }

        impl Algo {
            /// Every algorithm `--algo` accepts, in the order of the list.
            pub const ALL: &'static [Algo] = &[$(Algo::$variant),+];

            /// Its names and settings facts.
            pub fn info(self) -> &'static Info {
                match self {
                    // The facts alone (the list's comment above).
                    $(Algo::$variant => {
                        const INFO: Info = super::$module::REGISTRATION.info;
                        &INFO
                    },)+
                }
            }

            /// A fresh learner of this algorithm; `rng` fixes the initial weights.
            pub fn build(self, spec: &Spec, algos: &AlgoConfigs, rng: &mut ChaCha8Rng) -> Box<dyn Algorithm> {
                match self {
                    $(Algo::$variant => {
                        const F: fn(&Spec, &$config, &mut ChaCha8Rng) -> Box<dyn Algorithm> = super::$module::REGISTRATION.new;
                        F(spec, &algos.$module, rng)
                    },)+
                }
            }

            /// Whether its own settings are in range.
            fn validate_own(self, algos: &AlgoConfigs) -> Result<(), String> {
                match self {
                    $(Algo::$variant => {
                        const F: fn(&$config) -> Result<(), String> = super::$module::REGISTRATION.validate;
                        F(&algos.$module)
                    },)+
                }
            }

            /// Its own settings these settings would ignore, as (flag, the flags that use it).
            fn unused_own(self, algos: &AlgoConfigs) -> Vec<(&'static str, &'static str)> {
                match self {
                    $(Algo::$variant => {
                        const F: fn(&$config) -> Vec<(&'static str, &'static str)> = super::$module::REGISTRATION.unused;
                        F(&algos.$module)
                    },)+
                }
            }

            /// The flags of its own settings given away from their defaults.
            fn given(self, algos: &AlgoConfigs) -> Vec<String> {
                match self {
                    $(Algo::$variant => given_flags(&algos.$module, self.info().flag_prefix),)+
                }
            }

            /// The bytes a learner of this algorithm takes ([`super::algorithm::Registration::memory`]).
            pub fn memory(self, spec: &Spec, algos: &AlgoConfigs) -> u64 {
                match self {
                    $(Algo::$variant => {
                        const F: fn(&Spec, &$config) -> u64 = super::$module::REGISTRATION.memory;
                        F(spec, &algos.$module)
                    },)+
                }
            }

            /// Its own settings away from the paper's, in words ([`super::algorithm::Registration::describe`]).
            pub fn describe(self, algos: &AlgoConfigs) -> Vec<String> {
                match self {
                    $(Algo::$variant => {
                        const F: fn(&$config) -> Vec<String> = super::$module::REGISTRATION.describe;
                        F(&algos.$module)
                    },)+
                }
            }

            /// Gives `agent` (a learner of this algorithm) the settings a branch may change.
            ///
            /// # Errors
            /// An agent of another algorithm than these settings'.
            pub(crate) fn take_branch_settings(self, agent: &mut dyn Algorithm, algos: &AlgoConfigs) -> Result<(), String> {
                match self {
                    $(Algo::$variant => {
                        const F: fn(&mut dyn Algorithm, &$config) -> Result<(), String> = super::$module::REGISTRATION.take_branch;
                        F(agent, &algos.$module)
                    },)+
                }
            }
        }
    };
}

algorithms! {
    Ddpg: ddpg: super::ddpg::DdpgConfig,
    Pggd: pggd: super::pggd::PggdConfig,
    Sac: sac: super::sac::SacConfig,
    Bc: bc: super::bc::BcConfig,
    Dagger: dagger: super::dagger::DaggerConfig,
}

/// The flags of `config`'s settings that differ from their defaults.
fn given_flags<C: AlgorithmConfig>(config: &C, prefix: &str) -> Vec<String> {
    let (a, b) = (serde_json::to_value(config), serde_json::to_value(C::default()));
    let (Ok(serde_json::Value::Object(a)), Ok(serde_json::Value::Object(b))) = (a, b) else { return Vec::new() };
    a.iter().filter(|(k, v)| b.get(*k) != Some(*v)).map(|(k, _)| flag(prefix, k)).collect()
}

/// The flag of field `field` with `prefix`, e.g. `--pg-sigma-min`.
pub fn flag(prefix: &str, field: &str) -> String {
    format!("--{prefix}{}", field.replace('_', "-"))
}

impl Algo {
    /// The registered algorithm called `name`.
    ///
    /// # Errors
    /// An unknown name, with the known ones.
    pub fn named(name: &str) -> Result<Self, String> {
        Self::ALL.iter().copied().find(|a| a.name() == name).ok_or_else(|| {
            let known: Vec<&str> = Self::ALL.iter().map(|a| a.name()).collect();
            format!("unknown algorithm {name:?}; known: {}", known.join(", "))
        })
    }

    /// Its name, e.g. "ddpg".
    pub fn name(self) -> &'static str {
        self.info().name()
    }

    /// How it is shown, e.g. "DDPG".
    pub fn title(self) -> &'static str {
        self.info().title
    }

    /// Whether the settings are in range: the shared ones and every
    /// algorithm's own (a setting out of range is an error whoever reads it).
    ///
    /// # Errors
    /// The first setting out of range, naming the flag.
    pub fn validate(shared: &SharedConfig, algos: &AlgoConfigs) -> Result<(), String> {
        shared.validate()?;
        Self::ALL.iter().try_for_each(|a| a.validate_own(algos))
    }

    /// Whether it takes `--expert` when one is given.
    ///
    /// # Errors
    /// An expert for an algorithm that trains without one, naming those that take one.
    pub fn check_expert(self, expert: bool) -> Result<(), String> {
        if expert && !self.info().takes_expert {
            let takers: Vec<&str> = Self::ALL.iter().filter(|a| a.info().takes_expert).map(|a| a.name()).collect();
            let own = if self.info().imitates {
                "imitates the built-in solver, its expert; drop --expert".to_owned()
            } else {
                "trains without an expert".to_owned()
            };
            return Err(format!(
                "--expert is for AggreVaTeD (--algo {}); {} {own}",
                takers.join(" or --algo "),
                self.info().title
            ));
        }
        Ok(())
    }

    /// Settings given (away from their defaults) that a run of this algorithm
    /// would ignore, as (flag, the flags that use it): shared settings it does
    /// not read, other algorithms' settings, and its own that its other
    /// settings leave unused.
    pub fn unused(self, shared: &SharedConfig, algos: &AlgoConfigs) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for flag in given_flags(shared, "") {
            if !self.info().reads.contains(&flag.as_str()) {
                let readers: Vec<String> = Self::ALL
                    .iter()
                    .filter(|a| a.info().reads.contains(&flag.as_str()))
                    .map(|a| format!("--algo {a}"))
                    .collect();
                out.push((flag, readers.join(" or ")));
            }
        }
        for &a in Self::ALL {
            if a == self {
                out.extend(a.unused_own(algos).into_iter().map(|(f, by)| (f.to_owned(), by.to_owned())));
            } else {
                out.extend(a.given(algos).into_iter().map(|f| (f, format!("--algo {a}"))));
            }
        }
        out
    }

    /// clap's parser for `--algo`: the registered names, each with its summary.
    pub fn parser() -> impl clap::builder::TypedValueParser<Value = Self> {
        use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
        PossibleValuesParser::new(Self::ALL.iter().map(|a| PossibleValue::new(a.name()).help(a.info().about)))
            .map(|name| Self::named(&name).unwrap_or_default())
    }
}

/// The flags of every algorithm's settings a branch may change.
pub fn branchable_flags() -> Vec<String> {
    Algo::ALL.iter().flat_map(|a| a.info().branchable.iter().map(|f| flag(a.info().flag_prefix, f))).collect()
}

/// The groups of a run's `config.json` that hold one algorithm's settings,
/// with their flags' prefix: (group, prefix).
pub fn groups() -> impl Iterator<Item = (&'static str, &'static str)> {
    Algo::ALL.iter().map(|a| (a.name(), a.info().flag_prefix))
}

/// The first of the list (DDPG, the paper's).
impl Default for Algo {
    fn default() -> Self {
        Self::ALL[0]
    }
}

impl std::fmt::Debug for Algo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.title())
    }
}

impl std::fmt::Display for Algo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl serde::Serialize for Algo {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Algo {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Self::named(&name).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_lowercase_and_round_trip() {
        for (i, &a) in Algo::ALL.iter().enumerate() {
            assert_eq!(a.name(), a.name().to_lowercase());
            assert!(Algo::ALL[..i].iter().all(|o| o.name() != a.name()), "{a} twice");
            assert_eq!(Algo::named(a.name()).unwrap(), a);
            assert_eq!(serde_json::to_string(&a).unwrap(), format!("\"{a}\""));
            assert_eq!(serde_json::from_str::<Algo>(&format!("\"{a}\"")).unwrap(), a);
        }
        let e = Algo::named("ppo").unwrap_err();
        assert!(e.contains("unknown algorithm \"ppo\"") && e.contains("ddpg, pggd"), "{e}");
        assert_eq!((Algo::Ddpg.name(), Algo::Pggd.name()), ("ddpg", "pggd"));
        // An algorithm's name is the trainer policy files record for it; every trainer a file may
        // record is some algorithm's, but `td3` (DDPG with --td3).
        for t in crate::benchmark::saved::Trainer::ALL {
            let by = Algo::ALL.iter().filter(|a| a.info().trainer == t).count();
            assert_eq!(by, usize::from(t != crate::benchmark::saved::Trainer::Td3), "{t}: {by} algorithms record it");
        }
    }

    /// A branch's settings reach the learner loaded from the parent's checkpoint: the fields each
    /// registration lists as branchable, no other; a learner of another algorithm is an error, not
    /// nothing (issue 61).
    #[test]
    fn a_branch_takes_the_listed_settings_and_only_its_own_algorithms() {
        use rand::SeedableRng;
        let shared = SharedConfig::default();
        let spec = Spec { arch: super::super::arch::Arch::mlp(40), act_dim: 4, shared: &shared };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
        let parent = AlgoConfigs::default();
        let mut branch = AlgoConfigs::default();
        branch.ddpg.noise_eps = 0.05;
        branch.ddpg.td3 = true; // not branchable: not taken
        branch.dagger.beta0 = 0.5;
        branch.dagger.t0 = 0.0;
        let mut ddpg = Algo::Ddpg.build(&spec, &parent, &mut rng);
        Algo::Ddpg.take_branch_settings(&mut *ddpg, &branch).unwrap();
        let c = &ddpg.as_any().downcast_ref::<super::super::ddpg::Ddpg>().unwrap().config;
        assert_eq!((c.noise_eps, c.td3), (0.05, false));
        let dagger_algo = Algo::named("dagger").unwrap();
        let mut dagger = dagger_algo.build(&spec, &parent, &mut rng);
        assert_ne!(dagger.solver_share(0), Some(0.5));
        dagger_algo.take_branch_settings(&mut *dagger, &branch).unwrap();
        assert_eq!(dagger.solver_share(7), Some(0.5));
        let e = Algo::Ddpg.take_branch_settings(&mut *dagger, &branch).unwrap_err();
        assert!(e.contains("another algorithm"), "{e}");
    }

    #[test]
    fn every_shared_flag_an_algorithm_reads_exists_and_each_is_read() {
        let shared = serde_json::to_value(SharedConfig::ALL_WRITTEN).unwrap();
        let flags: Vec<String> = shared.as_object().unwrap().keys().map(|k| flag("", k)).collect();
        for &a in Algo::ALL {
            for f in a.info().reads {
                assert!(flags.iter().any(|g| g == f), "{a} reads {f}, which is no shared setting");
            }
        }
        for f in &flags {
            assert!(Algo::ALL.iter().any(|a| a.info().reads.contains(&f.as_str())), "no algorithm reads {f}");
        }
    }

    #[test]
    fn memory_counts_every_copy_of_every_network() {
        let shared = SharedConfig::default();
        let spec = Spec { arch: super::super::arch::Arch::mlp(40), act_dim: 4, shared: &shared };
        let plain = AlgoConfigs::default();
        let mut td3 = AlgoConfigs::default();
        td3.ddpg.td3 = true;
        let (ddpg, td3) = (Algo::Ddpg.memory(&spec, &plain), Algo::Ddpg.memory(&spec, &td3));
        let (sac, pggd) = (Algo::named("sac").unwrap().memory(&spec, &plain), Algo::Pggd.memory(&spec, &plain));
        // PGGD: one network; DDPG: actor and critic with targets; TD3 and SAC: a second critic.
        assert!(pggd < ddpg && ddpg < td3 && ddpg < sac, "{pggd} {ddpg} {td3} {sac}");
    }

    #[test]
    fn the_settings_groups_parse_from_their_flags_with_their_defaults() {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            algos: AlgoConfigs,
        }
        use clap::Parser;
        assert_eq!(Cli::parse_from(["x"]).algos, AlgoConfigs::default());
        assert_eq!(serde_json::from_str::<AlgoConfigs>("{}").unwrap(), AlgoConfigs::default());
        let cli = Cli::parse_from(["x", "--pg-lr", "0.5", "--td3"]);
        assert_eq!(given_flags(&cli.algos.pggd, "pg-"), ["--pg-lr"]);
        let unused = Algo::Ddpg.unused(&SharedConfig::default(), &cli.algos);
        assert_eq!(unused, [("--pg-lr".to_owned(), "--algo pggd".to_owned())]);
    }
}
