//! The BlockPuzzle task framework, as a pure state machine.
//!
//! Objects (the gripper, the table, each block) carry one [`Colour`]. At every
//! physics substep the environment reports which object pairs touch
//! ([`Touching`]); [`Rules::observe`] turns that sequence into an verdict:
//!
//! * **failure** at the first substep where any red object touches a blue one;
//! * **success** at the first substep where every blue object touches at least
//!   one green object at the same time, with no failure before;
//! * grey objects are neutral, and red–green contact means nothing.
//!
//! If failure and success conditions first hold at the same substep, the
//! failure wins (a broken constraint is never rewarded). A task needs at least
//! one blue and one green object. Nothing here knows about MuJoCo, so the
//! rules are unit-tested with synthetic contact sequences.

use serde::{Deserialize, Serialize};
use std::fmt;
use thiserror::Error;

/// Most objects a task may have (pairs are kept in 64-bit rows).
pub const MAX_OBJECTS: usize = 64;

/// The four colours of the framework.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Colour {
    /// Constraint: must never touch blue.
    Red,
    /// Manipulated: must each touch green.
    Blue,
    /// Goal.
    Green,
    /// Neutral.
    Grey,
}

impl Colour {
    /// All colours in one-hot order.
    pub const ALL: [Colour; 4] = [Colour::Red, Colour::Blue, Colour::Green, Colour::Grey];

    /// One-hot encoding in the order red, blue, green, grey.
    pub fn one_hot(self) -> [f32; 4] {
        let mut v = [0.0; 4];
        v[self as usize] = 1.0;
        v
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Colour::Red => "red",
            Colour::Blue => "blue",
            Colour::Green => "green",
            Colour::Grey => "grey",
        }
    }
}

impl fmt::Display for Colour {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Errors in a task definition.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum RuleError {
    /// More objects than [`MAX_OBJECTS`].
    #[error("a task may have at most {MAX_OBJECTS} objects, this one has {0}")]
    TooManyObjects(usize),
    /// No blue object: nothing to succeed with.
    #[error("a task needs at least one blue (manipulated) object")]
    NoBlue,
    /// No green object: success is impossible.
    #[error("a task needs at least one green (goal) object")]
    NoGreen,
}

/// The set of object pairs in contact at one instant (symmetric, no self pairs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Touching {
    rows: Vec<u64>,
}

impl Touching {
    /// No contacts among `n` objects (`n <= MAX_OBJECTS`).
    pub fn new(n: usize) -> Self {
        Self { rows: vec![0; n.min(MAX_OBJECTS)] }
    }

    /// Number of objects.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True for a set over zero objects.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Forgets every pair.
    pub fn clear(&mut self) {
        self.rows.iter_mut().for_each(|r| *r = 0);
    }

    /// Records that `a` and `b` touch. Self pairs and unknown objects are ignored.
    pub fn insert(&mut self, a: usize, b: usize) {
        if a == b || a >= self.rows.len() || b >= self.rows.len() {
            return;
        }
        self.rows[a] |= 1 << b;
        self.rows[b] |= 1 << a;
    }

    /// Whether `a` and `b` touch.
    pub fn contains(&self, a: usize, b: usize) -> bool {
        a < self.rows.len() && b < self.rows.len() && self.rows[a] & (1 << b) != 0
    }

    /// Adds every pair of `other` (same object count).
    pub fn union_with(&mut self, other: &Touching) {
        for (r, o) in self.rows.iter_mut().zip(&other.rows) {
            *r |= o;
        }
    }

    /// The pairs `(a, b)` with `a < b`, in increasing order.
    pub fn pairs(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (a, &row) in self.rows.iter().enumerate() {
            let mut bits = row & u64::MAX.checked_shl(a as u32 + 1).unwrap_or(0); // only b > a
            while bits != 0 {
                let b = bits.trailing_zeros() as usize;
                out.push((a, b));
                bits &= bits - 1;
            }
        }
        out
    }

    /// Builds a set from a list of pairs.
    pub fn from_pairs(n: usize, pairs: &[(usize, usize)]) -> Self {
        let mut t = Touching::new(n);
        for &(a, b) in pairs {
            t.insert(a, b);
        }
        t
    }

    fn row(&self, a: usize) -> u64 {
        self.rows[a]
    }
}

/// The state of one object pair, as in the authors' contact matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactState {
    /// The pair has not touched this episode.
    NeverTouched,
    /// The pair touched earlier this episode but does not touch now.
    TouchedBefore,
    /// The pair touches at the latest substep.
    TouchingNow,
}

/// Per-pair contact history of an episode.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ContactMatrix {
    ever: Touching,
    now: Touching,
}

