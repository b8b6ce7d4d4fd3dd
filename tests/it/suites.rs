//! Evaluation suites: the built-in ones load, malformed files are clear
//! errors naming the fix, and `eval --suite` runs end to end.

use blockpuzzle::benchmark::suite::{self, BUILTIN};

fn parse(text: &str) -> Result<suite::Suite, String> {
    suite::parse(text, "test.toml", None).map_err(|e| e.to_string())
}

const TINY: &str = r#"
version = 1
name = "tiny"
summary = "Two rows each way."
[[splits.train]]
task = "BlocksChoose-v0"
seed = 3000000
episodes = 6
[[splits.test]]
task = "BlocksChoose-v0"
distribution = "challenge"
seed = 1000000
episodes = 6
[[splits.test]]
task = "GripperTouch-v0"
seed = 1000000
episodes = 6
"#;

#[test]
fn the_built_in_suites_load_and_are_identified_by_their_text() {
    for (name, text) in BUILTIN {
        let s = suite::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(&s.name, name);
        assert_eq!((s.splits[0].name.as_str(), s.splits[1].name.as_str()), ("train", "test"));
        assert_eq!(s.sha256, suite::parse(text, name, None).unwrap().sha256);
        assert_eq!(s.sha256.len(), 64);
    }
    let layout = suite::load("layout").unwrap();
    assert_eq!(layout.splits[1].rows[0].distribution.as_deref(), Some("challenge"));
    // The hash follows the text: one more space is another suite version.
    let text = BUILTIN.iter().find(|(n, _)| *n == "layout").unwrap().1;
    assert_ne!(suite::parse(&format!("{text} "), "x", None).unwrap().sha256, layout.sha256);
}

#[test]
fn a_suite_file_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tiny.toml");
    std::fs::write(&path, TINY).unwrap();
    let s = suite::load(path.to_str().unwrap()).unwrap();
    assert_eq!(s.sha256, parse(TINY).unwrap().sha256);
    let test = &s.splits[1];
    assert_eq!(test.rows.len(), 2);
    assert_eq!(
        (test.rows[0].seed, test.rows[0].episodes, test.rows[0].distribution_label()),
        (1_000_000, 6, "challenge")
    );
    assert_eq!(test.rows[1].distribution_label(), "normal");
    assert_eq!(test.rows[1].task.id(), "GripperTouch-v0");
}

#[test]
fn malformed_suites_are_clear_errors() {
    let cases: &[(&str, &str, &str)] = &[
        ("task = \"BlocksChoose-v0\"", "task = \"NoSuchTask-v0\"", "unknown environment id"),
        ("seed = 3000000", "seed = 1000004", "overlap"),
        ("distribution = \"challenge\"", "distribution = \"storm\"", "no distribution \"storm\""),
        ("version = 1", "version = 7", "version 7"),
        (
            "episodes = 6\n[[splits.test]]",
            "episodes = 6\nlevel = 99\n[[splits.test]]",
            "beyond the task's maximum level",
        ),
        ("summary = \"Two rows each way.\"", "summary = \"x\"\ncolour = 1", "unknown field `colour`"),
        ("episodes = 6\n[[splits.test]]", "episodes = 0\n[[splits.test]]", "episodes = 0"),
    ];
    for (from, to, expected) in cases {
        assert!(TINY.contains(from), "{from}");
        let e = parse(&TINY.replacen(from, to, 1)).unwrap_err();
        assert!(e.contains(expected) && e.contains("test.toml"), "{to}: {e}");
    }
    let no_test = TINY.split("[[splits.test]]").next().unwrap();
    assert!(parse(no_test).unwrap_err().contains("no test split"));
    let empty = "version = 1\nname = \"e\"\nsummary = \"s\"\n[splits]\ntrain = []\ntest = []\n";
    assert!(
        parse(empty).unwrap_err().contains("split test is empty")
            || parse(empty).unwrap_err().contains("split train is empty")
    );
    let e = suite::load("no-such-suite").unwrap_err().to_string();
    assert!(e.contains("colour, layout, cross-task") && e.contains("suite file"), "{e}");
}

