//! Why an episode ended as it did, in the colour rules' own terms: the
//! failure modes `eval` and `rollout` count, so that a success rate comes
//! with what the failed episodes did.
//!
//! An episode gets the first outcome that fits:
//!
//! | outcome | meaning |
//! |---|---|
//! | `success` | every blue object touched a green one |
//! | `failure` | red touched blue |
//! | `unstable` | the simulation went unstable (the episode was cut short) |
//! | `no_contact` | the gripper touched no block (only the table or floor, if anything): the arm never reached an object |
//! | `off_table` | a blue or green block that started on the table ended below its top: knocked off, the task usually lost |
//! | `blue_met_grey` | a blue object touched a grey block (not the table, floor or gripper) at some step, e.g. pushed into the distractor; a blue block resting on a grey one (BlocksStack-v0's pedestal) always has |
//! | `timeout` | anything else: objects moved, blue did not reach green in time |

use crate::episode::rollout::EpisodeRecord;
use crate::sim::rules::Colour;
use crate::sim::scene::xml::TABLE_TOP_Z;
use crate::task::RESERVED_NAMES;
use serde::{Deserialize, Serialize};

/// One episode's outcome (see the module documentation for the order); serialised as [`Outcome::name`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The task's success.
    Success,
    /// The task's failure (red touched blue).
    Failure,
    /// Numerical instability cut the episode short.
    Unstable,
    /// The gripper touched no block (only the table or floor, if anything).
    NoContact,
    /// A blue or green block was knocked off the table.
    OffTable,
    /// A blue object touched a grey block (and the episode did not succeed).
    BlueMetGrey,
    /// Time ran out otherwise.
    Timeout,
}

impl Outcome {
    /// Every outcome, in the order they are tested.
    pub const ALL: [Outcome; 7] = [
        Outcome::Success,
        Outcome::Failure,
        Outcome::Unstable,
        Outcome::NoContact,
        Outcome::OffTable,
        Outcome::BlueMetGrey,
        Outcome::Timeout,
    ];

    /// The outcome's name in JSON and printed summaries.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Success => "success",
            Outcome::Failure => "failure",
            Outcome::Unstable => "unstable",
            Outcome::NoContact => "no_contact",
            Outcome::OffTable => "off_table",
            Outcome::BlueMetGrey => "blue_met_grey",
            Outcome::Timeout => "timeout",
        }
    }

    /// Classifies a recorded episode.
    pub fn of(ep: &EpisodeRecord) -> Outcome {
        // Blocks are the task's objects: everything but the robot and the surfaces.
        let blocks: Vec<bool> = ep.objects.iter().map(|o| !RESERVED_NAMES.contains(&o.name.as_str())).collect();
        let colours: Vec<Option<Colour>> = ep.objects.iter().map(|o| Some(o.colour)).collect();
        let n = ep.objects.len();
        let mut touched = vec![false; n * n];
        for (a, b) in ep.steps.iter().flat_map(|s| s.touching.iter().copied()) {
            if a < n && b < n {
                touched[a * n + b] = true;
                touched[b * n + a] = true;
            }
        }
        // The record's blocks are the objects that are not reserved, in order; their heights likewise.
        let last = ep.steps.last().map_or(&ep.initial, |s| &s.state);
        let z = |state: &crate::episode::rollout::StateRecord, k: usize| state.blocks.get(k).map(|b| b.pos[2]);
        let heights: Vec<(Option<f64>, Option<f64>)> =
            (0..blocks.iter().filter(|b| **b).count()).map(|k| (z(&ep.initial, k), z(last, k))).collect();
        Outcome::classify(&Summary {
            success: ep.success,
            failure: ep.failure,
            unstable: ep.steps.iter().any(|s| s.unstable),
            colours: &colours,
            blocks: &blocks,
            gripper: ep.objects.iter().position(|o| o.name == "gripper"),
            touched: &|a, b| touched[a * n + b],
            heights: &heights,
        })
    }

    /// Classifies an episode from what it did ([`Summary`]): the one
    /// classifier behind `eval`, `rollout` and Python's `evaluate`.
    pub fn classify(s: &Summary) -> Outcome {
        if s.success {
            return Outcome::Success;
        }
        if s.failure {
            return Outcome::Failure;
        }
        if s.unstable {
            return Outcome::Unstable;
        }
        let n = s.colours.len();
        let block = |i: usize| s.blocks.get(i).copied().unwrap_or(false);
        let colour = |i: usize| s.colours.get(i).copied().flatten();
        let gripper_reached = s.gripper.is_some_and(|g| (0..n).any(|b| block(b) && (s.touched)(g, b)));
        if !gripper_reached {
            return Outcome::NoContact;
        }
        let knocked_off = (0..n).filter(|&i| block(i)).enumerate().any(|(k, i)| {
            matches!(colour(i), Some(Colour::Blue | Colour::Green))
                && matches!(s.heights.get(k), Some((Some(a), Some(b))) if *a > TABLE_TOP_Z && *b < TABLE_TOP_Z)
        });
        if knocked_off {
            return Outcome::OffTable;
        }
        let blue_grey = (0..n).any(|a| {
            colour(a) == Some(Colour::Blue)
                && (0..n).any(|b| block(b) && colour(b) == Some(Colour::Grey) && (s.touched)(a, b))
        });
        if blue_grey {
            return Outcome::BlueMetGrey;
        }
        Outcome::Timeout
    }
}

