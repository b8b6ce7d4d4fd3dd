//! `blockpuzzle blend`: a fine-tuned policy interpolated towards the policy it started from, weight by
//! weight (WiSE-FT, Wortsman et al. 2022), written as a policy file that every command takes.

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct BlendArgs {
    /// The policy fine-tuned from: a zoo name, run directory or policy file (e.g. generalist-bc-entity).
    #[arg(long)]
    base: PathBuf,
    /// The fine-tuned policy: a zoo name, run directory or policy file (its task, normaliser and records
    /// are the result's).
    #[arg(long)]
    tuned: PathBuf,
    /// The tuned policy's share of each weight: 0 gives the base's weights, 1 the tuned one's.
    #[arg(long, value_parser = share)]
    weight: f64,
    /// The policy file to write (JSON, as runs write them).
    #[arg(long)]
    out: PathBuf,
}

pub fn run(a: BlendArgs) -> Result<()> {
    // The output is checked before the policies are read, which may take a while for large ones.
    crate::support::io::check_output(&a.out)?;
    let base = crate::benchmark::load::load_policy(&a.base)?;
    let tuned = crate::benchmark::load::load_policy(&a.tuned)?;
    let name = |p: &PathBuf| p.display().to_string();
    let blended =
        crate::benchmark::saved::SavedPolicy::blend((&name(&a.base), &base), (&name(&a.tuned), &tuned), a.weight)?;
    crate::support::io::write_json(&a.out, &blended)?;
    println!(
        "wrote {}: {:.2} x {} + {:.2} x {} (policy {})",
        a.out.display(),
        1.0 - a.weight,
        a.base.display(),
        a.weight,
        a.tuned.display(),
        blended.policy_id("").sha256.unwrap_or_default()
    );
    Ok(())
}

/// `--weight`: a number from 0 to 1.
fn share(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|w| (0.0..=1.0).contains(w))
        .ok_or_else(|| format!("give a number from 0 to 1 (the tuned policy's share of each weight), not {s:?}"))
}