/// A validation suite (train and validation splits, no test) loads, scores on its validation split,
/// and is refused a task any built-in suite holds out, compared by content: a copy of a shipped
/// family under another name, drawing procgen-v2's test seeds, is caught.
#[test]
fn validation_suites_never_read_a_test_split() {
    let held = suite::held_out_tasks().unwrap();
    assert!(held.iter().any(|h| h.suite == "procgen-v2" && h.split == "test" && h.id == "push-20003-v0"));
    // The shipped ones: the seven families, the seven with choose, and the eight stretched past
    // their ranges (family files of experiments/generalist/families-stretch, pinned by hash).
    for (file, rows) in [("validation.toml", 35), ("validation-v2.toml", 40), ("stretch-v1.toml", 40)] {
        let path = format!("{}/experiments/generalist/suites/{file}", env!("CARGO_MANIFEST_DIR"));
        let shipped = suite::load(&path).unwrap();
        let names: Vec<&str> = shipped.splits.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["train", "validation"], "{file}");
        assert_eq!(shipped.splits[1].rows.len(), rows, "{file}");
        for row in shipped.splits.iter().flat_map(|s| &s.rows) {
            assert!(!held.iter().any(|h| h.content == row.task.content_hash()), "{file}: {}", row.source);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let family = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/families/push.toml")).unwrap();
    let renamed = family.replacen("family = \"push\"", "family = \"my-pushes\"", 1);
    assert_ne!(renamed, family, "the family names itself");
    std::fs::write(dir.path().join("my-pushes.toml"), renamed).unwrap();
    let text = |family: &str, seeds: &str| {
        format!(
            "version = 1\nname = \"v\"\nsummary = \"s\"\n[[splits.train]]\nfamily = \"push\"\ngenerator_seeds = [300, 301]\n\
             candidates = [0]\nseed = 2000000\nepisodes = 5\n[[splits.validation]]\nfamily = \"{family}\"\n\
             generator_seeds = {seeds}\ncandidates = [0, 0]\nseed = 2000100\nepisodes = 5\n"
        )
    };
    let path = dir.path().join("v.toml");
    for family in ["push", "my-pushes.toml"] {
        std::fs::write(&path, text(family, "[20003, 20005]")).unwrap();
        let e = suite::load(path.to_str().unwrap()).unwrap_err().to_string();
        assert!(e.contains("procgen-v2 holds out in its test split") && e.contains("generator seeds outside"), "{e}");
    }
    std::fs::write(&path, text("my-pushes.toml", "[30000, 30002]")).unwrap();
    let ok = suite::load(path.to_str().unwrap()).unwrap();
    assert_eq!(ok.splits[1].name, "validation");
    // Without a validation split it is an ordinary suite, which needs its test split.
    let e = parse(&text("push", "[30000, 30002]").replace("validation", "check")).unwrap_err();
    assert!(e.contains("no test split") && e.contains("validation suite"), "{e}");
}

#[cfg(feature = "train")]
#[test]
fn eval_suite_writes_json_and_markdown_and_skips_rows_that_do_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("tiny.toml");
    std::fs::write(&file, TINY).unwrap();
    let out = dir.path().join("r.json");
    let o = crate::common::blockpuzzle(&[
        "eval",
        "--suite",
        file.to_str().unwrap(),
        "--checkpoint",
        "BlocksChoose-v0-ddpg",
        "--threads",
        "2",
    ])
    .args(["--out", out.to_str().unwrap()])
    .output()
    .unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{text}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(r["suite"]["sha256"], parse(TINY).unwrap().sha256.as_str());
    let test = &r["splits"][1];
    assert_eq!(test["name"], "test");
    // The BlocksChoose policy (67 inputs) cannot take GripperTouch-v0's 29: skipped, with the reason.
    assert!(test["rows"][1]["evaluation"].is_null());
    assert!(test["rows"][1]["skipped"].as_str().unwrap().contains("29"), "{}", test["rows"][1]);
    let challenge = test["rows"][0]["evaluation"]["success_rate"].as_f64().unwrap();
    assert_eq!(test["mean_success"].as_f64().unwrap(), challenge, "skipped rows do not count");
    let train = r["splits"][0]["mean_success"].as_f64().unwrap();
    assert!((r["gap"].as_f64().unwrap() - (train - challenge)).abs() < 1e-12);
    assert_eq!(r["score"].as_f64().unwrap(), challenge);
    // The same numbers as `eval` of the row alone.
    let single = dir.path().join("single.json");
    let o = crate::common::blockpuzzle(&[
        "eval",
        "--checkpoint",
        "BlocksChoose-v0-ddpg",
        "--env",
        "BlocksChoose-v0",
        "--challenge",
    ])
    .args(["--episodes", "6", "--seed", "1000000", "--out", single.to_str().unwrap()])
    .output()
    .unwrap();
    assert!(o.status.success());
    let single: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&single).unwrap()).unwrap();
    assert_eq!(single["success_rate"].as_f64().unwrap(), challenge);
    let md = std::fs::read_to_string(out.with_extension("md")).unwrap();
    assert!(
        md.contains("| BlocksChoose-v0 | challenge | 6 |") && md.contains("skipped:") && md.contains("Score"),
        "{md}"
    );
}

