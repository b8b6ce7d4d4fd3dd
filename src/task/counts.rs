//! Count ranges given from outside a task file (`train --counts grey=0-2`):
//! the same task, its scene unchanged, with fewer (or more) of a counted
//! entry's copies taking part in every episode. This is how a policy trains
//! on the `count` suite's train counts (BlocksChooseN-v0 with 0–2 greys) or
//! the `obstacles` suite's (BlocksAvoid-v0 with no red block) while keeping
//! the curriculum and the observation layout the suite's test split uses.

use super::{Task, TaskError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

/// Count ranges by entry name, `[least, most]` copies taking part.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Counts(pub BTreeMap<String, [usize; 2]>);

impl FromStr for Counts {
    type Err = String;

    /// `NAME=LO-HI` or `NAME=N`, comma-separated: `grey=0-2`, `red=0`, `grey=0-2,red=1`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let mut out = BTreeMap::new();
        for part in s.split(',').map(str::trim) {
            let bad = || {
                format!("{part:?} is not a count range: write NAME=LO-HI or NAME=N (e.g. grey=0-2 or red=0), comma-separated")
            };
            let (name, range) = part.split_once('=').ok_or_else(bad)?;
            let number = |t: &str| t.trim().parse::<usize>().map_err(|_| bad());
            let [lo, hi] = match range.split_once('-') {
                Some((lo, hi)) => [number(lo)?, number(hi)?],
                None => [number(range)?; 2],
            };
            let name = name.trim();
            if name.is_empty() {
                return Err(bad());
            }
            if lo > hi {
                return Err(format!("{part:?}: the least count {lo} is above the most {hi}; write {name}={hi}-{lo}"));
            }
            if out.insert(name.to_owned(), [lo, hi]).is_some() {
                return Err(format!("{name:?} is given twice; give each entry one range"));
            }
        }
        Ok(Counts(out))
    }
}

impl fmt::Display for Counts {
    /// The form [`Counts::from_str`] reads: `grey=0-2,red=0`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self
            .0
            .iter()
            .map(|(name, [lo, hi])| if lo == hi { format!("{name}={lo}") } else { format!("{name}={lo}-{hi}") })
            .collect();
        f.write_str(&parts.join(","))
    }
}

