//! Running observation normaliser (as in OpenAI baselines' HER DDPG):
//! mean and standard deviation from running sums, `std = sqrt(max(eps², var))`,
//! normalised values clipped to ±clip.

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
        }
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
