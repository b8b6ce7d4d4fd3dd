//! SAC: soft actor-critic with automatic entropy tuning (Haarnoja et al.
//! 2018, "Soft Actor-Critic Algorithms and Applications"), in this
//! project's update scheme (one gradient per shard, their mean, one Adam
//! step; target networks after each cycle).
//!
//! * actor: a Gaussian over the pre-squash action, `[μ | log σ]` from one
//!   MLP on the normalised observation (log σ clamped to [−20, 2]); an action
//!   is a = tanh(μ + σ ε), ε ~ N(0, I), with log π(a|s) = Σ log N(u; μ, σ²)
//!   − Σ log(1 − tanh²(u) + 10⁻⁶);
//! * twin critics Q₁, Q₂ with targets; the critic target is
//!   y = r + γᵐ (1 − terminated) (min Q'ᵢ(s̄', a') − α log π(a'|s̄')), a' ~ π(s̄')
//!   (m the stored n-step length; truncation does not stop the bootstrap);
//! * actor loss: mean(α log π(ã|s̄) − min Qᵢ(s̄, ã)), ã ~ π(s̄) reparameterised,
//!   the critics held fixed;
//! * temperature: log α learned with loss −mean(log α (log π(ã|s̄) + H̄)),
//!   target entropy H̄ = −dim(A), α starting at 1 (the SAC paper's rule and
//!   SB3's `ent_coef="auto"`), Adam at the actor's learning rate;
//! * all three gradients from the same parameters; targets follow by polyak
//!   averaging after each cycle (`--polyak`, as DDPG here);
//! * exploring: sampling the policy; testing, finals and the saved policy:
//!   the mean action tanh(μ(s̄)), saved as a deterministic tanh actor (the
//!   μ rows of the last layer), so the zoo, evaluation and Python read it as
//!   they read a DDPG actor.
//!
//! It reads every shared setting (`SharedConfig`: layers, hidden, `--lr-actor`,
//! `--lr-critic`, `--gamma`, `--polyak`, the normaliser, `--precision`,
//! `--n-step`, `--flat-critic`); its own are the temperature's start and
//! target ([`SacConfig`]). DDPG's exploration noise and action penalties do not apply.
//! The ε of update k and shard s come from a ChaCha8 stream of (seed, s, k),
//! so a run resumes bit for bit and the shards draw independent noise.

use super::algorithm::{
    param_count, split_gradient, Algorithm, Explorer, Info, Part, Registration, Spec, StartError, UpdateStats,
};
use super::arch::Arch;
use super::nets::{append_grads, Adam, Net};
use super::replay::Batch;
use super::shared::SharedConfig;
use crate::policy::actor::mlp::{Dense, PlainNet};
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::AnyPolicy;
use crate::policy::actor::DeterministicPolicy;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use tch::{Kind, Tensor};

/// σ of the pre-squash Gaussian everywhere when a run starts from a trained policy (`--init-from`):
/// the paper's DDPG exploration noise (`--noise-eps 0.2`).
pub const INIT_STD: f64 = 0.2;

/// SAC in the list of algorithms (`--algo sac`).
pub const REGISTRATION: Registration<SacConfig> = Registration {
    info: Info {
        trainer: crate::benchmark::saved::Trainer::Sac,
        title: "SAC",
        about: "soft actor-critic with automatic entropy tuning (twin critics)",
        takes_expert: false,
        imitates: false,
        // Every shared setting.
        reads: SharedConfig::FLAGS,
        flag_prefix: "sac-",
        branchable: &[],
        starts_from_policy: true,
    },
    new: |spec, own, rng| Box::new(Sac::new(spec, own, rng)),
    validate: SacConfig::validate,
    unused: |_| Vec::new(),
    // The actor with Adam's two moments; two critics, each with its target and moments.
    memory: |spec, _| spec.mlp_bytes(0, 2 * spec.act_dim, 3) + spec.mlp_bytes(spec.act_dim, 1, 8),
    take_branch: super::algorithm::no_branch,
    describe: |c| {
        let mut v = Vec::new();
        if c.alpha_init != SacConfig::DEFAULT.alpha_init {
            v.push(format!("initial temperature {}", c.alpha_init));
        }
        if let Some(h) = c.target_entropy {
            v.push(format!("target entropy {h}"));
        }
        v
    },
};

