//! Networks as explicit parameter tensors (so that the optimiser state, the
//! target-network averaging, checkpoints and the plain-Rust rollout copy are
//! all simple loops over a list of tensors), plus an Adam optimiser whose
//! state can be saved and restored exactly.

use crate::policy::actor::mlp::{Dense, PlainNet, SetLayout, COLOURS, NORM_EPS};
use rand::Rng;
use tch::{Kind, Tensor};

/// Saved values that do not fit a network or an optimiser: how many arrays there are, or one
/// array's size.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Shape {
    /// Another number of arrays.
    #[error("expected {expected} {what}, found {found}")]
    Count {
        /// What the arrays are.
        what: &'static str,
        /// How many the network or optimiser has.
        expected: usize,
        /// How many were given.
        found: usize,
    },
    /// An array of another size.
    #[error("{what} {index} has {found} values, expected {expected}")]
    Size {
        /// What the array is.
        what: &'static str,
        /// Its place.
        index: usize,
        /// The values the network or optimiser has there.
        expected: usize,
        /// The values given.
        found: usize,
    },
}

/// The layer sizes of an MLP: `input`, `layers` × `hidden`, `output`.
pub fn mlp_sizes(input: usize, hidden: usize, layers: usize, output: usize) -> Vec<usize> {
    std::iter::once(input).chain(std::iter::repeat(hidden).take(layers)).chain(std::iter::once(output)).collect()
}

/// A fully connected network: ReLU hidden layers, linear or tanh output;
/// or, with a [`SetLayout`], a set network (see [`crate::policy::actor::mlp`]): the same
/// list of layers, the first ones a per-object encoder, the rest a head.
pub struct Net {
    /// Weight `[out, in]` and bias `[out]` of each layer, input first.
    pub params: Vec<Tensor>,
    /// The network's input size.
    input: usize,
    /// `(in, out)` of each layer.
    shapes: Vec<(usize, usize)>,
    tanh_out: bool,
    /// Hidden-to-hidden products in bfloat16 (see [`Net::with_bf16`]).
    bf16: bool,
    /// A set network's layout.
    set: Option<SetLayout>,
    /// Layer normalisation of every hidden layer's output before its ReLU (see [`Net::with_hidden_norm`]).
    hidden_norm: bool,
}

/// Glorot-uniform weights and zero biases for layers of these shapes, in order.
fn init(shapes: &[(usize, usize)], rng: &mut impl Rng) -> Vec<Tensor> {
    let mut params = Vec::new();
    for &(n_in, n_out) in shapes {
        let a = (6.0 / (n_in + n_out) as f64).sqrt() as f32;
        let data: Vec<f32> = (0..n_in * n_out).map(|_| rng.gen_range(-a..a)).collect();
        params.push(Tensor::of_slice(&data).view([n_out as i64, n_in as i64]).set_requires_grad(true));
        params.push(Tensor::zeros(&[n_out as i64], (Kind::Float, tch::Device::Cpu)).set_requires_grad(true));
    }
    params
}

impl Net {
    /// Glorot-uniform weights and zero biases (TensorFlow's dense-layer
    /// defaults, as in OpenAI baselines), drawn from `rng` so that a seed
    /// fixes the initial network.
    pub fn new(sizes: &[usize], tanh_out: bool, rng: &mut impl Rng) -> Self {
        let shapes: Vec<(usize, usize)> = sizes.windows(2).map(|w| (w[0], w[1])).collect();
        let params = init(&shapes, rng);
        Self {
            params,
            input: sizes.first().copied().unwrap_or(0),
            shapes,
            tanh_out,
            bf16: false,
            set: None,
            hidden_norm: false,
        }
    }

    /// A set network over observations of `layout` followed by `extra`
    /// inputs (a critic's action): an encoder of `encoder_layers` layers of
    /// the layout's row width ([`SetLayout::row_width`]: `hidden` unless
    /// set) applied to each object row, masked mean and max
    /// pooling, then a head of `head_layers` hidden layers of `hidden` units
    /// and `out` outputs over the robot features, the pooled features and
    /// the extra inputs. Initialised as [`Net::new`].
    pub fn new_set(
        layout: SetLayout,
        extra: usize,
        (hidden, encoder_layers, head_layers): (usize, usize, usize),
        out: usize,
        tanh_out: bool,
        rng: &mut impl Rng,
    ) -> Self {
        let layout = SetLayout { encoder_layers: encoder_layers.max(1), ..layout };
        // The per-row layers are `width` wide; the head `hidden`.
        let width = layout.row_width(hidden);
        let mut shapes = vec![(layout.token_width(extra), width)];
        shapes.extend(std::iter::repeat((width, width)).take(layout.encoder_layers - 1));
        if layout.attention {
            shapes.extend(std::iter::repeat((width, width)).take(crate::policy::actor::mlp::ATTENTION_LAYERS));
        }
        shapes.extend(
            std::iter::repeat((width, width)).take(layout.transformer * crate::policy::actor::mlp::TRANSFORMER_LAYERS),
        );
        if layout.query {
            // The score (one output per row) and the value projection.
            shapes.extend([(width, 1), (width, width)]);
        }
        let head = mlp_sizes(layout.head_input(width, extra), hidden, head_layers, out);
        shapes.extend(head.windows(2).map(|w| (w[0], w[1])));
        let params = init(&shapes, rng);
        Self {
            params,
            input: layout.obs_dim() + extra,
            shapes,
            tanh_out,
            bf16: false,
            set: Some(layout),
            hidden_norm: false,
        }
    }

