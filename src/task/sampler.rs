//! Drawing layouts: each object's (x, y), optional height and yaw from its
//! start spec, rejection-sampled until every object lies on the table and
//! the objects resting on it are far enough apart.
//!
//! The draw order is part of the format: objects in file order; per object
//! the distance (one uniform), then the direction (one uniform), then the
//! rectangle (two), then the yaw (one, when a range). The built-in tasks
//! reproduce the episodes of the original hand-written samplers bit for bit
//! (`tests/it/golden.rs`).

use super::expr::Expr;
use super::spec::{Anchor, Density, ObjectSpec, StartSpec, TaskSpec, Value, Yaw};
use super::{parse_value, Checker, Scope, Task, TaskError};
use crate::sim::scene::xml::{TABLE_CENTER, TABLE_HALF, TABLE_TOP_Z};
use rand::Rng;
use std::f64::consts::TAU;
use thiserror::Error;
use toml::Spanned;

/// Why no layout came out.
#[derive(Debug, Error, PartialEq)]
pub enum PlacementError {
    /// The sampler found no layout that meets the constraints.
    #[error("{task}: no valid layout after {attempts} attempts ({level}): {reason}; widen the sampling ranges or loosen [placement]")]
    Exhausted { task: String, attempts: usize, level: String, reason: String },
}

/// Where an object is placed relative to.
#[derive(Debug, Clone)]
enum Ref {
    Gripper,
    Table,
    Objects(Vec<usize>),
}

/// A compiled start.
#[derive(Debug, Clone)]
pub(crate) struct Placement {
    at: Option<[Expr; 2]>,
    anchor: Ref,
    on: Option<usize>,
    towards: Option<Ref>,
    distance: Option<([Expr; 2], Density)>,
    angle: Option<[Expr; 2]>,
    rectangle: Option<[Expr; 2]>,
    offset: Option<[Expr; 2]>,
    height: Option<Expr>,
    yaw: Option<(Expr, Option<Expr>)>,
}

/// One object's drawn start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// Centre (x, y).
    pub xy: [f64; 2],
    /// Centre height, when the start sets it (otherwise the object keeps the
    /// height it settled at on the table during set-up).
    pub z: Option<f64>,
    /// Yaw, when the start sets it (otherwise the settled orientation).
    pub yaw: Option<f64>,
}

fn uniform(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    lo + rng.gen::<f64>() * (hi - lo)
}

impl Placement {
    pub(super) fn compile(
        c: &Checker,
        spec: &TaskSpec,
        index: usize,
        s: &StartSpec,
        span: Option<std::ops::Range<usize>>,
    ) -> Result<Placement, TaskError> {
        let name = &spec.objects[index].get_ref().name;
        let earlier: Vec<&str> = spec.objects[..index].iter().map(|o| o.get_ref().name.as_str()).collect();
        let err = |m: String| c.err(span.clone(), format!("object {name:?}: {m}"));
        let resolve = |n: &str, field: &str| -> Result<usize, TaskError> {
            if let Some(i) = earlier.iter().position(|m| *m == n) {
                return Ok(i);
            }
            if spec.objects.iter().any(|o| o.get_ref().name == n) {
                return Err(err(format!("start.{field} names {n:?}, which comes later in the file; objects are placed in file order, so move {n:?} above {name:?}")));
            }
            Err(err(format!(
                "start.{field} names {n:?}, which is not an object (objects: {})",
                spec.objects.iter().map(|o| o.get_ref().name.clone()).collect::<Vec<_>>().join(", ")
            )))
        };
        let reference = |n: &str, field: &str| -> Result<Ref, TaskError> {
            match n {
                "gripper" => Ok(Ref::Gripper),
                "table" => Ok(Ref::Table),
                _ => Ok(Ref::Objects(vec![resolve(n, field)?])),
            }
        };
        let pair = |v: &Option<[Value; 2]>, field: &str| -> Result<Option<[Expr; 2]>, TaskError> {
            v.as_ref()
                .map(|[a, b]| {
                    let what = format!("object {name:?}: start.{field}");
                    Ok([parse_value(c, span.clone(), &what, a)?, parse_value(c, span.clone(), &what, b)?])
                })
                .transpose()
        };
        if s.at.is_some() && (s.around.is_some() || s.on.is_some() || s.distance.is_some() || s.rectangle.is_some()) {
            return Err(err(
                "start.at places the object absolutely: drop around, on, distance and rectangle, or drop at".into(),
            ));
        }
        if s.on.is_some() && s.around.is_some() {
            return Err(err("start.on and start.around both give the anchor: keep one".into()));
        }
        if s.on.is_some() && s.height.is_some() {
            return Err(err("start.on sets the height: drop start.height".into()));
        }
        if s.angle.is_some() && s.distance.is_none() {
            return Err(err("start.angle needs start.distance".into()));
        }
        let on = s.on.as_deref().map(|n| resolve(n, "on")).transpose()?;
        let anchor = match (&s.around, on) {
            (_, Some(i)) => Ref::Objects(vec![i]),
            (None, None) => Ref::Gripper,
            (Some(Anchor::One(n)), None) => reference(n, "around")?,
            (Some(Anchor::Centroid(ns)), None) => {
                if ns.is_empty() {
                    return Err(err("start.around = [] names no objects".into()));
                }
                Ref::Objects(ns.iter().map(|n| resolve(n, "around")).collect::<Result<_, _>>()?)
            }
        };
        let towards = s.towards.as_deref().map(|n| reference(n, "towards")).transpose()?;
        let yaw = match &s.yaw {
            None => None,
            Some(Yaw::Fixed(v)) => {
                Some((parse_value(c, span.clone(), &format!("object {name:?}: start.yaw"), v)?, None))
            }
            Some(Yaw::Range(r)) => {
                let [a, b] = pair(&Some(r.clone()), "yaw")?.expect("a range was given");
                Some((a, Some(b)))
            }
        };
        Ok(Placement {
            at: pair(&s.at, "at")?,
            anchor,
            on,
            towards,
            distance: pair(&s.distance, "distance")?.map(|d| (d, s.density)),
            angle: pair(&s.angle, "angle")?,
            rectangle: pair(&s.rectangle, "rectangle")?,
            offset: pair(&s.offset, "offset")?,
            height: s
                .height
                .as_ref()
                .map(|v| parse_value(c, span.clone(), &format!("object {name:?}: start.height"), v))
                .transpose()?,
            yaw,
        })
    }

