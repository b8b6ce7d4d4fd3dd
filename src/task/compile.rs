//! The task compiler: a [`TaskSpec`] (a parsed file) checked field by field
//! against its ranges and references, its counts expanded into copies, its
//! parameters evaluated at every level, its starts, distributions and
//! shuffle groups compiled into a [`Task`]. Errors carry the file and line.

use super::diagnostics::{field_span, key_span, line_of};
use super::expr::Expr;
use super::sampler;
use super::spec::*;
use super::{
    is_safe_id, CountGroup, Distribution, Task, TaskError, TaskSource, MAX_LEVEL, MAX_TASK_OBJECTS, RESERVED_NAMES,
};
use crate::sim::rules::Rules;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

/// Checks and compiles a spec; `text` (the file) locates errors.
pub(crate) struct Checker<'a> {
    origin: &'a str,
    text: &'a str,
}

impl Checker<'_> {
    pub(crate) fn err(&self, span: Option<std::ops::Range<usize>>, message: impl Into<String>) -> TaskError {
        // Specs made in code have no text: their spans locate nothing.
        let line = span.filter(|_| !self.text.is_empty()).map(|s| line_of(self.text, s.start));
        TaskError { origin: self.origin.to_owned(), line, message: message.into() }
    }
}

fn canonical_hash(spec: &TaskSpec) -> String {
    // serde_json keeps struct field order and sorts nothing else: BTreeMaps are
    // already ordered, so equal specs give equal bytes.
    sha256_id(&serde_json::to_vec(spec).unwrap_or_default())
}

impl Task {
    /// `sha256:` of what the task *is*, whatever it is called: the canonical spec with its id and
    /// summary set aside. Two tasks with equal content hashes play the same episodes; held-out checks
    /// compare this, so that a renamed copy of a held-out task is still held out.
    pub fn content_hash(&self) -> String {
        let mut spec = self.spec.clone();
        spec.id.clear();
        spec.summary.clear();
        canonical_hash(&spec)
    }
}

/// `sha256:` and the hex digest of `bytes`: how tasks and families are identified.
pub(crate) fn sha256_id(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    format!("sha256:{}", Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect::<String>())
}

impl Task {
    /// Reads and compiles a task file.
    ///
    /// # Errors
    /// An unreadable file, or anything [`Task::from_toml`] reports.
    pub fn from_file(path: &Path) -> Result<Task, TaskError> {
        let origin = path.display().to_string();
        let err = |line, message| TaskError { origin: origin.clone(), line, message };
        let text = crate::support::io::read_text(path, "task file", crate::support::limits::TEXT_FILE_BYTES)
            .map_err(|e| err(None, format!("cannot read the task file: {e}")))?;
        if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) {
            return Task::from_toml(&text, Some(path));
        }
        // JSON: the same document as a JSON object, checked by the same code through its TOML
        // form (so later errors carry no line: they would count lines of that form).
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| err(Some(e.line()), format!("not JSON: {e}")))?;
        let toml = toml::to_string(&value).map_err(|e| err(None, format!("not a task: {e}")))?;
        Task::parse(&toml, &origin, Some(path)).map_err(|e| TaskError { line: None, ..e })
    }

    /// Parses and compiles task-file text; `path` names it in errors (and is recorded).
    ///
    /// # Errors
    /// [`TaskError`] with the file and line: malformed TOML (the parser's
    /// line and column), unknown keys, a task without blue or green, a bad
    /// reference, an expression that does not parse or goes out of range, …
    pub fn from_toml(text: &str, path: Option<&Path>) -> Result<Task, TaskError> {
        let origin = path.map_or_else(|| "task".to_owned(), |p| p.display().to_string());
        Task::parse(text, &origin, path)
    }

    /// As [`Task::from_toml`], with `origin` naming the text in errors.
    pub(crate) fn parse(text: &str, origin: &str, path: Option<&Path>) -> Result<Task, TaskError> {
        let spec: TaskSpec = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of(text, s.start));
            TaskError { origin: origin.to_owned(), line, message: e.message().trim_end().to_owned() }
        })?;
        Task::compile(spec, text, path, origin)
    }

    /// Compiles a spec made in code.
    ///
    /// # Errors
    /// As [`Task::from_toml`], without line numbers.
    pub fn from_spec(spec: TaskSpec) -> Result<Task, TaskError> {
        let text = toml::to_string(&spec).map_err(|e| TaskError {
            origin: spec.id.clone(),
            line: None,
            message: format!("cannot write the spec as TOML: {e}"),
        })?;
        let origin = format!("task {}", spec.id);
        Task::compile(spec, "", None, &origin).map(|mut t| {
            t.source.toml = text;
            t
        })
    }

    fn compile(spec: TaskSpec, text: &str, path: Option<&Path>, origin: &str) -> Result<Task, TaskError> {
        let c = Checker { origin, text };
        check_settings(&c, &spec)?;
        // Entries with a count become their copies; everything below sees the copies.
        let (expanded, groups) = expand_counts(&c, &spec)?;
        check_objects(&c, &expanded)?;
        let cur = &spec.curriculum;
        // Parameters in dependency order, then their values at every level.
        let order = param_order(&c, &cur.params)?;
        let names_all: Vec<String> = order.iter().map(|(n, _)| n.clone()).collect();
        let values = (0..=cur.max_level)
            .map(|level| eval_params(&c, &order, level, cur.max_level, &BTreeMap::new()))
            .collect::<Result<Vec<_>, _>>()?;
        let starts = compile_starts(&c, &expanded, &names_all, &values)?;
        let distributions = compile_distributions(&c, &expanded, &order, &names_all, &starts, &groups)?;
        let shuffle = compile_shuffle(&c, &expanded)?;
        check_optional(&c, &expanded, &groups, &starts, &distributions, &shuffle)?;

        let hash = canonical_hash(&spec);
        let source = TaskSource { id: spec.id.clone(), path: path.map(Path::to_path_buf), toml: text.to_owned(), hash };
        let deterministic = draws_nothing(&groups, &distributions, &shuffle, &starts);
        let objects = expanded.objects.into_iter().map(Spanned::into_inner).collect();
        Ok(Task {
            spec,
            objects,
            groups,
            source,
            names: names_all,
            values,
            starts,
            distributions,
            shuffle,
            deterministic,
        })
    }
}

