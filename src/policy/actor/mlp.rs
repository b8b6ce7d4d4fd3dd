//! A plain-Rust copy of a policy network for rollouts: single-observation
//! forward passes are matrix–vector products, which are several times faster
//! here than a libtorch call on a 1×N batch (per-op overhead dominates).
//!
//! A network is an MLP, or a set network ([`SetLayout`]): the same layers,
//! the first ones an encoder applied to each present object row of an
//! `objects` observation (shared across the rows), their outputs pooled
//! (masked mean and max), then the rest a head over the robot features,
//! the pooled features and anything after the observation (a critic's
//! action). Its output does not depend on the order of the object rows nor
//! on what the rows the mask leaves out hold.

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

    /// `W x + b` as a new vector.
    fn apply(&self, x: &[f32]) -> Vec<f32> {
        let mut y = Vec::new();
        self.forward(x, &mut y);
        y
    }
}

/// The softmax of `scores` (shifted by their maximum).
fn softmax(scores: &[f32]) -> Vec<f32> {
    let top = scores.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let weights: Vec<f32> = scores.iter().map(|s| (s - top).exp()).collect();
    let total: f32 = weights.iter().sum();
    weights.iter().map(|w| w / total).collect()
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

/// How a set network reads its input: `robot | slots × object | mask`
/// (an `objects` observation, [`crate::env::ObsSpec`]), then any extra inputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetLayout {
    /// Robot features.
    pub robot: usize,
    /// Features per object row.
    pub object: usize,
    /// Object slots.
    pub slots: usize,
    /// Layers of the per-object encoder (the network's first ones); the rest are the head.
    pub encoder_layers: usize,
    /// One self-attention block after the encoder: the next [`ATTENTION_LAYERS`] layers.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub attention: bool,
    /// Pooling per colour: the masked mean and max of the rows of each colour (red,
    /// blue, green, grey: the row's colour one-hot, which the normaliser passes
    /// unchanged), instead of over all rows.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub by_colour: bool,
    /// Layer normalisation of the pooled features (no gain, no bias): the
    /// head reads them with mean 0 and variance 1 across the features,
    /// however large the encoder's outputs grow.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub norm: bool,
    /// Robot tokens: the encoder reads each row with the robot features before it and the extra
    /// inputs (a critic's action) after it, `robot | row | extra`, instead of the row alone
    /// (Zhou et al. 2022, "Policy Architectures for Compositional Generalization in Control").
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub robot_tokens: bool,
    /// Statistics per type of row: the last `fixtures` rows (the `entities` observation's gripper,
    /// table and floor) are each normalised with statistics of their own, the blocks' rows with
    /// those they share (0: every row shares one set). The network itself reads the rows alike.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub fixtures: usize,
    /// Attention pooling with a learned query instead of the mean and max: the next
    /// [`QUERY_LAYERS`] layers after the encoder (and any attention block) score each encoded row
    /// (`s = w·h + b`, the query folded into `w`) and project its value (`v = V h + c`), and the
    /// pooled vector is `Σᵢ softmaxᵢ(sᵢ / √d) vᵢ` over the present rows (zeros where none is).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub query: bool,
    /// Pre-LayerNorm transformer blocks after the encoder (0: none), each the next
    /// [`TRANSFORMER_LAYERS`] layers: `h += O·MHA(LN(h))` with [`TRANSFORMER_HEADS`] heads over the
    /// present rows, then `h += W₂ ReLU(W₁ LN(h))`; the last block's output goes through ReLU, as
    /// the encoder's does, so every pooling reads features ≥ 0. LN has no gain or bias.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub transformer: usize,
    /// The width of the rows' features: the encoder's outputs, the attention or transformer
    /// blocks' and the query pooling's (0: the network's hidden width, as the head's). A narrower
    /// row width makes the per-row layers, which run once per row, cheaper; the head's first layer
    /// projects the pooled features out to the hidden width. The weights say it too: the layout
    /// records it so that a network can be built from the layout alone.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub width: usize,
}

/// The layers of one transformer block: query, key, value and output projections, then the
/// feed-forward pair.
pub const TRANSFORMER_LAYERS: usize = 6;

/// The attention heads of a transformer block (the hidden width splits evenly between them).
pub const TRANSFORMER_HEADS: usize = 4;

/// The layers of attention pooling with a learned query: the score and the value projections.
pub const QUERY_LAYERS: usize = 2;

pub(crate) fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// The variance floor of [`SetLayout::norm`] (libtorch's `layer_norm` default).
pub const NORM_EPS: f32 = 1e-5;

