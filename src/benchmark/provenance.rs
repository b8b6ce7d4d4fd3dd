//! What made a result. Every result the project writes (an evaluation, a
//! suite result, the paper's table, a zoo entry's recorded evaluations, a
//! leaderboard) carries one [`Provenance`]: the package and commit, the
//! MuJoCo that ran the episodes, the harness, the policy by content, and for
//! a suite its name and hash; each suite row carries its task's content hash.
//! Two results go in one column only when [`Provenance::comparable`] says so.
//!
//! Thread and environment counts are not part of it: episode k of a row plays
//! seed + k, so they do not change a result.

use crate::benchmark::suite::SuiteId;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// What played the episodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Harness {
    /// The `blockpuzzle` command line (Rust).
    Cli,
    /// The Python package (`blockpuzzle.evaluate`).
    Python,
}

impl Harness {
    /// As results spell it: `cli`, `python`.
    pub fn name(self) -> &'static str {
        match self {
            Harness::Cli => "cli",
            Harness::Python => "python",
        }
    }
}

/// A policy as results name it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PolicyId {
    /// As it was given: a zoo name, a file or run directory, or `baseline:NAME`.
    pub name: String,
    /// `sha256:` of what acts (the network's weights and layout, the
    /// normaliser's statistics, the algorithm's output settings) and the task
    /// it was trained on: the same for a policy file and its zoo entry. None
    /// for a baseline, whose behaviour is the code's (package and commit).
    pub sha256: Option<String>,
}

/// The code and engine that ran: package, commit, MuJoCo.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Build {
    /// The blockpuzzle package version.
    pub blockpuzzle: String,
    /// The git commit of the checkout it was built from, `-dirty` when a
    /// source file differed from it (None: not built from a checkout).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub commit: Option<String>,
    /// The MuJoCo that ran the episodes (the loaded library's version).
    pub mujoco: String,
    /// The solver's version ([`crate::policy::SOLVER_VERSION`]) in this build: what
    /// `baseline:scripted`, the generator's check and recorded demonstrations ran. None in what
    /// was written before it was recorded (the version-1 solver, which kept a plan).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<u32>,
}

/// The MuJoCo versions a build of this project runs: Debian's (the default) and the `mujoco3`
/// feature's (the Python wheel's). A record naming another engine was not made by this project.
pub const ENGINES: [&str; 2] = ["2.2.2", "3.11.0"];

impl Build {
    /// This build, with the engine it has loaded.
    pub fn current() -> Self {
        Self {
            blockpuzzle: version().to_owned(),
            commit: commit(),
            mujoco: crate::sim::mj::version(),
            solver: Some(crate::policy::SOLVER_VERSION),
        }
    }

    /// The solver version that made it (1 where none is recorded).
    pub fn solver_version(&self) -> u32 {
        self.solver.unwrap_or(1)
    }

    /// "MuJoCo M by blockpuzzle V (commit `C`)".
    pub fn describe(&self) -> String {
        format!("MuJoCo {} by {}", self.mujoco, self.maker())
    }

    /// The package and commit alone, e.g. "blockpuzzle 0.9.0 (commit `abc`)", for a page whose
    /// heading already names the engine.
    pub fn maker(&self) -> String {
        let commit = self.commit.as_deref().map_or_else(String::new, |c| format!(" (commit `{c}`)"));
        format!("blockpuzzle {}{commit}", self.blockpuzzle)
    }
}

/// What made a result (see the module).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// Package, commit and engine.
    #[serde(flatten)]
    pub build: Build,
    /// What played the episodes.
    pub harness: Harness,
    /// The policy evaluated.
    pub policy: PolicyId,
    /// The suite (suite results only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub suite: Option<SuiteId>,
}

impl Provenance {
    /// This build, running now, evaluating `policy` (on `suite`).
    pub fn new(harness: Harness, policy: PolicyId, suite: Option<SuiteId>) -> Self {
        Self { build: Build::current(), harness, policy, suite }
    }

