//! Running observation normaliser (as in OpenAI baselines' HER DDPG):
//! mean and standard deviation from running sums, `std = sqrt(max(eps², var))`,
//! normalised values clipped to ±clip. For a set network's `objects`
//! observation the statistics are per feature, not per slot: every object
//! row shares one mean and std per feature, counted over the rows present,
//! and the mask passes through unchanged.

use super::mlp::SetLayout;
use serde::{Deserialize, Serialize};

/// Running mean/std of each observation component.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Normalizer {
    sum: Vec<f64>,
    sumsq: Vec<f64>,
    count: u64,
    mean: Vec<f32>,
    std: Vec<f32>,
    eps: f64,
    clip: f32,
    /// Object rows share their statistics (kept in slot 0's entries of the sums).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    set: Option<SetLayout>,
    /// Object rows counted (present ones), with `set`: the blocks' rows where the layout keeps
    /// statistics per type ([`SetLayout::fixtures`]).
    #[serde(default)]
    rows: u64,
    /// With [`SetLayout::fixtures`]: each fixture row's count (present ones), in row order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    fixture_rows: Vec<u64>,
}

impl Normalizer {
    /// A normaliser of `dim` components with std floor `eps` and clip range `clip`.
    pub fn new(dim: usize, eps: f64, clip: f32) -> Self {
        Self {
            sum: vec![0.0; dim],
            sumsq: vec![0.0; dim],
            count: 0,
            mean: vec![0.0; dim],
            std: vec![1.0; dim],
            eps,
            clip,
            set: None,
            rows: 0,
            fixture_rows: Vec::new(),
        }
    }

    /// A normaliser of a set network's observations: per robot feature, per
    /// object feature shared by every slot, the mask untouched.
    pub fn for_set(layout: SetLayout, eps: f64, clip: f32) -> Self {
        Self { set: Some(layout), ..Self::new(layout.obs_dim(), eps, clip) }
    }

    /// A normaliser with the given statistics (as read from a saved policy):
    /// the running sums are rebuilt from mean, std and count, so that it
    /// normalises exactly as the one saved.
    pub fn from_stats(mean: Vec<f32>, std: Vec<f32>, count: u64, eps: f64, clip: f32) -> Self {
        let n = count as f64;
        let sum = mean.iter().map(|&m| f64::from(m) * n).collect();
        let sumsq = mean.iter().zip(&std).map(|(&m, &s)| (f64::from(s).powi(2) + f64::from(m).powi(2)) * n).collect();
        Self { sum, sumsq, count, mean, std, eps, clip, set: None, rows: 0, fixture_rows: Vec::new() }
    }

    /// The clip range of normalised values.
    pub fn clip(&self) -> f32 {
        self.clip
    }

    /// The floor of the standard deviation.
    pub fn eps(&self) -> f64 {
        self.eps
    }

    /// Whether the statistics can normalise: sizes agree, means finite and
    /// at most `max_abs`, standard deviations positive and finite, the clip
    /// range positive and finite. The error says which value is wrong.
    ///
    /// # Errors
    /// The first bad value, named.
    pub fn check(&self, max_abs: f32) -> Result<(), String> {
        if self.mean.len() != self.std.len() {
            return Err(format!("normaliser has {} means and {} standard deviations", self.mean.len(), self.std.len()));
        }
        if let Some(k) = self.mean.iter().position(|m| !m.is_finite() || m.abs() > max_abs) {
            return Err(format!("normaliser mean {k} is {}", self.mean[k]));
        }
        if let Some(k) = self.std.iter().position(|s| !s.is_finite() || *s <= 0.0 || *s > max_abs) {
            return Err(format!("normaliser standard deviation {k} is {}", self.std[k]));
        }
        if !self.clip.is_finite() || self.clip <= 0.0 {
            return Err(format!("normaliser clip range is {}", self.clip));
        }
        Ok(())
    }

    /// Number of components.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Samples seen so far.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Adds observations (a flat slice of whole rows) to the statistics and
    /// recomputes mean and std.
    pub fn update(&mut self, rows: &[f32]) {
        let d = self.dim();
        if d == 0 {
            return;
        }
        if let Some(layout) = self.set {
            return self.update_set(&layout, rows);
        }
        for row in rows.chunks_exact(d) {
            for (k, &x) in row.iter().enumerate() {
                let x = f64::from(x);
                self.sum[k] += x;
                self.sumsq[k] += x * x;
            }
            self.count += 1;
        }
        if self.count == 0 {
            return;
        }
        let n = self.count as f64;
        for k in 0..d {
            let mean = self.sum[k] / n;
            let var = (self.sumsq[k] / n - mean * mean).max(self.eps * self.eps);
            self.mean[k] = mean as f32;
            self.std[k] = var.sqrt() as f32;
        }
    }