/// `x` normalised to mean 0 and variance 1 (biased variance, `NORM_EPS` added), in place.
fn layer_norm(x: &mut [f32]) {
    if x.is_empty() {
        return;
    }
    let n = x.len() as f32;
    let mean = x.iter().sum::<f32>() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / n;
    let scale = 1.0 / (var + NORM_EPS).sqrt();
    for v in x.iter_mut() {
        *v = (*v - mean) * scale;
    }
}

/// The colours a row may have, in the order of the colour one-hot.
pub const COLOURS: usize = 4;

/// The layers of a self-attention block: query, key, value and output projections.
pub const ATTENTION_LAYERS: usize = 4;

impl SetLayout {
    /// The layout of a set observation (`objects`, `entities`: rows and a mask), with `encoder_layers` encoder layers.
    ///
    /// # Errors
    /// A flat observation: a set network reads object rows and a mask.
    pub fn of(spec: &crate::env::ObsSpec, encoder_layers: usize) -> Result<Self, super::FitError> {
        if !spec.mode.is_set() {
            return Err(super::FitError::SetOnFlat(spec.mode));
        }
        Ok(Self::new(spec.robot_dim(), spec.object_dim(), spec.rows(), encoder_layers))
    }

    /// `robot` features, `slots` rows of `object` features and a mask, read by an encoder of
    /// `encoder_layers` layers, with every option off (mean and max pooling of the rows alone).
    pub const fn new(robot: usize, object: usize, slots: usize, encoder_layers: usize) -> Self {
        Self {
            robot,
            object,
            slots,
            encoder_layers,
            attention: false,
            by_colour: false,
            norm: false,
            robot_tokens: false,
            fixtures: 0,
            query: false,
            transformer: 0,
            width: 0,
        }
    }

    /// The rows' feature width for a network of `hidden` units (see [`SetLayout::width`]).
    pub fn row_width(&self, hidden: usize) -> usize {
        if self.width == 0 {
            hidden
        } else {
            self.width
        }
    }

    /// The encoder's input size, with `extra` inputs after the observation: a row, or with
    /// [`SetLayout::robot_tokens`] the robot features, a row and the extra inputs.
    pub fn token_width(&self, extra: usize) -> usize {
        if self.robot_tokens {
            self.robot + self.object + extra
        } else {
            self.object
        }
    }

    /// The index of the head's first layer: after the encoder, the attention block and the query pooling.
    pub fn head_start(&self) -> usize {
        self.pool_start() + if self.query { QUERY_LAYERS } else { 0 }
    }

    /// The index of the first transformer block's first layer: after the encoder and the attention block.
    pub fn transformer_start(&self) -> usize {
        self.encoder_layers + if self.attention { ATTENTION_LAYERS } else { 0 }
    }

    /// The index of the query pooling's first layer: after the encoder, the attention block and
    /// the transformer blocks.
    pub fn pool_start(&self) -> usize {
        self.transformer_start() + self.transformer * TRANSFORMER_LAYERS
    }

    /// The same network on observations with `slots` object slots (its
    /// weights do not depend on the number of objects).
    pub fn with_slots(self, slots: usize) -> Self {
        Self { slots, ..self }
    }

    /// The observation's length: robot, rows and mask.
    pub fn obs_dim(&self) -> usize {
        self.robot + self.slots * self.object + self.slots
    }

    /// The head's input size for an encoder of `width` outputs and `extra`
    /// inputs after the observation: robot, pooled mean and max (of every
    /// colour, with `by_colour`), extra.
    pub fn head_input(&self, width: usize, extra: usize) -> usize {
        if self.query {
            return self.robot + width + extra;
        }
        self.robot + 2 * self.groups() * width + extra
    }

    /// The groups of rows pooled apart: one, or one per colour.
    pub fn groups(&self) -> usize {
        if self.by_colour {
            COLOURS
        } else {
            1
        }
    }

    /// The pooling group of an object row (as the network sees it, normalised):
    /// 0, or its colour's index (None: no colour set, pooled nowhere).
    pub fn group(&self, row: &[f32]) -> Option<usize> {
        if !self.by_colour {
            return Some(0);
        }
        let at = crate::env::COLOUR_FEATURE;
        row.get(at..at + COLOURS)?.iter().position(|&v| v > 0.5)
    }
}

