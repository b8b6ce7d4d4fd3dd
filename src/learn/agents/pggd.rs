//! PGGD, the paper's "Policy Gradient with Gaussian Distribution": no
//! critic; the actor outputs a Gaussian over actions.
//!
//! * trunk: `layers` × `hidden` ReLU on the normalised observation; a linear
//!   head for the mean μ(s) and a softplus head for the standard deviation
//!   σ(s) = softplus(·) + σ_min (both heads are the last layer of one net,
//!   outputs `[μ | σ pre-activation]`);
//! * exploring: a ~ N(μ, σ²) per component, the environment gets clip(a, ±1),
//!   the replay buffer keeps the pre-clip `a` (its log-probability is what
//!   the gradient uses); testing and finals use clip(μ, ±1);
//! * update, off-policy from replay: loss = −mean_i(w_i · log π(a_i | s_i)),
//!   w the per-transition weight (the discounted return-to-go stored with the
//!   transition, or an expert's advantage), optionally standardised over the
//!   batch (see [`WeightNorm`]); Adam, lr 1e-4.

use super::algorithm::{param_count, Algorithm, Explorer, Info, Part, Registration, UpdateStats};
use super::arch::Arch;
use super::nets::{append_grads, Adam, Net};
use super::replay::Batch;
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::AnyPolicy;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use tch::Tensor;

/// PGGD in the list of algorithms (`--algo pggd`; with `--expert`, AggreVaTeD).
pub const REGISTRATION: Registration<PggdConfig> = Registration {
    info: Info {
        trainer: crate::benchmark::saved::Trainer::Pggd,
        title: "PGGD",
        about: "policy gradient with a Gaussian policy (the paper's; with --expert, AggreVaTeD)",
        takes_expert: true,
        imitates: false,
        // The network's shape, the normaliser and the discount of the return-to-go; no critic.
        reads: &["--layers", "--hidden", "--gamma", "--norm-eps", "--norm-clip"],
        flag_prefix: "pg-",
        branchable: &[],
        starts_from_policy: false,
    },
    new: |spec, own, rng| {
        let s = spec.shared;
        let (shape, norm) = ((s.layers, s.hidden), (s.norm_eps, s.norm_clip));
        Box::new(Pggd::new(spec.arch, spec.act_dim, shape, norm, own.clone(), rng))
    },
    validate: PggdConfig::validate,
    unused: |_| Vec::new(),
    // The network with Adam's two moments.
    memory: |spec, _| spec.mlp_bytes(0, 2 * spec.act_dim, 3),
    // The title names the method ("PGGD + AggreVaTeD"); its settings are the paper's or given in the config.
    take_branch: super::algorithm::no_branch,
    describe: |_| Vec::new(),
};

/// What happens to the per-transition weights before the gradient.
///
/// With a negative weight, −w·log π(a|s) falls without bound as μ(s) moves
/// away from `a`: trained off-policy on replayed actions, any scheme that
/// leaves weights negative lets μ run off (seen here: |μ| > 1000 within ten
/// epochs of AggreVaTeD with `standardize`). BlockPuzzle returns are all
/// ≤ 0, so the raw weights are all negative.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum WeightNorm {
    /// (w − min) / (max − min) over the batch: the policy gradient with the
    /// batch's lowest weight as its baseline, scaled to [0, 1]. All weights
    /// are ≥ 0, so the objective is a return-weighted likelihood and bounded
    /// (σ has a floor).
    MinMax,
    /// (w − mean) / std over the batch (the usual REINFORCE baseline);
    /// unstable off-policy, see above.
    Standardize,
    /// The weights as they are; unstable, see above.
    None,
}

/// PGGD's own settings (defaults: the paper's), besides the shared ones it reads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "PGGD's settings (--algo pggd)")]
pub struct PggdConfig {
    /// PGGD learning rate (Adam).
    #[arg(long = "pg-lr", default_value_t = Self::DEFAULT.lr)]
    pub lr: f64,
    /// PGGD: floor added to the softplus standard deviation.
    #[arg(long = "pg-sigma-min", default_value_t = Self::DEFAULT.sigma_min)]
    pub sigma_min: f64,
    /// PGGD: normalisation of the per-transition weights within a batch.
    #[arg(long = "pg-normalize", value_enum, default_value_t = Self::DEFAULT.normalize)]
    pub normalize: WeightNorm,
}