    /// The objects this start is placed relative to (anchor, `on`, `towards`).
    pub fn references(&self) -> Vec<usize> {
        let mut out = Vec::new();
        for r in [Some(&self.anchor), self.towards.as_ref()].into_iter().flatten() {
            if let Ref::Objects(idx) = r {
                out.extend(idx);
            }
        }
        out.extend(self.on);
        out
    }

    /// Whether drawing this start uses the random generator.
    pub fn is_random(&self) -> bool {
        self.distance.is_some() || self.rectangle.is_some() || self.yaw.as_ref().is_some_and(|y| y.1.is_some())
    }

    /// Checks the start's expressions in `scope`: known names, finite values, ranges in order.
    pub(super) fn check(
        &self,
        c: &Checker,
        scope: &Scope,
        object: &Spanned<ObjectSpec>,
        when: &str,
    ) -> Result<(), TaskError> {
        let name = &object.get_ref().name;
        let span = Some(object.span());
        let eval = |field: &str, e: &Expr| -> Result<f64, TaskError> {
            let v = e
                .eval(&|n| scope.lookup(n))
                .map_err(|m| c.err(span.clone(), format!("object {name:?}: start.{field}: {m} {when}")))?;
            if !v.is_finite() {
                return Err(
                    c.err(span.clone(), format!("object {name:?}: start.{field} is {v} {when}: it must stay finite"))
                );
            }
            Ok(v)
        };
        for (field, e) in self.all_exprs() {
            eval(field, e)?;
        }
        if let Some(([lo, hi], _)) = &self.distance {
            let (lo, hi) = (eval("distance", lo)?, eval("distance", hi)?);
            if lo < 0.0 || lo > hi {
                return Err(
                    c.err(span, format!("object {name:?}: start.distance = [{lo}, {hi}] {when}: needs 0 ≤ lo ≤ hi"))
                );
            }
        }
        for (field, r) in [("angle", &self.angle), ("rectangle", &self.rectangle)] {
            if let Some([lo, hi]) = r {
                let (lo, hi) = (eval(field, lo)?, eval(field, hi)?);
                if field == "angle" && lo > hi {
                    return Err(
                        c.err(span, format!("object {name:?}: start.angle = [{lo}, {hi}] {when}: needs lo ≤ hi"))
                    );
                }
                if field == "rectangle" && (lo < 0.0 || hi < 0.0) {
                    return Err(c.err(
                        span,
                        format!("object {name:?}: start.rectangle half sides [{lo}, {hi}] {when}: must be ≥ 0"),
                    ));
                }
            }
        }
        Ok(())
    }

