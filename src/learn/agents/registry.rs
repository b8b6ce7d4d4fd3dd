//! The list of algorithms: one line per algorithm file names the module and
//! its settings type, and from it come [`ALGORITHMS`] (what `--algo`
//! accepts), [`AlgoConfigs`] (every algorithm's own settings, as flags and
//! as groups of a run's `config.json`) and [`Algo`] (an algorithm by name).
//! The trainer, checkpoints, `bench --train` and the settings checks ask
//! these and name no algorithm.

use super::algorithm::{Algorithm, AlgorithmConfig, Info, Spec};
use super::shared::SharedConfig;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// An algorithm's [`super::algorithm::Registration`] with its settings type
/// erased: each function takes every algorithm's settings and uses its own.
pub struct Entry {
    /// Its names and settings facts.
    pub info: Info,
    new: fn(&Spec, &AlgoConfigs, &mut ChaCha8Rng) -> Box<dyn Algorithm>,
    validate: fn(&AlgoConfigs) -> Result<(), String>,
    unused: fn(&AlgoConfigs) -> Vec<(&'static str, &'static str)>,
    given: fn(&AlgoConfigs) -> Vec<String>,
    memory: fn(&Spec, &AlgoConfigs) -> u64,
    describe: fn(&AlgoConfigs) -> Vec<String>,
    take_branch: fn(&mut dyn Algorithm, &AlgoConfigs) -> Result<(), String>,
}

/// Lists the algorithms: `module: SettingsType`, the first the default.
macro_rules! algorithms {
    ($($module:ident: $config:ty),+ $(,)?) => {
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

        /// Each algorithm's place in [`ALGORITHMS`], by its module's name (so that a named
        /// constant such as [`Algo::PGGD`] follows the list, whatever its order).
        #[allow(non_camel_case_types, dead_code)]
        enum Slot {
            $($module),+
        }

        /// Every algorithm `--algo` accepts, in the order of the list.
        pub const ALGORITHMS: &[Entry] = &[$(Entry {
            info: super::$module::REGISTRATION.info,
            new: |spec, c, rng| (super::$module::REGISTRATION.new)(spec, &c.$module, rng),
            validate: |c| (super::$module::REGISTRATION.validate)(&c.$module),
            unused: |c| (super::$module::REGISTRATION.unused)(&c.$module),
            given: |c| given_flags(&c.$module, super::$module::REGISTRATION.info.flag_prefix),
            memory: |spec, c| (super::$module::REGISTRATION.memory)(spec, &c.$module),
            describe: |c| (super::$module::REGISTRATION.describe)(&c.$module),
            take_branch: |agent, c| (super::$module::REGISTRATION.take_branch)(agent, &c.$module),
        }),+];
    };
}