/// ReLU hidden layers and a tanh (or linear) output; with `set`, a set network.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlainNet {
    /// The layers, input first.
    pub layers: Vec<Dense>,
    /// Whether the output goes through tanh.
    pub tanh_out: bool,
    /// A set network's layout (none: an MLP over the whole input).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub set: Option<SetLayout>,
    /// Layer normalisation (no gain, no bias) of every hidden layer's output before its ReLU: the
    /// MLP's, a set network's encoder's and head's (RLPD's critics, `train --critic-norm`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hidden_norm: bool,
}

impl PlainNet {
    /// The network in words, for messages that compare two: its kind, what it reads and its layers'
    /// widths.
    pub fn describe(&self) -> String {
        let widths: Vec<usize> = self.layers.iter().map(|l| l.b.len()).collect();
        match self.set {
            None => format!(
                "an MLP over {} observation features, layers {widths:?}",
                self.layers.first().map_or(0, |l| l.n_in)
            ),
            Some(s) => format!(
                "a set network over rows of {} features (robot features {}, encoder layers {}), layers {widths:?}",
                s.object, s.robot, s.encoder_layers
            ),
        }
    }

    /// Whether `other` is the same network as this one: kind, layout, layers and options (a set
    /// network's slots aside, which its weights do not depend on).
    pub fn same_network(&self, other: &PlainNet) -> bool {
        let shape = |n: &PlainNet| n.layers.iter().map(|l| (l.n_in, l.b.len(), l.w.len())).collect::<Vec<_>>();
        let layout = |n: &PlainNet| n.set.map(|s| s.with_slots(0));
        shape(self) == shape(other)
            && layout(self) == layout(other)
            && self.tanh_out == other.tanh_out
            && self.hidden_norm == other.hidden_norm
    }

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
        if let Some(s) = &self.set {
            if n_in < s.obs_dim() {
                return Err(format!(
                    "set network: its layout `set` (robot {}, slots {}, object {}) reads {} + {} × ({} + 1 mask) = {} \
                     observation values, but the normaliser has {n_in}; the layout or the normaliser was edited: \
                     restore the file (or export it again from its run's policy.json)",
                    s.robot,
                    s.slots,
                    s.object,
                    s.robot,
                    s.slots,
                    s.object,
                    s.obs_dim()
                ));
            }
            if s.encoder_layers == 0 || s.head_start() >= self.layers.len() {
                return Err(format!(
                    "set network: its layout `set` names {} encoder{} layers, but the network has {} layers in all; \
                     the layout or the layers were edited: restore the file (or export it again from its run's \
                     policy.json)",
                    s.encoder_layers,
                    if s.attention { " and 4 attention" } else { "" },
                    self.layers.len()
                ));
            }
            let width = self.layers.get(s.encoder_layers - 1).map_or(0, |l| l.b.len());
            if s.width != 0 && width != s.width {
                return Err(format!("set network: the layout's rows are {} wide, the encoder's {width}", s.width));
            }
            if s.transformer > 0 && width % TRANSFORMER_HEADS != 0 {
                return Err(format!(
                    "set network: transformer blocks of {width} features do not split into {TRANSFORMER_HEADS} heads"
                ));
            }
            if s.by_colour && s.object < crate::env::COLOUR_FEATURE + COLOURS {
                return Err(format!(
                    "set network pooled by colour over rows of {} features: the colour one-hot is features {}..{}",
                    s.object,
                    crate::env::COLOUR_FEATURE,
                    crate::env::COLOUR_FEATURE + COLOURS
                ));
            }
        }
        let mut width = self.set.map_or(n_in, |s| s.token_width(n_in - s.obs_dim()));
        // Query pooling's two layers both read the encoded rows; the value layer's outputs are pooled.
        let mut pooled = 0;
        for (i, l) in self.layers.iter().enumerate() {
            if let Some(s) = self.set.filter(|s| s.head_start() == i) {
                width = s.head_input(if s.query { pooled } else { width }, n_in - s.obs_dim());
            }
            let query = self.set.filter(|s| s.query).map(|s| i.checked_sub(s.pool_start()));
            if query == Some(Some(0)) && l.b.len() != 1 {
                return Err(format!("layer {i} scores the rows for query pooling: 1 output, not {}", l.b.len()));
            }
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
            match query {
                Some(Some(0)) => {}
                Some(Some(1)) => pooled = l.b.len(),
                _ => width = l.b.len(),
            }
        }
        if width != n_out {
            return Err(format!("the network has {width} outputs, {n_out} expected"));
        }
        Ok(())
    }

    /// Output for one (already normalised) input.
    pub fn forward(&self, x: &[f32]) -> Vec<f32> {
        match &self.set {
            None => run(&self.layers, x.to_vec(), self.tanh_out, self.hidden_norm),
            Some(s) => self.forward_set(s, x),
        }
    }

    /// The set network: encode each present row, pool, then the head.
    fn forward_set(&self, s: &SetLayout, x: &[f32]) -> Vec<f32> {
        let (front, head) = self.layers.split_at(s.head_start().min(self.layers.len()));
        let (front, pool) = front.split_at(s.pool_start().min(front.len()));
        let (front, blocks) = front.split_at(s.transformer_start().min(front.len()));
        let (encoder, attention) = front.split_at(s.encoder_layers.min(front.len()));
        let width = encoder.last().map_or(0, |l| l.b.len());
        let rows_end = s.robot + s.slots * s.object;
        // Every encoder layer ends in ReLU: pooled features are ≥ 0 (an empty set pools to 0).
        let present: Vec<&[f32]> = (0..s.slots)
            .filter(|&k| x.get(rows_end + k).is_some_and(|&m| m > 0.5))
            .map(|k| &x[s.robot + k * s.object..s.robot + (k + 1) * s.object])
            .collect();
        let extra = x.get(rows_end + s.slots..).unwrap_or(&[]);
        let token = |row: &[f32]| if s.robot_tokens { [&x[..s.robot], row, extra].concat() } else { row.to_vec() };
        let mut rows: Vec<Vec<f32>> =
            present.iter().map(|row| run_hidden(encoder, token(row), self.hidden_norm)).collect();
        if let [q, k, v, o] = attention {
            rows = attend(&rows, (q, k, v, o));
        }
        if !blocks.is_empty() {
            rows = transform(rows, blocks);
        }
        let mut input = x[..s.robot].to_vec();
        match pool {
            [score, value] => input.extend(query_pool(&rows, score, value, width)),
            _ => input.extend(mean_max_pool(s, &rows, &present, width)),
        }
        if s.norm {
            layer_norm(&mut input[s.robot..]);
        }
        input.extend_from_slice(extra);
        run(head, input, self.tanh_out, self.hidden_norm)
    }
}

