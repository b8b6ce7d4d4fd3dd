//! Experiment recipes (`experiments/**/*.toml`, `train --config FILE`): every
//! shipped recipe is a valid `train` command line, the study's variants are
//! the settings results/headline.md reports, and the command line wins over the file.
#![cfg(feature = "train")]

use blockpuzzle::cli::train_config;
use blockpuzzle::learn::agents::registry::Algo;
use blockpuzzle::learn::agents::shared::Precision;
use blockpuzzle::learn::train::TrainConfig;
use std::path::{Path, PathBuf};

fn recipe(path: &Path, extra: &[&str]) -> anyhow::Result<TrainConfig> {
    let mut args: Vec<std::ffi::OsString> = vec!["blockpuzzle".into(), "train".into(), "--config".into()];
    args.push(path.into());
    args.extend(extra.iter().map(Into::into));
    train_config(args)
}

/// Every `.toml` under `experiments/`, at any depth, but for the suite files in `suites/` folders.
fn recipes() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() && !p.ends_with("suites") {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "toml") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments"), &mut out);
    out.sort();
    out
}

#[test]
fn every_recipe_is_a_valid_train_command_line() {
    let all = recipes();
    assert!(all.len() >= 20, "{all:?}");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for path in all {
        // A task file or a family file kept beside the recipes that train on it is not a recipe.
        let text = std::fs::read_to_string(&path).unwrap();
        if blockpuzzle::task::Task::from_file(&path).is_ok()
            || blockpuzzle::task::family::Family::from_toml(&text, &path.display().to_string()).is_ok()
        {
            continue;
        }
        // A recipe that names no task (env, suite or families) takes it from the command line (--env ID).
        let keys: toml::Table = toml::from_str(&text).unwrap();
        let names_task = ["env", "suite", "families"].iter().any(|k| keys.contains_key(*k));
        let env: &[&str] = if names_task { &[] } else { &["--env", "ReachAvoid-v0"] };
        let c = recipe(&path, env).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
        // A run of a suite's or a family stream's tasks names no single task.
        let many = c.suite.is_some() || c.families.is_some();
        let known = many
            || c.env.split(',').all(|id| blockpuzzle::env::registry::ids().contains(&id) || root.join(id).is_file());
        assert!(known, "{}: {}", path.display(), c.env);
        // Counts name entries the task has, in range.
        if let Some(counts) = &c.counts {
            let task = blockpuzzle::env::registry::task(&c.env).unwrap();
            task.with_counts(counts).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
}

#[test]
fn the_study_recipes_are_the_reported_settings_and_flags_win() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/study");
    let c = recipe(&dir.join("ours-nol2-pre-rho9.toml"), &["--workers", "2"]).unwrap();
    assert_eq!((c.algo, c.env.as_str(), c.snapshot_every), (Algo::Ddpg, "BlocksChoose-v0", 10));
    let (d, s) = (&c.algos.ddpg, &c.shared);
    assert!(d.td3 && s.n_step == 3 && s.precision == Precision::Bf16, "{d:?} {s:?}");
    assert_eq!(
        (c.level_replay, c.challenge_share, d.action_l2, d.preact_l2, d.noise_correlation),
        (0.2, 0.25, 0.0, 0.01, 0.9)
    );
    // The paper's recipe is the defaults.
    let paper = recipe(&dir.join("paper.toml"), &[]).unwrap();
    let plain = train_config(
        ["blockpuzzle", "train", "--env", "BlocksChoose-v0", "--snapshot-every", "10"].map(Into::into).to_vec(),
    )
    .unwrap();
    assert_eq!(paper, plain);
    // A flag on the command line wins over the file.
    let f32 = recipe(&dir.join("ours.toml"), &["--precision", "f32", "--n-step", "5"]).unwrap();
    assert_eq!((f32.shared.precision, f32.shared.n_step), (Precision::F32, 5));
}

#[test]
fn a_bad_recipe_is_named_with_the_key_and_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("r.toml");
    std::fs::write(&p, "env = \"BlocksTouch-v0\"\nepoch = 3\n").unwrap();
    let e = format!("{:#}", recipe(&p, &[]).unwrap_err());
    assert!(e.contains("r.toml: `epoch` is not a flag of `blockpuzzle train`") && e.contains("epochs"), "{e}");
    // A bad value names the file, the key and the range (issue 60).
    for (line, want) in [("epochs = 0", "allowed are 1 to 100,000"), ("epochs = \"ten\"", "whole number")] {
        std::fs::write(&p, format!("env = \"BlocksTouch-v0\"\n{line}\n")).unwrap();
        let e = format!("{:#}", recipe(&p, &[]).unwrap_err());
        assert!(e.contains(&format!("r.toml: `{line}`")) && e.contains(want) && e.contains("fix the value"), "{e}");
    }
    let e = format!("{:#}", recipe(&dir.path().join("none.toml"), &[]).unwrap_err());
    assert!(e.contains("cannot read the recipe"), "{e}");
}