    /// Whether numbers of `self` and `other` may stand in one column: the same
    /// engine and the same suite (name and hash), and where both are the solver's
    /// (`baseline:scripted`), the same solver version. The package, commit, harness
    /// and policy may differ (a column compares policies; harnesses give the
    /// same numbers for the same policy and engine).
    ///
    /// # Errors
    /// The first field that differs, with both values.
    pub fn comparable(&self, other: &Provenance) -> Result<(), Mismatch> {
        if self.build.mujoco != other.build.mujoco {
            return Err(Mismatch::new("provenance.mujoco (the engine)", &self.build.mujoco, &other.build.mujoco));
        }
        match (&self.suite, &other.suite) {
            (Some(a), Some(b)) if a.name != b.name => Err(Mismatch::new("provenance.suite.name", &a.name, &b.name)),
            (Some(a), Some(b)) if a.sha256 != b.sha256 => {
                Err(Mismatch::new("provenance.suite.sha256 (the suite file's text)", &a.sha256, &b.sha256))
            }
            (Some(a), None) | (None, Some(a)) => Err(Mismatch::new("provenance.suite", &a.name, "none")),
            _ if self.policy.name == SOLVER_POLICY
                && other.policy.name == SOLVER_POLICY
                && self.build.solver_version() != other.build.solver_version() =>
            {
                Err(Mismatch::new(
                    "provenance.solver (the solver's version)",
                    &self.build.solver_version().to_string(),
                    &other.build.solver_version().to_string(),
                ))
            }
            _ => Ok(()),
        }
    }
}

/// How results name the solver as a policy.
pub const SOLVER_POLICY: &str = "baseline:scripted";

/// A field two results differ in, which keeps them out of one column.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{field} differs: {left} vs {right}")]
pub struct Mismatch {
    /// The field, as results spell it.
    pub field: String,
    /// The first result's value.
    pub left: String,
    /// The second's.
    pub right: String,
}

impl Mismatch {
    /// `field` is `left` in one result and `right` in the other.
    pub fn new(field: impl Into<String>, left: &str, right: &str) -> Self {
        Self { field: field.into(), left: left.to_owned(), right: right.to_owned() }
    }
}

/// The package version.
pub fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// The commit this build was made from (build.rs), where built from a checkout.
pub fn commit() -> Option<String> {
    Some(env!("BLOCKPUZZLE_COMMIT")).filter(|c| !c.is_empty()).map(str::to_owned)
}

/// A digest of the sources this build was made from (build.rs): the same for the two engines'
/// builds of one checkout, and different for two `-dirty` builds of one commit whose changes
/// differ. Not recorded in results (the commit is); ranks of one job compare it.
pub fn sources() -> &'static str {
    env!("BLOCKPUZZLE_SOURCES")
}

/// `sha256:` and the hex digest of `bytes`, the form every content hash of results takes.
pub fn sha256(bytes: &[u8]) -> String {
    let digest = Sha256::digest(bytes);
    format!("sha256:{}", digest.iter().map(|b| format!("{b:02x}")).collect::<String>())
}

impl Provenance {
    /// One Markdown line for a result's footnote: engine, package, commit, harness, policy and suite.
    pub fn markdown(&self) -> String {
        let policy = match &self.policy.sha256 {
            Some(h) => format!("`{}` ({h})", self.policy.name),
            None if self.policy.name == SOLVER_POLICY => {
                format!("`{}` (solver version {})", self.policy.name, self.build.solver_version())
            }
            None => format!("`{}`", self.policy.name),
        };
        let suite =
            self.suite.as_ref().map_or_else(String::new, |s| format!("; suite `{}` sha256 {}", s.name, s.sha256));
        format!("Made on {}, harness {}; policy {policy}{suite}.", self.build.describe(), self.harness.name())
    }
}
