//! Where two JSON documents differ, as paths to the differing values: the
//! one comparison behind a task's changed fields (`Task::differences`) and a
//! run's changed settings (`--resume`, `--branch-from`).

use serde_json::Value;
use std::fmt;

/// One step into a JSON value: an object's key or an array's index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Step {
    /// An object's key.
    Key(String),
    /// An array's index.
    Index(usize),
}

/// A path from the document's root, e.g. `objects[1].start`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Path(pub Vec<Step>);

impl Path {
    /// The object key of step `i` (None past the end or at an index).
    pub fn key(&self, i: usize) -> Option<&str> {
        match self.0.get(i) {
            Some(Step::Key(k)) => Some(k),
            _ => None,
        }
    }

    fn with(&self, step: Step) -> Self {
        let mut p = self.clone();
        p.0.push(step);
        p
    }
}

impl fmt::Display for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, step) in self.0.iter().enumerate() {
            match step {
                Step::Key(k) if i == 0 => write!(f, "{k}")?,
                Step::Key(k) => write!(f, ".{k}")?,
                Step::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// The paths at which `a` and `b` differ, in key order: objects are compared
/// key by key (a key on one side only is a difference at that key), arrays
/// of equal length element by element, anything else whole. Empty when equal.
pub fn differences(a: &Value, b: &Value) -> Vec<Path> {
    let mut out = Vec::new();
    walk(&Path::default(), a, b, &mut out);
    out
}

fn walk(path: &Path, a: &Value, b: &Value, out: &mut Vec<Path>) {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
            for k in keys {
                let p = path.with(Step::Key(k.clone()));
                match (x.get(k), y.get(k)) {
                    (Some(u), Some(v)) => walk(&p, u, v, out),
                    _ => out.push(p),
                }
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                walk(&path.with(Step::Index(i)), u, v, out);
            }
        }
        _ if a != b => out.push(path.clone()),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn paths_name_each_differing_value() {
        let a = json!({"id": "A-v0", "objects": [{"start": [1, 2]}, {"start": [3]}], "only_a": 1, "same": {"x": 1}});
        let b = json!({"id": "B-v0", "objects": [{"start": [1, 5]}, {"start": [3, 4]}], "same": {"x": 1}});
        let d: Vec<String> = differences(&a, &b).iter().map(ToString::to_string).collect();
        assert_eq!(d, ["id", "objects[0].start[1]", "objects[1].start", "only_a"]);
        assert!(differences(&a, &a).is_empty());
        assert_eq!(differences(&json!(1), &json!(2)), [Path::default()]);
        assert_eq!(differences(&a, &b)[1].key(0), Some("objects"));
    }
}
