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

/// Every Markdown file of the repository (git-tracked, outside `target/`): the docs, the README's,
/// ARCHITECTURE.md, the research logs in results/, the recipes' notes.
fn all_markdown() -> Vec<PathBuf> {
    let out = std::process::Command::new("git").args(["ls-files", "*.md"]).current_dir(root()).output().unwrap();
    assert!(out.status.success(), "git ls-files: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap().lines().map(|l| root().join(l)).filter(|p| p.is_file()).collect()
}

/// The `src/…` paths a text names (a word that starts with `src/`, not a part of a longer path such
/// as `python/src/lib.rs`), trailing punctuation cut; globs and placeholders left out.
fn src_paths(text: &str) -> Vec<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    for (at, _) in text.match_indices("src/") {
        let before = at.checked_sub(1).map(|k| bytes[k] as char);
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || matches!(c, '/' | '_' | '-' | '.')) {
            continue;
        }
        let path: String = text[at..]
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '/' | '_' | '-' | '.'))
            .collect();
        let path = path.trim_end_matches(['.', '/']).to_owned();
        if path.len() > "src/".len() && !path.contains("..") {
            out.push(path);
        }
    }
    out
}

/// Issue 75: a doc that names a `src/` file or folder names one that exists (at the root, or in the
/// crate beside it: `mujoco-sys/`, `python/`).
#[test]
fn every_src_path_the_docs_name_exists() {
    let files = all_markdown();
    assert!(files.len() > 30, "{files:?}");
    let mut missing = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for (n, line) in text.lines().enumerate() {
            for p in src_paths(line) {
                if !["", "mujoco-sys/", "python/"].iter().any(|dir| root().join(format!("{dir}{p}")).exists()) {
                    missing.push(format!("{}:{}: {p}", file.strip_prefix(root()).unwrap().display(), n + 1));
                }
            }
        }
    }
    assert!(missing.is_empty(), "docs name src/ paths that do not exist:\n{}", missing.join("\n"));
    // The check can fail, and reads a path as a word.
    assert_eq!(src_paths("see `src/no/such.rs`, and python/src/lib.rs."), ["src/no/such.rs"]);
    assert_eq!(src_paths("(src/learn/train/mod.rs)."), ["src/learn/train/mod.rs"]);
}

/// The flags of a command line that name a policy, and the `zoo` subcommands that take an entry.
const POLICY_FLAGS: &[&str] = &[
    "--checkpoint",
    "--policy",
    "--init-from",
    "--expert",
    "--ddpg",
    "--pggd",
    "--pggd-alone",
    "--base",
    "--started-from",
];

/// The zoo entries a command line names (values of [`POLICY_FLAGS`], `zoo check|describe|evaluate|upgrade
/// NAME…`): words that read as a name, not a path, a placeholder (`NAME`) or a baseline.
fn zoo_names(command: &str) -> Vec<String> {
    let w = words(command);
    let Some(start) = w.iter().position(|a| a == "blockpuzzle" || a.ends_with("/blockpuzzle") || a == "--") else {
        return Vec::new();
    };
    let args = &w[start + 1..];
    let mut named: Vec<&str> =
        args.windows(2).filter(|p| POLICY_FLAGS.contains(&p[0].as_str())).map(|p| p[1].as_str()).collect();
    if let [zoo, sub, rest @ ..] = args {
        if zoo == "zoo" && matches!(sub.as_str(), "check" | "describe" | "evaluate" | "upgrade") {
            let mut rest = rest.iter();
            while let Some(a) = rest.next() {
                match a.as_str() {
                    "--zoo" | "--description" | "--algo" | "--started-from" | "--threads" => {
                        rest.next();
                    }
                    a if !a.starts_with('-') => named.push(a),
                    _ => {}
                }
            }
        }
    }
    let is_name = |v: &&str| {
        v.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
            && v.chars().any(|c| c.is_ascii_lowercase())
            && !v.ends_with(".json")
            && !v.ends_with(".safetensors")
            && !matches!(*v, "scripted" | "random" | "obs-hash" | "solver")
    };
    named.into_iter().filter(is_name).map(str::to_owned).collect()
}