    /// The libtorch twin of a plain network (the inverse of [`Net::to_plain`]),
    /// for batched forward passes of a saved network.
    ///
    /// # Errors
    /// A message naming the first layer whose sizes do not chain.
    pub(crate) fn from_plain(mlp: &PlainNet) -> Result<Self, String> {
        let Some(first) = mlp.layers.first() else {
            return Err("the network has no layers".into());
        };
        let input = match mlp.set {
            None => first.n_in,
            Some(s) => {
                let width = mlp.layers.get(s.encoder_layers.max(1) - 1).map_or(0, |l| l.b.len());
                let head_in = mlp.layers.get(s.head_start()).map_or(0, |l| l.n_in);
                s.obs_dim() + head_in.saturating_sub(s.head_input(width, 0))
            }
        };
        mlp.check(input, mlp.layers.last().map_or(0, |l| l.b.len()), f32::INFINITY)?;
        let mut params = Vec::new();
        for layer in &mlp.layers {
            let (n_in, n_out) = (layer.n_in as i64, layer.b.len() as i64);
            params.push(Tensor::of_slice(&layer.w).view([n_out, n_in]));
            params.push(Tensor::of_slice(&layer.b));
        }
        let shapes = mlp.layers.iter().map(|l| (l.n_in, l.b.len())).collect();
        Ok(Self {
            params,
            input,
            shapes,
            tanh_out: mlp.tanh_out,
            bf16: false,
            set: mlp.set,
            hidden_norm: mlp.hidden_norm,
        })
    }

    /// Layer normalisation (no gain, no bias) of every hidden layer's output before its ReLU: an
    /// MLP's, a set network's encoder's and head's (RLPD's critics, Ball et al. 2023; `--critic-norm`).
    pub fn with_hidden_norm(mut self, on: bool) -> Self {
        self.hidden_norm = on;
        self
    }

    /// `h` layer-normalised over its last dimension (no gain, no bias) where the network has
    /// [`Net::with_hidden_norm`]; else `h` itself.
    fn hidden(&self, h: Tensor) -> Tensor {
        if !self.hidden_norm {
            return h;
        }
        let width = h.size().last().copied().unwrap_or(0);
        h.layer_norm([width].as_slice(), None::<Tensor>, None::<Tensor>, NORM_EPS.into(), false)
    }

    /// Computes the matrix products whose inputs are hidden features (the
    /// bulk of the work: 91% of the multiply-adds of a 3 × 256 MLP) in
    /// bfloat16 with float accumulation, the parameters staying float (mixed
    /// precision). The products with the observation, the action and the
    /// output layer stay float. A set network's hidden products are its
    /// encoder's layers after the first, the attention block's and the head's
    /// product with the pooled features (the head's with the robot features
    /// and the action stays float). On CPUs with AMX these products run
    /// several times faster.
    pub fn with_bf16(mut self, on: bool) -> Self {
        self.bf16 = on;
        self
    }

    /// Sizes: the input, then each layer's output (an MLP's layer sizes).
    pub fn sizes(&self) -> Vec<usize> {
        std::iter::once(self.input).chain(self.shapes.iter().map(|s| s.1)).collect()
    }

    /// The set network's layout (none for an MLP).
    pub fn set_layout(&self) -> Option<SetLayout> {
        self.set
    }

    /// Output for a batch `[n, in]`.
    pub fn forward(&self, x: &Tensor) -> Tensor {
        let h = self.preactivation(x);
        if self.tanh_out {
            h.tanh()
        } else {
            h
        }
    }

    /// A critic's value Q(s̄, a): the output for the rows `[obs | act]`.
    pub fn q(&self, obs: &Tensor, act: &Tensor) -> Tensor {
        self.forward(&Tensor::cat(&[obs, act], 1))
    }

    /// The output layer's values before its `tanh` (the output itself for a linear output).
    pub fn preactivation(&self, x: &Tensor) -> Tensor {
        match self.set {
            None => self.layers(x.shallow_clone(), 0, 1),
            Some(s) => self.set_preactivation(&s, x),
        }
    }

    /// A set network's head input for a batch: robot features, the masked
    /// mean and max of the encoded rows, the extra inputs.
    fn set_preactivation(&self, s: &SetLayout, x: &Tensor) -> Tensor {
        let (r, f, m) = (s.robot as i64, s.object as i64, s.slots as i64);
        let n = x.size()[0];
        let robot = x.narrow(1, 0, r);
        let rows = x.narrow(1, r, m * f).reshape(&[n * m, f]);
        let mask = x.narrow(1, r + m * f, m).gt(0.5).to_kind(Kind::Float).unsqueeze(2);
        let extra = x.narrow(1, r + m * f + m, x.size()[1] - (r + m * f + m));
        let mut h = if s.robot_tokens {
            // Each token: the robot features, the row, the extra inputs ([n·m, r + f + e]).
            let each = |t: &Tensor| t.unsqueeze(1).expand(&[n, m, t.size()[1]], false);
            Tensor::cat(&[each(&robot), rows.reshape(&[n, m, f]), each(&extra)], 2).reshape(&[n * m, -1])
        } else {
            rows
        };
        for l in 0..s.encoder_layers {
            h = self.hidden(self.affine(&h, l, l > 0)).relu();
        }
        let mut h = h.reshape(&[n, m, -1]);
        if s.attention {
            h = self.attend(&h, &mask, s.encoder_layers);
        }
        if s.transformer > 0 {
            h = self.transform(&h, &mask, s.transformer_start(), s.transformer);
        }
        let mut pooled = if s.query {
            self.query_pool(&h, &mask, s.pool_start())
        } else {
            let (mean, max) = self.mean_max(s, x, &h, &mask);
            Tensor::cat(&[mean, max], 1)
        };
        if s.norm {
            let width = pooled.size()[1];
            pooled = pooled.layer_norm([width].as_slice(), None::<Tensor>, None::<Tensor>, NORM_EPS.into(), false);
        }
        self.head(s, robot, pooled, extra)
    }

