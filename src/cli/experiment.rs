//! `train --config FILE`: an experiment recipe as a TOML file of `train`'s
//! flags (`epochs = 500`, `td3 = true`, `n-step = 3`), the way the paper's
//! runs and the study's variants are kept in `experiments/`. The file's
//! settings are put before the command line's own flags, and a flag given on
//! the command line wins over the file.

use anyhow::{bail, Context, Result};
use std::ffi::OsString;
use std::path::Path;

/// The command line with every `train --config FILE` replaced by the file's
/// flags (`--key value`, `--key` for `true`), placed right after `train`.
///
/// # Errors
/// An unreadable file, malformed TOML, a key that is not a flag of `train`
/// (the error lists them), or a value that is not a number, string or boolean.
pub fn expand(args: Vec<OsString>, train: &clap::Command) -> Result<(Vec<OsString>, Vec<Origin>)> {
    if args.get(1).map_or(true, |a| a != "train") {
        return Ok((args, Vec::new()));
    }
    let (head, rest) = args.split_at(2);
    let mut own = Vec::new();
    let mut files = Vec::new();
    let mut it = rest.iter();
    while let Some(a) = it.next() {
        if a == "--config" {
            let Some(file) = it.next() else {
                bail!("--config needs a FILE (an experiment recipe, e.g. experiments/ddpg3.toml)")
            };
            files.push(file.clone());
        } else if let Some(file) = a.to_str().and_then(|s| s.strip_prefix("--config=")) {
            files.push(file.into());
        } else {
            own.push(a.clone());
        }
    }
    let (mut out, mut origins) = (head.to_vec(), Vec::new());
    for file in &files {
        let (f, o) = flags(Path::new(file), train)?;
        out.extend(f);
        origins.extend(o);
    }
    out.extend(own);
    Ok((out, origins))
}

/// Where a flag of the expanded command line came from: a recipe's file, key and value.
#[derive(Debug, Clone)]
pub struct Origin {
    flag: String,
    file: std::path::PathBuf,
    /// The recipe's line, `key = value`, as errors show it.
    line: String,
    /// The value given to the flag (none for a switch).
    value: Option<String>,
}

/// `e`, clap's error for the expanded command line, naming the recipe file and key where the
/// flag it is about came from one with the value it refuses.
pub fn name_recipe(e: clap::Error, origins: &[Origin]) -> anyhow::Error {
    use clap::error::{ContextKind, ContextValue};
    let (Some(ContextValue::String(arg)), Some(ContextValue::String(value))) =
        (e.get(ContextKind::InvalidArg), e.get(ContextKind::InvalidValue))
    else {
        return e.into();
    };
    let from = origins
        .iter()
        .rev()
        .find(|o| arg.split(' ').next() == Some(o.flag.as_str()) && o.value.as_deref() == Some(value.as_str()));
    match from {
        Some(o) => {
            let said = e.to_string();
            let first = said.lines().next().unwrap_or_default().trim_start_matches("error: ");
            anyhow::anyhow!("{}: `{}`: {first}; fix the value in the file", o.file.display(), o.line)
        }
        None => e.into(),
    }
}

/// The flags of one recipe file (keys in sorted order; each flag once), and where each came from.
fn flags(path: &Path, train: &clap::Command) -> Result<(Vec<OsString>, Vec<Origin>)> {
    let text = crate::support::io::read_text(path, "recipe", crate::support::limits::TEXT_FILE_BYTES)
        .with_context(|| format!("cannot read the recipe {}", path.display()))?;
    let table: toml::Table = toml::from_str(&text).with_context(|| format!("{} is not TOML", path.display()))?;
    let known: Vec<&str> = train.get_arguments().filter_map(|a| a.get_long()).filter(|l| *l != "config").collect();
    let (mut out, mut origins) = (Vec::new(), Vec::new());
    for (key, value) in table {
        let flag = key.replace('_', "-");
        let Some(arg) = train.get_arguments().find(|a| a.get_long() == Some(flag.as_str()) && flag != "config") else {
            bail!("{}: `{key}` is not a flag of `blockpuzzle train` (they are: {})", path.display(), known.join(", "));
        };
        // A switch takes true or false; every other flag a value.
        match (arg.get_action().takes_values(), &value) {
            (false, toml::Value::Boolean(_))
            | (true, toml::Value::String(_) | toml::Value::Integer(_) | toml::Value::Float(_)) => {}
            (false, other) => {
                bail!("{}: `{key} = {other}`: `{key}` is a switch; write {key} = true or false", path.display())
            }
            (true, other) => bail!(
                "{}: `{key} = {other}`: `{key}` takes a value (as --{flag} VALUE): give a number or a string",
                path.display()
            ),
        }
        let given = match &value {
            toml::Value::Boolean(on) => {
                if *on {
                    out.push(format!("--{flag}").into());
                }
                None
            }
            toml::Value::String(s) => Some(s.clone()),
            toml::Value::Integer(i) => Some(i.to_string()),
            toml::Value::Float(x) => Some(x.to_string()),
            other => bail!("{}: `{key}` = {other}: give a number, a string or true/false", path.display()),
        };
        if let Some(v) = &given {
            out.extend([format!("--{flag}").into(), v.into()]);
        }
        let line = format!("{key} = {value}");
        origins.push(Origin { flag: format!("--{flag}"), file: path.to_owned(), line, value: given });
    }
    Ok((out, origins))
}