/// Issue 75: every zoo entry a command line of the docs names is in the zoo.
#[test]
fn every_zoo_entry_the_docs_name_exists() {
    let commands: Vec<(String, String)> = all_markdown()
        .iter()
        .flat_map(|p| blocks(p))
        .filter(|b| matches!(b.lang.as_str(), "sh" | "bash"))
        .flat_map(|b| shell_commands(&b))
        .collect();
    let named: Vec<(String, String)> =
        commands.iter().flat_map(|(at, c)| zoo_names(c).into_iter().map(move |n| (at.clone(), n))).collect();
    assert!(named.len() > 10, "{named:?}");
    let zoo = blockpuzzle::benchmark::zoo::dir();
    let missing: Vec<String> = named
        .iter()
        .filter(|(_, n)| !zoo.join(format!("{n}.json")).is_file())
        .map(|(at, n)| format!("{at}: {n}"))
        .collect();
    assert!(missing.is_empty(), "docs name zoo entries that do not exist:\n{}", missing.join("\n"));
    // The check can fail: a name that is no entry is found, a path or a placeholder is not a name.
    let names = zoo_names("blockpuzzle eval --checkpoint no-such-entry --episodes 3");
    assert_eq!(names, ["no-such-entry"]);
    assert!(zoo_names("blockpuzzle eval --checkpoint runs/x/policy.json").is_empty());
    assert!(zoo_names("blockpuzzle zoo check NAME").is_empty());
    assert_eq!(zoo_names("blockpuzzle zoo describe e --description d --zoo z"), ["e"]);
}

/// The inline code spans of a text that are command lines: `` `blockpuzzle …` ``.
fn inline_commands(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut spans = text.split('`');
    // Odd pieces are inside backticks (fences are whole lines of them: their pieces are empty).
    spans.next();
    while let Some(inside) = spans.next() {
        if inside.starts_with("blockpuzzle ") && !inside.contains('\n') {
            out.push(inside.to_owned());
        }
        spans.next();
    }
    out
}

/// Why an inline command names a subcommand or flag that does not exist, or None. Prose names a
/// command by part of its line (`blockpuzzle demos`, `eval --suite`), so a missing argument or value
/// is no fault here; an unknown word is.
fn unknown_words(command: &str) -> Option<String> {
    let argv = words(command).into_iter().map(Into::into).collect();
    let e = blockpuzzle::cli::check_args(argv).err()?;
    use clap::error::ErrorKind;
    let kind = e.downcast_ref::<clap::Error>().map(clap::Error::kind);
    matches!(kind, Some(ErrorKind::UnknownArgument | ErrorKind::InvalidSubcommand)).then(|| format!("{e:#}"))
}

/// Issue 75: the command lines the docs' prose names inline name subcommands and flags that exist,
/// unless they are synopses (`…`, `NAME`, `[--flag]`).
#[test]
fn every_inline_command_in_the_docs_names_real_flags() {
    let mut checked = 0;
    let mut wrong = Vec::new();
    for file in docs().iter().chain(&[root().join("ARCHITECTURE.md")]) {
        let text = std::fs::read_to_string(file).unwrap();
        for paragraph in text.split("\n\n").filter(|p| !p.trim_start().starts_with("```")) {
            for c in inline_commands(&paragraph.replace('\n', " ")) {
                let synopsis = c.contains('…')
                    || c.contains("...")
                    || c.contains('[')
                    || c.contains('|')
                    || c.contains('<')
                    || c.split_whitespace()
                        .any(|w| w.len() > 1 && w.chars().all(|ch| ch.is_ascii_uppercase() || ch == '_'));
                if synopsis {
                    continue;
                }
                checked += 1;
                if let Some(why) = unknown_words(&c) {
                    wrong.push(format!("{}: `{c}`: {why}", file.strip_prefix(root()).unwrap().display()));
                }
            }
        }
    }
    assert!(checked > 20, "{checked}");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    assert_eq!(inline_commands("run `blockpuzzle envs` or `make test`"), ["blockpuzzle envs"]);
    // The check can fail: an unknown flag or subcommand is named; a partial line is not.
    assert!(unknown_words("blockpuzzle eval --no-such-flag").is_some());
    assert!(unknown_words("blockpuzzle no-such-command").is_some());
    assert!(unknown_words("blockpuzzle demos").is_none());
}
