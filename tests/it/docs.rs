//! The command lines of the README's and the docs' shell blocks: each `blockpuzzle` command parses
//! (its subcommand and flags exist and its values are in range), each `make` target is in the
//! Makefile, each script or recipe named exists. A block that is a synopsis or otherwise not meant to
//! run as written says so on the line above its fence (`<!-- fragment: why -->`). The Python blocks
//! run in the wheel's tests (python/tests/test_docs.py); the README's Rust block is a doctest.

#![cfg(feature = "train")]

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn docs() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.sort();
    files.extend(["README.md", "python/README.md", "zoo/README.md"].map(|f| root().join(f)));
    files
}

/// A fenced block: its language, the line of its first line, its text, and whether the line above
/// its fence marks it as a fragment.
struct Block {
    lang: String,
    at: String,
    text: String,
    fragment: bool,
}

fn blocks(path: &Path) -> Vec<Block> {
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let fence = lines[i].trim_start();
        if !fence.starts_with("```") {
            i += 1;
            continue;
        }
        let indent = lines[i].len() - fence.len();
        let fragment = lines[..i].iter().rev().find(|l| !l.trim().is_empty()).is_some_and(|l| {
            let l = l.trim();
            l.starts_with("<!--") && l.trim_start_matches("<!--").trim_start().starts_with("fragment")
        });
        let mut j = i + 1;
        while j < lines.len() && !lines[j].trim_start().starts_with("```") {
            j += 1;
        }
        let body: Vec<&str> = lines[i + 1..j.min(lines.len())].iter().map(|l| l.get(indent..).unwrap_or("")).collect();
        out.push(Block {
            lang: fence.trim_start_matches('`').trim().to_owned(),
            at: format!("{}:{}", path.strip_prefix(root()).unwrap().display(), i + 2),
            text: body.join("\n"),
            fragment,
        });
        i = j + 1;
    }
    out
}

/// The command lines (continuations joined, comments cut) of a shell block: (file:line, command).
fn shell_commands(block: &Block) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut command = String::new();
    for line in block.text.lines() {
        let line = line.trim();
        let code = match line.find(" #") {
            Some(k) => &line[..k],
            None if line.starts_with('#') => "",
            None => line,
        };
        command.push_str(code.trim_end_matches('\\').trim());
        command.push(' ');
        if !code.ends_with('\\') {
            if !command.trim().is_empty() {
                out.push((block.at.clone(), command.trim().to_owned()));
            }
            command.clear();
        }
    }
    out
}

/// Shell words (quotes group, no expansion).
fn words(command: &str) -> Vec<String> {
    let (mut out, mut word, mut quote, mut any) = (Vec::new(), String::new(), None, false);
    for c in command.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => (quote, any) = (Some(c), true),
            (None, c) if c.is_whitespace() => {
                if any || !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
                any = false;
            }
            (None, c) => word.push(c),
        }
    }
    if any || !word.is_empty() {
        out.push(word);
    }
    out
}

/// Why `command` is wrong, or None.
fn check(command: &str, makefile: &str) -> Option<String> {
    let w = words(command);
    let w: Vec<&str> = w.iter().map(String::as_str).collect();
    // `mpirun -np N [--hostfile F] BIN ARGS`, `cargo run --release [--quiet] -- ARGS`, a built binary.
    let cli = match w.as_slice() {
        ["blockpuzzle", ..] => Some(&w[1..]),
        ["cargo", "run", rest @ ..] => rest.iter().position(|a| *a == "--").map(|k| &rest[k + 1..]),
        [bin, rest @ ..] if bin.ends_with("/blockpuzzle") => Some(rest),
        ["mpirun", ..] => w.iter().position(|a| a.ends_with("blockpuzzle")).map(|k| &w[k + 1..]),
        _ => None,
    };
    if let Some(args) = cli {
        let argv = std::iter::once("blockpuzzle").chain(args.iter().copied()).map(Into::into).collect();
        // Recipes (`train --config FILE`) are read relative to the repository, as the docs run them.
        return blockpuzzle::cli::check_args(argv).err().map(|e| format!("{e:#}"));
    }
    match w.as_slice() {
        ["make", targets @ ..] => targets
            .iter()
            .find(|t| !makefile.lines().any(|l| l.starts_with(&format!("{t}:"))))
            .map(|t| format!("no make target {t}")),
        ["bash" | "python3", script, ..] => (!root().join(script).is_file()).then(|| format!("no file {script}")),
        // A diagnostic built by `cargo build --release --example NAME`: its source must exist.
        [bin, ..] if bin.starts_with("./target/release/examples/") => {
            let name = bin.trim_start_matches("./target/release/examples/");
            let source = format!("examples/{name}.rs");
            (!root().join(&source).is_file()).then(|| format!("no example {source}"))
        }
        // Installing and building: what they run is the package's and cargo's business.
        ["pip", "install", ..] | ["cargo", "build", ..] => None,
        _ => Some("a command this test does not know: check it here, or mark the block as a fragment".into()),
    }
}

#[test]
fn every_command_line_in_the_docs_parses() {
    let makefile = std::fs::read_to_string(root().join("Makefile")).unwrap();
    let all: Vec<Block> = docs().iter().flat_map(|p| blocks(p)).filter(|b| !b.fragment).collect();
    let commands: Vec<(String, String)> =
        all.iter().filter(|b| matches!(b.lang.as_str(), "sh" | "bash")).flat_map(shell_commands).collect();
    assert!(commands.len() > 20, "{commands:?}");
    let wrong: Vec<String> =
        commands.iter().filter_map(|(at, c)| check(c, &makefile).map(|why| format!("{at}: `{c}`: {why}"))).collect();
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    // The check can fail: an unknown flag and an out-of-range value are caught.
    assert!(check("blockpuzzle eval --suite layout --no-such-flag", &makefile).is_some());
    assert!(check("blockpuzzle rollout --env BlocksTouch-v0 --episodes 0 --out x.jsonl", &makefile).is_some());
    assert!(check("./target/release/examples/no_such_probe --steps 1", &makefile).is_some());
    assert!(check("./target/release/examples/solver_probe --steps 1", &makefile).is_none());
    assert!(check("make no-such-target", &makefile).is_some());
}

#[test]
fn every_toml_block_in_the_docs_is_a_valid_task_family_or_suite_file() {
    let dir = tempfile::tempdir().unwrap();
    let tomls: Vec<Block> = docs().iter().flat_map(|p| blocks(p)).filter(|b| b.lang == "toml" && !b.fragment).collect();
    assert!(tomls.len() >= 2);
    for b in &tomls {
        let file = dir.path().join("block.toml");
        std::fs::write(&file, &b.text).unwrap();
        // A task file has an id; a family file a family; a suite file has splits.
        if b.text.lines().any(|l| l.starts_with("family =")) {
            let family = blockpuzzle::task::family::Family::from_toml(&b.text, &b.at);
            assert!(family.is_ok(), "{}: {}", b.at, family.err().unwrap());
        } else if b.text.lines().any(|l| l.starts_with("id =")) {
            let task = blockpuzzle::task::Task::from_file(&file);
            assert!(task.is_ok(), "{}: {}", b.at, task.err().unwrap());
        } else {
            let suite = blockpuzzle::benchmark::suite::parse(&b.text, &b.at, Some(dir.path()));
            assert!(suite.is_ok(), "{}: {}", b.at, suite.err().unwrap());
        }
    }
}