#[cfg(feature = "train")]
#[test]
fn baselines_run_on_every_row_and_on_one_task() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("counts.toml");
    let text = r#"
version = 1
name = "counts"
summary = "Tasks with object counts."
[[splits.train]]
task = "BlocksChooseN-v0"
distribution = "few"
seed = 3000000
episodes = 6
[[splits.test]]
task = "BlocksAvoid-v0"
seed = 1000000
episodes = 6
"#;
    std::fs::write(&file, text).unwrap();
    let run = |args: &[&str]| crate::common::blockpuzzle(args).current_dir(dir.path()).output().unwrap();
    let o = run(&["eval", "--suite", file.to_str().unwrap(), "--baseline", "scripted", "--threads", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("eval-scripted-suite-counts.json");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(r["policy"], "baseline:scripted");
    assert!(r["policy_epoch"].is_null() && r["policy_task"].is_null());
    // A baseline fits every task: no row skipped, and the scripted controller succeeds.
    for split in r["splits"].as_array().unwrap() {
        let row = &split["rows"][0];
        assert!(row["skipped"].is_null(), "{row}");
        assert!(row["evaluation"]["success_rate"].as_f64().unwrap() >= 0.5, "{row}");
    }
    let md = std::fs::read_to_string(out.with_extension("md")).unwrap();
    assert!(md.contains("A baseline (no training)"), "{md}");
    // --baseline needs a suite or a task, and cannot be given with --checkpoint; neither is an error naming both.
    let e = run(&["eval", "--baseline", "scripted"]);
    assert!(!e.status.success() && String::from_utf8_lossy(&e.stderr).contains("--suite"));
    let e = run(&["eval", "--suite", "count", "--baseline", "scripted", "--checkpoint", "x"]);
    assert!(!e.status.success() && String::from_utf8_lossy(&e.stderr).contains("cannot be used with"));
    let e = run(&["eval", "--suite", "count"]);
    let stderr = String::from_utf8_lossy(&e.stderr);
    assert!(!e.status.success() && stderr.contains("--checkpoint") && stderr.contains("--baseline"), "{stderr}");
    // On one task too (one resolver: --baseline NAME or --checkpoint NAME), the same episodes either way.
    let tmp = tempfile::tempdir().unwrap();
    let mut results = Vec::new();
    for (k, how) in [["--baseline", "scripted"], ["--checkpoint", "scripted"]].iter().enumerate() {
        let out = tmp.path().join(format!("one-{k}.json"));
        let args =
            ["eval", how[0], how[1], "--env", "BlocksTouch-v0", "--episodes", "3", "--out", out.to_str().unwrap()];
        let o = run(&args);
        assert!(o.status.success(), "{how:?}: {}", String::from_utf8_lossy(&o.stderr));
        let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(
            (r["policy"].as_str(), r["provenance"]["policy"]["name"].as_str()),
            (Some("baseline:scripted"), Some("baseline:scripted"))
        );
        results.push(r["successes"].clone());
    }
    assert_eq!(results[0], results[1]);
    let e = run(&["eval", "--checkpoint", "random", "--env", "BlocksTouch-v0", "--episodes", "3"]);
    assert!(!e.status.success() && String::from_utf8_lossy(&e.stderr).contains("random actions"));
}