algorithms! {
    ddpg: super::ddpg::DdpgConfig,
    pggd: super::pggd::PggdConfig,
    sac: super::sac::SacConfig,
    bc: super::bc::BcConfig,
    dagger: super::dagger::DaggerConfig,
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

/// An algorithm by name (`--algo`, a run's `config.json`, a checkpoint):
/// one of [`ALGORITHMS`].
#[derive(Clone, Copy)]
pub struct Algo(&'static Entry);

impl Algo {
    /// DDPG (the default; the paper's).
    pub const DDPG: Self = Self(&ALGORITHMS[Slot::ddpg as usize]);
    /// PGGD (the paper's; with `--expert`, AggreVaTeD).
    pub const PGGD: Self = Self(&ALGORITHMS[Slot::pggd as usize]);

    /// The registered algorithm called `name`.
    ///
    /// # Errors
    /// An unknown name, with the known ones.
    pub fn named(name: &str) -> Result<Self, String> {
        ALGORITHMS.iter().find(|r| r.info.name == name).map(Self).ok_or_else(|| {
            let known: Vec<&str> = ALGORITHMS.iter().map(|r| r.info.name).collect();
            format!("unknown algorithm {name:?}; known: {}", known.join(", "))
        })
    }

    /// Its registration.
    pub fn registration(self) -> &'static Entry {
        self.0
    }

    /// Its name, e.g. "ddpg".
    pub fn name(self) -> &'static str {
        self.0.info.name
    }

    /// How it is shown, e.g. "DDPG".
    pub fn title(self) -> &'static str {
        self.0.info.title
    }

    /// Whether the settings are in range: the shared ones and every
    /// algorithm's own (a setting out of range is an error whoever reads it).
    ///
    /// # Errors
    /// The first setting out of range, naming the flag.
    pub fn validate(shared: &SharedConfig, algos: &AlgoConfigs) -> Result<(), String> {
        shared.validate()?;
        ALGORITHMS.iter().try_for_each(|r| (r.validate)(algos))
    }

    /// Whether it takes `--expert` when one is given.
    ///
    /// # Errors
    /// An expert for an algorithm that trains without one, naming those that take one.
    pub fn check_expert(self, expert: bool) -> Result<(), String> {
        if expert && !self.0.info.takes_expert {
            let takers: Vec<&str> = ALGORITHMS.iter().filter(|r| r.info.takes_expert).map(|r| r.info.name).collect();
            let own = if self.0.info.imitates {
                "imitates the built-in solver, its expert; drop --expert".to_owned()
            } else {
                "trains without an expert".to_owned()
            };
            return Err(format!(
                "--expert is for AggreVaTeD (--algo {}); {} {own}",
                takers.join(" or --algo "),
                self.0.info.title
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
            if !self.0.info.reads.contains(&flag.as_str()) {
                let readers: Vec<String> = ALGORITHMS
                    .iter()
                    .filter(|r| r.info.reads.contains(&flag.as_str()))
                    .map(|r| format!("--algo {}", r.info.name))
                    .collect();
                out.push((flag, readers.join(" or ")));
            }
        }
        for r in ALGORITHMS {
            if r.info.name == self.0.info.name {
                out.extend((r.unused)(algos).into_iter().map(|(f, by)| (f.to_owned(), by.to_owned())));
            } else {
                out.extend((r.given)(algos).into_iter().map(|f| (f, format!("--algo {}", r.info.name))));
            }
        }
        out
    }

    /// A fresh learner of this algorithm.
    pub fn build(self, spec: &Spec, algos: &AlgoConfigs, rng: &mut ChaCha8Rng) -> Box<dyn Algorithm> {
        (self.0.new)(spec, algos, rng)
    }

    /// The bytes a learner of this algorithm takes ([`super::algorithm::Registration::memory`]).
    pub fn memory(self, spec: &Spec, algos: &AlgoConfigs) -> u64 {
        (self.0.memory)(spec, algos)
    }

    /// Its own settings away from the paper's, in words ([`super::algorithm::Registration::describe`]).
    pub fn describe(self, algos: &AlgoConfigs) -> Vec<String> {
        (self.0.describe)(algos)
    }

    /// Gives `agent` (a learner of this algorithm) the settings a branch may change.
    ///
    /// # Errors
    /// An agent of another algorithm than these settings'.
    pub(crate) fn take_branch_settings(self, agent: &mut dyn Algorithm, algos: &AlgoConfigs) -> Result<(), String> {
        (self.0.take_branch)(agent, algos)
    }

    /// clap's parser for `--algo`: the registered names, each with its summary.
    pub fn parser() -> impl clap::builder::TypedValueParser<Value = Self> {
        use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
        PossibleValuesParser::new(ALGORITHMS.iter().map(|r| PossibleValue::new(r.info.name).help(r.info.about)))
            .map(|name| Self::named(&name).unwrap_or_default())
    }
}

/// The flags of every algorithm's settings a branch may change.
pub fn branchable_flags() -> Vec<String> {
    ALGORITHMS.iter().flat_map(|r| r.info.branchable.iter().map(|f| flag(r.info.flag_prefix, f))).collect()
}

/// The groups of a run's `config.json` that hold one algorithm's settings,
/// with their flags' prefix: (group, prefix).
pub fn groups() -> impl Iterator<Item = (&'static str, &'static str)> {
    ALGORITHMS.iter().map(|r| (r.info.name, r.info.flag_prefix))
}

impl Default for Algo {
    fn default() -> Self {
        Self(&ALGORITHMS[0])
    }
}

/// Two algorithms are the same when their names are (a registration's
/// address is not unique: `const` items may be copied).
impl PartialEq for Algo {
    fn eq(&self, other: &Self) -> bool {
        self.0.info.name == other.0.info.name
    }
}

impl Eq for Algo {}

impl std::fmt::Debug for Algo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.info.title)
    }
}