impl PggdConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { lr: 1e-4, sigma_min: 0.01, normalize: WeightNorm::MinMax };

    /// Whether every setting is in range; the error names the flag.
    ///
    /// # Errors
    /// The first setting out of range.
    pub fn validate(&self) -> Result<(), String> {
        let (lr, sigma_min) = (self.lr, self.sigma_min);
        if !lr.is_finite() || lr <= 0.0 || !sigma_min.is_finite() || sigma_min < 0.0 {
            return Err("--pg-lr must be a positive number and --pg-sigma-min a number ≥ 0".into());
        }
        Ok(())
    }
}

impl Default for PggdConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// ln √(2π).
const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_8;

/// log N(a; μ, σ²) summed over the action components, one value per row.
pub fn gaussian_log_prob(a: &Tensor, mean: &Tensor, std: &Tensor) -> Tensor {
    let z = (a - mean) / std;
    (z.square() * -0.5 - std.log() - LN_SQRT_2PI).sum_dim_intlist(Some(&[1i64][..]), false, tch::Kind::Float)
}

/// σ = softplus(x) + floor, computed stably.
fn softplus_std(x: &Tensor, floor: f64) -> Tensor {
    x.relu() + (-x.abs()).exp().log1p() + floor
}

/// The PGGD learner.
pub struct Pggd {
    /// Hyperparameters.
    pub config: PggdConfig,
    /// Observation normaliser.
    pub norm: Normalizer,
    /// The policy network: outputs `[μ | σ pre-activation]`.
    pub net: Net,
    /// Its optimiser.
    pub opt: Adam,
    act_dim: usize,
}

impl Pggd {
    /// A fresh learner with the network of `arch` (`layers` × `hidden`); `rng` fixes the initial weights.
    pub fn new(
        arch: Arch,
        act_dim: usize,
        (layers, hidden): (usize, usize),
        (norm_eps, norm_clip): (f64, f32),
        config: PggdConfig,
        rng: &mut impl Rng,
    ) -> Self {
        let net = arch.net((hidden, layers), 0, 2 * act_dim, false, rng);
        let opt = Adam::new(&net.params, config.lr);
        Self { norm: arch.normalizer(norm_eps, norm_clip), net, opt, act_dim, config }
    }

    /// Action size.
    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// Mean and standard deviation for a batch of raw observations.
    pub fn distribution(&self, obs: &[f32]) -> (Tensor, Tensor) {
        let out = self.net.forward(&self.norm.tensor(obs));
        let a = self.act_dim as i64;
        (out.narrow(1, 0, a), softplus_std(&out.narrow(1, a, a), self.config.sigma_min))
    }

    /// One gradient step on `batch` with per-transition `weights`.
    pub fn update(&mut self, batch: &Batch, weights: &[f32]) -> UpdateStats {
        let (gradient, stats) = self.gradient(batch, weights);
        self.apply_gradient(&gradient);
        stats
    }

    /// The flattened gradient of the policy network on `batch` with
    /// per-transition `weights`, and the update's statistics; nothing changes.
    pub fn gradient(&mut self, batch: &Batch, weights: &[f32]) -> (Vec<f32>, UpdateStats) {
        let n = batch.len() as i64;
        let raw = Tensor::of_slice(weights).view([n, 1]);
        let w = match self.config.normalize {
            WeightNorm::None => raw.shallow_clone(),
            WeightNorm::MinMax => {
                let lo = raw.min();
                (&raw - &lo) / ((raw.max() - lo) + 1e-8)
            }
            WeightNorm::Standardize => {
                let centred = &raw - raw.mean(tch::Kind::Float);
                let sd = centred.square().mean(tch::Kind::Float).sqrt();
                centred / (sd + 1e-8)
            }
        };
        let (mean, std) = self.distribution(&batch.obs);
        let act = Tensor::of_slice(&batch.act).view([n, self.act_dim as i64]);
        let log_prob = gaussian_log_prob(&act, &mean, &std);
        let loss = -(w.view([-1]) * &log_prob).mean(tch::Kind::Float);
        self.net.zero_grad();
        loss.backward();
        let mut flat = Vec::new();
        append_grads(&self.net.params, &mut flat);
        let stats = UpdateStats {
            critic_loss: 0.0,
            actor_loss: loss.double_value(&[]),
            mean_q: raw.mean(tch::Kind::Float).double_value(&[]),
        };
        (flat, stats)
    }