    /// Attention pooling with a learned query (layers `first`, `first + 1`: score and value) over
    /// encoded rows `h` `[n, m, d]`, absent rows (mask 0) left out; zeros where none is present.
    fn query_pool(&self, h: &Tensor, mask: &Tensor, first: usize) -> Tensor {
        let d = h.size()[2] as f64;
        let scores = (self.affine(h, first, true) / d.sqrt()).masked_fill(&mask.eq(0.0), -1e9);
        let w = scores.softmax(1, Kind::Float);
        let any = mask.amax([1i64].as_slice(), false);
        (w * self.affine(h, first + 1, true)).sum_dim_intlist([1i64].as_slice(), false, Kind::Float) * any
    }

    /// The masked mean and max of encoded rows `h` `[n, m, d]` (per colour with `by_colour`).
    fn mean_max(&self, s: &SetLayout, x: &Tensor, h: &Tensor, mask: &Tensor) -> (Tensor, Tensor) {
        let (r, f, m) = (s.robot as i64, s.object as i64, s.slots as i64);
        let n = x.size()[0];
        // Encoded features are ≥ 0 (ReLU), so the max over masked rows (set to 0) is theirs, or 0.
        if s.by_colour {
            // weights [n, m, 4]: present rows of each colour (the one-hot passes the normaliser unchanged).
            let at = crate::env::COLOUR_FEATURE as i64;
            let hot = x.narrow(1, r, m * f).reshape(&[n, m, f]).narrow(2, at, COLOURS as i64).gt(0.5);
            let w = hot.to_kind(Kind::Float) * mask;
            let count = w.sum_dim_intlist([1i64].as_slice(), false, Kind::Float).clamp_min(1.0).unsqueeze(2);
            let mean = (w.transpose(1, 2).matmul(h) / count).reshape(&[n, -1]);
            let max: Vec<Tensor> =
                (0..COLOURS as i64).map(|c| (h * w.narrow(2, c, 1)).amax([1i64].as_slice(), false)).collect();
            (mean, Tensor::cat(&max, 1))
        } else {
            let h = h * mask;
            let count = mask.sum_dim_intlist([1i64].as_slice(), false, Kind::Float).clamp_min(1.0);
            (h.sum_dim_intlist([1i64].as_slice(), false, Kind::Float) / count, h.amax([1i64].as_slice(), false))
        }
    }

    /// The head on the robot features, the pooled features and the extra inputs.
    fn head(&self, s: &SetLayout, robot: Tensor, pooled: Tensor, extra: Tensor) -> Tensor {
        let r = s.robot as i64;
        let first = s.head_start();
        if !self.bf16 || first + 1 >= self.params.len() / 2 {
            return self.layers(Tensor::cat(&[robot, pooled, extra], 1), first, first + 1);
        }
        // The head's first (hidden) layer in three products, the pooled features' in bfloat16.
        let (w, b) = (&self.params[2 * first], &self.params[2 * first + 1]);
        let width = pooled.size()[1];
        let part = |h: &Tensor, at: i64, hidden: bool| self.product(h, &w.narrow(1, at, h.size()[1]), hidden);
        let mut h = part(&robot, 0, false) + part(&pooled, r, true) + b;
        if extra.size()[1] > 0 {
            h += part(&extra, r + width, false);
        }
        self.layers(self.hidden(h).relu(), first + 1, first + 1)
    }

    /// `h · wᵀ`, in bfloat16 with float accumulation where `hidden` (its
    /// input is hidden features) and the network is bf16.
    fn product(&self, h: &Tensor, w: &Tensor, hidden: bool) -> Tensor {
        if self.bf16 && hidden {
            h.to_kind(Kind::BFloat16).matmul(&w.to_kind(Kind::BFloat16).tr()).to_kind(Kind::Float)
        } else {
            h.matmul(&w.tr())
        }
    }

    /// Layer `l` applied to `h`, `h · Wₗᵀ + bₗ` (see [`Net::product`]).
    fn affine(&self, h: &Tensor, l: usize, hidden: bool) -> Tensor {
        self.product(h, &self.params[2 * l], hidden) + &self.params[2 * l + 1]
    }

    /// The self-attention block of layers `first..first + 4` over encoded rows
    /// `h` `[n, m, d]` whose keys the mask `[n, m, 1]` leaves out where 0 (see
    /// [`crate::policy::actor::mlp`]); rows that are absent come out as junk, masked later.
    fn attend(&self, h: &Tensor, mask: &Tensor, first: usize) -> Tensor {
        let project = |l: usize| self.affine(h, l, true);
        let (q, k, v) = (project(first), project(first + 1), project(first + 2));
        let d = h.size()[2] as f64;
        // Absent keys get −1e9: their weight is exactly 0 wherever one key is present.
        let absent = mask.transpose(1, 2).eq(0.0);
        let scores = (q.matmul(&k.transpose(1, 2)) / d.sqrt()).masked_fill(&absent, -1e9);
        let z = scores.softmax(-1, tch::Kind::Float).matmul(&v);
        let o = first + 3;
        (h + self.affine(&z, o, true)).relu()
    }

