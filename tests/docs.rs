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

/// The command lines (continuations joined, comments cut) of each shell block not marked as a
/// fragment: (file:line, command).
fn shell_commands(path: &Path) -> Vec<(String, String)> {
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
        let lang = fence.trim_start_matches('`').trim();
        let mark = lines[..i].iter().rev().find(|l| !l.trim().is_empty()).is_some_and(|l| {
            let l = l.trim();
            l.starts_with("<!--") && l.trim_start_matches("<!--").trim_start().starts_with("fragment")
        });
        let mut j = i + 1;
        let mut command = String::new();
        while j < lines.len() && !lines[j].trim_start().starts_with("```") {
            if matches!(lang, "sh" | "bash") && !mark {
                let line = lines[j].trim();
                let code = match line.find(" #") {
                    Some(k) => &line[..k],
                    None if line.starts_with('#') => "",
                    None => line,
                };
                command.push_str(code.trim_end_matches('\\').trim());
                command.push(' ');
                if !code.ends_with('\\') {
                    if !command.trim().is_empty() {
                        out.push((
                            format!("{}:{}", path.strip_prefix(root()).unwrap().display(), j + 1),
                            command.trim().to_owned(),
                        ));
                    }
                    command.clear();
                }
            }
            j += 1;
        }
        i = j + 1;
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
        // Installing and building: what they run is the package's and cargo's business.
        ["pip", "install", ..] | ["cargo", "build", ..] => None,
        _ => Some("a command this test does not know: check it here, or mark the block as a fragment".into()),
    }
}

#[test]
fn every_command_line_in_the_docs_parses() {
    std::env::set_current_dir(root()).unwrap();
    let makefile = std::fs::read_to_string(root().join("Makefile")).unwrap();
    let commands: Vec<(String, String)> = docs().iter().flat_map(|p| shell_commands(p)).collect();
    assert!(commands.len() > 20, "{commands:?}");
    let wrong: Vec<String> =
        commands.iter().filter_map(|(at, c)| check(c, &makefile).map(|why| format!("{at}: `{c}`: {why}"))).collect();
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    // The check can fail: an unknown flag and an out-of-range value are caught.
    assert!(check("blockpuzzle eval --suite layout --no-such-flag", &makefile).is_some());
    assert!(check("blockpuzzle rollout --env BlocksTouch-v0 --episodes 0 --out x.jsonl", &makefile).is_some());
    assert!(check("make no-such-target", &makefile).is_some());
}