    /// One Adam step with a gradient laid out as [`Pggd::gradient`] returns it.
    ///
    /// # Panics
    /// If `gradient` does not have that layout.
    pub fn apply_gradient(&mut self, gradient: &[f32]) {
        self.opt.step(&mut self.net.params, gradient);
    }

    /// A self-contained policy for rollouts (weights and normaliser frozen).
    pub fn policy(&self) -> PggdPolicy {
        PggdPolicy {
            net: self.net.to_plain(),
            norm: self.norm.clone(),
            act_dim: self.act_dim,
            sigma_min: self.config.sigma_min,
        }
    }
}

impl Algorithm for Pggd {
    super::algorithm::learner_basics!(REGISTRATION.info.name());

    /// Each transition's weight is `weights` (an expert's advantage) or else the stored return-to-go.
    fn gradient(&mut self, batch: &Batch, _shard: u64, weights: Option<&[f32]>) -> (Vec<f32>, UpdateStats) {
        Pggd::gradient(self, batch, weights.unwrap_or(&batch.return_to_go))
    }

    fn apply_gradient(&mut self, gradient: &[f32]) {
        Pggd::apply_gradient(self, gradient);
    }

    fn gradient_len(&self) -> usize {
        param_count(&[&self.net])
    }

    fn policy(&self) -> AnyPolicy {
        AnyPolicy::Pggd(Pggd::policy(self))
    }

    fn explorer(&self) -> Box<dyn Explorer> {
        Box::new(Pggd::policy(self))
    }

    fn parts(&mut self) -> Vec<(&'static str, Part<'_>)> {
        vec![("actor", Part::Net(&mut self.net)), ("actor_adam", Part::Adam(&mut self.opt))]
    }
}

/// PGGD explores by sampling its Gaussian (the action stored before clipping).
impl Explorer for PggdPolicy {
    fn explore(&self, obs: &[f32], _noise: &mut Vec<f32>, rng: &mut ChaCha8Rng) -> Vec<f32> {
        self.sample(obs, rng)
    }
}

use crate::policy::actor::PggdPolicy;