/// One self-attention block over the encoded rows `h` (all present):
/// `h'ᵢ = ReLU(hᵢ + O Σⱼ softmaxⱼ(qᵢ·kⱼ / √d) vⱼ)` with `q = Q h`, `k = K h`, `v = V h`.
fn attend(h: &[Vec<f32>], (q, k, v, o): (&Dense, &Dense, &Dense, &Dense)) -> Vec<Vec<f32>> {
    let project = |l: &Dense| -> Vec<Vec<f32>> { h.iter().map(|x| l.apply(x)).collect() };
    let (qs, ks, vs) = (project(q), project(k), project(v));
    let scale = 1.0 / (q.b.len() as f32).sqrt();
    let mut out = Vec::with_capacity(h.len());
    for (hi, qi) in h.iter().zip(&qs) {
        let scores: Vec<f32> = ks.iter().map(|kj| dot(qi, kj) * scale).collect();
        let mut z = vec![0.0f32; vs.first().map_or(0, Vec::len)];
        for (p, vj) in softmax(&scores).iter().zip(&vs) {
            for (zi, x) in z.iter_mut().zip(vj) {
                *zi += p * x;
            }
        }
        out.push(hi.iter().zip(&o.apply(&z)).map(|(a, b)| (a + b).max(0.0)).collect());
    }
    out
}

/// `x` layer-normalised (see [`layer_norm`]) as a new vector.
fn normalised(x: &[f32]) -> Vec<f32> {
    let mut x = x.to_vec();
    layer_norm(&mut x);
    x
}