/// Whether a task with these compiled parts draws nothing: every count range
/// one value, no shuffle, no random start (its layouts are all the same).
pub(crate) fn draws_nothing(
    groups: &[CountGroup],
    distributions: &[Distribution],
    shuffle: &[Vec<usize>],
    starts: &[sampler::Placement],
) -> bool {
    groups.iter().all(|g| g.range[0] == g.range[1])
        && distributions.iter().flat_map(|d| &d.counts).all(|r| r[0] == r[1])
        && shuffle.is_empty()
        && starts.iter().chain(distributions.iter().flat_map(|d| &d.starts)).all(|s| !s.is_random())
}

/// The fewest copies of count group `g` that take part anywhere: in the
/// curriculum or in a named distribution.
pub(crate) fn least_count(groups: &[CountGroup], distributions: &[Distribution], g: usize) -> usize {
    distributions.iter().map(|d| d.counts[g][0]).fold(groups[g].range[0], usize::min)
}

/// Names an expression may read, and their values.
pub(crate) struct Scope<'a> {
    pub names: &'a [String],
    pub values: &'a [f64],
    pub level: usize,
    pub max_level: usize,
}

impl Scope<'_> {
    pub fn lookup(&self, name: &str) -> Option<f64> {
        match name {
            "level" => Some(self.level as f64),
            "max_level" => Some(self.max_level as f64),
            "pi" => Some(std::f64::consts::PI),
            _ => self.names.iter().position(|n| n == name).map(|i| self.values[i]),
        }
    }
}

pub(crate) fn parse_value(
    c: &Checker,
    span: Option<std::ops::Range<usize>>,
    what: &str,
    v: &Value,
) -> Result<Expr, TaskError> {
    match v {
        Value::Num(x) => Ok(Expr::Num(*x)),
        Value::Expr(s) => Expr::parse(s).map_err(|e| c.err(span, format!("{what} = {s:?} does not parse: {e}"))),
    }
}