impl ContactMatrix {
    fn new(n: usize) -> Self {
        Self { ever: Touching::new(n), now: Touching::new(n) }
    }

    /// State of the pair `(a, b)`.
    pub fn get(&self, a: usize, b: usize) -> ContactState {
        if self.now.contains(a, b) {
            ContactState::TouchingNow
        } else if self.ever.contains(a, b) {
            ContactState::TouchedBefore
        } else {
            ContactState::NeverTouched
        }
    }

    /// The full matrix (`n × n`, diagonal `NeverTouched`).
    pub fn to_rows(&self) -> Vec<Vec<ContactState>> {
        let n = self.now.len();
        (0..n).map(|a| (0..n).map(|b| self.get(a, b)).collect()).collect()
    }
}

/// The rules' verdict on an episode (the episode-level [`crate::episode::outcome::Outcome`]
/// adds why an episode without one ended).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Every blue object touched a green one.
    Success,
    /// A red object touched a blue one.
    Failure,
}

/// The rules of one task: colours per object plus the episode's history.
#[derive(Debug, Clone)]
pub struct Rules {
    colours: Vec<Colour>,
    red: u64,
    blue: u64,
    green: u64,
    matrix: ContactMatrix,
    verdict: Option<Verdict>,
}

fn mask(colours: &[Colour], c: Colour) -> u64 {
    colours.iter().enumerate().filter(|(_, &k)| k == c).fold(0, |m, (i, _)| m | (1 << i))
}

impl Rules {
    /// Rules for objects with these colours (object `i` has `colours[i]`).
    ///
    /// # Errors
    /// [`RuleError`] for too many objects, or a task without blue or green.
    pub fn new(colours: Vec<Colour>) -> Result<Self, RuleError> {
        if colours.len() > MAX_OBJECTS {
            return Err(RuleError::TooManyObjects(colours.len()));
        }
        let (red, blue, green) =
            (mask(&colours, Colour::Red), mask(&colours, Colour::Blue), mask(&colours, Colour::Green));
        if blue == 0 {
            return Err(RuleError::NoBlue);
        }
        if green == 0 {
            return Err(RuleError::NoGreen);
        }
        let matrix = ContactMatrix::new(colours.len());
        Ok(Self { colours, red, blue, green, matrix, verdict: None })
    }

    /// Colours of the objects.
    pub fn colours(&self) -> &[Colour] {
        &self.colours
    }

    /// Forgets the episode: no verdict, empty contact matrix.
    pub fn reset(&mut self) {
        self.matrix = ContactMatrix::new(self.colours.len());
        self.verdict = None;
    }

    /// A red–blue pair among `touching`, if any (red first).
    pub fn violation(&self, touching: &Touching) -> Option<(usize, usize)> {
        let mut reds = self.red;
        while reds != 0 {
            let r = reds.trailing_zeros() as usize;
            let hit = touching.row(r) & self.blue;
            if hit != 0 {
                return Some((r, hit.trailing_zeros() as usize));
            }
            reds &= reds - 1;
        }
        None
    }

    /// Whether every blue object touches a green one in `touching`.
    pub fn all_blue_on_green(&self, touching: &Touching) -> bool {
        let mut blues = self.blue;
        while blues != 0 {
            let b = blues.trailing_zeros() as usize;
            if touching.row(b) & self.green == 0 {
                return false;
            }
            blues &= blues - 1;
        }
        true
    }

    /// Feeds the contacts of one substep. Returns the verdict if the episode
    /// has one by now (the first one is kept: later substeps cannot change it).
    pub fn observe(&mut self, touching: &Touching) -> Option<Verdict> {
        self.matrix.now.clone_from(touching);
        self.matrix.ever.union_with(touching);
        if self.verdict.is_none() {
            if self.violation(touching).is_some() {
                self.verdict = Some(Verdict::Failure);
            } else if self.all_blue_on_green(touching) {
                self.verdict = Some(Verdict::Success);
            }
        }
        self.verdict
    }

    /// The verdict so far.
    pub fn verdict(&self) -> Option<Verdict> {
        self.verdict
    }