    /// [`Normalizer::update`] with object rows sharing their statistics: the
    /// blocks' in slot 0's entries of the sums, each fixture's (with
    /// [`SetLayout::fixtures`]) in its own slot's.
    fn update_set(&mut self, s: &SetLayout, rows: &[f32]) {
        let (r, f, m) = (s.robot, s.object, s.slots);
        let blocks = m.saturating_sub(s.fixtures);
        self.fixture_rows.resize(m - blocks, 0);
        let d = self.dim();
        for row in rows.chunks_exact(d) {
            for (k, &x) in row[..r].iter().enumerate() {
                self.sum[k] += f64::from(x);
                self.sumsq[k] += f64::from(x) * f64::from(x);
            }
            for slot in (0..m).filter(|&k| row[r + m * f + k] > 0.5) {
                let into = if slot < blocks { 0 } else { slot };
                for (j, &x) in row[r + slot * f..r + (slot + 1) * f].iter().enumerate() {
                    self.sum[r + into * f + j] += f64::from(x);
                    self.sumsq[r + into * f + j] += f64::from(x) * f64::from(x);
                }
                match slot.checked_sub(blocks) {
                    None => self.rows += 1,
                    Some(i) => self.fixture_rows[i] += 1,
                }
            }
            self.count += 1;
        }
        let stats = |sum: f64, sumsq: f64, n: u64| {
            let mean = sum / n as f64;
            (mean as f32, (sumsq / n as f64 - mean * mean).max(self.eps * self.eps).sqrt() as f32)
        };
        for k in 0..r {
            if self.count > 0 {
                (self.mean[k], self.std[k]) = stats(self.sum[k], self.sumsq[k], self.count);
            }
        }
        for j in 0..f {
            if self.rows > 0 {
                let (mean, std) = stats(self.sum[r + j], self.sumsq[r + j], self.rows);
                for slot in 0..blocks {
                    (self.mean[r + slot * f + j], self.std[r + slot * f + j]) = (mean, std);
                }
            }
            for (i, &n) in self.fixture_rows.iter().enumerate().filter(|(_, &n)| n > 0) {
                let at = r + (blocks + i) * f + j;
                (self.mean[at], self.std[at]) = stats(self.sum[at], self.sumsq[at], n);
            }
        }
        // The mask: (x − 0) / 1, as it is; so are the colour one-hots that a network pooling by
        // colour reads.
        self.mean[r + m * f..].fill(0.0);
        self.std[r + m * f..].fill(1.0);
        if s.by_colour {
            for slot in 0..m {
                let at = r + slot * f + crate::env::COLOUR_FEATURE;
                self.mean[at..at + super::mlp::COLOURS].fill(0.0);
                self.std[at..at + super::mlp::COLOURS].fill(1.0);
            }
        }
    }

    /// This normaliser of a set network's observations for `layout` (the
    /// same robot and row features, another number of slots): the robot
    /// statistics, slot 0's row statistics in every block slot (set
    /// statistics are shared by the slots), each fixture's own (the last
    /// [`SetLayout::fixtures`] rows, those of the last rows here), the mask
    /// passed unchanged. The running sums are rebuilt from the statistics, each part with its own
    /// count (robot features: observations; block rows: rows; each fixture: its rows; a count not
    /// recorded, as in zoo entries, taken as one row per observation), so that training on from
    /// it (`train --init-from`) moves the statistics as the saved counts weigh them.
    pub fn with_slots(&self, layout: SetLayout) -> Self {
        let (r, f) = (layout.robot, layout.object);
        let here = (self.dim().saturating_sub(r)) / (f + 1);
        let pick = |v: &[f32], pass: f32| -> Vec<f32> {
            let mut out = v[..r.min(v.len())].to_vec();
            let row = |slot: usize| v.get(r + slot * f..r + (slot + 1) * f).unwrap_or(&[]);
            for slot in 0..layout.slots {
                let fixture = (slot + layout.fixtures).checked_sub(layout.slots);
                out.extend_from_slice(fixture.map_or(row(0), |i| row(here.saturating_sub(layout.fixtures) + i)));
            }
            out.extend(std::iter::repeat(pass).take(layout.slots));
            out
        };
        let mut n = Self::from_stats(pick(&self.mean, 0.0), pick(&self.std, 1.0), self.count, self.eps, self.clip);
        n.set = Some(layout);
        n.rows = if self.rows > 0 { self.rows } else { self.count };
        let blocks = layout.slots.saturating_sub(layout.fixtures);
        n.fixture_rows = (0..layout.slots - blocks)
            .map(|i| self.fixture_rows.get(i).copied().filter(|&c| c > 0).unwrap_or(n.rows))
            .collect();
        for slot in 0..layout.slots {
            let c = slot.checked_sub(blocks).map_or(n.rows, |i| n.fixture_rows[i]) as f64;
            for at in r + slot * f..r + (slot + 1) * f {
                let (m, sd) = (f64::from(n.mean[at]), f64::from(n.std[at]));
                (n.sum[at], n.sumsq[at]) = (m * c, (sd * sd + m * m) * c);
            }
        }
        n
    }