/// The task's settings outside objects and parameters: format version, id,
/// episode length, robot, curriculum and placement, each within its range.
fn check_settings(c: &Checker, spec: &TaskSpec) -> Result<(), TaskError> {
    let text = c.text;
    if spec.version != FORMAT_VERSION {
        return Err(c.err(None, format!("version = {}: this build reads task files of version {FORMAT_VERSION}; write version = {FORMAT_VERSION}", spec.version)));
    }
    if !is_safe_id(&spec.id) {
        return Err(c.err(
            field_span(text, "id"),
            format!(
                "id = {:?}: give a versioned id such as \"MyTask-v0\" (a letter, then letters, digits, '_' or \
                 '-', ending in -vN; at most 64 characters: ids name files)",
                spec.id
            ),
        ));
    }
    crate::support::limits::EPISODE_STEPS
        .check_usize(spec.max_episode_steps)
        .map_err(|e| c.err(field_span(text, "max_episode_steps"), e))?;
    if !spec.robot.extra_height.is_finite() {
        return Err(c.err(None, "robot.extra_height must be a finite number of metres"));
    }
    let cur = &spec.curriculum;
    if cur.max_level > MAX_LEVEL {
        return Err(c.err(None, format!("curriculum.max_level = {} is above the limit {MAX_LEVEL}", cur.max_level)));
    }
    if !(0.0..=1.0).contains(&cur.success_threshold) {
        return Err(c.err(None, "curriculum.success_threshold must be in [0, 1]"));
    }
    let p = &spec.placement;
    let non_negative = |v: f64| v.is_finite() && v >= 0.0;
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !(non_negative(p.min_separation)
        && p.table_margin.is_finite()
        && non_negative(p.settle_seconds)
        && positive(p.settle_tolerance))
    {
        return Err(
            c.err(None, "placement: min_separation and settle_seconds must be ≥ 0, settle_tolerance > 0, all finite")
        );
    }
    if !crate::support::limits::within(p.settle_seconds, crate::support::limits::SETTLE_SECONDS) {
        return Err(c.err(
            field_span(text, "settle_seconds"),
            format!("placement.settle_seconds = {}: allowed are 0 to 10 s of simulated time", p.settle_seconds),
        ));
    }
    for (name, v) in [("max_attempts", p.max_attempts), ("max_reset_attempts", p.max_reset_attempts)] {
        crate::support::limits::PLACEMENT_ATTEMPTS
            .check_usize(v)
            .map_err(|e| c.err(field_span(text, name), format!("placement.{name}: {e}")))?;
    }
    if let Some(physics) = &spec.physics {
        physics.check().map_err(|e| c.err(None, e))?;
    }
    Ok(())
}

/// The spec with every entry that has a count replaced by its copies
/// (`NAME.0` … `NAME.(max-1)`, the entry's fields without the count), and
/// a distribution's start for the entry given to each copy that has none of
/// its own; the entries with a count, in file order.
fn expand_counts(c: &Checker, spec: &TaskSpec) -> Result<(TaskSpec, Vec<CountGroup>), TaskError> {
    let mut out = spec.clone();
    out.objects.clear();
    let mut groups = Vec::new();
    for o in &spec.objects {
        let (span, entry) = (o.span(), o.get_ref());
        let Some([lo, hi]) = entry.count else {
            out.objects.push(o.clone());
            continue;
        };
        if lo > hi || hi == 0 || hi > MAX_TASK_OBJECTS {
            return Err(c.err(
                Some(span),
                format!(
                    "object {:?}: count = [{lo}, {hi}]: give [min, max] with min ≤ max and 1 ≤ max ≤ \
                     {MAX_TASK_OBJECTS}",
                    entry.name
                ),
            ));
        }
        groups.push(CountGroup { entry: entry.name.clone(), first: out.objects.len(), max: hi, range: [lo, hi] });
        for k in 0..hi {
            let copy = ObjectSpec { name: format!("{}.{k}", entry.name), count: None, ..entry.clone() };
            out.objects.push(Spanned::new(span.clone(), copy));
        }
    }
    for d in out.distributions.values_mut() {
        for g in &groups {
            if let Some(start) = d.starts.remove(&g.entry) {
                for k in 0..g.max {
                    d.starts.entry(format!("{}.{k}", g.entry)).or_insert_with(|| start.clone());
                }
            }
        }
    }
    Ok((out, groups))
}

