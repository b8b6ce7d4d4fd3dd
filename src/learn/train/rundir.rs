//! The run directory: its files and `progress.csv`.

use super::{Context, EpochRow, Result, TrainConfig};
use crate::benchmark::provenance::Build;
use std::path::{Path, PathBuf};

/// Why a CSV log (a run's `progress.csv`, another trainer's log) could not be read; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file could not be read.
    #[error("cannot read {}", path.display())]
    Read {
        /// The log.
        path: PathBuf,
        /// The OS's error, or the bound or kind refused.
        #[source]
        source: std::io::Error,
    },
    /// Its rows are not the log's columns.
    #[error("{} is not a {what} ({columns})", path.display())]
    Malformed {
        /// The log.
        path: PathBuf,
        /// What the log is ("progress log").
        what: String,
        /// The columns it must hold.
        columns: String,
        /// The CSV reader's error.
        #[source]
        source: csv::Error,
    },
    /// It has no rows.
    #[error("{} has no rows: a {what} gains one per epoch (train the run for at least one epoch)", path.display())]
    Empty {
        /// The log.
        path: PathBuf,
        /// What the log is.
        what: String,
    },
    /// A success column holds no rate from 0 to 1.
    #[error(
        "{}: epoch {epoch}: {column} is {value}, not a rate from 0 to 1; the log was edited or damaged",
        path.display()
    )]
    NotRate {
        /// The log.
        path: PathBuf,
        /// The row's epoch.
        epoch: usize,
        /// The column.
        column: String,
        /// What it holds.
        value: f64,
    },
}

/// Files of a run directory.
pub struct RunDir {
    /// The folder.
    pub dir: PathBuf,
}