    fn all_exprs(&self) -> Vec<(&'static str, &Expr)> {
        let mut v: Vec<(&'static str, &Expr)> = Vec::new();
        for (name, p) in
            [("at", &self.at), ("angle", &self.angle), ("rectangle", &self.rectangle), ("offset", &self.offset)]
        {
            if let Some([a, b]) = p {
                v.push((name, a));
                v.push((name, b));
            }
        }
        if let Some(([a, b], _)) = &self.distance {
            v.push(("distance", a));
            v.push(("distance", b));
        }
        if let Some(h) = &self.height {
            v.push(("height", h));
        }
        if let Some((a, b)) = &self.yaw {
            v.push(("yaw", a));
            if let Some(b) = b {
                v.push(("yaw", b));
            }
        }
        v
    }
}

/// Half extents (x, y) of the footprint of a box with half extents `h` turned by `yaw`.
pub fn footprint(h: [f64; 3], yaw: Option<f64>) -> [f64; 2] {
    match yaw {
        None => [h[0], h[1]],
        Some(t) => {
            let (s, c) = (t.sin().abs(), t.cos().abs());
            [c * h[0] + s * h[1], s * h[0] + c * h[1]]
        }
    }
}

/// The centroid of the objects `idx` (each present: the task's checks keep
/// starts from referring to objects that may be absent).
fn centroid(placed: &[Option<Placed>], idx: &[usize]) -> [f64; 2] {
    let mut sum = [0.0; 2];
    for p in idx.iter().filter_map(|&i| placed[i]) {
        sum[0] += p.xy[0];
        sum[1] += p.xy[1];
    }
    let n = idx.len() as f64;
    [sum[0] / n, sum[1] / n]
}

impl Placement {
    fn point(r: &Ref, placed: &[Option<Placed>], gripper: [f64; 2]) -> [f64; 2] {
        match r {
            Ref::Gripper => gripper,
            Ref::Table => TABLE_CENTER,
            Ref::Objects(idx) => centroid(placed, idx),
        }
    }

    /// Draws this object's start given the objects placed before it.
    fn draw(
        &self,
        object: &ObjectSpec,
        specs: &[&ObjectSpec],
        placed: &[Option<Placed>],
        gripper: [f64; 2],
        scope: &Scope,
        rng: &mut impl Rng,
    ) -> Placed {
        // Expressions were checked at every level when the task was compiled.
        let ev = |e: &Expr| e.eval(&|n| scope.lookup(n)).unwrap_or(f64::NAN);
        let anchor = Self::point(&self.anchor, placed, gripper);
        let frame = self.towards.as_ref().map(|t| {
            let p = Self::point(t, placed, gripper);
            (p[1] - anchor[1]).atan2(p[0] - anchor[0])
        });
        let mut local: Option<[f64; 2]> = None;
        let add = |l: &mut Option<[f64; 2]>, d: [f64; 2]| {
            *l = Some(match *l {
                None => d,
                Some(v) => [v[0] + d[0], v[1] + d[1]],
            })
        };
        if let Some(([lo, hi], density)) = &self.distance {
            let (lo, hi) = (ev(lo), ev(hi));
            let r = match density {
                Density::Area => {
                    let u: f64 = rng.gen();
                    (lo * lo + u * (hi * hi - lo * lo)).sqrt()
                }
                Density::Distance => uniform(rng, lo, hi),
            };
            let (a0, a1) = self.angle.as_ref().map_or((0.0, TAU), |[a, b]| (ev(a), ev(b)));
            let t = uniform(rng, a0, a1);
            add(&mut local, [r * t.cos(), r * t.sin()]);
        }
        if let Some([a, b]) = &self.rectangle {
            let (a, b) = (ev(a), ev(b));
            let dx = uniform(rng, -a, a);
            let dy = uniform(rng, -b, b);
            add(&mut local, [dx, dy]);
        }
        if let Some([a, b]) = &self.offset {
            add(&mut local, [ev(a), ev(b)]);
        }
        let yaw = self.yaw.as_ref().map(|(a, b)| {
            let y = match b {
                Some(b) => uniform(rng, ev(a), ev(b)),
                None => ev(a),
            };
            frame.map_or(y, |f| f + y)
        });
        let xy = if let Some([x, y]) = &self.at {
            [ev(x), ev(y)]
        } else {
            match (local, frame) {
                (None, _) => anchor,
                (Some(l), None) => [anchor[0] + l[0], anchor[1] + l[1]],
                (Some(l), Some(f)) => {
                    let (s, c) = f.sin_cos();
                    [anchor[0] + c * l[0] - s * l[1], anchor[1] + s * l[0] + c * l[1]]
                }
            }
        };
        let z = match (self.on, &self.height) {
            (Some(i), _) => {
                let below = specs[i].half_extents[2];
                let z = placed[i].and_then(|p| p.z);
                Some(z.unwrap_or(TABLE_TOP_Z + below) + below + object.half_extents[2])
            }
            (None, Some(h)) => Some(TABLE_TOP_Z + ev(h)),
            (None, None) => None,
        };
        Placed { xy, z, yaw }
    }
}

impl Task {
    /// Draws which objects take part ([`Task::draw_present`]), then their
    /// starts at `level` (clamped to the maximum) or in `distribution`,
    /// around the gripper's initial (x, y), redrawing until every object
    /// lies on the table and the objects resting on it are `min_separation`
    /// apart. Absent objects are `None`.
    ///
    /// # Errors
    /// [`PlacementError::Exhausted`] after `placement.max_attempts` draws, naming the constraint that failed most.
    ///
    /// # Panics
    /// A `distribution` index that [`Task::distribution`] did not give.
    pub fn sample(
        &self,
        level: usize,
        distribution: Option<usize>,
        gripper: [f64; 2],
        rng: &mut impl Rng,
    ) -> Result<Vec<Option<Placed>>, PlacementError> {
        let present = self.draw_present(distribution, rng);
        self.sample_counted(level, distribution, gripper, &present, rng, &mut 0)
    }

