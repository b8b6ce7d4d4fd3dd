//! `blockpuzzle results`: suite results side by side and as a leaderboard.

use anyhow::{bail, Context, Result};
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
pub(super) enum ResultsCommand {
    /// Suite results (JSON of `eval --suite` or Python's `evaluate`) side by side, one column per
    /// file; refused, naming the field, when their engines, suites or task contents differ.
    Compare {
        /// The result files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// A Markdown leaderboard of suite results: one table per suite and engine, rows per policy
    /// by score with 95% intervals and gaps, the provenance in footnotes.
    Leaderboard {
        /// Result files, or folders of them (`*.json`).
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Write it here (atomically) instead of printing it.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Instead of writing --out, check that it holds exactly what the files give (exit 1 if stale).
        #[arg(long, requires = "out")]
        check: bool,
    },
}

/// `blockpuzzle results compare | leaderboard`.
pub(super) fn run(c: ResultsCommand) -> Result<()> {
    match c {
        ResultsCommand::Compare { files } => {
            let files = files.iter().map(|f| crate::benchmark::results::read(f)).collect::<Result<Vec<_>, _>>()?;
            print!("{}", crate::benchmark::results::compare(&files)?);
        }
        ResultsCommand::Leaderboard { paths, out, check } => {
            let md = crate::benchmark::results::leaderboard(&crate::benchmark::results::read_all(&paths)?)?;
            match (out, check) {
                (Some(out), true) => {
                    let now =
                        crate::support::io::read_text(&out, "leaderboard", crate::support::limits::RESULT_FILE_BYTES)
                            .with_context(|| format!("cannot read {}", out.display()))?;
                    if now != md {
                        bail!("{} is stale: regenerate it with the same command without --check", out.display());
                    }
                    println!("{} is up to date", out.display());
                }
                (Some(out), false) => {
                    crate::support::io::write_file(&out, md.as_bytes())?;
                    println!("wrote {}", out.display());
                }
                (None, _) => print!("{md}"),
            }
        }
    }
    Ok(())
}