/// SAC's own settings, besides the shared ones ([`SharedConfig`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "SAC's settings (--algo sac)")]
pub struct SacConfig {
    /// The entropy temperature α at the start (1: the SAC paper's and SB3's `ent_coef="auto"`).
    #[arg(long = "sac-alpha-init", default_value_t = Self::DEFAULT.alpha_init)]
    pub alpha_init: f64,
    /// The entropy α is tuned towards (default: −dim(A), the SAC paper's rule).
    #[arg(long = "sac-target-entropy")]
    pub target_entropy: Option<f64>,
}

impl SacConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self { alpha_init: 1.0, target_entropy: None };

    /// Whether every setting is in range; the error names the flag.
    ///
    /// # Errors
    /// The first setting out of range.
    pub fn validate(&self) -> Result<(), String> {
        if !self.alpha_init.is_finite() || self.alpha_init <= 0.0 {
            return Err("--sac-alpha-init must be a positive number".into());
        }
        if self.target_entropy.is_some_and(|h| !h.is_finite()) {
            return Err("--sac-target-entropy must be a number".into());
        }
        Ok(())
    }
}

impl Default for SacConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// log σ is clamped to [`LOG_STD_MIN`, `LOG_STD_MAX`].
const LOG_STD_MIN: f64 = -20.0;
const LOG_STD_MAX: f64 = 2.0;
/// Keeps log(1 − tanh²) finite where tanh saturates.
const SQUASH_EPS: f64 = 1e-6;
/// ln √(2π).
const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_8;

/// The SAC learner.
pub struct Sac {
    shared: SharedConfig,
    target_entropy: f64,
    norm: Normalizer,
    actor: Net,
    q1: Net,
    q2: Net,
    q1_target: Net,
    q2_target: Net,
    /// log α, one value.
    log_alpha: Tensor,
    actor_opt: Adam,
    q1_opt: Adam,
    q2_opt: Adam,
    alpha_opt: Adam,
    noise_seed: u64,
    act_dim: usize,
    /// The actor (and the temperature) held still: updates step the critics alone (a critic warm-up).
    actor_held: bool,
}

impl Sac {
    /// A fresh learner; `rng` fixes the initial weights and the noise seed.
    pub fn new(spec: &Spec, own: &SacConfig, rng: &mut ChaCha8Rng) -> Self {
        let (c, arch, a) = (spec.shared.clone(), spec.arch, spec.act_dim);
        let bf16 = c.bf16();
        let net = |arch: Arch, rng: &mut ChaCha8Rng, extra, out| {
            arch.net((c.hidden, c.layers), extra, out, false, rng).with_bf16(bf16)
        };
        let actor = net(arch, rng, 0, 2 * a);
        let critics = arch.critics(c.flat_critic);
        let critic = |rng: &mut ChaCha8Rng| net(critics, rng, a, 1).with_hidden_norm(c.critic_norm);
        let (q1, q2) = (critic(rng), critic(rng));
        let log_alpha =
            Tensor::full(&[1], own.alpha_init.ln(), (Kind::Float, tch::Device::Cpu)).set_requires_grad(true);
        Self {
            norm: arch.normalizer(c.norm_eps, c.norm_clip),
            actor_opt: Adam::new(&actor.params, c.lr_actor),
            q1_opt: Adam::new(&q1.params, c.lr_critic),
            q2_opt: Adam::new(&q2.params, c.lr_critic),
            alpha_opt: Adam::new(std::slice::from_ref(&log_alpha), c.lr_actor),
            q1_target: q1.detached_copy(),
            q2_target: q2.detached_copy(),
            noise_seed: rng.gen(),
            actor,
            q1,
            q2,
            log_alpha,
            target_entropy: own.target_entropy.unwrap_or(-(a as f64)),
            shared: c,
            act_dim: a,
            actor_held: false,
        }
    }

    /// The entropy temperature α.
    pub fn alpha(&self) -> f64 {
        self.log_alpha.exp().double_value(&[0])
    }

    /// A reparameterised sample a = tanh(μ + σ ε) of `actor` at `obs`, with log π(a|s), one per row.
    fn sample(&self, actor: &Net, obs: &Tensor, eps: &Tensor) -> (Tensor, Tensor) {
        let out = actor.forward(obs);
        let a = self.act_dim as i64;
        let (mean, log_std) = (out.narrow(1, 0, a), out.narrow(1, a, a).clamp(LOG_STD_MIN, LOG_STD_MAX));
        let u = &mean + log_std.exp() * eps;
        let act = u.tanh();
        let gauss = eps.square() * -0.5 - &log_std - LN_SQRT_2PI;
        let squash = (act.square().neg() + (1.0 + SQUASH_EPS)).log();
        let log_prob = (gauss - squash).sum_dim_intlist(Some(&[1i64][..]), true, Kind::Float);
        (act, log_prob)
    }