/// Objects that may be absent (a copy beyond its entry's smallest minimum
/// over the curriculum and the distributions) may not anchor another
/// object's start nor be shuffled, and the objects always there must make
/// a task (a blue and a green).
fn check_optional(
    c: &Checker,
    spec: &TaskSpec,
    groups: &[CountGroup],
    starts: &[sampler::Placement],
    distributions: &[Distribution],
    shuffle: &[Vec<usize>],
) -> Result<(), TaskError> {
    let mut optional = vec![false; spec.objects.len()];
    for (g, group) in groups.iter().enumerate() {
        let least = least_count(groups, distributions, g);
        optional[group.first + least..group.first + group.max].fill(true);
    }
    let name = |i: usize| spec.objects[i].get_ref().name.as_str();
    let all = std::iter::once(("", starts)).chain(distributions.iter().map(|d| (d.name.as_str(), &d.starts[..])));
    for (dist, starts) in all {
        for (i, s) in starts.iter().enumerate() {
            if let Some(r) = s.references().into_iter().find(|&r| optional[r]) {
                let place = if dist.is_empty() { String::new() } else { format!(" in distribution {dist:?}") };
                return Err(c.err(
                    Some(spec.objects[i].span()),
                    format!(
                        "object {:?}: its start{place} is placed relative to {:?}, which is absent in some \
                     episodes (its count's minimum is below its index): anchor it to an object that is always \
                     there",
                        name(i),
                        name(r)
                    ),
                ));
            }
        }
    }
    if let Some(&i) = shuffle.iter().flatten().find(|&&i| optional[i]) {
        return Err(c.err(
            None,
            format!("shuffle names {:?}, which is absent in some episodes: shuffle only objects always there", name(i)),
        ));
    }
    let mut colours = vec![spec.robot.gripper, spec.table.colour];
    colours.extend((0..spec.objects.len()).filter(|&i| !optional[i]).map(|i| spec.objects[i].get_ref().colour));
    colours.extend(spec.floor.as_ref().map(|f| f.colour));
    Rules::new(colours).map_err(|e| {
    c.err(
            None,
    format!("with the fewest objects its counts allow, {e}: raise the minimum of a count (the gripper, table and floor count too)"),
        )
    })?;
    Ok(())
}

/// Objects: names, shapes and masses in range, and colours the rules accept.
fn check_objects(c: &Checker, spec: &TaskSpec) -> Result<(), TaskError> {
    if spec.objects.is_empty() {
        return Err(c.err(None, "the task has no objects: add [[objects]] entries"));
    }
    if spec.objects.len() > MAX_TASK_OBJECTS {
        return Err(c.err(
            Some(spec.objects[MAX_TASK_OBJECTS].span()),
            format!("too many objects: {} (at most {MAX_TASK_OBJECTS})", spec.objects.len()),
        ));
    }
    let names: Vec<&str> = spec.objects.iter().map(|o| o.get_ref().name.as_str()).collect();
    for (i, o) in spec.objects.iter().enumerate() {
        let (span, o) = (Some(o.span()), o.get_ref());
        if o.name.trim().is_empty() || RESERVED_NAMES.contains(&o.name.as_str()) {
            return Err(c.err(
                span,
                format!("object name {:?} is empty or reserved (gripper, table, floor): choose another", o.name),
            ));
        }
        if names[..i].contains(&o.name.as_str()) {
            return Err(c.err(span, format!("two objects are named {:?}: names must be unique", o.name)));
        }
        use crate::support::limits::{within, FRICTION, HALF_EXTENT_M, MASS_KG};
        if !o.half_extents.iter().all(|&h| within(h, HALF_EXTENT_M)) {
            return Err(c.err(
                span,
                format!(
                    "object {:?}: half_extents = {:?}: each must be from {} to {} m (a block wider than the \
                     0.5 × 0.7 m table cannot stand on it)",
                    o.name, o.half_extents, HALF_EXTENT_M.0, HALF_EXTENT_M.1
                ),
            ));
        }
        if !within(o.mass, MASS_KG) {
            return Err(c.err(
                span,
                format!(
                    "object {:?}: mass = {:?}: allowed are {} to {} kg (the simulation loses accuracy beyond)",
                    o.name, o.mass, MASS_KG.0, MASS_KG.1
                ),
            ));
        }
        if o.friction.is_some_and(|f| !f.iter().all(|&v| within(v, FRICTION))) {
            return Err(c.err(
                span,
                format!("object {:?}: friction values must be from {} to {}", o.name, FRICTION.0, FRICTION.1),
            ));
        }
    }
    let mut colours = vec![spec.robot.gripper, spec.table.colour];
    colours.extend(spec.objects.iter().map(|o| o.get_ref().colour));
    colours.extend(spec.floor.as_ref().map(|f| f.colour));
    Rules::new(colours).map_err(|e| c.err(None, format!("{e} (the gripper, table and floor count too)")))?;
    Ok(())
}

