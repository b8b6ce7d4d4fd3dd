//! What a task file's errors say: [`TaskError`] (file, line, message with the
//! fix), how an entry is located in the file's text, and how two tasks differ.

use super::Task;
use std::fmt;

/// A problem with a task file: where (file and line) and what, with the fix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TaskError {
    /// The file, or `built-in ID`.
    pub origin: String,
    /// 1-based line of the offending entry, when known.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for TaskError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{l}: {}", self.origin, self.message),
            None => write!(f, "{}: {}", self.origin, self.message),
        }
    }
}

impl std::error::Error for TaskError {}

/// Where `[KEY` or `[KEY.` first appears in `text` (a table header).
pub(super) fn key_span(text: &str, key: &str) -> Option<std::ops::Range<usize>> {
    let at = text.find(&format!("[{key}]")).or_else(|| text.find(&format!("[{key}.")))?;
    Some(at..at)
}

/// Where the top-level key `key = ...` (or one inside a table) first appears in `text`.
pub(super) fn field_span(text: &str, key: &str) -> Option<std::ops::Range<usize>> {
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let t = line.trim_start();
        if t.strip_prefix(key).is_some_and(|rest| rest.trim_start().starts_with('=')) {
            let at = offset + (line.len() - t.len());
            return Some(at..at);
        }
        offset += line.len();
    }
    None
}

/// 1-based line of byte `offset` in `text`.
pub(super) fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())].iter().filter(|&&b| b == b'\n').count() + 1
}

impl Task {
    /// The fields in which `other` differs from this task, as dotted paths
    /// (`curriculum.params.R`, `objects[1].start`, …); empty when equal.
    pub fn differences(&self, other: &Task) -> Vec<String> {
        let (Ok(a), Ok(b)) = (serde_json::to_value(&self.spec), serde_json::to_value(&other.spec)) else {
            return Vec::new();
        };
        crate::support::diff::differences(&a, &b)
            .into_iter()
            .map(|p| if p.0.is_empty() { "(the whole task)".to_owned() } else { p.to_string() })
            .collect()
    }
}