    /// Standard normal noise `[rows, act_dim]` for update `k` of `shard`, draw `which` (0: target, 1: actor).
    fn noise(&self, rows: usize, shard: u64, which: u64) -> Tensor {
        let k = self.q1_opt.t;
        let key = [self.noise_seed, shard, k, which]
            .iter()
            .fold(0x243F_6A88_85A3_08D3u64, |h, &x| (h ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(29));
        let mut rng = ChaCha8Rng::seed_from_u64(key);
        let v: Vec<f32> = (0..rows * self.act_dim).map(|_| StandardNormal.sample(&mut rng)).collect();
        Tensor::of_slice(&v).view([rows as i64, self.act_dim as i64])
    }

    /// The gradients of critics, actor and log α on `batch` (flattened in that order) and the statistics.
    fn compute_gradient(&mut self, batch: &Batch, shard: u64) -> (Vec<f32>, UpdateStats) {
        let n = batch.len();
        let obs = self.norm.tensor(&batch.obs);
        let next_obs = self.norm.tensor(&batch.next_obs);
        let col = |v: &[f32]| Tensor::of_slice(v).view([n as i64, 1]);
        let act = Tensor::of_slice(&batch.act).view([n as i64, self.act_dim as i64]);
        let alpha = self.log_alpha.exp().detach();

        let target = tch::no_grad(|| {
            let (next_act, next_log_prob) = self.sample(&self.actor, &next_obs, &self.noise(n, shard, 0));
            let q1 = self.q1_target.q(&next_obs, &next_act);
            let q2 = self.q2_target.q(&next_obs, &next_act);
            let soft = q1.minimum(&q2) - &alpha * next_log_prob;
            col(&batch.rew) + (1.0 - col(&batch.terminated)) * col(&batch.discount) * soft
        });
        let q1 = self.q1.q(&obs, &act);
        let critic_loss =
            (&q1 - &target).square().mean(Kind::Float) + (self.q2.q(&obs, &act) - &target).square().mean(Kind::Float);

        let (pi, log_prob) = self.sample(&self.actor, &obs, &self.noise(n, shard, 1));
        let (f1, f2) = (self.q1.detached_view(), self.q2.detached_view());
        let q_pi = f1.q(&obs, &pi).minimum(&f2.q(&obs, &pi));
        let actor_loss = (&alpha * &log_prob - q_pi).mean(Kind::Float);
        let target_entropy = self.target_entropy;
        let alpha_loss = -(&self.log_alpha * (log_prob.detach() + target_entropy)).mean(Kind::Float);

        for net in [&mut self.q1, &mut self.q2, &mut self.actor] {
            net.zero_grad();
        }
        let mut g = self.log_alpha.grad();
        if g.defined() {
            let _ = g.zero_();
        }
        (critic_loss.shallow_clone() + actor_loss.shallow_clone() + alpha_loss).backward();
        let mut flat = Vec::with_capacity(self.gradient_len());
        for net in [&self.q1, &self.q2, &self.actor] {
            append_grads(&net.params, &mut flat);
        }
        append_grads(std::slice::from_ref(&self.log_alpha), &mut flat);
        let stats = UpdateStats {
            critic_loss: critic_loss.double_value(&[]),
            actor_loss: actor_loss.double_value(&[]),
            mean_q: q1.mean(Kind::Float).double_value(&[]),
        };
        (flat, stats)
    }

    /// The mean action tanh(μ(s̄)) as a deterministic tanh actor: the actor
    /// with its last layer cut to the μ rows.
    fn mean_actor(&self) -> PlainNet {
        let mut net = self.actor.to_plain();
        if let Some(last) = net.layers.last_mut() {
            *last =
                Dense { w: last.w[..self.act_dim * last.n_in].to_vec(), b: last.b[..self.act_dim].to_vec(), ..*last };
        }
        net.tanh_out = true;
        net
    }
}

impl Algorithm for Sac {
    super::algorithm::learner_basics!(REGISTRATION.info.name());

    fn gradient(&mut self, batch: &Batch, shard: u64, _weights: Option<&[f32]>) -> (Vec<f32>, UpdateStats) {
        self.compute_gradient(batch, shard)
    }

