//! A plain-Rust copy of a policy network for rollouts: single-observation
//! forward passes are matrix–vector products, which are several times faster
//! here than a libtorch call on a 1×N batch (per-op overhead dominates).

use serde::{Deserialize, Serialize};

/// One dense layer, `out × in` weights in row-major order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dense {
    /// Weights, row-major `out × in`.
    pub w: Vec<f32>,
    /// Biases, `out`.
    pub b: Vec<f32>,
    /// Input size.
    pub n_in: usize,
}

impl Dense {
    fn forward(&self, x: &[f32], out: &mut Vec<f32>) {
        out.clear();
        for (row, b) in self.w.chunks_exact(self.n_in).zip(&self.b) {
            out.push(dot(row, x) + b);
        }
    }
}

/// Dot product with eight independent accumulators, which the compiler
/// vectorises (a single float accumulator cannot be reordered).
fn dot(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    let tail: f32 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    acc.iter().sum::<f32>() + tail
}

/// ReLU hidden layers and a tanh (or linear) output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TanhMlp {
    /// The layers, input first.
    pub layers: Vec<Dense>,
    /// Whether the output goes through tanh.
    pub tanh_out: bool,
}

impl TanhMlp {
    /// Whether the network is whole and sane: layers chain from `n_in`
    /// inputs to `n_out` outputs, every weight and bias is finite and at
    /// most `max_abs` in size.
    ///
    /// # Errors
    /// The first problem, naming the layer (counted from the input, 0-based).
    pub fn check(&self, n_in: usize, n_out: usize, max_abs: f32) -> Result<(), String> {
        if self.layers.is_empty() {
            return Err("the network has no layers".into());
        }
        let mut width = n_in;
        for (i, l) in self.layers.iter().enumerate() {
            if l.n_in != width || l.b.is_empty() || l.w.len() != l.b.len() * l.n_in {
                return Err(format!(
                    "layer {i} has {} weights, {} biases and {} inputs where {width} inputs were expected",
                    l.w.len(),
                    l.b.len(),
                    l.n_in
                ));
            }
            if let Some(k) = l.w.iter().chain(&l.b).position(|v| !v.is_finite() || v.abs() > max_abs) {
                let v = if k < l.w.len() { l.w[k] } else { l.b[k - l.w.len()] };
                return Err(format!(
                    "layer {i} holds {v} (element {k}): weights must be finite and at most {max_abs:e}"
                ));
            }
            width = l.b.len();
        }
        if width != n_out {
            return Err(format!("the network has {width} outputs, {n_out} expected"));
        }
        Ok(())
    }

    /// Output for one (already normalised) input.
    pub fn forward(&self, x: &[f32]) -> Vec<f32> {
        let (mut a, mut b) = (x.to_vec(), Vec::new());
        for (i, layer) in self.layers.iter().enumerate() {
            layer.forward(&a, &mut b);
            let last = i + 1 == self.layers.len();
            for v in b.iter_mut() {
                *v = if !last {
                    v.max(0.0)
                } else if self.tanh_out {
                    v.tanh()
                } else {
                    *v
                };
            }
            std::mem::swap(&mut a, &mut b);
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relu_then_tanh() {
        let net = TanhMlp {
            layers: vec![
                Dense { w: vec![1.0, 0.0, 0.0, -1.0], b: vec![0.0, 0.0], n_in: 2 },
                Dense { w: vec![1.0, 1.0], b: vec![0.5], n_in: 2 },
            ],
            tanh_out: true,
        };
        // hidden = relu([x0, -x1]) = [2, 0]; out = tanh(2 + 0 + 0.5)
        assert!((net.forward(&[2.0, 3.0])[0] - 2.5f32.tanh()).abs() < 1e-7);
    }
}