    /// The starts of the objects `present` says take part (the others
    /// `None`, drawing nothing), adding the number of draws (rejected ones
    /// included) to `draws`.
    ///
    /// # Errors
    /// As [`Task::sample`].
    pub fn sample_counted(
        &self,
        level: usize,
        distribution: Option<usize>,
        gripper: [f64; 2],
        present: &[bool],
        rng: &mut impl Rng,
        draws: &mut u64,
    ) -> Result<Vec<Option<Placed>>, PlacementError> {
        let (level, values, starts) = match distribution {
            Some(d) => {
                let d = &self.distributions[d];
                (d.level, &d.values, &d.starts)
            }
            None => {
                let level = level.min(self.max_level());
                (level, &self.values[level], &self.starts)
            }
        };
        let scope = Scope { names: &self.names, values, level, max_level: self.max_level() };
        let specs: Vec<&ObjectSpec> = self.objects().collect();
        let p = &self.spec.placement;
        let mut reasons = super::Tally::default();
        let mut placed = Vec::with_capacity(specs.len());
        for _ in 0..p.max_attempts {
            *draws += 1;
            placed.clear();
            for (i, (start, object)) in starts.iter().zip(&specs).enumerate() {
                let here = present.get(i).copied().unwrap_or(true);
                let next = here.then(|| start.draw(object, &specs, &placed, gripper, &scope, rng));
                placed.push(next);
            }
            match self.broken_constraint(&placed, starts, &specs) {
                None => return Ok(placed),
                Some(r) => reasons.add(&r),
            }
        }
        let reason = reasons.most();
        Err(PlacementError::Exhausted {
            task: self.id().to_owned(),
            attempts: p.max_attempts,
            level: match distribution {
                Some(d) => format!("distribution {}", self.distributions[d].name),
                None => format!("level {level}"),
            },
            reason,
        })
    }

    /// The first constraint the layout breaks, in words.
    fn broken_constraint(
        &self,
        placed: &[Option<Placed>],
        starts: &[Placement],
        specs: &[&ObjectSpec],
    ) -> Option<String> {
        let p = &self.spec.placement;
        // Objects placed `at` fixed coordinates are where the file says, checked by nothing;
        // absent objects are nowhere.
        let free = |i: usize| starts[i].at.is_none() && placed[i].is_some();
        let at = |i: usize| placed[i].unwrap_or(Placed { xy: [0.0; 2], z: None, yaw: None });
        for (i, s) in specs.iter().enumerate().filter(|(i, _)| free(*i)) {
            let o = at(i);
            let fp = footprint(s.half_extents, o.yaw);
            if !(0..2).all(|k| (o.xy[k] - TABLE_CENTER[k]).abs() <= TABLE_HALF[k] - (fp[k] + p.table_margin)) {
                return Some(format!("{:?} off the table", s.name));
            }
        }
        let resting: Vec<usize> =
            (0..placed.len()).filter(|&i| free(i) && starts[i].on.is_none() && starts[i].height.is_none()).collect();
        for (k, &i) in resting.iter().enumerate() {
            for &j in &resting[k + 1..] {
                let (a, b) = (at(i).xy, at(j).xy);
                if (a[0] - b[0]).hypot(a[1] - b[1]) < p.min_separation {
                    return Some(format!("{:?} and {:?} closer than min_separation", specs[i].name, specs[j].name));
                }
            }
        }
        None
    }
}