    /// The set network's layout whose object rows share statistics (None: per component).
    pub fn set_layout(&self) -> Option<SetLayout> {
        self.set
    }

    /// Current means.
    pub fn mean(&self) -> &[f32] {
        &self.mean
    }

    /// Current standard deviations (floored at eps).
    pub fn std(&self) -> &[f32] {
        &self.std
    }

    /// Normalises rows in place: `clip((x - mean) / std, ±clip)`.
    pub fn normalize_in_place(&self, rows: &mut [f32]) {
        let d = self.dim();
        for row in rows.chunks_exact_mut(d) {
            for (k, x) in row.iter_mut().enumerate() {
                *x = ((*x - self.mean[k]) / self.std[k]).clamp(-self.clip, self.clip);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_two_pass_mean_and_std() {
        let rows: Vec<f32> = (0..300).map(|i| ((i * 37 % 101) as f32) * 0.1 - 3.0 + (i % 3) as f32).collect();
        let mut n = Normalizer::new(3, 0.01, 5.0);
        n.update(&rows[..90]);
        n.update(&rows[90..]);
        for k in 0..3 {
            let col: Vec<f64> = rows.iter().skip(k).step_by(3).map(|&x| f64::from(x)).collect();
            let mean = col.iter().sum::<f64>() / col.len() as f64;
            let var = col.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / col.len() as f64;
            assert!((f64::from(n.mean()[k]) - mean).abs() < 1e-5, "mean {k}");
            assert!((f64::from(n.std()[k]) - var.sqrt()).abs() < 1e-4, "std {k}");
        }
    }

    #[test]
    fn set_statistics_are_per_feature_over_the_rows_present_and_the_mask_passes() {
        let layout = SetLayout::new(2, 3, 3, 1);
        // Rows (robot | 3 object rows | mask): the same objects in other slots, absent rows junk.
        let a = [
            1.0, 2.0, /**/ 1.0, 10.0, -1.0, /**/ 3.0, 20.0, 1.0, /**/ 99.0, 99.0, 99.0, /**/ 1.0,
            1.0, 0.0,
        ];
        let b = [
            3.0, 4.0, /**/ 99.0, 99.0, 99.0, /**/ 3.0, 20.0, 1.0, /**/ 1.0, 10.0, -1.0, /**/ 0.0,
            1.0, 1.0,
        ];
        let mut n = Normalizer::for_set(layout, 0.01, 5.0);
        n.update(&[a, b].concat());
        // Object features over the four present rows: (1, 3, 3, 1), (10, 20, 20, 10), (-1, 1, 1, -1).
        for slot in 0..3 {
            let at = 2 + slot * 3;
            assert_eq!(&n.mean()[at..at + 3], &[2.0, 15.0, 0.0]);
            assert_eq!(&n.std()[at..at + 3], &[1.0, 5.0, 1.0]);
        }
        assert_eq!(&n.mean()[..2], &[2.0, 3.0]);
        assert_eq!(&n.mean()[11..], &[0.0; 3]);
        assert_eq!(&n.std()[11..], &[1.0; 3]);
        let mut x = a.to_vec();
        n.normalize_in_place(&mut x);
        assert_eq!(&x[11..], &[1.0, 1.0, 0.0], "the mask passes unchanged");
        assert_eq!(&x[2..5], &[-1.0, -1.0, -1.0]);
        // The same rows in the other order of updates: the same statistics.
        let mut m = Normalizer::for_set(layout, 0.01, 5.0);
        m.update(&b);
        m.update(&a);
        assert_eq!((m.mean(), m.std()), (n.mean(), n.std()));
    }

    /// A normaliser moved to another number of slots (as `train --init-from` does) goes on
    /// counting as the original would: each part's sums weigh by its own count. A zoo entry's,
    /// which records no row count, takes one row per observation.
    #[test]
    fn a_normaliser_with_other_slots_goes_on_as_the_original_would() {
        let layout = SetLayout::new(2, 3, 3, 1);
        let rows = |seed: f32| -> Vec<f32> {
            (0..4)
                .flat_map(|k| {
                    let v = seed + k as f32;
                    [
                        v,
                        -v,
                        /**/ v,
                        2.0 * v,
                        1.0,
                        /**/ -v,
                        v,
                        0.5,
                        /**/ 9.0,
                        9.0,
                        9.0,
                        /**/ 1.0,
                        1.0,
                        0.0,
                    ]
                })
                .collect()
        };
        let mut n = Normalizer::for_set(layout, 0.01, 5.0);
        n.update(&rows(1.0));
        let mut moved = n.with_slots(layout);
        assert_eq!((moved.mean(), moved.std()), (n.mean(), n.std()));
        n.update(&rows(5.0));
        moved.update(&rows(5.0));
        for (a, b) in n.mean().iter().chain(n.std()).zip(moved.mean().iter().chain(moved.std())) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        // Read back from its statistics alone (rows unknown): new rows at the mean leave the mean there.
        let bare = Normalizer {
            set: None,
            ..Normalizer::from_stats(n.mean().to_vec(), n.std().to_vec(), n.count(), 0.01, 5.0)
        };
        let mut zoo = bare.with_slots(layout);
        let at_mean: Vec<f32> = n.mean()[..2]
            .iter()
            .chain(&n.mean()[2..5])
            .chain(&n.mean()[2..5])
            .chain(&n.mean()[2..5])
            .chain(&[1.0, 1.0, 1.0])
            .copied()
            .collect();
        zoo.update(&at_mean);
        for (a, b) in zoo.mean()[..11].iter().zip(&n.mean()[..11]) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
    }

    #[test]
    fn fixture_rows_keep_statistics_of_their_own_and_the_blocks_share_theirs() {
        // Two block slots, then two fixtures (as the entities rows end with the gripper, table, floor).
        let layout = SetLayout { fixtures: 2, ..SetLayout::new(1, 2, 4, 1) };
        // robot | block, block, fixture 0, fixture 1 | mask; the second fixture absent in `b`.
        let a = [0.0, /**/ 1.0, 10.0, 3.0, 30.0, 100.0, -1.0, 7.0, 7.0, /**/ 1.0, 1.0, 1.0, 1.0];
        let b = [2.0, /**/ 5.0, 50.0, 9.0, 9.0, 300.0, 1.0, 0.0, 0.0, /**/ 1.0, 0.0, 1.0, 0.0];
        let mut n = Normalizer::for_set(layout, 0.01, 5.0);
        n.update(&[a, b].concat());
        // Blocks: rows (1, 10), (3, 30), (5, 50), in both block slots.
        for slot in 0..2 {
            assert_eq!(&n.mean()[1 + slot * 2..3 + slot * 2], &[3.0, 30.0]);
        }
        // Fixture 0: (100, -1) and (300, 1); fixture 1: (7, 7) alone (its std floored).
        assert_eq!((&n.mean()[5..7], &n.std()[5..7]), (&[200.0, 0.0][..], &[100.0, 1.0][..]));
        assert_eq!((&n.mean()[7..9], &n.std()[7..9]), (&[7.0, 7.0][..], &[0.01, 0.01][..]));
        // Without fixtures, the four rows would share one set.
        let shared = Normalizer::for_set(SetLayout { fixtures: 0, ..layout }, 0.01, 5.0);
        assert_eq!(shared.fixture_rows.len(), 0);
        // Another slot count keeps the blocks' statistics in every block slot and each fixture's own.
        let wider = n.with_slots(SetLayout { slots: 5, ..layout });
        assert_eq!(wider.dim(), 1 + 5 * 2 + 5);
        for slot in 0..3 {
            assert_eq!(&wider.mean()[1 + slot * 2..3 + slot * 2], &[3.0, 30.0]);
        }
        assert_eq!((&wider.mean()[7..11], &wider.std()[7..11]), (&n.mean()[5..9], &n.std()[5..9]));
        assert_eq!(&wider.std()[11..], &[1.0; 5]);
        // The running counts survive a checkpoint (JSON) and resume the same statistics.
        let mut back: Normalizer = serde_json::from_str(&serde_json::to_string(&n).unwrap()).unwrap();
        back.update(&a);
        n.update(&a);
        assert_eq!((back.mean(), back.std()), (n.mean(), n.std()));
    }

    #[test]
    fn floors_std_and_clips() {
        let mut n = Normalizer::new(2, 0.01, 5.0);
        n.update(&[1.0, 0.0, 1.0, 10.0]);
        assert_eq!(n.std()[0], 0.01);
        let mut x = [2.0, 5.0];
        n.normalize_in_place(&mut x);
        assert_eq!(x[0], 5.0); // (2-1)/0.01 = 100, clipped
        assert!((x[1] - 0.0).abs() < 1e-6);
    }
}