    /// `blocks` pre-LayerNorm transformer blocks of layers `first..` over encoded rows `h`
    /// `[n, m, d]` whose keys the mask `[n, m, 1]` leaves out where 0, then ReLU (see
    /// [`SetLayout::transformer`]); absent rows come out as junk, masked later.
    fn transform(&self, h: &Tensor, mask: &Tensor, first: usize, blocks: usize) -> Tensor {
        let (n, m, d) = (h.size()[0], h.size()[1], h.size()[2]);
        let heads = crate::policy::actor::mlp::TRANSFORMER_HEADS as i64;
        let dh = d / heads;
        let ln = |t: &Tensor| t.layer_norm([d].as_slice(), None::<Tensor>, None::<Tensor>, NORM_EPS.into(), false);
        // [n, 1, 1, m]: absent keys get −1e9 in every head and query.
        let absent = mask.transpose(1, 2).eq(0.0).unsqueeze(1);
        let mut h = h.shallow_clone();
        for b in 0..blocks {
            let l = first + b * crate::policy::actor::mlp::TRANSFORMER_LAYERS;
            let a = ln(&h);
            let split = |t: Tensor| t.reshape([n, m, heads, dh].as_slice()).transpose(1, 2);
            let (q, k, v) = (
                split(self.affine(&a, l, true)),
                split(self.affine(&a, l + 1, true)),
                split(self.affine(&a, l + 2, true)),
            );
            // Products of a few rows, broadcast and summed rather than batched matrix products: a
            // batched product of n·heads tiny matrices costs one BLAS call each.
            let scores = ((q.unsqueeze(3) * k.unsqueeze(2)).sum_dim_intlist([-1i64].as_slice(), false, Kind::Float)
                / (dh as f64).sqrt())
            .masked_fill(&absent, -1e9);
            let w = scores.softmax(-1, Kind::Float).unsqueeze(-1);
            let z = (w * v.unsqueeze(2))
                .sum_dim_intlist([3i64].as_slice(), false, Kind::Float)
                .transpose(1, 2)
                .reshape([n, m, d].as_slice());
            h = &h + self.affine(&z, l + 3, true);
            let inner = self.affine(&ln(&h), l + 4, true).relu();
            h = &h + self.affine(&inner, l + 5, true);
        }
        h.relu()
    }

    /// The layers from `first` on, applied to `h`: ReLU between them, none
    /// after the last; those from `hidden` on but the last read hidden features.
    fn layers(&self, mut h: Tensor, first: usize, hidden: usize) -> Tensor {
        let n_layers = self.params.len() / 2;
        for l in first..n_layers {
            h = self.affine(&h, l, l >= hidden && l + 1 < n_layers);
            if l + 1 < n_layers {
                h = self.hidden(h).relu();
            }
        }
        h
    }

    /// A copy with the same parameter values that tracks no gradients.
    pub fn detached_copy(&self) -> Net {
        Net { params: self.params.iter().map(|p| p.detach().copy()).collect(), shapes: self.shapes.clone(), ..*self }
    }

    /// The same parameters without gradient tracking (shared storage: valid
    /// until the parameters are next changed).
    pub fn detached_view(&self) -> Net {
        Net { params: self.params.iter().map(Tensor::detach).collect(), shapes: self.shapes.clone(), ..*self }
    }

    /// `self = polyak · self + (1 − polyak) · source` (target-network update).
    pub fn polyak_from(&mut self, source: &Net, polyak: f64) {
        tch::no_grad(|| {
            for (t, s) in self.params.iter_mut().zip(&source.params) {
                let mixed = &*t * polyak + s * (1.0 - polyak);
                t.copy_(&mixed);
            }
        });
    }

    /// Parameter values as flat vectors (checkpoints).
    pub fn to_vecs(&self) -> Vec<Vec<f32>> {
        self.params.iter().map(tensor_to_vec).collect()
    }

    /// Overwrites the parameter values; shapes must match.
    ///
    /// # Errors
    /// The first count or size that differs ([`Shape`]).
    pub(crate) fn load_vecs(&mut self, vecs: &[Vec<f32>]) -> Result<(), Shape> {
        if vecs.len() != self.params.len() {
            return Err(Shape::Count { what: "parameter tensors", expected: self.params.len(), found: vecs.len() });
        }
        for (i, (p, v)) in self.params.iter_mut().zip(vecs).enumerate() {
            if p.numel() != v.len() {
                return Err(Shape::Size { what: "parameter", index: i, expected: p.numel(), found: v.len() });
            }
            let src = Tensor::of_slice(v).view(p.size().as_slice());
            tch::no_grad(|| p.copy_(&src));
        }
        Ok(())
    }

    /// A plain-Rust copy for fast single-observation rollouts.
    pub fn to_plain(&self) -> PlainNet {
        let layers = self
            .shapes
            .iter()
            .enumerate()
            .map(|(l, &(n_in, _))| Dense {
                w: tensor_to_vec(&self.params[2 * l]),
                b: tensor_to_vec(&self.params[2 * l + 1]),
                n_in,
            })
            .collect();
        PlainNet { layers, tanh_out: self.tanh_out, set: self.set, hidden_norm: self.hidden_norm }
    }

    /// Sets every parameter's gradient to zero.
    pub fn zero_grad(&mut self) {
        for p in &mut self.params {
            let mut g = p.grad();
            if g.defined() {
                let _ = g.zero_();
            }
        }
    }
}

/// A tensor's values as a flat `Vec<f32>`.
pub fn tensor_to_vec(t: &Tensor) -> Vec<f32> {
    let flat = t.detach().to_kind(Kind::Float).contiguous().view(-1);
    Vec::<f32>::from(&flat)
}

/// Adam (Kingma & Ba) with bias correction, as OpenAI baselines' MpiAdam:
/// β1 = 0.9, β2 = 0.999, ε = 1e-8. Its moments are plain vectors, so the
/// state can be checkpointed and restored exactly.
///
/// The step runs in one pass over each parameter in plain Rust, with the
/// same float32 operations in the same order as libtorch's element-wise
/// kernels would do them one tensor at a time (each product, sum, square
/// root and quotient rounded to float32; scalars rounded to float32 first),
/// so its results are bit for bit those of that tensor formulation (tested),
/// at about 40% of its cost: its dozen whole-tensor passes and allocations
/// per parameter were 23% of a bf16 update's time (results/ddpg.md).
pub struct Adam {
    /// Learning rate.
    pub lr: f64,
    /// Steps taken.
    pub t: u64,
    m: Vec<Vec<f32>>,
    v: Vec<Vec<f32>>,
    /// Scratch for a parameter's values.
    values: Vec<f32>,
}

const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;
const EPS: f64 = 1e-8;