impl Task {
    /// The same task with `counts` in place of the count ranges of the named
    /// entries, at every curriculum level and in every named distribution
    /// (so a training run's challenge episodes keep them too). The scene,
    /// the observation layout, the spec and the source are unchanged: a
    /// policy trained with other counts plays the task as written.
    ///
    /// # Errors
    /// A name that is not an entry with a count; a range beyond the entry's
    /// copies in the scene; a least count below the fewest copies the task
    /// already lets take part somewhere (its checks, such as starts anchored
    /// to a copy, hold only down to that number).
    pub fn with_counts(&self, counts: &Counts) -> Result<Task, TaskError> {
        let err = |message: String| TaskError { origin: format!("--counts for {}", self.id()), line: None, message };
        let mut task = self.clone();
        for (name, &[lo, hi]) in &counts.0 {
            let Some(g) = task.groups.iter().position(|g| &g.entry == name) else {
                let entries: Vec<&str> = task.groups.iter().map(|g| g.entry.as_str()).collect();
                return Err(err(if entries.is_empty() {
                    format!("the task has no entry with a count, so {name:?} cannot be counted; drop --counts")
                } else {
                    format!("{name:?} is not an entry with a count (the task's are: {})", entries.join(", "))
                }));
            };
            let max = task.groups[g].max;
            if hi > max {
                return Err(err(format!(
                    "{name}={lo}-{hi}: the scene holds {max} copies of {name}; give a range within 0-{max}"
                )));
            }
            let least = super::least_count(&self.groups, &self.distributions, g);
            if lo < least {
                return Err(err(format!(
                    "{name}={lo}-{hi}: the task lets no fewer than {least} copies of {name} take part anywhere \
                     (curriculum or named distributions), and its checks hold only down to that; raise the least \
                     count to {least}"
                )));
            }
            task.groups[g].range = [lo, hi];
            for d in &mut task.distributions {
                d.counts[g] = [lo, hi];
            }
        }
        task.deterministic = super::draws_nothing(&task.groups, &task.distributions, &task.shuffle, &task.starts);
        Ok(task)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// A built-in task from its file (the registry lives above this module).
    fn builtin(id: &str) -> Task {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks").join(format!("{id}.toml"));
        Task::from_file(&path).unwrap()
    }

    fn counts(s: &str) -> Counts {
        s.parse().unwrap()
    }

    #[test]
    fn parses_and_prints_ranges() {
        let c = counts("grey=0-2, red=1");
        assert_eq!(c.0["grey"], [0, 2]);
        assert_eq!(c.0["red"], [1, 1]);
        assert_eq!(c.to_string(), "grey=0-2,red=1");
        assert_eq!(counts(&c.to_string()), c);
        for bad in ["grey", "grey=", "=1", "grey=a-2", "grey=2-1", "grey=1,grey=2", "grey=-1"] {
            let e = bad.parse::<Counts>().unwrap_err();
            assert!(e.contains("grey") || e.contains("count range"), "{bad}: {e}");
        }
        assert!("grey=2-1".parse::<Counts>().unwrap_err().contains("grey=1-2"));
    }

    #[test]
    fn every_draw_keeps_to_the_given_range_and_the_scene_is_unchanged() {
        let task = builtin("BlocksChooseN-v0");
        let few = task.with_counts(&counts("grey=0-2")).unwrap();
        assert_eq!(few.object_count(), task.object_count(), "the scene keeps its four greys");
        assert_eq!(few.source, task.source);
        let group = &few.count_groups()[0];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut seen = [0usize; 5];
        let dists: Vec<Option<usize>> =
            std::iter::once(None).chain((0..few.distribution_names().len()).map(Some)).collect();
        for d in dists {
            for _ in 0..200 {
                let present = few.draw_present(d, &mut rng);
                let n = present[group.first..group.first + group.max].iter().filter(|&&p| p).count();
                seen[n] += 1;
            }
        }
        assert!(seen[0] > 0 && seen[1] > 0 && seen[2] > 0, "{seen:?}");
        assert_eq!(seen[3] + seen[4], 0, "no episode has 3 or 4 greys: {seen:?}");
        // The task as written draws them.
        let mut many = 0;
        for _ in 0..200 {
            let present = task.draw_present(None, &mut rng);
            many += usize::from(present[group.first..group.first + group.max].iter().filter(|&&p| p).count() > 2);
        }
        assert!(many > 0);
    }

    #[test]
    fn bad_counts_are_refused_naming_the_fix() {
        let choose_n = builtin("BlocksChooseN-v0");
        let e = choose_n.with_counts(&counts("red=0")).unwrap_err().to_string();
        assert!(e.contains("\"red\" is not an entry with a count") && e.contains("grey"), "{e}");
        let e = choose_n.with_counts(&counts("grey=0-5")).unwrap_err().to_string();
        assert!(e.contains("holds 4 copies") && e.contains("0-4"), "{e}");
        let choose = builtin("BlocksChoose-v0");
        let e = choose.with_counts(&counts("grey=0")).unwrap_err().to_string();
        assert!(e.contains("no entry with a count") && e.contains("drop --counts"), "{e}");
        // BlocksAvoid-v0 draws 1-3 red blocks, and 0 in its `clear` distribution: 0 is allowed.
        let avoid = builtin("BlocksAvoid-v0");
        let clear = avoid.with_counts(&counts("red=0")).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
        let g = &clear.count_groups()[0];
        assert!(clear.draw_present(None, &mut rng)[g.first..g.first + g.max].iter().all(|&p| !p));
        // Without that distribution the least is 1, and starts may rely on it.
        let mut spec = avoid.spec.clone();
        spec.distributions.remove("clear");
        let no_clear = Task::from_spec(spec).unwrap();
        let e = no_clear.with_counts(&counts("red=0-1")).unwrap_err().to_string();
        assert!(e.contains("no fewer than 1") && e.contains("raise the least count to 1"), "{e}");
        assert!(no_clear.with_counts(&counts("red=1")).is_ok());
    }
}