impl RunDir {
    /// `config.json`.
    pub fn config(&self) -> PathBuf {
        self.dir.join(crate::benchmark::saved::CONFIG_FILE)
    }
    /// `progress.csv`.
    pub fn progress(&self) -> PathBuf {
        self.dir.join("progress.csv")
    }
    /// `checkpoint.bin`.
    pub fn checkpoint(&self) -> PathBuf {
        self.dir.join("checkpoint.bin")
    }
    /// `policy.json`.
    pub fn policy(&self) -> PathBuf {
        self.dir.join(crate::benchmark::saved::POLICY_FILE)
    }
    /// `success.png`.
    pub fn plot(&self) -> PathBuf {
        self.dir.join("success.png")
    }
    /// `best_policy.json`.
    pub fn best_policy(&self) -> PathBuf {
        self.dir.join(crate::benchmark::saved::BEST_POLICY_FILE)
    }
    /// `snapshots/`: policies kept with `--snapshot-every`.
    pub fn snapshots(&self) -> PathBuf {
        self.dir.join("snapshots")
    }
    /// `snapshots/epoch-NNNN.json`: the policy after `epoch` epochs.
    pub fn snapshot(&self, epoch: usize) -> PathBuf {
        self.snapshots().join(format!("epoch-{epoch:04}.json"))
    }
    /// The run's `config.json`.
    ///
    /// # Errors
    /// A missing or malformed file, named.
    pub fn read_config(&self) -> Result<TrainConfig> {
        let path = self.config();
        if !self.dir.exists() {
            refuse!(
                "there is no run directory {}: give a folder that `blockpuzzle train --run-dir` wrote",
                self.dir.display()
            );
        }
        if self.dir.is_dir() && !path.exists() {
            refuse!(
                "{} holds no run (no {}): give a folder that `blockpuzzle train --run-dir` wrote",
                self.dir.display(),
                path.display()
            );
        }
        let text = crate::support::io::read_text(&path, "run config", crate::support::limits::RESULT_FILE_BYTES)
            .with_context(|| format!("cannot read {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("{} is not a training config", path.display()))
    }
    /// `provenance.json`: the builds and engines that ran the run's epochs ([`Span`]).
    pub fn provenance(&self) -> PathBuf {
        self.dir.join("provenance.json")
    }
    /// The builds that ran the run's epochs, in order (empty for runs started before runs recorded them).
    ///
    /// # Errors
    /// A malformed file, named.
    pub fn read_provenance(&self) -> Result<Vec<Span>> {
        let path = self.provenance();
        if !path.exists() {
            return Ok(Vec::new());
        }
        let text = crate::support::io::read_text(&path, "run provenance", crate::support::limits::RESULT_FILE_BYTES)
            .with_context(|| format!("cannot read {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("{} is not a run's provenance", path.display()))
    }
    /// Records that the epochs from `from_epoch` on run on this build (rank 0), its job's ranks on
    /// `rank_engines` ([`rank_engines`]; empty when every rank runs this build's engine). Nothing is
    /// written when the last span is this one and the replay buffers were not rebuilt.
    ///
    /// # Errors
    /// The file cannot be read or written.
    pub fn record_provenance(
        &self,
        from_epoch: usize,
        replay: Option<ReplayRebuilt>,
        rank_engines: Vec<String>,
    ) -> Result<()> {
        let mut spans = self.read_provenance()?;
        let build = Build::current();
        if replay.is_none() && spans.last().is_some_and(|s| s.build == build && s.rank_engines == rank_engines) {
            return Ok(());
        }
        spans.push(Span { from_epoch, build, replay, rank_engines });
        Ok(crate::support::io::write_json(&self.provenance(), &spans)?)
    }
    /// `expert_policy.json`: AggreVaTeD's expert as the run first loaded it
    /// (a resumed run uses this copy, so the expert cannot change under it).
    pub fn expert_policy(&self) -> PathBuf {
        self.dir.join("expert_policy.json")
    }
}

/// The build that ran a run's epochs from `from_epoch` on (until the next span's).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Span {
    /// The first epoch it ran (0-based: the number of epochs done before).
    pub from_epoch: usize,
    /// Package, commit and engine.
    #[serde(flatten)]
    pub build: Build,
    /// How the replay buffers were rebuilt when the run resumed here without its replay log
    /// (`train --resume --rebuild-replay`); absent when they were read back as saved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replay: Option<ReplayRebuilt>,
    /// The MuJoCo of each rank, in rank order, where the job's ranks ran more than one engine
    /// (`mpirun -np 1 BIN_2.2.2 train … : -np 1 BIN_3.11.0 train …`; `build` is rank 0's); absent
    /// when every rank ran `build.mujoco`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rank_engines: Vec<String>,
}

impl Span {
    /// "MuJoCo M by blockpuzzle V (commit `C`)", or with the ranks' engines where they differ:
    /// "MuJoCo 2.2.2 on rank 0, 3.11.0 on rank 1 by …".
    pub fn describe(&self) -> String {
        if self.rank_engines.is_empty() {
            return self.build.describe();
        }
        let ranks: Vec<String> =
            self.rank_engines.iter().enumerate().map(|(rank, engine)| format!("{engine} on rank {rank}")).collect();
        format!("MuJoCo {} by {}", ranks.join(", "), self.build.maker())
    }
}

/// What a rank of a job reports of itself at the start: its build, and the digest of the sources it
/// was built from ([`crate::benchmark::provenance::sources`]), which tells apart two `-dirty` builds
/// of one commit.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RankBuild {
    /// Package, commit, engine and solver version.
    #[serde(flatten)]
    pub build: Build,
    /// The sources' digest.
    pub sources: String,
}

impl RankBuild {
    /// This process's.
    pub fn current() -> Self {
        Self { build: Build::current(), sources: crate::benchmark::provenance::sources().to_owned() }
    }
}

/// The engine of each rank of a job whose ranks report `ranks` (in rank order), where they differ;
/// empty when every rank runs one engine. The ranks of one job may run different engines (each
/// engine's binary of one checkout), never different code: their gradients are averaged, and the
/// run's record names one commit and one solver version.
///
/// # Errors
/// A rank built from another package version, commit, solver version or sources than rank 0, named.
pub fn rank_engines(ranks: &[RankBuild]) -> Result<Vec<String>> {
    const FIX: &str = "build every rank's binary from one checkout, unchanged between the builds (cargo build \
                       --release, and --features mujoco3 for MuJoCo 3.11.0)";
    let Some(first) = ranks.first() else { return Ok(Vec::new()) };
    let (b0, code0) = (&first.build, (&first.build.blockpuzzle, &first.build.commit, first.build.solver));
    for (rank, this) in ranks.iter().enumerate().skip(1) {
        let b = &this.build;
        if (&b.blockpuzzle, &b.commit, b.solver) != code0 {
            refuse!(
                "rank {rank} runs {} (solver version {}), rank 0 {} (solver version {}): the ranks of one job may run \
                 different engines but not different code; {FIX}",
                b.maker(),
                b.solver_version(),
                b0.maker(),
                b0.solver_version()
            );
        }
        if this.sources != first.sources {
            refuse!(
                "rank {rank} and rank 0 both run {}, but from different sources (digest {} against {}: the \
                 checkout's uncommitted changes differ between their builds); the ranks of one job may run \
                 different engines but not different code; {FIX}",
                b.maker(),
                this.sources,
                first.sources
            );
        }
    }
    Ok(match ranks.iter().all(|r| r.build.mujoco == b0.mujoco) {
        true => Vec::new(),
        false => ranks.iter().map(|r| r.build.mujoco.clone()).collect(),
    })
}

/// How a run resumed without its replay log rebuilt its buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReplayRebuilt {
    /// Collected again from the run's seeds, transition for transition: every stored transition was
    /// the solver's (behaviour cloning at level 0), so the resumed run is the uninterrupted one.
    Regenerated,
    /// Started empty and refilled by the epochs that follow: the past transitions depended on
    /// policies the run no longer has (DAgger's learner, DDPG's actor), so the resumed run is a
    /// new computation from this epoch on.
    Refilled,
}

impl ReplayRebuilt {
    /// In words, for the run's log and `report`.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Regenerated => "replay regenerated from the run's seeds (exactly the transitions it had)",
            Self::Refilled => "replay refilled from empty (the earlier transitions were not recoverable)",
        }
    }
}