    fn apply_gradient(&mut self, gradient: &[f32]) {
        let (alpha_len, nets) = (1, [&self.q1, &self.q2, &self.actor]);
        let (g_nets, g_alpha) = gradient.split_at(gradient.len().saturating_sub(alpha_len));
        let parts = split_gradient(g_nets, &nets);
        self.q1_opt.step(&mut self.q1.params, parts[0]);
        self.q2_opt.step(&mut self.q2.params, parts[1]);
        if !self.actor_held {
            self.actor_opt.step(&mut self.actor.params, parts[2]);
            self.alpha_opt.step(std::slice::from_mut(&mut self.log_alpha), g_alpha);
        }
    }

    fn gradient_len(&self) -> usize {
        param_count(&[&self.q1, &self.q2, &self.actor]) + 1
    }

    fn end_cycle(&mut self) {
        let p = self.shared.polyak;
        self.q1_target.polyak_from(&self.q1, p);
        self.q2_target.polyak_from(&self.q2, p);
    }

    /// The mean rows of the last layer from the policy's; the log σ rows' weights zero and their
    /// biases ln [`INIT_STD`], so that the first exploration is the policy's action with small noise
    /// (the fresh rows would draw σ about 1, which undoes the policy's skill).
    fn init_from(&mut self, policy: &DeterministicPolicy) -> Result<(), StartError> {
        let ours = self.mean_actor();
        let fitted = super::algorithm::fit_actor(&ours, &self.norm, policy)?;
        let mut vecs = super::algorithm::plain_vecs(&fitted.net);
        let a = self.act_dim;
        if let [.., w, b] = &mut vecs[..] {
            let n_in = w.len() / a;
            w.extend(std::iter::repeat(0.0).take(a * n_in));
            b.extend(std::iter::repeat(INIT_STD.ln() as f32).take(a));
        }
        self.actor.load_vecs(&vecs)?;
        self.norm = fitted.norm;
        Ok(())
    }

    fn hold_actor(&mut self, held: bool) {
        self.actor_held = held;
    }

    fn policy(&self) -> AnyPolicy {
        AnyPolicy::Deterministic(DeterministicPolicy { net: self.mean_actor(), norm: self.norm.clone() })
    }

    fn explorer(&self) -> Box<dyn Explorer> {
        Box::new(SacExplorer { net: self.actor.to_plain(), norm: self.norm.clone(), act_dim: self.act_dim })
    }

    /// Q₁ (a soft critic: it values the policy's entropy too).
    fn critic(&self) -> Option<PlainNet> {
        Some(self.q1.to_plain())
    }