/// Every object's start, checked at every level against the parameters' values there.
fn compile_starts(
    c: &Checker,
    spec: &TaskSpec,
    names_all: &[String],
    values: &[Vec<f64>],
) -> Result<Vec<sampler::Placement>, TaskError> {
    let cur = &spec.curriculum;
    let starts = spec
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| sampler::Placement::compile(c, spec, i, &o.get_ref().start, Some(o.span())))
        .collect::<Result<Vec<_>, _>>()?;
    for (level, vals) in values.iter().enumerate() {
        for (i, s) in starts.iter().enumerate() {
            s.check(
                c,
                &Scope { names: names_all, values: vals, level, max_level: cur.max_level },
                &spec.objects[i],
                &format!("at level {level}"),
            )?;
        }
    }
    Ok(starts)
}

/// The named evaluation distributions: a level, parameters replaced, starts replaced.
fn compile_distributions(
    c: &Checker,
    spec: &TaskSpec,
    order: &[(String, Expr)],
    names_all: &[String],
    starts: &[sampler::Placement],
    groups: &[CountGroup],
) -> Result<Vec<Distribution>, TaskError> {
    let (cur, text) = (&spec.curriculum, c.text);
    let names: Vec<&str> = spec.objects.iter().map(|o| o.get_ref().name.as_str()).collect();
    let mut distributions = Vec::new();
    for (name, d) in &spec.distributions {
        // (toml cannot give spans of tables made implicitly by a dotted header.)
        let span = key_span(text, &format!("distributions.{name}"));
        let level = d.level.unwrap_or(cur.max_level);
        if level > cur.max_level {
            return Err(c.err(
                span,
                format!("distribution {name:?}: level {level} is above curriculum.max_level {}", cur.max_level),
            ));
        }
        for key in d.params.keys() {
            if !cur.params.contains_key(key) {
                return Err(c.err(
                    span,
                    format!(
                        "distribution {name:?} replaces parameter {key:?}, which [curriculum.params] does not define"
                    ),
                ));
            }
        }
        let vals = eval_params(c, order, level, cur.max_level, &d.params)?;
        let mut dstarts = starts.to_vec();
        for (obj, start) in &d.starts {
            let Some(i) = names.iter().position(|n| n == obj) else {
                return Err(c.err(
                    span,
                    format!(
                        "distribution {name:?} gives a start for {obj:?}, which is not an object (objects: {})",
                        names.join(", ")
                    ),
                ));
            };
            dstarts[i] = sampler::Placement::compile(c, spec, i, start, span.clone())?;
        }
        for (i, s) in dstarts.iter().enumerate() {
            s.check(
                c,
                &Scope { names: names_all, values: &vals, level, max_level: cur.max_level },
                &spec.objects[i],
                &format!("in distribution {name:?}"),
            )?;
        }
        let mut counts: Vec<[usize; 2]> = groups.iter().map(|g| g.range).collect();
        for (entry, &[lo, hi]) in &d.counts {
            let Some(g) = groups.iter().position(|g| &g.entry == entry) else {
                return Err(c.err(
                    span,
                    format!(
                        "distribution {name:?} gives a count for {entry:?}, which is not an object entry with a count \
                     (entries with one: {})",
                        groups.iter().map(|g| g.entry.as_str()).collect::<Vec<_>>().join(", ")
                    ),
                ));
            };
            if lo > hi || hi > groups[g].max {
                return Err(c.err(
                    span,
                    format!(
                        "distribution {name:?}: counts.{entry} = [{lo}, {hi}]: give min ≤ max within the entry's \
                     [0, {}] (the scene holds {} copies)",
                        groups[g].max, groups[g].max
                    ),
                ));
            }
            counts[g] = [lo, hi];
        }
        distributions.push(Distribution { name: name.clone(), level, values: vals, starts: dstarts, counts });
    }
    Ok(distributions)
}