/// What [`Outcome::classify`] reads of an episode.
pub struct Summary<'a> {
    /// The task's success.
    pub success: bool,
    /// The task's failure.
    pub failure: bool,
    /// Whether the simulation went unstable.
    pub unstable: bool,
    /// Each rule object's colour (None: an absent object), in rule-object order.
    pub colours: &'a [Option<Colour>],
    /// Whether each rule object is a block (not the gripper, table or floor).
    pub blocks: &'a [bool],
    /// The gripper's index among the rule objects.
    pub gripper: Option<usize>,
    /// Whether rule objects `a` and `b` touched during the episode (either order).
    pub touched: &'a dyn Fn(usize, usize) -> bool,
    /// The k-th block's height (m) at the start and at the end (None: unknown).
    pub heights: &'a [(Option<f64>, Option<f64>)],
}

/// Episode counts per outcome.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Outcomes {
    /// Successful episodes.
    pub success: usize,
    /// Failed episodes (red touched blue).
    pub failure: usize,
    /// Episodes cut short by numerical instability.
    pub unstable: usize,
    /// Timeouts where the gripper touched no block.
    pub no_contact: usize,
    /// Timeouts where a blue or green block was knocked off the table (absent
    /// in counts written before it was told apart: counted under the others).
    #[serde(default)]
    pub off_table: usize,
    /// Timeouts where blue touched a grey block.
    pub blue_met_grey: usize,
    /// Other timeouts.
    pub timeout: usize,
}

impl Outcomes {
    /// Counts one more episode.
    pub fn add(&mut self, outcome: Outcome) {
        *self.count_mut(outcome) += 1;
    }

    /// Sums two tallies.
    pub fn merge(mut self, other: Outcomes) -> Outcomes {
        for o in Outcome::ALL {
            *self.count_mut(o) += other.count(o);
        }
        self
    }

    /// The count of one outcome.
    pub fn count(&self, outcome: Outcome) -> usize {
        match outcome {
            Outcome::Success => self.success,
            Outcome::Failure => self.failure,
            Outcome::Unstable => self.unstable,
            Outcome::NoContact => self.no_contact,
            Outcome::OffTable => self.off_table,
            Outcome::BlueMetGrey => self.blue_met_grey,
            Outcome::Timeout => self.timeout,
        }
    }

    fn count_mut(&mut self, outcome: Outcome) -> &mut usize {
        match outcome {
            Outcome::Success => &mut self.success,
            Outcome::Failure => &mut self.failure,
            Outcome::Unstable => &mut self.unstable,
            Outcome::NoContact => &mut self.no_contact,
            Outcome::OffTable => &mut self.off_table,
            Outcome::BlueMetGrey => &mut self.blue_met_grey,
            Outcome::Timeout => &mut self.timeout,
        }
    }