pub(super) fn write_progress(path: &Path, rows: &[EpochRow]) -> Result<(), crate::support::io::WriteError> {
    crate::support::io::write_atomic_via(path, |tmp| -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
        let mut w = csv::Writer::from_path(tmp)?;
        for r in rows {
            w.serialize(r)?;
        }
        w.flush()?;
        Ok(())
    })
}

/// The largest log read whole: a million epochs of about 400 bytes.
const MAX_LOG_BYTES: u64 = 400 << 20;

/// Reads the rows of a CSV log (`what` names it in messages, `columns` says
/// what it must hold), refusing a log without rows.
///
/// # Errors
/// A missing, oversized, malformed or empty file, named.
pub fn read_log<T: serde::de::DeserializeOwned>(path: &Path, what: &str, columns: &str) -> Result<Vec<T>, LogError> {
    let text = crate::support::io::read_text(path, what, MAX_LOG_BYTES)
        .map_err(|source| LogError::Read { path: path.to_owned(), source })?;
    let rows =
        csv::Reader::from_reader(text.as_bytes()).deserialize().collect::<Result<Vec<T>, _>>().map_err(|source| {
            LogError::Malformed { path: path.to_owned(), what: what.to_owned(), columns: columns.to_owned(), source }
        })?;
    if rows.is_empty() {
        return Err(LogError::Empty { path: path.to_owned(), what: what.to_owned() });
    }
    Ok(rows)
}

/// Reads `progress.csv`, whose success rates must be rates.
///
/// # Errors
/// A message naming the file for a missing, malformed or empty file, or a
/// success rate that is not a number from 0 to 1.
pub fn read_progress(path: &Path) -> Result<Vec<EpochRow>, LogError> {
    let rows: Vec<EpochRow> = read_log(path, "progress log", "a run's progress.csv, written by `blockpuzzle train`")?;
    for r in &rows {
        for (column, v) in
            [("train/success", r.train_success), ("test/success", r.test_success), ("finals/success", r.finals_success)]
        {
            check_rate(path, r.epoch, column, v)?;
        }
    }
    Ok(rows)
}

/// A log's success column must hold a rate from 0 to 1.
///
/// # Errors
/// Anything else (NaN included), naming the file, epoch and column.
pub fn check_rate(path: &Path, epoch: usize, column: &str, v: f64) -> Result<(), LogError> {
    if !(0.0..=1.0).contains(&v) {
        return Err(LogError::NotRate { path: path.to_owned(), epoch, column: column.to_owned(), value: v });
    }
    Ok(())
}