    /// The contact-state matrix of the episode so far.
    pub fn matrix(&self) -> &ContactMatrix {
        &self.matrix
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use Colour::*;

    // objects: 0 gripper (grey), 1 table (grey), 2 blue, 3 green, 4 red, 5 grey block
    fn rules() -> Rules {
        Rules::new(vec![Grey, Grey, Blue, Green, Red, Grey]).unwrap()
    }
    fn t(pairs: &[(usize, usize)]) -> Touching {
        Touching::from_pairs(6, pairs)
    }

    #[test]
    fn blue_on_green_succeeds() {
        let mut r = rules();
        assert_eq!(r.observe(&t(&[(1, 2), (1, 3)])), None);
        assert_eq!(r.observe(&t(&[(3, 2)])), Some(Verdict::Success));
    }

    #[test]
    fn red_on_blue_fails_and_outcome_is_sticky() {
        let mut r = rules();
        assert_eq!(r.observe(&t(&[(4, 2)])), Some(Verdict::Failure));
        assert_eq!(r.observe(&t(&[(2, 3)])), Some(Verdict::Failure));
    }

    #[test]
    fn success_first_then_red_touch_keeps_success() {
        let mut r = rules();
        assert_eq!(r.observe(&t(&[(2, 3)])), Some(Verdict::Success));
        assert_eq!(r.observe(&t(&[(2, 4)])), Some(Verdict::Success));
    }

    #[test]
    fn failure_wins_a_tie() {
        let mut r = rules();
        assert_eq!(r.observe(&t(&[(2, 3), (2, 4)])), Some(Verdict::Failure));
    }

    #[test]
    fn grey_and_red_green_are_neutral() {
        let mut r = rules();
        for pairs in [&[(5, 2)][..], &[(5, 3)], &[(4, 3)], &[(0, 2), (1, 2), (0, 3)], &[(5, 4)]] {
            assert_eq!(r.observe(&t(pairs)), None, "{pairs:?}");
        }
    }

    #[test]
    fn every_blue_must_touch_green_at_the_same_time() {
        // 0 blue, 1 blue, 2 green, 3 green
        let mut r = Rules::new(vec![Blue, Blue, Green, Green]).unwrap();
        assert_eq!(r.observe(&Touching::from_pairs(4, &[(0, 2)])), None);
        assert_eq!(r.observe(&Touching::from_pairs(4, &[(1, 3)])), None);
        assert_eq!(r.observe(&Touching::from_pairs(4, &[(0, 3), (1, 3)])), Some(Verdict::Success));
    }

    #[test]
    fn blue_touching_blue_is_not_success() {
        let mut r = Rules::new(vec![Blue, Blue, Green]).unwrap();
        assert_eq!(r.observe(&Touching::from_pairs(3, &[(0, 1), (1, 2)])), None);
    }

    #[test]
    fn coloured_gripper_and_table_count() {
        // blue gripper must reach the green block; red table must not touch blue
        let mut r = Rules::new(vec![Blue, Green, Grey]).unwrap();
        assert_eq!(r.observe(&Touching::from_pairs(3, &[(0, 1)])), Some(Verdict::Success));
        let mut r = Rules::new(vec![Grey, Red, Blue, Green]).unwrap();
        assert_eq!(r.violation(&Touching::from_pairs(4, &[(1, 2)])), Some((1, 2)));
        assert_eq!(r.observe(&Touching::from_pairs(4, &[(2, 1)])), Some(Verdict::Failure));
    }

    #[test]
    fn reset_clears_history() {
        let mut r = rules();
        r.observe(&t(&[(4, 2)]));
        r.reset();
        assert_eq!(r.verdict(), None);
        assert_eq!(r.matrix().get(4, 2), ContactState::NeverTouched);
    }

    #[test]
    fn contact_matrix_tracks_never_before_now() {
        let mut r = rules();
        r.observe(&t(&[(0, 5)]));
        assert_eq!(r.matrix().get(5, 0), ContactState::TouchingNow);
        r.observe(&t(&[(1, 5)]));
        assert_eq!(r.matrix().get(0, 5), ContactState::TouchedBefore);
        assert_eq!(r.matrix().get(1, 5), ContactState::TouchingNow);
        assert_eq!(r.matrix().get(2, 3), ContactState::NeverTouched);
        let rows = r.matrix().to_rows();
        assert_eq!(rows.len(), 6);
        assert_eq!(rows[5][1], ContactState::TouchingNow);
    }

    #[test]
    fn invalid_tasks_are_rejected() {
        assert_eq!(Rules::new(vec![Green, Grey]).unwrap_err(), RuleError::NoBlue);
        assert_eq!(Rules::new(vec![Blue, Red]).unwrap_err(), RuleError::NoGreen);
        assert_eq!(Rules::new(vec![Blue; 65]).unwrap_err(), RuleError::TooManyObjects(65));
    }

    #[test]
    fn touching_pairs_are_symmetric_and_sorted() {
        let tt = Touching::from_pairs(6, &[(5, 1), (2, 0), (3, 3), (9, 1)]);
        assert_eq!(tt.pairs(), vec![(0, 2), (1, 5)]);
        assert!(tt.contains(1, 5) && tt.contains(5, 1));
    }

    #[test]
    fn one_hot_order() {
        assert_eq!(Red.one_hot(), [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(Grey.one_hot(), [0.0, 0.0, 0.0, 1.0]);
    }
}