impl Adam {
    /// Zero moments for `params`.
    pub fn new(params: &[Tensor], lr: f64) -> Self {
        let zeros = || params.iter().map(|p| vec![0.0f32; p.numel()]).collect();
        Self { lr, t: 0, m: zeros(), v: zeros(), values: Vec::new() }
    }

    /// One update of `params` with their gradients flattened in parameter
    /// order (as [`append_grads`] writes them).
    ///
    /// # Panics
    /// If `grads` does not hold exactly one value per parameter value (a
    /// caller's bug: gradients are only ever produced for the same networks).
    pub fn step(&mut self, params: &mut [Tensor], grads: &[f32]) {
        let total: usize = params.iter().map(Tensor::numel).sum();
        assert_eq!(grads.len(), total, "a gradient of another layout");
        self.t += 1;
        let t = self.t as i32;
        // libtorch rounds a double scalar to the tensor's float32 before the
        // element-wise product; so do we.
        let step = (self.lr * (1.0 - BETA2.powi(t)).sqrt() / (1.0 - BETA1.powi(t))) as f32;
        let (b1, one_minus_b1) = (BETA1 as f32, (1.0 - BETA1) as f32);
        let (b2, one_minus_b2) = (BETA2 as f32, (1.0 - BETA2) as f32);
        let eps = EPS as f32;
        let mut offset = 0;
        for ((p, m), v) in params.iter_mut().zip(&mut self.m).zip(&mut self.v) {
            let n = m.len();
            let g = &grads[offset..offset + n];
            offset += n;
            self.values.resize(n, 0.0);
            p.copy_data(&mut self.values, n);
            for (((x, m), v), &g) in self.values.iter_mut().zip(m.iter_mut()).zip(v.iter_mut()).zip(g) {
                *m = *m * b1 + g * one_minus_b1;
                *v = *v * b2 + (g * g) * one_minus_b2;
                *x -= *m / (v.sqrt() + eps) * step;
            }
            let updated = Tensor::of_slice(&self.values).view(p.size().as_slice());
            tch::no_grad(|| p.copy_(&updated));
        }
    }

    /// Moments as flat vectors: all first moments, then all second moments.
    pub fn to_vecs(&self) -> Vec<Vec<f32>> {
        self.m.iter().chain(&self.v).cloned().collect()
    }

    /// Restores moments saved by [`Adam::to_vecs`] and the step count.
    ///
    /// # Errors
    /// The first count or size of the moments that differs ([`Shape`]).
    pub(crate) fn load_vecs(&mut self, vecs: &[Vec<f32>], t: u64) -> Result<(), Shape> {
        let n = self.m.len();
        if vecs.len() != 2 * n {
            return Err(Shape::Count { what: "optimiser moments", expected: 2 * n, found: vecs.len() });
        }
        for (i, (dst, src)) in self.m.iter_mut().chain(self.v.iter_mut()).zip(vecs).enumerate() {
            if dst.len() != src.len() {
                return Err(Shape::Size { what: "optimiser moment", index: i, expected: dst.len(), found: src.len() });
            }
            dst.copy_from_slice(src);
        }
        self.t = t;
        Ok(())
    }
}

/// Appends the current gradients of `params` (zeros where none was
/// computed) to `out`, flattened in parameter order.
pub fn append_grads(params: &[Tensor], out: &mut Vec<f32>) {
    for g in grads(params) {
        out.extend(tensor_to_vec(&g));
    }
}

/// The current gradients of `params` (zeros where none was computed).
pub fn grads(params: &[Tensor]) -> Vec<Tensor> {
    params
        .iter()
        .map(|p| {
            let g = p.grad();
            if g.defined() {
                g
            } else {
                Tensor::zeros_like(p)
            }
        })
        .collect()
}

impl crate::policy::actor::normalizer::Normalizer {
    /// Rows of raw observations, normalised, as a `[n, dim]` tensor.
    pub fn tensor(&self, rows: &[f32]) -> Tensor {
        let mut x = rows.to_vec();
        self.normalize_in_place(&mut x);
        Tensor::of_slice(&x).view([-1, self.dim() as i64])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn from_plain_inverts_to_plain() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let net = Net::new(&[5, 8, 1], false, &mut rng);
        let plain = net.to_plain();
        let twin = Net::from_plain(&plain).unwrap();
        assert_eq!(twin.sizes(), net.sizes());
        let x = Tensor::of_slice(&[0.3f32, -1.0, 0.5, 2.0, 0.0, 1.0, 1.0, -0.2, 0.1, 0.4]).view([2, 5]);
        assert_eq!(tensor_to_vec(&twin.forward(&x)), tensor_to_vec(&net.forward(&x)));
        let mut broken = plain;
        broken.layers[1].n_in = 7;
        assert!(Net::from_plain(&broken).err().is_some_and(|e| e.contains("layer 1")));
    }