/// The transformer blocks `layers` ([`TRANSFORMER_LAYERS`] each, see [`SetLayout::transformer`])
/// over the encoded rows `h` (all present), then ReLU.
fn transform(mut h: Vec<Vec<f32>>, layers: &[Dense]) -> Vec<Vec<f32>> {
    for block in layers.chunks(TRANSFORMER_LAYERS) {
        let [q, k, v, o, f1, f2] = block else { break };
        let a: Vec<Vec<f32>> = h.iter().map(|x| normalised(x)).collect();
        let project = |l: &Dense| a.iter().map(|x| l.apply(x)).collect::<Vec<_>>();
        let (qs, ks, vs) = (project(q), project(k), project(v));
        let d = q.b.len();
        let dh = d / TRANSFORMER_HEADS;
        let scale = 1.0 / (dh.max(1) as f32).sqrt();
        for (hi, qi) in h.iter_mut().zip(&qs) {
            let mut z = vec![0.0f32; d];
            for head in 0..TRANSFORMER_HEADS {
                let part = head * dh..(head + 1) * dh;
                let scores: Vec<f32> = ks.iter().map(|kj| dot(&qi[part.clone()], &kj[part.clone()]) * scale).collect();
                for (p, vj) in softmax(&scores).iter().zip(&vs) {
                    for (zi, x) in z[part.clone()].iter_mut().zip(&vj[part.clone()]) {
                        *zi += p * x;
                    }
                }
            }
            hi.iter_mut().zip(o.apply(&z)).for_each(|(x, y)| *x += y);
        }
        for hi in h.iter_mut() {
            let mut inner = f1.apply(&normalised(hi));
            inner.iter_mut().for_each(|v| *v = v.max(0.0));
            hi.iter_mut().zip(f2.apply(&inner)).for_each(|(x, y)| *x += y);
        }
    }
    for hi in h.iter_mut() {
        hi.iter_mut().for_each(|v| *v = v.max(0.0));
    }
    h
}

/// The masked mean and max of the encoded rows `h` (all present; `present` their rows as
/// observed), per colour with [`SetLayout::by_colour`]: all means, then all maxima.
fn mean_max_pool(s: &SetLayout, h: &[Vec<f32>], present: &[&[f32]], width: usize) -> Vec<f32> {
    let groups = s.groups();
    let (mut sum, mut max, mut n) = (vec![0.0f32; groups * width], vec![0.0f32; groups * width], vec![0; groups]);
    for (h, row) in h.iter().zip(present) {
        let Some(g) = s.group(row) else { continue };
        n[g] += 1;
        for (i, v) in h.iter().enumerate() {
            sum[g * width + i] += v;
            max[g * width + i] = max[g * width + i].max(*v);
        }
    }
    let mut pooled: Vec<f32> = sum.iter().enumerate().map(|(i, v)| v / n[i / width.max(1)].max(1) as f32).collect();
    pooled.extend(max);
    pooled
}

/// Attention pooling with a learned query over the encoded rows `h` (all present): scores
/// `sᵢ = score(hᵢ)`, values `vᵢ = value(hᵢ)`, `Σᵢ softmaxᵢ(sᵢ / √width) vᵢ` (zeros for no rows).
fn query_pool(h: &[Vec<f32>], score: &Dense, value: &Dense, width: usize) -> Vec<f32> {
    let mut out = vec![0.0f32; value.b.len()];
    if h.is_empty() {
        return out;
    }
    let scale = 1.0 / (width.max(1) as f32).sqrt();
    let scores: Vec<f32> = h.iter().map(|x| score.apply(x)[0] * scale).collect();
    for (p, x) in softmax(&scores).iter().zip(h) {
        for (o, v) in out.iter_mut().zip(&value.apply(x)) {
            *o += p * v;
        }
    }
    out
}

/// `layers` on `x`, every output through ReLU (layer-normalised first where `norm`).
fn run_hidden(layers: &[Dense], x: Vec<f32>, norm: bool) -> Vec<f32> {
    let (mut a, mut b) = (x, Vec::new());
    for layer in layers {
        layer.forward(&a, &mut b);
        if norm {
            layer_norm(&mut b);
        }
        b.iter_mut().for_each(|v| *v = v.max(0.0));
        std::mem::swap(&mut a, &mut b);
    }
    a
}

/// `layers` on `x`: ReLU between them (each hidden output layer-normalised first where `norm`),
/// tanh (or nothing) after the last.
fn run(layers: &[Dense], x: Vec<f32>, tanh_out: bool, norm: bool) -> Vec<f32> {
    let Some((last, hidden)) = layers.split_last() else { return x };
    let a = run_hidden(hidden, x, norm);
    let mut out = Vec::new();
    last.forward(&a, &mut out);
    if tanh_out {
        out.iter_mut().for_each(|v| *v = v.tanh());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relu_then_tanh() {
        let net = PlainNet {
            layers: vec![
                Dense { w: vec![1.0, 0.0, 0.0, -1.0], b: vec![0.0, 0.0], n_in: 2 },
                Dense { w: vec![1.0, 1.0], b: vec![0.5], n_in: 2 },
            ],
            tanh_out: true,
            set: None,
            hidden_norm: false,
        };
        // hidden = relu([x0, -x1]) = [2, 0]; out = tanh(2 + 0 + 0.5)
        assert!((net.forward(&[2.0, 3.0])[0] - 2.5f32.tanh()).abs() < 1e-7);
    }
}