/// PGGD's exploration (training only: the policy itself is the core's).
impl PggdPolicy {
    /// A sampled action `a ~ N(μ, σ²)`, before clipping.
    pub fn sample(&self, obs: &[f32], rng: &mut impl Rng) -> Vec<f32> {
        let (mean, std) = self.distribution(obs);
        mean.iter()
            .zip(&std)
            .map(|(m, s)| {
                let z: f64 = StandardNormal.sample(rng);
                m + s * z as f32
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn gaussian_log_prob_matches_the_closed_form() {
        // Two components: N(0.3; 0.1, 0.5²) and N(−1.2; 0.4, 2²).
        let a = Tensor::of_slice(&[0.3f32, -1.2]).view([1, 2]);
        let m = Tensor::of_slice(&[0.1f32, 0.4]).view([1, 2]);
        let s = Tensor::of_slice(&[0.5f32, 2.0]).view([1, 2]);
        let lp = gaussian_log_prob(&a, &m, &s).double_value(&[0]);
        let one = |x: f64, mu: f64, sd: f64| {
            -((x - mu) * (x - mu)) / (2.0 * sd * sd) - sd.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln()
        };
        let expected = one(0.3, 0.1, 0.5) + one(-1.2, 0.4, 2.0);
        assert!((lp - expected).abs() < 1e-5, "{lp} vs {expected}");
    }

    fn batch_of(obs: Vec<f32>, act: Vec<f32>) -> Batch {
        let n = act.len() / 4;
        Batch {
            next_obs: obs.clone(),
            obs,
            act,
            rew: vec![0.0; n],
            terminated: vec![0.0; n],
            return_to_go: vec![0.0; n],
            discount: vec![0.98; n],
        }
    }

    #[test]
    fn a_positively_weighted_action_becomes_more_likely() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut agent = Pggd::new(
            Arch::mlp(6),
            4,
            (2, 32),
            (0.01, 5.0),
            PggdConfig { lr: 1e-3, normalize: WeightNorm::None, ..PggdConfig::default() },
            &mut rng,
        );
        let obs: Vec<f32> = (0..6).map(|k| k as f32 * 0.1).collect();
        let act = vec![0.5f32, -0.3, 0.2, 0.9];
        let b = batch_of(obs.clone(), act.clone());
        let log_prob = |agent: &Pggd| {
            let (m, s) = agent.distribution(&obs);
            gaussian_log_prob(&Tensor::of_slice(&act).view([1, 4]), &m, &s).double_value(&[0])
        };
        let before = log_prob(&agent);
        agent.update(&b, &[1.0]);
        let up = log_prob(&agent);
        assert!(up > before, "weight +1: {before} -> {up}");
        agent.update(&b, &[-1.0]);
        agent.update(&b, &[-1.0]);
        let down = log_prob(&agent);
        assert!(down < up, "weight -1: {up} -> {down}");
    }

    #[test]
    fn normalised_weights_favour_the_better_action() {
        for normalize in [WeightNorm::MinMax, WeightNorm::Standardize] {
            better_action_gains(normalize);
        }
    }

    /// Same state, two actions; the better return (−1 vs −10) must gain
    /// probability relative to the worse one, although both are negative.
    fn better_action_gains(normalize: WeightNorm) {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let config = PggdConfig { lr: 1e-3, normalize, ..PggdConfig::default() };
        let mut agent = Pggd::new(Arch::mlp(3), 4, (2, 32), (0.01, 5.0), config, &mut rng);
        let obs = vec![0.1f32, 0.2, 0.3, 0.1, 0.2, 0.3];
        let (good, bad) = ([0.5f32, 0.5, 0.5, 0.5], [-0.5f32, -0.5, -0.5, -0.5]);
        let b = batch_of(obs.clone(), good.iter().chain(&bad).copied().collect());
        let gap = |agent: &Pggd| {
            let (m, s) = agent.distribution(&obs[..3]);
            let lp = |a: &[f32]| gaussian_log_prob(&Tensor::of_slice(a).view([1, 4]), &m, &s).double_value(&[0]);
            lp(&good) - lp(&bad)
        };
        let before = gap(&agent);
        for _ in 0..5 {
            agent.update(&b, &[-1.0, -10.0]);
        }
        assert!(gap(&agent) > before, "{normalize:?}: {before} -> {}", gap(&agent));
    }

    #[test]
    fn min_max_weights_keep_the_mean_bounded() {
        // Many updates on a fixed batch of all-negative returns: with min-max
        // weights the mean stays near the replayed actions (weighted maximum
        // likelihood); it does not run off as with raw negative weights.
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let obs: Vec<f32> = (0..3 * 8).map(|k| (k as f32 * 0.3).sin()).collect();
        let act: Vec<f32> = (0..4 * 8).map(|k| (k as f32 * 0.7).cos() * 0.8).collect();
        let b = batch_of(obs.clone(), act);
        let weights: Vec<f32> = (0..8).map(|k| -(k as f32) - 1.0).collect();
        let run = |normalize: WeightNorm, rng: &mut ChaCha8Rng| {
            let config = PggdConfig { lr: 1e-2, normalize, ..PggdConfig::default() };
            let mut agent = Pggd::new(Arch::mlp(3), 4, (2, 32), (0.01, 5.0), config, rng);
            for _ in 0..300 {
                agent.update(&b, &weights);
            }
            let (m, _) = agent.distribution(&obs);
            m.abs().max().double_value(&[])
        };
        let bounded = run(WeightNorm::MinMax, &mut rng);
        let raw = run(WeightNorm::None, &mut rng);
        assert!(bounded < 1.5, "min-max: max |mu| = {bounded}");
        assert!(raw > 3.0 * bounded, "raw negative weights: max |mu| = {raw}");
    }

    #[test]
    fn plain_policy_matches_the_tensor_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let agent = Pggd::new(Arch::mlp(5), 4, (3, 16), (0.01, 5.0), PggdConfig::default(), &mut rng);
        let obs = [0.3f32, -0.2, 0.9, 0.0, 1.5];
        let (m, s) = agent.distribution(&obs);
        let (pm, ps) = agent.policy().distribution(&obs);
        for k in 0..4 {
            assert!((m.double_value(&[0, k]) - pm[k as usize] as f64).abs() < 1e-5);
            assert!((s.double_value(&[0, k]) - ps[k as usize] as f64).abs() < 1e-5);
            assert!(ps[k as usize] >= 0.01);
        }
    }
}