    /// Layer-normalised hidden layers (`--critic-norm`): the MLP's and a set critic's encoder and head
    /// (in bfloat16 too), and the plain copy computes the same values.
    #[test]
    fn hidden_layer_norm_agrees_with_its_plain_copy() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let obs: Vec<f32> = (0..2 * 9).map(|_| rng.gen_range(-2.0..2.0)).collect();
        let mlp = Net::new(&[9, 16, 16, 1], false, &mut rng);
        let normed = mlp.detached_copy().with_hidden_norm(true);
        let x = Tensor::of_slice(&obs).view([2, 9]);
        let (a, b) = (tensor_to_vec(&mlp.forward(&x)), tensor_to_vec(&normed.forward(&x)));
        assert_ne!(a, b, "the norm changes the values");
        let plain = normed.to_plain();
        assert!(plain.hidden_norm);
        for (row, want) in obs.chunks(9).zip(&b) {
            assert!((plain.forward(row)[0] - want).abs() < 1e-4, "{} vs {want}", plain.forward(row)[0]);
        }
        for bf16 in [false, true] {
            let critic = Net::new_set(SET, 4, (16, 2, 2), 1, false, &mut rng).with_hidden_norm(true).with_bf16(bf16);
            let x = set_obs(&mut rng, &[true, false, true, true], 7.0, 4);
            let t = tensor_to_vec(&critic.forward(&Tensor::of_slice(&x).view([1, x.len() as i64])))[0];
            let p = critic.to_plain().forward(&x)[0];
            assert!((t - p).abs() < if bf16 { 5e-2 } else { 1e-4 }, "bf16 {bf16}: {t} vs {p}");
            let twin = Net::from_plain(&critic.to_plain()).unwrap();
            assert!(twin.hidden_norm, "from_plain keeps the norm");
        }
    }

    /// A set network's layout: 3 robot features, 4 slots of 5 features, a mask.
    const SET: SetLayout = SetLayout::new(3, 5, 4, 2);

    /// One observation of [`SET`] with the slots `present` (the others hold `fill`), then `extra`.
    fn set_obs(rng: &mut impl Rng, present: &[bool; 4], fill: f32, extra: usize) -> Vec<f32> {
        let mut x: Vec<f32> = (0..SET.robot).map(|_| rng.gen_range(-1.0..1.0)).collect();
        for &p in present {
            x.extend((0..SET.object).map(|_| if p { rng.gen_range(-1.0..1.0) } else { fill }));
        }
        x.extend(present.iter().map(|&p| if p { 1.0 } else { 0.0 }));
        x.extend((0..extra).map(|_| rng.gen_range(-1.0..1.0)));
        x
    }

    /// `x` with the object slots (rows and mask entries) in the order `perm`.
    fn permuted(x: &[f32], perm: &[usize; 4]) -> Vec<f32> {
        let (r, f, m) = (SET.robot, SET.object, SET.slots);
        let mut y = x[..r].to_vec();
        for &k in perm {
            y.extend_from_slice(&x[r + k * f..r + (k + 1) * f]);
        }
        y.extend(perm.iter().map(|&k| x[r + m * f + k]));
        y.extend_from_slice(&x[r + m * f + m..]);
        y
    }

    #[test]
    fn a_set_network_ignores_row_order_and_absent_rows_and_its_plain_copy_agrees() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let cases = [
            (0, 4, true, false, false, false, false, 0, 0),
            (4, 1, false, false, false, false, false, 0, 0),
            (0, 4, true, true, false, false, false, 0, 0),
            (4, 1, false, true, false, false, false, 0, 0),
            (0, 4, true, false, true, false, false, 0, 0),
            (4, 1, false, true, true, false, false, 0, 0),
            (0, 4, true, false, false, true, false, 0, 0),
            (4, 1, false, false, false, true, false, 0, 0),
            (4, 1, false, true, true, true, false, 0, 0),
            (0, 4, true, false, false, false, true, 0, 0),
            (4, 1, false, false, true, false, true, 0, 0),
            (4, 1, false, true, false, true, true, 0, 0),
            (0, 4, true, false, false, false, false, 2, 0),
            (4, 1, false, false, true, true, true, 2, 0),
            (0, 4, true, false, true, false, true, 1, 0),
            // Rows narrower than the head (--set-width): Deep Sets, attention, transformer, query.
            (0, 4, true, false, false, false, false, 0, 8),
            (4, 1, false, true, true, false, false, 0, 8),
            (0, 4, true, false, false, true, true, 2, 8),
            (4, 1, false, false, true, true, true, 1, 8),
        ];
        for (extra, out, tanh, attention, norm, robot_tokens, query, transformer, width) in cases {
            // An actor (tanh, 4 outputs) and a critic (the action as 4 extra inputs, 1 output),
            // with mean-max pooling or a self-attention block first, the pooled features
            // layer-normalised or not, the encoder reading rows or robot tokens, pooled by the mean
            // and max or by a learned query, with pre-LayerNorm transformer blocks or none, the rows
            // as wide as the head (16) or narrower.
            let layout = SetLayout { attention, norm, robot_tokens, query, transformer, width, ..SET };
            let net = Net::new_set(layout, extra, (16, 2, 2), out, tanh, &mut rng);
            let tokens = if robot_tokens { SET.robot + SET.object + extra } else { SET.object };
            assert_eq!(net.to_plain().layers[0].n_in, tokens);
            let rows_wide = if width == 0 { 16 } else { width };
            assert_eq!(net.to_plain().layers[0].b.len(), rows_wide);
            assert_eq!(net.to_plain().layers[layout.head_start()].b.len(), 16, "the head keeps the hidden width");
            if width != 0 {
                // A layout whose width the weights contradict is refused.
                let mut wrong = net.to_plain();
                wrong.set = Some(SetLayout { width: 4, ..layout });
                let e = wrong.check(SET.obs_dim() + extra, out, f32::INFINITY).unwrap_err();
                assert!(e.contains("rows are 4 wide, the encoder's 8"), "{e}");
            }
            assert_eq!(net.sizes()[0], SET.obs_dim() + extra);
            let plain = net.to_plain();
            plain.check(SET.obs_dim() + extra, out, f32::INFINITY).unwrap();
            let twin = Net::from_plain(&plain).unwrap();
            for present in [[true, true, false, true], [true, false, false, false], [false; 4], [true; 4]] {
                let x = set_obs(&mut rng, &present, 0.0, extra);
                let batch = |v: &[f32]| Tensor::of_slice(v).view([1, v.len() as i64]);
                let y = tensor_to_vec(&net.forward(&batch(&x)));
                assert_eq!(y.len(), out);
                // The plain-Rust copy (rollouts) and its libtorch twin give the same output.
                for (a, b) in y.iter().zip(plain.forward(&x)) {
                    assert!((a - b).abs() < 1e-5, "{a} vs {b}");
                }
                assert_eq!(tensor_to_vec(&twin.forward(&batch(&x))), y);
                // Any order of the slots gives the same output.
                let p = permuted(&x, &[2, 0, 3, 1]);
                for (a, b) in y.iter().zip(tensor_to_vec(&net.forward(&batch(&p)))) {
                    assert!((a - b).abs() < 1e-5, "permuted: {a} vs {b}");
                }
                // What an absent row holds changes nothing.
                let mut junk = x.clone();
                for k in (0..4).filter(|&k| !present[k]) {
                    junk[SET.robot + k * SET.object..SET.robot + (k + 1) * SET.object].fill(7.5);
                }
                assert_eq!(tensor_to_vec(&net.forward(&batch(&junk))), y);
                assert_eq!(plain.forward(&junk), plain.forward(&x));
            }
            // A batch is row by row.
            let rows: Vec<Vec<f32>> =
                (0..3).map(|_| set_obs(&mut rng, &[true, false, true, true], 0.0, extra)).collect();
            let flat: Vec<f32> = rows.concat();
            let all = tensor_to_vec(&net.forward(&Tensor::of_slice(&flat).view([3, (SET.obs_dim() + extra) as i64])));
            for (i, row) in rows.iter().enumerate() {
                let one = tensor_to_vec(&net.forward(&Tensor::of_slice(row).view([1, row.len() as i64])));
                for (a, b) in all[i * out..(i + 1) * out].iter().zip(&one) {
                    assert!((a - b).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn a_bf16_set_network_rounds_its_hidden_products_only_and_keeps_its_invariances() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let batch = |v: &[f32]| Tensor::of_slice(v).view([1, v.len() as i64]);
        let worst = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        // (encoder layers, head layers, attention, norm): with one encoder and one head layer the
        // only hidden product is the head's with the pooled features, so a difference from the
        // float network shows that one is rounded.
        for (enc, head, attention, norm) in
            [(1, 1, false, false), (2, 2, false, false), (2, 2, true, false), (2, 1, false, true)]
        {
            for (extra, out, tanh) in [(0, 4, true), (4, 1, false)] {
                let layout = SetLayout { attention, norm, ..SET };
                let float = Net::new_set(layout, extra, (32, enc, head), out, tanh, &mut rng);
                let low = float.detached_copy().with_bf16(true);
                let x = set_obs(&mut rng, &[true, false, true, true], 0.0, extra);
                let (y, y16) = (tensor_to_vec(&float.forward(&batch(&x))), tensor_to_vec(&low.forward(&batch(&x))));
                let err = worst(&y, &y16);
                assert!(err > 0.0 && err < 0.05, "{enc} {head} {attention} {norm}: max |bf16 - f32| = {err}");
                // Slot order and absent rows still change nothing (up to the rounding of the sums).
                assert!(worst(&y16, &tensor_to_vec(&low.forward(&batch(&permuted(&x, &[3, 1, 0, 2]))))) < 1e-2);
                let mut junk = x.clone();
                junk[SET.robot + SET.object..SET.robot + 2 * SET.object].fill(7.5);
                assert_eq!(tensor_to_vec(&low.forward(&batch(&junk))), y16);
            }
        }
        // The observation's and the action's products stay float: a head without hidden layers
        // (its only layer is the output) and a one-layer encoder round nothing.
        let float = Net::new_set(SET, 4, (32, 1, 0), 1, false, &mut rng);
        let x = set_obs(&mut rng, &[true; 4], 0.0, 4);
        let low = float.detached_copy().with_bf16(true);
        assert_eq!(tensor_to_vec(&low.forward(&batch(&x))), tensor_to_vec(&float.forward(&batch(&x))));
        // Gradients reach every parameter through the mixed products.
        let mut net = Net::new_set(SET, 4, (32, 2, 2), 1, false, &mut rng).with_bf16(true);
        net.forward(&batch(&x)).sum(Kind::Float).backward();
        assert!(grads(&net.params).iter().all(|g| g.abs().sum(Kind::Float).double_value(&[]) > 0.0));
        net.zero_grad();
    }

    #[test]
    fn pooling_by_colour_agrees_with_its_plain_copy_and_keeps_colours_apart() {
        use crate::env::COLOUR_FEATURE;
        let layout = SetLayout { by_colour: true, ..SetLayout::new(3, 22, 4, 1) };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        // Rows of colours red, blue, blue (two of one colour), none (absent); then the mask.
        let obs = |rng: &mut rand_chacha::ChaCha8Rng, colours: [Option<usize>; 4]| {
            let mut x: Vec<f32> = (0..3).map(|_| rng.gen_range(-1.0..1.0)).collect();
            for c in colours {
                let mut row: Vec<f32> = (0..22).map(|_| rng.gen_range(-1.0..1.0)).collect();
                row[COLOUR_FEATURE..COLOUR_FEATURE + 4].fill(0.0);
                if let Some(c) = c {
                    row[COLOUR_FEATURE + c] = 1.0;
                }
                x.extend(row);
            }
            x.extend(colours.iter().map(|c| if c.is_some() { 1.0 } else { 0.0 }));
            x
        };
        for (extra, out, tanh) in [(0, 4, true), (4, 1, false)] {
            let net = Net::new_set(layout, extra, (8, 1, 1), out, tanh, &mut rng);
            assert_eq!(net.params[2].size(), vec![8, 3 + 2 * 4 * 8 + extra as i64], "robot, mean and max per colour");
            let plain = net.to_plain();
            plain.check(layout.obs_dim() + extra, out, f32::INFINITY).unwrap();
            let mut x = obs(&mut rng, [Some(0), Some(1), Some(1), None]);
            x.extend((0..extra).map(|_| 0.3));
            let batch = |v: &[f32]| Tensor::of_slice(v).view([1, v.len() as i64]);
            let y = tensor_to_vec(&net.forward(&batch(&x)));
            for (a, b) in y.iter().zip(plain.forward(&x)) {
                assert!((a - b).abs() < 1e-5, "{a} vs {b}");
            }
            assert_eq!(tensor_to_vec(&Net::from_plain(&plain).unwrap().forward(&batch(&x))), y);
            // Rows too short to hold the colour one-hot are refused, not read out of range.
            let short = SetLayout { object: 10, ..layout };
            let broken = PlainNet { set: Some(short), ..plain.clone() };
            assert!(broken.check(short.obs_dim() + extra, out, f32::INFINITY).unwrap_err().contains("colour one-hot"));
            // Recolouring the red row green changes the output: colours are pooled apart.
            let mut green = x.clone();
            let at = 3 + COLOUR_FEATURE;
            green[at..at + 4].copy_from_slice(&[0.0, 0.0, 1.0, 0.0]);
            assert_ne!(tensor_to_vec(&net.forward(&batch(&green))), y);
            for (a, b) in tensor_to_vec(&net.forward(&batch(&green))).iter().zip(plain.forward(&green)) {
                assert!((a - b).abs() < 1e-5, "{a} vs {b}");
            }
        }
    }

    #[test]
    fn a_set_network_is_the_mlp_plumbing_plus_pooling() {
        // Its parameters are an ordinary list of [w, b] pairs: the optimiser, target averaging and
        // checkpoints loop over them unchanged.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let net = Net::new_set(SET, 0, (8, 1, 1), 2, true, &mut rng);
        let shapes: Vec<Vec<i64>> = net.params.iter().map(Tensor::size).collect();
        assert_eq!(shapes, vec![vec![8, 5], vec![8], vec![8, 3 + 16], vec![8], vec![2, 8], vec![2]]);
        let mut copy = Net::new_set(SET, 0, (8, 1, 1), 2, true, &mut rng);
        copy.load_vecs(&net.to_vecs()).unwrap();
        let x = Tensor::of_slice(&set_obs(&mut rng, &[true, true, false, false], 0.0, 0)).view([1, -1]);
        assert_eq!(tensor_to_vec(&copy.forward(&x)), tensor_to_vec(&net.forward(&x)));
        // A plain copy whose head does not fit its encoder is refused.
        let mut broken = net.to_plain();
        broken.layers[1].n_in = 20;
        assert!(Net::from_plain(&broken).is_err());
    }

    /// Adam as libtorch tensor operations, one whole-tensor pass each (the
    /// formulation the runs up to 2026-11-23 trained with).
    fn tensor_adam_step(params: &mut [Tensor], grads: &[Tensor], m: &mut [Tensor], v: &mut [Tensor], lr: f64, t: i32) {
        let step = lr * (1.0 - BETA2.powi(t)).sqrt() / (1.0 - BETA1.powi(t));
        tch::no_grad(|| {
            for ((p, g), (m, v)) in params.iter_mut().zip(grads).zip(m.iter_mut().zip(v.iter_mut())) {
                let new_m = &*m * BETA1 + g * (1.0 - BETA1);
                let new_v = &*v * BETA2 + g.square() * (1.0 - BETA2);
                m.copy_(&new_m);
                v.copy_(&new_v);
                let update = &new_m / (new_v.sqrt() + EPS) * step;
                let _ = p.f_sub_(&update);
            }
        });
    }

    #[test]
    fn adam_matches_the_tensor_formulation_bit_for_bit() {
        use rand::Rng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut ours = Net::new(&[9, 256, 256, 5], true, &mut rng).params;
        let mut theirs: Vec<Tensor> = ours.iter().map(|p| p.detach().copy()).collect();
        let mut adam = Adam::new(&ours, 1e-3);
        let mut m: Vec<Tensor> = theirs.iter().map(Tensor::zeros_like).collect();
        let mut v: Vec<Tensor> = theirs.iter().map(Tensor::zeros_like).collect();
        let n: usize = ours.iter().map(Tensor::numel).sum();
        for t in 1..=30 {
            // Gradients over many magnitudes, some exactly zero.
            let flat: Vec<f32> = (0..n)
                .map(|_| {
                    if rng.gen_bool(0.1) {
                        0.0
                    } else {
                        rng.gen_range(-1.0f32..1.0) * 10f32.powi(rng.gen_range(-6..3))
                    }
                })
                .collect();
            let mut off = 0;
            let grads: Vec<Tensor> = theirs
                .iter()
                .map(|p| {
                    let g = Tensor::of_slice(&flat[off..off + p.numel()]).view(p.size().as_slice());
                    off += p.numel();
                    g
                })
                .collect();
            adam.step(&mut ours, &flat);
            tensor_adam_step(&mut theirs, &grads, &mut m, &mut v, 1e-3, t);
            for (a, b) in ours.iter().zip(&theirs) {
                let (a, b) = (tensor_to_vec(a), tensor_to_vec(b));
                assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()), "step {t}: parameters differ");
            }
        }
        let moments: Vec<Vec<f32>> = m.iter().chain(&v).map(tensor_to_vec).collect();
        assert_eq!(adam.to_vecs(), moments);
        // Restored moments continue identically.
        let mut again = Adam::new(&ours, 1e-3);
        again.load_vecs(&adam.to_vecs(), adam.t).unwrap();
        let mut copy: Vec<Tensor> = ours.iter().map(|p| p.detach().copy()).collect();
        let g = vec![0.25f32; n];
        adam.step(&mut ours, &g);
        again.step(&mut copy, &g);
        assert_eq!(
            ours.iter().map(tensor_to_vec).collect::<Vec<_>>(),
            copy.iter().map(tensor_to_vec).collect::<Vec<_>>()
        );
        assert!(again
            .load_vecs(&adam.to_vecs()[1..], 3)
            .unwrap_err()
            .to_string()
            .contains("expected 12 optimiser moments"));
    }
}