/// The shuffle groups: objects that exist, each in one group, alike in all but their roles.
fn compile_shuffle(c: &Checker, spec: &TaskSpec) -> Result<Vec<Vec<usize>>, TaskError> {
    let names: Vec<&str> = spec.objects.iter().map(|o| o.get_ref().name.as_str()).collect();
    let mut shuffle = Vec::new();
    let mut seen = Vec::new();
    for group in &spec.shuffle {
        let mut idx = Vec::new();
        for n in group {
            let Some(i) = names.iter().position(|m| m == n) else {
                return Err(c.err(
                    None,
                    format!("shuffle names {n:?}, which is not an object (objects: {})", names.join(", ")),
                ));
            };
            if seen.contains(&i) {
                return Err(c.err(None, format!("object {n:?} is in two shuffle groups (or twice in one)")));
            }
            seen.push(i);
            idx.push(i);
        }
        if idx.len() < 2 {
            return Err(c.err(None, "a shuffle group needs at least two objects"));
        }
        let shape = |i: usize| {
            let o = spec.objects[i].get_ref();
            (o.kind, o.half_extents, o.mass, o.friction)
        };
        if idx.iter().any(|&i| shape(i) != shape(idx[0])) {
            return Err(c.err(None, format!("shuffle group {group:?}: the objects must have the same kind, size, mass and friction (only their roles move)")));
        }
        shuffle.push(idx);
    }
    Ok(shuffle)
}

/// Parameters sorted so that each comes after those it reads; cycles and
/// unknown names are errors.
fn param_order(c: &Checker, params: &BTreeMap<String, Spanned<Value>>) -> Result<Vec<(String, Expr)>, TaskError> {
    let mut pending: Vec<(String, Expr, std::ops::Range<usize>)> = Vec::new();
    for (name, v) in params {
        if ["level", "max_level", "pi"].contains(&name.as_str()) {
            return Err(c.err(
                Some(v.span()),
                format!("parameter {name:?} shadows a built-in name (level, max_level, pi): rename it"),
            ));
        }
        let e = parse_value(c, Some(v.span()), &format!("curriculum.params.{name}"), v.get_ref())?;
        for n in e.names() {
            if !["level", "max_level", "pi"].contains(&n) && !params.contains_key(n) {
                return Err(c.err(
                    Some(v.span()),
                    format!(
                        "curriculum.params.{name} reads {n:?}, which is neither a parameter nor level, max_level or pi"
                    ),
                ));
            }
        }
        pending.push((name.clone(), e, v.span()));
    }
    let mut order: Vec<(String, Expr)> = Vec::new();
    while !pending.is_empty() {
        let ready = pending.iter().position(|(_, e, _)| {
            e.names().iter().all(|n| ["level", "max_level", "pi"].contains(n) || order.iter().any(|(m, _)| m == n))
        });
        let Some(i) = ready else {
            let (name, _, span) = &pending[0];
            return Err(c.err(
                Some(span.clone()),
                format!("curriculum.params.{name} depends on itself through other parameters: break the cycle"),
            ));
        };
        let (name, e, _) = pending.remove(i);
        order.push((name, e));
    }
    Ok(order)
}

fn eval_params(
    c: &Checker,
    order: &[(String, Expr)],
    level: usize,
    max_level: usize,
    overrides: &BTreeMap<String, Spanned<Value>>,
) -> Result<Vec<f64>, TaskError> {
    let names: Vec<String> = order.iter().map(|(n, _)| n.clone()).collect();
    let mut values = vec![f64::NAN; order.len()];
    for (i, (name, e)) in order.iter().enumerate() {
        let (e, span) = match overrides.get(name) {
            Some(v) => (parse_value(c, Some(v.span()), &format!("params.{name}"), v.get_ref())?, Some(v.span())),
            None => (e.clone(), None),
        };
        let scope = Scope { names: &names[..i], values: &values[..i], level, max_level };
        let v = e.eval(&|n| scope.lookup(n)).map_err(|m| c.err(span.clone(), format!("parameter {name}: {m}")))?;
        if !v.is_finite() {
            return Err(c.err(span, format!("parameter {name} is {v} at level {level}: expressions must stay finite")));
        }
        values[i] = v;
    }
    Ok(values)
}