impl std::fmt::Display for Algo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.info.name)
    }
}

impl serde::Serialize for Algo {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0.info.name)
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
        for (i, r) in ALGORITHMS.iter().enumerate() {
            assert_eq!(r.info.name, r.info.name.to_lowercase());
            assert!(ALGORITHMS[..i].iter().all(|o| o.info.name != r.info.name), "{} twice", r.info.name);
            let a = Algo::named(r.info.name).unwrap();
            assert_eq!(serde_json::to_string(&a).unwrap(), format!("\"{}\"", r.info.name));
            assert_eq!(serde_json::from_str::<Algo>(&format!("\"{}\"", r.info.name)).unwrap(), a);
        }
        let e = Algo::named("ppo").unwrap_err();
        assert!(e.contains("unknown algorithm \"ppo\"") && e.contains("ddpg, pggd"), "{e}");
        assert_eq!((Algo::DDPG.name(), Algo::PGGD.name()), ("ddpg", "pggd"));
        // What policy files and zoo entries record as the training algorithm (`td3`: DDPG with --td3).
        for r in ALGORITHMS {
            assert_eq!(r.info.trainer.name(), r.info.name, "{} records itself as another trainer", r.info.name);
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
        let mut ddpg = Algo::DDPG.build(&spec, &parent, &mut rng);
        Algo::DDPG.take_branch_settings(&mut *ddpg, &branch).unwrap();
        let c = &ddpg.as_any().downcast_ref::<super::super::ddpg::Ddpg>().unwrap().config;
        assert_eq!((c.noise_eps, c.td3), (0.05, false));
        let dagger_algo = Algo::named("dagger").unwrap();
        let mut dagger = dagger_algo.build(&spec, &parent, &mut rng);
        assert_ne!(dagger.solver_share(0), Some(0.5));
        dagger_algo.take_branch_settings(&mut *dagger, &branch).unwrap();
        assert_eq!(dagger.solver_share(7), Some(0.5));
        let e = Algo::DDPG.take_branch_settings(&mut *dagger, &branch).unwrap_err();
        assert!(e.contains("another algorithm"), "{e}");
    }

    #[test]
    fn every_shared_flag_an_algorithm_reads_exists_and_each_is_read() {
        let shared = serde_json::to_value(SharedConfig::ALL_WRITTEN).unwrap();
        let flags: Vec<String> = shared.as_object().unwrap().keys().map(|k| flag("", k)).collect();
        for r in ALGORITHMS {
            for f in r.info.reads {
                assert!(flags.iter().any(|g| g == f), "{} reads {f}, which is no shared setting", r.info.name);
            }
        }
        for f in &flags {
            assert!(ALGORITHMS.iter().any(|r| r.info.reads.contains(&f.as_str())), "no algorithm reads {f}");
        }
    }

    #[test]
    fn memory_counts_every_copy_of_every_network() {
        let shared = SharedConfig::default();
        let spec = Spec { arch: super::super::arch::Arch::mlp(40), act_dim: 4, shared: &shared };
        let plain = AlgoConfigs::default();
        let mut td3 = AlgoConfigs::default();
        td3.ddpg.td3 = true;
        let (ddpg, td3) = (Algo::DDPG.memory(&spec, &plain), Algo::DDPG.memory(&spec, &td3));
        let (sac, pggd) = (Algo::named("sac").unwrap().memory(&spec, &plain), Algo::PGGD.memory(&spec, &plain));
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
        let unused = Algo::DDPG.unused(&SharedConfig::default(), &cli.algos);
        assert_eq!(unused, [("--pg-lr".to_owned(), "--algo pggd".to_owned())]);
    }
}