    /// Episodes counted.
    pub fn total(&self) -> usize {
        Outcome::ALL.iter().map(|&o| self.count(o)).sum()
    }

    /// One line for people: the unsuccessful outcomes with their shares of all
    /// episodes, e.g. `failure 0.000, no_contact 0.070, blue_met_grey 0.050,
    /// timeout 0.125` (`unstable`, `off_table` and `blue_met_grey` only when they occurred).
    pub fn summary(&self) -> String {
        let n = self.total().max(1) as f64;
        Outcome::ALL[1..]
            .iter()
            .filter(|&&o| self.count(o) > 0 || matches!(o, Outcome::Failure | Outcome::NoContact | Outcome::Timeout))
            .map(|&o| format!("{} {:.3}", o.name(), self.count(o) as f64 / n))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl<'a> FromIterator<&'a EpisodeRecord> for Outcomes {
    fn from_iter<I: IntoIterator<Item = &'a EpisodeRecord>>(iter: I) -> Self {
        let mut out = Outcomes::default();
        for ep in iter {
            out.add(Outcome::of(ep));
        }
        out
    }
}

/// Whether a stored number (a rate, an interval's end) is the one recomputed from counts, up to
/// rounding in another harness's arithmetic.
pub fn same_number(stored: f64, derived: f64) -> bool {
    stored.is_finite() && (stored - derived).abs() <= 1e-9 * derived.abs().max(1.0)
}

/// Wilson score interval for a binomial proportion at 95% (success rates of `eval`, suites and
/// Python's `blockpuzzle.evaluate`).
pub fn wilson95(successes: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (z, nf) = (1.959_963_984_540_054, n as f64);
    let p = successes as f64 / nf;
    let denom = 1.0 + z * z / nf;
    let centre = (p + z * z / (2.0 * nf)) / denom;
    let half = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::episode::rollout::{BlockPose, ObjectRecord, StateRecord, StepRecord};

    fn state() -> StateRecord {
        StateRecord { qpos: vec![], gripper: [0.0; 3], blocks: vec![] }
    }

    /// An episode of BlocksChoose's objects (gripper and table grey) whose
    /// steps touched the given pairs.
    fn episode(touching: &[&[(usize, usize)]]) -> EpisodeRecord {
        let objects = [
            ("gripper", Colour::Grey),
            ("table", Colour::Grey),
            ("blue", Colour::Blue),
            ("green", Colour::Green),
            ("grey", Colour::Grey),
        ];
        EpisodeRecord {
            env_id: "BlocksChoose-v0".into(),
            task: None,
            distribution: None,
            seed: 0,
            level: 0,
            challenge: false,
            objects: objects.iter().map(|&(n, c)| ObjectRecord { name: n.into(), colour: c, absent: false }).collect(),
            initial: state(),
            steps: touching
                .iter()
                .map(|t| StepRecord {
                    action: [0.0; 4],
                    state: state(),
                    touching: t.to_vec(),
                    reward: -1.0,
                    terminated: false,
                    truncated: false,
                    is_success: false,
                    is_failure: false,
                    unstable: false,
                })
                .collect(),
            success: false,
            failure: false,
            episode_return: 0.0,
            physics: None,
        }
    }

    #[test]
    fn each_outcome_is_recognised() {
        // Blocks on the table, the gripper on the table only: the arm never reached.
        let idle = episode(&[&[(1, 2), (1, 3), (1, 4), (0, 1)]]);
        assert_eq!(Outcome::of(&idle), Outcome::NoContact);
        // The gripper pushed blue into grey (blue touching the grey gripper and
        // the grey table does not count as meeting grey).
        let grey = episode(&[&[(0, 2), (1, 2)], &[(2, 4), (1, 4)]]);
        assert_eq!(Outcome::of(&grey), Outcome::BlueMetGrey);
        let pushed = episode(&[&[(0, 2), (1, 2)], &[(0, 2)]]);
        assert_eq!(Outcome::of(&pushed), Outcome::Timeout);
        // Touching only grey with the gripper still counts as reaching.
        assert_eq!(Outcome::of(&episode(&[&[(4, 0)]])), Outcome::Timeout);
        // A floor is a surface like the table, not a block: blue falling onto a grey
        // floor is not meeting grey, and a gripper on the floor has reached nothing.
        let mut fell = episode(&[&[(0, 2)], &[(2, 5)]]);
        fell.objects.push(ObjectRecord { name: "floor".into(), colour: Colour::Grey, absent: false });
        assert_eq!(Outcome::of(&fell), Outcome::Timeout);
        let mut floor_only = episode(&[&[(0, 5), (0, 1)]]);
        floor_only.objects.push(ObjectRecord { name: "floor".into(), colour: Colour::Grey, absent: false });
        assert_eq!(Outcome::of(&floor_only), Outcome::NoContact);

        let mut won = grey.clone();
        won.success = true;
        assert_eq!(Outcome::of(&won), Outcome::Success);
        let mut lost = idle.clone();
        lost.failure = true;
        assert_eq!(Outcome::of(&lost), Outcome::Failure);
        let mut shaky = pushed.clone();
        shaky.steps[1].unstable = true;
        assert_eq!(Outcome::of(&shaky), Outcome::Unstable);

        // Blocks knocked off the table: green (the task is lost) counts, grey (a
        // distractor out of the way) does not; neither does a block that started below.
        let z = |blue: f64, green: f64, grey: f64| StateRecord {
            blocks: [blue, green, grey]
                .iter()
                .map(|&z| BlockPose { pos: [1.3, 0.75, z], quat: [1.0, 0.0, 0.0, 0.0] })
                .collect(),
            ..state()
        };
        let mut off = grey.clone();
        off.initial = z(0.425, 0.425, 0.425);
        off.steps[1].state = z(0.425, 0.025, 0.025);
        assert_eq!(Outcome::of(&off), Outcome::OffTable);
        let mut grey_off = off.clone();
        grey_off.steps[1].state = z(0.425, 0.425, 0.025);
        assert_eq!(Outcome::of(&grey_off), Outcome::BlueMetGrey);
        let mut below = off.clone();
        below.initial = z(0.425, 0.025, 0.425);
        assert_eq!(Outcome::of(&below), Outcome::BlueMetGrey);

        let tally: Outcomes = [&idle, &grey, &pushed, &won, &lost, &shaky, &off].into_iter().collect();
        assert_eq!(
            tally,
            Outcomes { success: 1, failure: 1, unstable: 1, no_contact: 1, off_table: 1, blue_met_grey: 1, timeout: 1 }
        );
        assert_eq!(tally.merge(tally).total(), 14);
        assert_eq!(
            tally.summary(),
            "failure 0.143, unstable 0.143, no_contact 0.143, off_table 0.143, blue_met_grey 0.143, timeout 0.143"
        );
    }

    #[test]
    fn summary_keeps_the_common_classes_and_drops_empty_rare_ones() {
        let t = Outcomes { success: 3, timeout: 1, ..Outcomes::default() };
        assert_eq!(t.summary(), "failure 0.000, no_contact 0.000, timeout 0.250");
    }

    #[test]
    fn wilson_interval_matches_known_values() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-3;
        let (lo, hi) = wilson95(50, 100);
        assert!(close(lo, 0.4038) && close(hi, 0.5962), "{lo} {hi}");
        let (lo, hi) = wilson95(0, 10);
        assert!(close(lo, 0.0) && close(hi, 0.2775), "{lo} {hi}");
        let (lo, hi) = wilson95(10, 10);
        assert!(close(lo, 0.7225) && close(hi, 1.0), "{lo} {hi}");
        assert_eq!(wilson95(0, 0), (0.0, 1.0));
    }
}
