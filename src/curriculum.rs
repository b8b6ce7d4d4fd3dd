//! Where blocks start: the curriculum levels of the paper ("Curriculum
//! Settings", values of the original BlockPuzzle code) and the challenge
//! distribution, all rejection-sampled so that every block lies on the table
//! with a block's margin and no two block centres are closer than 7.5 cm.

use rand::Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use thiserror::Error;

use crate::scene::xml::{BLOCK_HALF, TABLE_CENTER, TABLE_HALF};

/// Smallest distance between two block centres.
pub const MIN_SEPARATION: f64 = 0.075;
/// Most attempts of the rejection sampler before it gives up.
pub const MAX_ATTEMPTS: usize = 100_000;

/// Errors of block placement.
#[derive(Debug, Error, PartialEq)]
pub enum PlacementError {
    /// The sampler found no valid layout (only possible for custom layouts).
    #[error("no valid block layout after {MAX_ATTEMPTS} attempts: blocks must lie on the table and be at least {MIN_SEPARATION} m apart")]
    Exhausted,
    /// A fixed layout with the wrong number of positions.
    #[error("fixed layout has {given} positions but the scene has {expected} blocks")]
    Count { given: usize, expected: usize },
}

/// A distribution of block (x, y) positions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// BlocksTouch: blue uniform in the disc of radius R around the gripper,
    /// green at a uniform distance in [0.075, R] from it in a uniform direction;
    /// R = 0.08 + 0.025·level, capped at 0.20. Blocks: [blue, green].
    Touch,
    /// BlocksChoose: blue and green as in `Touch` with R = 0.08 + 0.025·level
    /// capped at 0.30, grey at a uniform distance in [R_min, 0.30] from their
    /// midpoint, R_min = 0.20 − 0.02·level floored at 0. Challenge mode: blue–green
    /// distance uniform in [0.15, 0.30], grey within 0.04 of their midpoint.
    /// Blocks: [blue, green, grey].
    Choose,
    /// One block uniform (by area) in the annulus [min, max] around the gripper.
    NearGripper {
        /// Inner radius.
        min: f64,
        /// Outer radius.
        max: f64,
    },
    /// Fixed positions (custom scenes, tests). Not checked against the table
    /// or the separation rule.
    Fixed(Vec<[f64; 2]>),
}

/// BlocksTouch radius at `level`.
pub fn touch_radius(level: usize) -> f64 {
    (0.08 + 0.025 * level as f64).min(0.20)
}

/// BlocksChoose `(R, R_min)` at `level`.
pub fn choose_radii(level: usize) -> (f64, f64) {
    ((0.08 + 0.025 * level as f64).min(0.30), (0.20 - 0.02 * level as f64).max(0.0))
}

/// Whether `p` is on the table with a block's margin.
pub fn on_table(p: [f64; 2]) -> bool {
    (0..2).all(|k| (p[k] - TABLE_CENTER[k]).abs() <= TABLE_HALF[k] - BLOCK_HALF)
}

/// Whether a layout is on the table and well separated.
pub fn is_valid(ps: &[[f64; 2]]) -> bool {
    ps.iter().all(|&p| on_table(p))
        && ps.iter().enumerate().all(|(i, a)| ps[i + 1..].iter().all(|b| dist(*a, *b) >= MIN_SEPARATION))
}

/// Euclidean distance in the plane.
pub fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn polar(rng: &mut impl Rng, centre: [f64; 2], r: f64) -> [f64; 2] {
    let t = rng.gen::<f64>() * TAU;
    [centre[0] + r * t.cos(), centre[1] + r * t.sin()]
}

/// Uniform by area in the annulus [r0, r1] around `centre`.
fn in_annulus(rng: &mut impl Rng, centre: [f64; 2], r0: f64, r1: f64) -> [f64; 2] {
    let u: f64 = rng.gen();
    let r = (r0 * r0 + u * (r1 * r1 - r0 * r0)).sqrt();
    polar(rng, centre, r)
}

fn uniform(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    lo + rng.gen::<f64>() * (hi - lo)
}

fn midpoint(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
}

impl Layout {
    /// Highest curriculum level (0 for layouts without a curriculum).
    pub fn max_level(&self) -> usize {
        match self {
            Layout::Touch => 5,
            Layout::Choose => 10,
            Layout::NearGripper { .. } | Layout::Fixed(_) => 0,
        }
    }

    /// Whether the layout has a challenge mode.
    pub fn has_challenge(&self) -> bool {
        matches!(self, Layout::Choose)
    }

    /// Draws block positions around the gripper's initial (x, y).
    /// `level` is clamped to [`Layout::max_level`]; `challenge` only affects `Choose`.
    ///
    /// # Errors
    /// [`PlacementError`] when no valid layout is found or a fixed layout has
    /// the wrong size.
    pub fn sample(
        &self,
        level: usize,
        challenge: bool,
        gripper: [f64; 2],
        n_blocks: usize,
        rng: &mut impl Rng,
    ) -> Result<Vec<[f64; 2]>, PlacementError> {
        if let Layout::Fixed(ps) = self {
            if ps.len() != n_blocks {
                return Err(PlacementError::Count { given: ps.len(), expected: n_blocks });
            }
            return Ok(ps.clone());
        }
        let level = level.min(self.max_level());
        for _ in 0..MAX_ATTEMPTS {
            let ps = self.draw(level, challenge, gripper, rng);
            if ps.len() == n_blocks && is_valid(&ps) {
                return Ok(ps);
            }
            if ps.len() != n_blocks {
                return Err(PlacementError::Count { given: ps.len(), expected: n_blocks });
            }
        }
        Err(PlacementError::Exhausted)
    }

    fn draw(&self, level: usize, challenge: bool, g: [f64; 2], rng: &mut impl Rng) -> Vec<[f64; 2]> {
        match self {
            Layout::Touch => {
                let r = touch_radius(level);
                let blue = in_annulus(rng, g, 0.0, r);
                let d = uniform(rng, MIN_SEPARATION, r);
                let green = polar(rng, blue, d);
                vec![blue, green]
            }
            Layout::Choose if challenge => {
                let (r, _) = choose_radii(self.max_level());
                let blue = in_annulus(rng, g, 0.0, r);
                let d = uniform(rng, 0.15, 0.30);
                let green = polar(rng, blue, d);
                let grey = in_annulus(rng, midpoint(blue, green), 0.0, 0.04);
                vec![blue, green, grey]
            }
            Layout::Choose => {
                let (r, r_min) = choose_radii(level);
                let blue = in_annulus(rng, g, 0.0, r);
                let d = uniform(rng, MIN_SEPARATION, r);
                let green = polar(rng, blue, d);
                let d = uniform(rng, r_min, 0.30);
                let grey = polar(rng, midpoint(blue, green), d);
                vec![blue, green, grey]
            }
            Layout::NearGripper { min, max } => vec![in_annulus(rng, g, *min, *max)],
            Layout::Fixed(ps) => ps.clone(),
        }
    }
}