    fn parts(&mut self) -> Vec<(&'static str, Part<'_>)> {
        vec![
            ("actor", Part::Net(&mut self.actor)),
            ("critic", Part::Net(&mut self.q1)),
            ("critic2", Part::Net(&mut self.q2)),
            ("critic_target", Part::Net(&mut self.q1_target)),
            ("critic2_target", Part::Net(&mut self.q2_target)),
            ("log_alpha", Part::Tensor(&mut self.log_alpha)),
            ("actor_adam", Part::Adam(&mut self.actor_opt)),
            ("critic_adam", Part::Adam(&mut self.q1_opt)),
            ("critic2_adam", Part::Adam(&mut self.q2_opt)),
            ("alpha_adam", Part::Adam(&mut self.alpha_opt)),
            ("noise_seed", Part::Counter(&mut self.noise_seed)),
        ]
    }
}

/// SAC's exploration: a sample tanh(μ + σ z) of the frozen actor.
pub struct SacExplorer {
    net: PlainNet,
    norm: Normalizer,
    act_dim: usize,
}

impl Explorer for SacExplorer {
    fn explore(&self, obs: &[f32], _noise: &mut Vec<f32>, rng: &mut ChaCha8Rng) -> Vec<f32> {
        let mut x = obs.to_vec();
        self.norm.normalize_in_place(&mut x);
        let out = self.net.forward(&x);
        let (mean, log_std) = out.split_at(self.act_dim);
        mean.iter()
            .zip(log_std)
            .map(|(m, l)| {
                let z: f32 = StandardNormal.sample(rng);
                (m + (l.clamp(LOG_STD_MIN as f32, LOG_STD_MAX as f32)).exp() * z).tanh()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(shared: &SharedConfig) -> Spec<'static> {
        Spec { arch: super::super::arch::Arch::mlp(6), act_dim: 4, shared: Box::leak(Box::new(shared.clone())) }
    }

    fn batch(n: usize, rng: &mut ChaCha8Rng) -> Batch {
        let mut b = Batch::default();
        for i in 0..n {
            b.obs.extend((0..6).map(|_| rng.gen_range(-1.0f32..1.0)));
            b.act.extend((0..4).map(|_| rng.gen_range(-0.9f32..0.9)));
            b.rew.push(if i % 5 == 0 { 0.0 } else { -1.0 });
            b.next_obs.extend((0..6).map(|_| rng.gen_range(-1.0f32..1.0)));
            b.terminated.push(if i % 5 == 0 { 1.0 } else { 0.0 });
            b.return_to_go.push(0.0);
            b.discount.push(0.98);
        }
        b
    }

    fn small() -> Sac {
        let d = SharedConfig { hidden: 16, layers: 2, ..SharedConfig::default() };
        Sac::new(&spec(&d), &SacConfig::default(), &mut ChaCha8Rng::seed_from_u64(1))
    }

    #[test]
    fn log_prob_is_the_squashed_gaussian_density() {
        // One row, one component checked against the closed form.
        let sac = small();
        let obs = Tensor::of_slice(&[0.1f32, -0.2, 0.3, 0.0, 0.5, -0.4]).view([1, 6]);
        let eps = Tensor::of_slice(&[0.7f32, -1.1, 0.2, 0.0]).view([1, 4]);
        let (a, lp) = sac.sample(&sac.actor, &obs, &eps);
        let out = Vec::<f32>::from(&sac.actor.forward(&obs).view(-1));
        let mut expected = 0.0f64;
        let e = [0.7f64, -1.1, 0.2, 0.0];
        for k in 0..4 {
            let (mu, ls) = (out[k] as f64, (out[4 + k] as f64).clamp(LOG_STD_MIN, LOG_STD_MAX));
            let u = mu + ls.exp() * e[k];
            let density = -0.5 * e[k] * e[k] - ls - LN_SQRT_2PI;
            expected += density - (1.0 - u.tanh().powi(2) + SQUASH_EPS).ln();
            assert!((a.double_value(&[0, k as i64]) - u.tanh()).abs() < 1e-5);
        }
        assert!((lp.double_value(&[0, 0]) - expected).abs() < 1e-4, "{} vs {expected}", lp.double_value(&[0, 0]));
    }

    #[test]
    fn gradient_is_deterministic_per_shard_and_differs_across_shards() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let b = batch(32, &mut rng);
        let (mut x, mut y) = (small(), small());
        let (g0, _) = x.compute_gradient(&b, 0);
        let (g0b, _) = y.compute_gradient(&b, 0);
        let (g1, _) = y.compute_gradient(&b, 1);
        assert_eq!(g0, g0b);
        assert_ne!(g0, g1);
        assert_eq!(g0.len(), x.gradient_len());
    }

    #[test]
    fn updates_lower_alpha_when_entropy_is_above_target_and_fit_the_critic() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let b = batch(64, &mut rng);
        let mut sac = small();
        let a0 = sac.alpha();
        let first = sac.compute_gradient(&b, 0).1.critic_loss;
        let mut last = first;
        for _ in 0..200 {
            let (g, s) = sac.compute_gradient(&b, 0);
            sac.apply_gradient(&g);
            last = s.critic_loss;
        }
        // A fresh policy's entropy (about 4 × 1.4 nats) is far above −dim(A) = −4.
        assert!(sac.alpha() < a0 * 0.9, "alpha {} from {a0}", sac.alpha());
        assert!(last < first, "critic loss {last} from {first}");
    }

    #[test]
    fn state_round_trips_and_the_policy_is_the_mean_action() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let b = batch(16, &mut rng);
        let mut sac = small();
        let (g, _) = sac.compute_gradient(&b, 0);
        sac.apply_gradient(&g);
        let mut other = Sac::new(
            &spec(&SharedConfig { hidden: 16, layers: 2, ..SharedConfig::default() }),
            &SacConfig::default(),
            &mut ChaCha8Rng::seed_from_u64(99),
        );
        other.load_state(&sac.state()).unwrap();
        assert_eq!(other.state(), sac.state());
        assert_eq!(other.compute_gradient(&b, 3).0, sac.compute_gradient(&b, 3).0);
        let obs = [0.3f32, -0.1, 0.2, 0.9, -0.5, 0.0];
        let AnyPolicy::Deterministic(p) = sac.policy() else { panic!("a deterministic actor") };
        let full = sac.actor.to_plain().forward(&obs);
        let mean: Vec<f32> = full[..4].iter().map(|m| m.tanh()).collect();
        let got = p.act(&obs);
        assert!(got.iter().zip(&mean).all(|(a, b)| (a - b).abs() < 1e-6), "{got:?} vs {mean:?}");
        let mut broken = sac.state();
        broken.tensors.remove("critic2_adam.0");
        assert!(other.load_state(&broken).unwrap_err().to_string().contains("critic2_adam"));
    }
}
