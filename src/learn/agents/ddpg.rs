//! DDPG as in OpenAI baselines' HER code with the hyperparameters of
//! Plappert et al. 2018 (without hindsight relabelling: BlockPuzzle rewards
//! are not goal-conditioned).
//!
//! * actor π(s) = tanh(MLP(s̄)), critic Q(s̄, a), s̄ the normalised observation;
//! * critic target y = clip(r + γ (1 − terminated) Q'(s̄', π'(s̄')), −1/(1−γ), 0):
//!   `terminated` masks the bootstrap, truncation at the time limit does not;
//! * actor loss −Q(s̄, π(s̄)) + λ‖π(s̄)‖², λ = 1 (action L2 penalty);
//! * both gradients from the same parameters, then one Adam step each;
//! * targets follow with polyak averaging after each cycle's batches;
//! * exploration: with probability 0.3 a uniform random action, otherwise
//!   π(s) + N(0, 0.2²), clipped to [−1, 1].
//!
//! Options beyond the paper (all off by default), studied for the headline
//! row (`results/headline.md`):
//!
//! * `--n-step N`: the reward is the discounted sum of the next m = min(N,
//!   steps left) rewards and the bootstrap is γᵐ Q'(s̄ₜ₊ₘ, ·) (no off-policy
//!   correction, as in Rainbow and D4PG);
//! * `--td3` (Fujimoto et al. 2018): two critics, the target takes the
//!   smaller of the two target critics (clipped double Q) at a smoothed
//!   target action clip(π'(s̄') + clip(N(0, σ²), ±c), ±1), and the actor and
//!   the target networks' schedule stay as above except that the actor is
//!   updated on every `policy_delay`-th critic update only.

use super::algorithm::{
    param_count, split_gradient, Algorithm, Explorer, Info, Part, Registration, StartError, StartUses, UpdateStats,
};
use super::arch::Arch;
use super::nets::{append_grads, Adam, Net};
use super::replay::Batch;
use super::shared::SharedConfig;
use crate::policy::actor::mlp::PlainNet;
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::AnyPolicy;
use crate::support::limits::Bound;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use tch::Tensor;

/// TD3's critic updates per actor update.
pub const POLICY_DELAY: Bound = Bound::new("--policy-delay", 1, 1_000, "");

/// DDPG in the list of algorithms (`--algo ddpg`).
pub const REGISTRATION: Registration<DdpgConfig> = Registration {
    info: Info {
        trainer: crate::benchmark::saved::Trainer::Ddpg,
        title: "DDPG",
        about: "deep deterministic policy gradient (the paper's; --td3 for TD3)",
        takes_expert: false,
        imitates: false,
        // Every shared setting.
        reads: SharedConfig::FLAGS,
        flag_prefix: "",
        branchable: &["random_eps", "noise_eps", "noise_correlation", "action_l2", "preact_l2", "preact_margin"],
        starts_from_policy: true,
    },
    new: |spec, own, rng| Box::new(Ddpg::build(spec.arch, spec.act_dim, spec.shared.clone(), own.clone(), rng)),
    validate: DdpgConfig::validate,
    unused: |c| {
        let d = DdpgConfig::DEFAULT;
        let td3_only = [
            ("--target-noise", c.target_noise != d.target_noise),
            ("--target-noise-clip", c.target_noise_clip != d.target_noise_clip),
            ("--policy-delay", c.policy_delay != d.policy_delay),
        ];
        td3_only.into_iter().filter(|(_, given)| *given && !c.td3).map(|(f, _)| (f, "--algo ddpg --td3")).collect()
    },
    // Actor and critic(s), each with its target and Adam's two moments.
    memory: |spec, c| spec.mlp_bytes(0, spec.act_dim, 4) + spec.mlp_bytes(spec.act_dim, 1, if c.td3 { 8 } else { 4 }),
    take_branch: |agent, own| {
        let ddpg = super::algorithm::learner_mut::<Ddpg>(agent, "ddpg")?;
        ddpg.config = super::algorithm::take_fields(&ddpg.config, own, REGISTRATION.info.branchable)?;
        Ok(())
    },
    describe: |c| {
        let paper = DdpgConfig::DEFAULT;
        let mut v = Vec::new();
        if c.td3 {
            v.push("TD3".to_owned());
        }
        if c.action_l2 == 0.0 {
            v.push("no action penalty".to_owned());
        } else if c.action_l2 != paper.action_l2 {
            v.push(format!("action penalty {}", c.action_l2));
        }
        if c.noise_correlation > 0.0 {
            v.push(format!("noise correlation {}", c.noise_correlation));
        }
        if c.preact_l2 > 0.0 && c.preact_margin > 0.0 {
            v.push(format!("pre-tanh penalty {} beyond {}", c.preact_l2, c.preact_margin));
        } else if c.preact_l2 > 0.0 {
            v.push(format!("pre-tanh penalty {}", c.preact_l2));
        }
        v
    },
};

/// DDPG's own settings (defaults: the paper's, i.e. Plappert et al. 2018),
/// besides the shared ones ([`SharedConfig`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "DDPG's settings (--algo ddpg)")]
pub struct DdpgConfig {
    /// Weight of the L2 penalty on the actor's (pre-scaling) actions.
    #[arg(long, default_value_t = Self::DEFAULT.action_l2)]
    pub action_l2: f64,
    /// Weight of an L2 penalty on the actor's output before its tanh (0: off,
    /// the paper's). Unlike `--action-l2`, its gradient does not vanish where
    /// the tanh saturates, so it keeps actions in the range where the critic
    /// can still steer them.
    #[arg(long, default_value_t = Self::DEFAULT.preact_l2)]
    pub preact_l2: f64,
    /// With `--preact-l2`: penalise only the part of each pre-tanh output
    /// beyond this size, `(|u| − margin)²` where `|u| > margin` (0: all of
    /// it, `u²`). Inside the margin the actor is free (tanh(2) = 0.96), so
    /// the penalty keeps actions off the tanh's flat ends without pulling
    /// them towards 0.
    #[arg(long, default_value_t = Self::DEFAULT.preact_margin)]
    pub preact_margin: f64,
    /// Probability of a uniform random action while exploring.
    #[arg(long, default_value_t = Self::DEFAULT.random_eps)]
    pub random_eps: f64,
    /// Standard deviation of the Gaussian exploration noise.
    #[arg(long, default_value_t = Self::DEFAULT.noise_eps)]
    pub noise_eps: f64,
    /// Correlation of the exploration noise between consecutive steps of an
    /// episode, in [0, 1): AR(1) noise with the same standard deviation, whose
    /// deviations persist for about 1 / (1 − ρ) steps (0: independent, the paper's).
    #[arg(long, default_value_t = Self::DEFAULT.noise_correlation)]
    pub noise_correlation: f64,
    /// TD3's changes: twin critics (clipped double Q), target policy smoothing, delayed actor updates.
    #[arg(long)]
    pub td3: bool,
    /// TD3: standard deviation of the target action's smoothing noise.
    #[arg(long, default_value_t = Self::DEFAULT.target_noise)]
    pub target_noise: f64,
    /// TD3: the smoothing noise is clipped to ±this.
    #[arg(long, default_value_t = Self::DEFAULT.target_noise_clip)]
    pub target_noise_clip: f64,
    /// TD3: the actor is updated on every this-many critic updates.
    #[arg(long, default_value_t = Self::DEFAULT.policy_delay, value_parser = POLICY_DELAY.parser::<usize>())]
    pub policy_delay: usize,
}

impl DdpgConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        action_l2: 1.0,
        preact_l2: 0.0,
        preact_margin: 0.0,
        random_eps: 0.3,
        noise_eps: 0.2,
        noise_correlation: 0.0,
        td3: false,
        target_noise: 0.2,
        target_noise_clip: 0.5,
        policy_delay: 2,
    };

    /// Whether every setting is in range; the error names the flag.
    ///
    /// # Errors
    /// The first setting out of range.
    pub fn validate(&self) -> Result<(), String> {
        POLICY_DELAY.check_usize(self.policy_delay)?;
        let checks: [(bool, &str); 8] = [
            (self.action_l2.is_finite() && self.action_l2 >= 0.0, "--action-l2 must be a number ≥ 0"),
            (self.preact_l2.is_finite() && self.preact_l2 >= 0.0, "--preact-l2 must be a number ≥ 0"),
            (self.preact_margin.is_finite() && self.preact_margin >= 0.0, "--preact-margin must be a number ≥ 0"),
            (
                self.preact_margin == 0.0 || self.preact_l2 > 0.0,
                "--preact-margin sets where --preact-l2's penalty starts: give --preact-l2 W > 0 too",
            ),
            ((0.0..=1.0).contains(&self.random_eps), "--random-eps must be in [0, 1]"),
            (self.noise_eps.is_finite() && self.noise_eps >= 0.0, "--noise-eps must be a number ≥ 0"),
            ((0.0..1.0).contains(&self.noise_correlation), "--noise-correlation must be in [0, 1)"),
            (
                self.target_noise.is_finite()
                    && self.target_noise >= 0.0
                    && self.target_noise_clip.is_finite()
                    && self.target_noise_clip >= 0.0,
                "--target-noise and --target-noise-clip must be numbers ≥ 0",
            ),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, msg)) => Err((*msg).to_owned()),
            None => Ok(()),
        }
    }
}

impl Default for DdpgConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The DDPG learner.
pub struct Ddpg {
    /// The shared settings it reads (shape, learning rates, discount, targets, normaliser, precision).
    pub shared: SharedConfig,
    /// Its own settings.
    pub config: DdpgConfig,
    /// Observation normaliser.
    pub norm: Normalizer,
    /// Actor π.
    pub actor: Net,
    /// Critic Q.
    pub critic: Net,
    /// Target actor π'.
    pub actor_target: Net,
    /// Target critic Q'.
    pub critic_target: Net,
    /// Actor optimiser.
    pub actor_opt: Adam,
    /// Critic optimiser.
    pub critic_opt: Adam,
    /// TD3's second critic (None for DDPG).
    pub twin: Option<Twin>,
    obs_dim: usize,
    act_dim: usize,
    last_targets: Vec<f32>,
    /// The actor is held still: updates step the critics alone (a critic warm-up).
    actor_held: bool,
    /// The policy the run started from, frozen, and what it is kept for ([`Algorithm::keep_start`]);
    /// not checkpointed.
    start: Option<(Net, StartUses)>,
}

/// TD3's second critic, its target and optimiser, and the seed of the
/// target-smoothing noise (update k draws its noise from a stream of
/// (seed, k), so a resumed run draws the same noise).
pub struct Twin {
    /// Second critic Q₂.
    pub critic: Net,
    /// Its target Q₂'.
    pub target: Net,
    /// Its optimiser.
    pub opt: Adam,
    /// Seed of the smoothing noise.
    pub noise_seed: u64,
}

impl Ddpg {
    /// A fresh learner with MLPs over `obs_dim`-long observations; `rng` fixes the initial weights.
    pub fn new(obs_dim: usize, act_dim: usize, shared: SharedConfig, config: DdpgConfig, rng: &mut impl Rng) -> Self {
        Self::build(Arch::mlp(obs_dim), act_dim, shared, config, rng)
    }

    /// A fresh learner with the networks of `arch`; `rng` fixes the initial weights.
    pub fn build(arch: Arch, act_dim: usize, shared: SharedConfig, config: DdpgConfig, rng: &mut impl Rng) -> Self {
        let (bf16, shape) = (shared.bf16(), (shared.hidden, shared.layers));
        let obs_dim = arch.obs_dim;
        let actor = arch.net(shape, 0, act_dim, true, rng).with_bf16(bf16);
        let critics = arch.critics(shared.flat_critic);
        let critic = critics.net(shape, act_dim, 1, false, rng).with_bf16(bf16).with_hidden_norm(shared.critic_norm);
        let (actor_target, critic_target) = (actor.detached_copy(), critic.detached_copy());
        let actor_opt = Adam::new(&actor.params, shared.lr_actor);
        let critic_opt = Adam::new(&critic.params, shared.lr_critic);
        let norm = arch.normalizer(shared.norm_eps, shared.norm_clip);
        // Drawn after the first critic, so a DDPG agent's initial weights do not depend on TD3.
        let twin = config.td3.then(|| {
            let critic =
                critics.net(shape, act_dim, 1, false, rng).with_bf16(bf16).with_hidden_norm(shared.critic_norm);
            let (target, opt) = (critic.detached_copy(), Adam::new(&critic.params, shared.lr_critic));
            Twin { critic, target, opt, noise_seed: rng.gen() }
        });
        Self {
            twin,
            shared,
            config,
            norm,
            actor,
            critic,
            actor_target,
            critic_target,
            actor_opt,
            critic_opt,
            obs_dim,
            act_dim,
            last_targets: Vec::new(),
            actor_held: false,
            start: None,
        }
    }

    /// Observation size.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Action size.
    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// The smoothed target actions clip(π'(s̄') + clip(ε, ±c), ±1), ε ~ N(0, σ²)
    /// from the stream of update `k`.
    fn smoothed(&self, next_act: Tensor, noise_seed: u64, k: u64) -> Tensor {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(noise_seed ^ k.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let c = self.config.target_noise_clip as f32;
        let noise: Vec<f32> = (0..next_act.numel())
            .map(|_| {
                let z: f64 = StandardNormal.sample(&mut rng);
                ((self.config.target_noise * z) as f32).clamp(-c, c)
            })
            .collect();
        let noise = Tensor::of_slice(&noise).view_as(&next_act);
        (next_act + noise).clamp(-1.0, 1.0)
    }

    /// One gradient step of the critic(s) and (unless TD3 delays it) the actor on `batch`.
    pub fn update(&mut self, batch: &Batch) -> UpdateStats {
        let (gradient, stats) = self.gradient(batch, 0);
        self.apply_gradient(&gradient);
        stats
    }

    /// Whether the next update steps the actor (TD3 delays it to every
    /// `policy_delay`-th critic update).
    fn actor_steps(&self) -> bool {
        !self.actor_held && (self.twin.is_none() || self.critic_opt.t % self.config.policy_delay as u64 == 0)
    }

    /// The gradients of the next update on `batch`, flattened (critic, TD3's
    /// second critic, then the actor when it steps), and the update's
    /// statistics; nothing is changed. `shard` (0, 1, …) picks TD3's
    /// smoothing noise when several batches' gradients are averaged into one
    /// update (shard 0 draws the stream a single batch draws).
    pub fn gradient(&mut self, batch: &Batch, shard: u64) -> (Vec<f32>, UpdateStats) {
        let n = batch.len() as i64;
        let obs = self.norm.tensor(&batch.obs);
        let next_obs = self.norm.tensor(&batch.next_obs);
        let act = Tensor::of_slice(&batch.act).view([n, self.act_dim as i64]);
        let rew = Tensor::of_slice(&batch.rew).view([n, 1]);
        let not_done = 1.0 - Tensor::of_slice(&batch.terminated).view([n, 1]);
        let discount = Tensor::of_slice(&batch.discount).view([n, 1]);
        let clip_return = 1.0 / (1.0 - self.shared.gamma);
        let k = self.critic_opt.t;

        let target = tch::no_grad(|| {
            let next_act = self.actor_target.forward(&next_obs);
            let next_q = match &self.twin {
                None => self.critic_target.q(&next_obs, &next_act),
                Some(t) => {
                    let seed = if shard == 0 { t.noise_seed } else { shard_seed(t.noise_seed, shard) };
                    let next_act = self.smoothed(next_act, seed, k);
                    let q1 = self.critic_target.q(&next_obs, &next_act);
                    q1.minimum(&t.target.q(&next_obs, &next_act))
                }
            };
            // IBRL: the better of the actor's and the proposer's action at the next state.
            let next_q = match &self.start {
                Some((il, uses)) if uses.propose => {
                    let a = il.forward(&next_obs);
                    let q = self.critic_target.q(&next_obs, &a);
                    let q = match &self.twin {
                        None => q,
                        Some(t) => q.minimum(&t.target.q(&next_obs, &a)),
                    };
                    next_q.maximum(&q)
                }
                _ => next_q,
            };
            let y: Tensor = rew + not_done * next_q * discount;
            y.clamp(-clip_return, 0.0)
        });
        self.last_targets = super::nets::tensor_to_vec(&target);
        let q = self.critic.q(&obs, &act);
        let mut critic_loss = (&q - &target).square().mean(tch::Kind::Float);
        if let Some(t) = &self.twin {
            critic_loss += (t.critic.q(&obs, &act) - &target).square().mean(tch::Kind::Float);
        }

        // The actor's loss goes through the critic with its parameters
        // detached: gradients reach the actor only, and both losses see the
        // same (pre-update) parameters, as in baselines.
        let actor_loss = self.actor_steps().then(|| {
            let u = self.actor.preactivation(&obs);
            let pi = u.tanh();
            let frozen_critic = self.critic.detached_view();
            let q_pi = frozen_critic.q(&obs, &pi);
            let value = match &self.start {
                Some((start, uses)) if uses.anchor_alpha > 0.0 => {
                    // TD3+BC's balance: the critic's term scaled to mean |Q| = alpha.
                    let scale = q_pi.abs().mean(tch::Kind::Float).detach().clamp_min(1e-6);
                    let near = (&pi - tch::no_grad(|| start.forward(&obs))).square().mean(tch::Kind::Float);
                    -q_pi.mean(tch::Kind::Float) * uses.anchor_alpha / scale + near
                }
                _ => -q_pi.mean(tch::Kind::Float),
            };
            let loss = value + pi.square().mean(tch::Kind::Float) * self.config.action_l2;
            if self.config.preact_l2 == 0.0 {
                loss
            } else if self.config.preact_margin > 0.0 {
                let beyond = (u.abs() - self.config.preact_margin).relu();
                loss + beyond.square().mean(tch::Kind::Float) * self.config.preact_l2
            } else {
                loss + u.square().mean(tch::Kind::Float) * self.config.preact_l2
            }
        });

        self.critic.zero_grad();
        self.actor.zero_grad();
        if let Some(t) = &mut self.twin {
            t.critic.zero_grad();
        }
        critic_loss.backward();
        if let Some(l) = &actor_loss {
            l.backward();
        }
        let mut flat = Vec::new();
        append_grads(&self.critic.params, &mut flat);
        if let Some(t) = &self.twin {
            append_grads(&t.critic.params, &mut flat);
        }
        if actor_loss.is_some() {
            append_grads(&self.actor.params, &mut flat);
        }
        let stats = UpdateStats {
            critic_loss: critic_loss.double_value(&[]),
            actor_loss: actor_loss.map_or(f64::NAN, |l| l.double_value(&[])),
            mean_q: q.mean(tch::Kind::Float).double_value(&[]),
        };
        (flat, stats)
    }

    /// One Adam step of each network with a gradient laid out as
    /// [`Ddpg::gradient`] returns it (e.g. the mean of several).
    ///
    /// # Panics
    /// If `gradient` does not have that layout.
    pub fn apply_gradient(&mut self, gradient: &[f32]) {
        let actor_step = self.actor_steps();
        let mut nets = vec![&self.critic];
        nets.extend(self.twin.as_ref().map(|t| &t.critic));
        if actor_step {
            nets.push(&self.actor);
        }
        let parts = split_gradient(gradient, &nets);
        self.critic_opt.step(&mut self.critic.params, parts[0]);
        if let Some(t) = &mut self.twin {
            t.opt.step(&mut t.critic.params, parts[1]);
        }
        if actor_step {
            self.actor_opt.step(&mut self.actor.params, parts[parts.len() - 1]);
        }
    }

    /// The critic targets y of the last update, one per transition.
    pub fn last_targets(&self) -> &[f32] {
        &self.last_targets
    }

    /// Polyak-averages the target networks towards the learned ones.
    pub fn update_targets(&mut self) {
        let p = self.shared.polyak;
        self.actor_target.polyak_from(&self.actor, p);
        self.critic_target.polyak_from(&self.critic, p);
        if let Some(t) = &mut self.twin {
            t.target.polyak_from(&t.critic, p);
        }
    }

    /// A self-contained policy for rollouts (weights and normaliser frozen).
    pub fn policy(&self) -> DeterministicPolicy {
        DeterministicPolicy { net: self.actor.to_plain(), norm: self.norm.clone() }
    }
}

impl Algorithm for Ddpg {
    super::algorithm::learner_basics!(REGISTRATION.info.name());

    fn gradient(&mut self, batch: &Batch, shard: u64, _weights: Option<&[f32]>) -> (Vec<f32>, UpdateStats) {
        Ddpg::gradient(self, batch, shard)
    }

    fn apply_gradient(&mut self, gradient: &[f32]) {
        Ddpg::apply_gradient(self, gradient);
    }

    fn gradient_len(&self) -> usize {
        let twin = self.twin.as_ref().map_or(0, |t| param_count(&[&t.critic]));
        param_count(&[&self.critic, &self.actor]) + twin
    }

    fn end_cycle(&mut self) {
        self.update_targets();
    }

    fn policy(&self) -> AnyPolicy {
        AnyPolicy::Deterministic(Ddpg::policy(self))
    }

    fn init_from(&mut self, policy: &DeterministicPolicy) -> Result<(), StartError> {
        let fitted = super::algorithm::fit_actor(&self.actor.to_plain(), &self.norm, policy)?;
        let vecs = super::algorithm::plain_vecs(&fitted.net);
        self.actor.load_vecs(&vecs)?;
        self.actor_target.load_vecs(&vecs)?;
        self.norm = fitted.norm;
        Ok(())
    }

    fn keep_start(&mut self, policy: &DeterministicPolicy, uses: StartUses) -> Result<(), StartError> {
        let fitted = super::algorithm::fit_actor(&self.actor.to_plain(), &self.norm, policy)?;
        let mut start = self.actor.detached_copy();
        start.load_vecs(&super::algorithm::plain_vecs(&fitted.net))?;
        self.start = Some((start, uses));
        Ok(())
    }

    fn hold_actor(&mut self, held: bool) {
        self.actor_held = held;
    }

    fn explorer(&self) -> Box<dyn Explorer> {
        let c = &self.config;
        Box::new(DdpgExplorer {
            policy: Ddpg::policy(self),
            random_eps: c.random_eps,
            noise_eps: c.noise_eps,
            noise_correlation: c.noise_correlation,
            proposal: match &self.start {
                Some((il, uses)) if uses.propose => Some((il.to_plain(), self.critic.to_plain())),
                _ => None,
            },
        })
    }

    fn critic(&self) -> Option<PlainNet> {
        Some(self.critic.to_plain())
    }

    fn parts(&mut self) -> Vec<(&'static str, Part<'_>)> {
        let mut parts = vec![
            ("actor", Part::Net(&mut self.actor)),
            ("critic", Part::Net(&mut self.critic)),
            ("actor_target", Part::Net(&mut self.actor_target)),
            ("critic_target", Part::Net(&mut self.critic_target)),
            ("actor_adam", Part::Adam(&mut self.actor_opt)),
            ("critic_adam", Part::Adam(&mut self.critic_opt)),
        ];
        if let Some(t) = &mut self.twin {
            parts.extend([
                ("critic2", Part::Net(&mut t.critic)),
                ("critic2_target", Part::Net(&mut t.target)),
                ("critic2_adam", Part::Adam(&mut t.opt)),
                ("critic2.noise_seed", Part::Counter(&mut t.noise_seed)),
            ]);
        }
        parts
    }
}

/// DDPG's exploration with a frozen actor: see [`DeterministicPolicy::explore_correlated`].
pub struct DdpgExplorer {
    /// The actor.
    pub policy: DeterministicPolicy,
    /// Probability of a uniform random action.
    pub random_eps: f64,
    /// Standard deviation of the Gaussian noise.
    pub noise_eps: f64,
    /// Correlation of the noise between consecutive steps.
    pub noise_correlation: f64,
    /// IBRL: the imitation policy's network and the critic, which picks between its action and the
    /// actor's before the noise ([`Algorithm::keep_start`]).
    pub proposal: Option<(PlainNet, PlainNet)>,
}

impl Explorer for DdpgExplorer {
    fn explore(&self, obs: &[f32], noise: &mut Vec<f32>, rng: &mut ChaCha8Rng) -> Vec<f32> {
        let settings = (self.random_eps, self.noise_eps, self.noise_correlation);
        let Some((il, critic)) = &self.proposal else {
            return self.policy.explore_correlated(obs, settings, noise, rng);
        };
        let mut x = obs.to_vec();
        self.policy.norm.normalize_in_place(&mut x);
        let (ours, theirs) = (self.policy.act(obs), il.forward(&x));
        let q = |a: &[f32]| critic.forward(&[&x[..], a].concat())[0];
        let a = if q(&theirs) > q(&ours) { theirs } else { ours };
        DeterministicPolicy::perturb(a, settings, noise, rng)
    }
}

use crate::policy::actor::DeterministicPolicy;

/// DDPG's exploration (training only: the policy itself is the core's).
impl DeterministicPolicy {
    /// The exploration action with noise correlated across an episode's
    /// steps: uniform with probability `random_eps`, else π(s) + n, clipped to
    /// [−1, 1], where n follows n ← ρ n + √(1 − ρ²) noise_eps z, z ~ N(0, I),
    /// from a first draw noise_eps z (so each step's noise has standard
    /// deviation noise_eps). `noise` is the episode's state (empty at its
    /// start). With ρ = 0 every step's noise is noise_eps z, exactly (the
    /// paper's independent noise, draw for draw).
    pub fn explore_correlated(
        &self,
        obs: &[f32],
        (random_eps, noise_eps, rho): (f64, f64, f64),
        noise: &mut Vec<f32>,
        rng: &mut impl Rng,
    ) -> Vec<f32> {
        Self::perturb(self.act(obs), (random_eps, noise_eps, rho), noise, rng)
    }

    /// The action `a` explored as [`DeterministicPolicy::explore_correlated`] explores π(s).
    pub fn perturb(
        a: Vec<f32>,
        (random_eps, noise_eps, rho): (f64, f64, f64),
        noise: &mut Vec<f32>,
        rng: &mut impl Rng,
    ) -> Vec<f32> {
        if rng.gen_bool(random_eps.clamp(0.0, 1.0)) {
            return a.iter().map(|_| rng.gen_range(-1.0..=1.0)).collect();
        }
        let fresh = noise.is_empty();
        noise.resize(a.len(), 0.0);
        let keep = (1.0 - rho * rho).sqrt();
        a.iter()
            .zip(noise.iter_mut())
            .map(|(&x, n)| {
                let z: f64 = StandardNormal.sample(rng);
                *n = if fresh { (noise_eps * z) as f32 } else { (rho * *n as f64 + keep * noise_eps * z) as f32 };
                (x + *n).clamp(-1.0, 1.0)
            })
            .collect()
    }

    /// The exploration action: uniform with probability `random_eps`, else
    /// π(s) + N(0, noise_eps²), clipped to [−1, 1] (independent noise: no state).
    pub fn explore(&self, obs: &[f32], random_eps: f64, noise_eps: f64, rng: &mut impl Rng) -> Vec<f32> {
        self.explore_correlated(obs, (random_eps, noise_eps, 0.0), &mut Vec::new(), rng)
    }
}

/// The smoothing-noise seed of shard `shard` > 0 of an averaged update.
fn shard_seed(seed: u64, shard: u64) -> u64 {
    let mut z = seed ^ shard.wrapping_mul(0xD6E8_FEB8_6659_FD93);
    z = (z ^ (z >> 32)).wrapping_mul(0xD6E8_FEB8_6659_FD93);
    z ^ (z >> 32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learn::agents::algorithm::StateError;
    use crate::learn::agents::shared::Precision;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn batch(n: usize, obs_dim: usize, rng: &mut ChaCha8Rng) -> Batch {
        let mut b = Batch::default();
        for i in 0..n {
            b.obs.extend((0..obs_dim).map(|_| rng.gen_range(-1.0..1.0)));
            b.act.extend((0..4).map(|_| rng.gen_range(-1.0..1.0)));
            b.rew.push(if i % 5 == 0 { 0.0 } else { -1.0 });
            b.next_obs.extend((0..obs_dim).map(|_| rng.gen_range(-1.0..1.0)));
            b.terminated.push(if i % 5 == 0 { 1.0 } else { 0.0 });
            b.return_to_go.push(0.0);
            b.discount.push(0.98);
        }
        b
    }

    fn small() -> SharedConfig {
        SharedConfig { hidden: 32, layers: 2, ..SharedConfig::default() }
    }

    /// IBRL: the critic's target bootstraps from the better of the actor's and the proposer's action
    /// (never below the actor's alone), TD3's twin included; exploration takes the proposer's action
    /// where the critic values it more; the saved policy is the actor's.
    #[test]
    fn ibrl_targets_take_the_better_proposal() {
        for td3 in [false, true] {
            let mut rng = ChaCha8Rng::seed_from_u64(11);
            let config = DdpgConfig { td3, random_eps: 0.0, noise_eps: 0.0, ..DdpgConfig::default() };
            let mut a = Ddpg::new(6, 4, small(), config.clone(), &mut rng);
            let other = Ddpg::new(6, 4, small(), config, &mut rng).policy();
            let b = batch(64, 6, &mut rng);
            a.gradient(&b, 0);
            let alone = a.last_targets().to_vec();
            a.keep_start(&other, StartUses { propose: true, ..StartUses::default() }).unwrap();
            a.gradient(&b, 0);
            let with = a.last_targets().to_vec();
            assert!(with.iter().zip(&alone).all(|(w, o)| w >= o), "td3 {td3}");
            assert!(with.iter().zip(&alone).any(|(w, o)| w > o), "td3 {td3}: the proposer is better somewhere");
            assert_eq!(Algorithm::policy(&a), AnyPolicy::Deterministic(a.policy()), "the saved policy is the actor");
            // Without noise, exploration is whichever action the critic values more.
            let explorer = Algorithm::explorer(&a);
            let critic = a.critic.to_plain();
            for obs in b.obs.chunks(6).take(16) {
                let mut x = obs.to_vec();
                a.norm.normalize_in_place(&mut x);
                let (ours, theirs) = (a.policy().act(obs), other.net.forward(&x));
                let q = |act: &[f32]| critic.forward(&[&x[..], act].concat())[0];
                let want = if q(&theirs) > q(&ours) { theirs } else { ours };
                assert_eq!(explorer.explore(obs, &mut Vec::new(), &mut rng), want);
            }
        }
    }

    #[test]
    fn updates_change_weights_and_lower_the_critic_loss() {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let mut agent = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut rng);
        let b = batch(256, 6, &mut rng);
        agent.norm.update(&b.obs);
        let before = agent.actor.to_vecs();
        let critic_before = agent.critic.to_vecs();
        let first = agent.update(&b);
        assert_ne!(agent.actor.to_vecs(), before, "actor weights changed");
        assert_ne!(agent.critic.to_vecs(), critic_before, "critic weights changed");
        let mut last = first;
        for _ in 0..50 {
            last = agent.update(&b);
        }
        assert!(last.critic_loss < first.critic_loss * 0.5, "{first:?} -> {last:?}");
    }

    #[test]
    fn bf16_products_stay_close_to_f32_and_still_learn() {
        if !Precision::bf16_supported() {
            // Past the harness's capture, so a green run says what it did not check.
            use std::io::Write;
            let _ =
                writeln!(std::io::stderr().lock(), "SKIPPED in {}: no AMX / AVX512-BF16 on this CPU", module_path!());
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let f32_agent = Ddpg::new(6, 4, SharedConfig::default(), DdpgConfig::default(), &mut rng);
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let bf16 = SharedConfig { precision: Precision::Bf16, ..SharedConfig::default() };
        let mut agent = Ddpg::new(6, 4, bf16, DdpgConfig::default(), &mut rng);
        let b = batch(256, 6, &mut rng);
        // Same weights, products rounded to bfloat16 (8-bit mantissa): close, not equal.
        let x = agent.norm.tensor(&b.obs);
        let (y16, y32) = tch::no_grad(|| (agent.actor.forward(&x), f32_agent.actor.forward(&x)));
        let err = (&y16 - &y32).abs().max().double_value(&[]);
        assert!(err > 0.0 && err < 0.05, "max |bf16 - f32| = {err}");
        agent.norm.update(&b.obs);
        let first = agent.update(&b);
        let mut last = first;
        for _ in 0..50 {
            last = agent.update(&b);
        }
        assert!(last.critic_loss < first.critic_loss * 0.5, "{first:?} -> {last:?}");
    }

    #[test]
    fn flat_critics_read_the_rows_in_order_while_the_set_actor_ignores_it() {
        use crate::policy::actor::mlp::SetLayout;
        // 3 robot features, 3 slots of 4 features, a mask.
        let layout = SetLayout::new(3, 4, 3, 1);
        let arch = Arch { obs_dim: layout.obs_dim(), set: Some(layout) };
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let shared = SharedConfig { flat_critic: true, ..small() };
        let mut agent = Ddpg::build(arch, 4, shared, td3(), &mut rng);
        assert!(agent.actor.set_layout().is_some());
        let twin = agent.twin.as_ref().unwrap();
        assert!(agent.critic.set_layout().is_none() && twin.critic.set_layout().is_none());
        assert_eq!(agent.critic.sizes()[0], layout.obs_dim() + 4, "the whole observation and the action");
        let row = |v: &[f32]| Tensor::of_slice(v).view([1, v.len() as i64]);
        let x: Vec<f32> = (0..layout.obs_dim()).map(|i| if i >= 15 { 1.0 } else { (i as f32 * 0.37).sin() }).collect();
        let mut swapped = x.clone();
        swapped[3..7].copy_from_slice(&x[7..11]);
        swapped[7..11].copy_from_slice(&x[3..7]);
        let a = Tensor::of_slice(&[0.1f32, -0.2, 0.3, 0.0]).view([1, 4]);
        let (pi, pi_swapped) = (agent.actor.forward(&row(&x)), agent.actor.forward(&row(&swapped)));
        assert!((pi - pi_swapped).abs().max().double_value(&[]) < 1e-6, "the actor: a set");
        let (q, q_swapped) = (agent.critic.q(&row(&x), &a), agent.critic.q(&row(&swapped), &a));
        assert!((q - q_swapped).abs().max().double_value(&[]) > 1e-6, "the critic: slots in order");
        // It learns as any agent does.
        let b = batch(64, layout.obs_dim(), &mut rng);
        let before = agent.actor.to_vecs();
        let first = agent.update(&b);
        let mut last = first;
        for _ in 0..50 {
            last = agent.update(&b);
        }
        assert_ne!(agent.actor.to_vecs(), before);
        assert!(last.critic_loss < first.critic_loss * 0.5, "{first:?} -> {last:?}");
    }

    #[test]
    fn terminal_transitions_do_not_bootstrap_and_targets_are_clipped() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut agent = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut rng);
        let mut b = batch(10, 6, &mut rng);
        b.rew = vec![-60.0, 0.0, -1.0, -1.0, -1.0, 0.0, -1.0, -1.0, -1.0, -1.0];
        b.terminated = vec![1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        agent.update(&b);
        let y = agent.last_targets();
        assert_eq!(y[0], -50.0, "clipped at -1/(1-gamma)");
        assert_eq!(y[1], 0.0, "terminal: the reward alone");
        assert_eq!(y[2], -1.0);
        assert!(y[3..].iter().all(|v| (-50.0..=0.0).contains(v)));
        assert!(y[3..].iter().any(|&v| v != -1.0), "non-terminal targets bootstrap");
    }

    fn td3() -> DdpgConfig {
        DdpgConfig { td3: true, ..DdpgConfig::default() }
    }

    #[test]
    fn td3_updates_both_critics_and_lowers_their_loss() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut agent = Ddpg::new(6, 4, small(), td3(), &mut rng);
        let b = batch(256, 6, &mut rng);
        agent.norm.update(&b.obs);
        let twin_before = agent.twin.as_ref().unwrap().critic.to_vecs();
        assert_ne!(twin_before, agent.critic.to_vecs(), "the critics start apart");
        let first = agent.update(&b);
        assert_ne!(agent.twin.as_ref().unwrap().critic.to_vecs(), twin_before);
        let mut last = first;
        for _ in 0..50 {
            last = agent.update(&b);
        }
        assert!(last.critic_loss < first.critic_loss * 0.5, "{first:?} -> {last:?}");
        // A DDPG agent of the same seed has the same actor and first critic: TD3 draws after them.
        let ddpg = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut ChaCha8Rng::seed_from_u64(5));
        let twin = Ddpg::new(6, 4, small(), td3(), &mut ChaCha8Rng::seed_from_u64(5));
        assert_eq!((ddpg.actor.to_vecs(), ddpg.critic.to_vecs()), (twin.actor.to_vecs(), twin.critic.to_vecs()));
    }

    #[test]
    fn td3_targets_take_the_smaller_target_critic_and_mask_terminals() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        // No smoothing noise: the target action is π'(s̄') itself.
        let mut agent = Ddpg::new(6, 4, small(), DdpgConfig { target_noise: 0.0, ..td3() }, &mut rng);
        let mut b = batch(8, 6, &mut rng);
        b.rew = vec![-1.0; 8];
        b.terminated = vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        b.discount = vec![0.98, 0.98, 0.5, 0.5, 0.98, 0.98, 0.98, 0.98];
        let next = agent.norm.tensor(&b.next_obs);
        let want: Vec<f32> = tch::no_grad(|| {
            let a = agent.actor_target.forward(&next);
            let q1 = agent.critic_target.q(&next, &a);
            let q2 = agent.twin.as_ref().unwrap().target.q(&next, &a);
            super::super::nets::tensor_to_vec(&q1.minimum(&q2))
        });
        agent.update(&b);
        let y = agent.last_targets().to_vec();
        assert_eq!(y[0], -1.0, "terminal: the reward alone");
        for i in 1..8 {
            let expect = (-1.0 + b.discount[i] * want[i]).clamp(-50.0, 0.0);
            assert!((y[i] - expect).abs() < 1e-5, "{i}: {} vs {expect}", y[i]);
        }
        // With noise, the targets move (smoothed actions), deterministically for the update number.
        let mut noisy = Ddpg::new(6, 4, small(), td3(), &mut ChaCha8Rng::seed_from_u64(6));
        noisy.update(&b);
        assert_ne!(noisy.last_targets(), &y[..]);
    }

    #[test]
    fn the_discount_column_scales_the_bootstrap() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let agent = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut rng);
        let mut b = batch(4, 6, &mut rng);
        b.rew = vec![-1.0; 4];
        b.terminated = vec![0.0; 4];
        let mut one = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut ChaCha8Rng::seed_from_u64(7));
        let mut three = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut ChaCha8Rng::seed_from_u64(7));
        drop(agent);
        one.update(&b);
        b.discount = vec![0.98f32.powi(3); 4];
        three.update(&b);
        // y = r + d Q': the same Q', so (y - r) scales with d.
        for (y1, y3) in one.last_targets().iter().zip(three.last_targets()) {
            assert!(((y3 + 1.0) - (y1 + 1.0) * 0.98f32.powi(2)).abs() < 1e-5, "{y1} {y3}");
        }
    }

    #[test]
    fn settings_out_of_range_name_their_flag() {
        assert!(DdpgConfig::default().validate().is_ok() && SharedConfig::default().validate().is_ok());
        let shared = |c: SharedConfig, flag: &str| assert!(c.validate().unwrap_err().contains(flag), "{flag}");
        shared(SharedConfig { lr_actor: f64::NAN, ..small() }, "--lr-actor");
        shared(SharedConfig { lr_critic: -1.0, ..small() }, "--lr-critic");
        shared(SharedConfig { gamma: 1.0, ..small() }, "--gamma");
        shared(SharedConfig { n_step: 0, ..small() }, "--n-step");
        shared(SharedConfig { hidden: 0, ..small() }, "--hidden");
        let own = |c: DdpgConfig, flag: &str| assert!(c.validate().unwrap_err().contains(flag), "{flag}");
        let d = DdpgConfig::default();
        own(DdpgConfig { target_noise: f64::INFINITY, ..d.clone() }, "--target-noise");
        own(DdpgConfig { preact_l2: -0.1, ..d.clone() }, "--preact-l2");
        own(DdpgConfig { preact_margin: f64::NAN, ..d.clone() }, "--preact-margin");
        own(DdpgConfig { preact_margin: 2.0, preact_l2: 0.0, ..d.clone() }, "--preact-l2 W > 0");
        own(DdpgConfig { noise_correlation: 1.0, ..d }, "--noise-correlation");
    }

    #[test]
    fn state_round_trips_and_a_part_the_settings_lack_is_named() {
        let mut td3_agent = Ddpg::new(6, 4, small(), td3(), &mut ChaCha8Rng::seed_from_u64(3));
        let mut other = Ddpg::new(6, 4, small(), td3(), &mut ChaCha8Rng::seed_from_u64(4));
        other.load_state(&td3_agent.state()).unwrap();
        assert_eq!(other.state(), td3_agent.state());
        let mut plain = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut ChaCha8Rng::seed_from_u64(4));
        let e = plain.load_state(&td3_agent.state()).unwrap_err();
        assert!(matches!(&e, StateError::Foreign(p) if p.starts_with("critic2")), "{e}");
    }

    /// Correlated exploration noise: ρ = 0 is the paper's independent noise
    /// draw for draw; with ρ = 0.9 consecutive steps' noise correlates about
    /// 0.9 and keeps its standard deviation.
    #[test]
    fn correlated_noise_persists_and_keeps_its_size() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let agent = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut rng);
        let policy = agent.policy();
        let obs = [0.1f32, -0.2, 0.3, 0.0, 0.5, -0.5];
        let mean = policy.act(&obs);
        let (mut r1, mut r2) = (ChaCha8Rng::seed_from_u64(1), ChaCha8Rng::seed_from_u64(1));
        let mut state = Vec::new();
        // The paper's noise, written out: uniform with probability 0.3, else π(s) + 0.2 z.
        let paper = |rng: &mut ChaCha8Rng| -> Vec<f32> {
            if rng.gen_bool(0.3) {
                return mean.iter().map(|_| rng.gen_range(-1.0..=1.0)).collect();
            }
            mean.iter()
                .map(|&x| {
                    let z: f64 = StandardNormal.sample(rng);
                    (x + (0.2 * z) as f32).clamp(-1.0, 1.0)
                })
                .collect()
        };
        for _ in 0..20 {
            let a = paper(&mut r1);
            assert_eq!(a, policy.explore_correlated(&obs, (0.3, 0.2, 0.0), &mut state, &mut r2));
        }
        let (mut r1, mut r2) = (ChaCha8Rng::seed_from_u64(2), ChaCha8Rng::seed_from_u64(2));
        assert_eq!(paper(&mut r1), policy.explore(&obs, 0.3, 0.2, &mut r2));
        // Small noise so that clipping at ±1 does not bias the statistics.
        let (sigma, rho) = (0.05, 0.9);
        let mut noise = Vec::new();
        let mut series = Vec::new();
        for _ in 0..20_000 {
            let a = policy.explore_correlated(&obs, (0.0, sigma, rho), &mut noise, &mut r1);
            series.push((a[0] - mean[0]) as f64);
        }
        let var = series.iter().map(|x| x * x).sum::<f64>() / series.len() as f64;
        let lag1 = series.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / (series.len() - 1) as f64;
        assert!((var.sqrt() - sigma).abs() < 0.1 * sigma, "std {} vs {sigma}", var.sqrt());
        assert!((lag1 / var - rho).abs() < 0.03, "lag-1 correlation {}", lag1 / var);
    }

    /// The pre-tanh penalty pulls a saturated actor back into the tanh's
    /// responsive range, where the action penalty's gradient (and the
    /// critic's) has vanished; off (the default), the loss is the paper's.
    #[test]
    fn preact_penalty_pulls_saturated_actions_back() {
        let run = |preact_l2: f64, preact_margin: f64| {
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            let own = DdpgConfig { preact_l2, preact_margin, ..DdpgConfig::default() };
            let mut agent = Ddpg::new(6, 4, small(), own, &mut rng);
            let b = batch(256, 6, &mut rng);
            agent.norm.update(&b.obs);
            // Saturate: scale the output layer by 100.
            let mut v = agent.actor.to_vecs();
            let n = v.len();
            for x in v[n - 2..].iter_mut().flatten() {
                *x *= 100.0;
            }
            agent.actor.load_vecs(&v).unwrap();
            let obs = agent.norm.tensor(&b.obs);
            let size = |a: &Ddpg| a.actor.preactivation(&obs).abs().mean(tch::Kind::Float).double_value(&[]);
            let before = size(&agent);
            let stats: Vec<UpdateStats> = (0..40).map(|_| agent.update(&b)).collect();
            (before, size(&agent), stats)
        };
        let (before, penalised, with) = run(0.01, 0.0);
        let (_, unpenalised, without) = run(0.0, 0.0);
        let (_, beyond_margin, _) = run(0.01, 2.0);
        assert!(before > 10.0, "saturated: mean |u| {before}");
        assert!(penalised < 0.8 * before, "{before} -> {penalised}");
        assert!(penalised < 0.8 * unpenalised, "{penalised} vs {unpenalised}");
        // The critic's side is untouched: the first update's critic loss is the same.
        assert_eq!(with[0].critic_loss, without[0].critic_loss);
        assert!(with[0].actor_loss > without[0].actor_loss, "the penalty is part of the actor's loss");
        // With a margin the saturated actor is pulled back too, and an actor inside the margin
        // (the fresh one: |u| is well below 100 there) is not penalised at all.
        assert!(beyond_margin < 0.8 * unpenalised, "{beyond_margin} vs {unpenalised}");
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let config = DdpgConfig { preact_l2: 0.01, preact_margin: 100.0, ..DdpgConfig::default() };
        let mut inside = Ddpg::new(6, 4, small(), config, &mut rng);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut free = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut rng);
        let b = batch(256, 6, &mut rng);
        inside.norm.update(&b.obs);
        free.norm.update(&b.obs);
        let (a, f) = (inside.update(&b), free.update(&b));
        assert_eq!(a.actor_loss, f.actor_loss, "nothing beyond the margin: no penalty");
    }

    #[test]
    fn polyak_moves_targets_towards_the_learned_nets() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let mut agent = Ddpg::new(6, 4, small(), DdpgConfig::default(), &mut rng);
        let b = batch(64, 6, &mut rng);
        agent.update(&b);
        let (t0, a) = (agent.actor_target.to_vecs(), agent.actor.to_vecs());
        agent.update_targets();
        let t1 = agent.actor_target.to_vecs();
        let (x0, x, x1) = (t0[0][0], a[0][0], t1[0][0]);
        assert!((x1 - (0.95 * x0 + 0.05 * x)).abs() < 1e-6);
        // TD3's second target critic follows its critic the same way.
        let mut agent = Ddpg::new(6, 4, small(), td3(), &mut rng);
        agent.update(&b);
        let twin = agent.twin.as_ref().unwrap();
        let (t0, c) = (twin.target.to_vecs(), twin.critic.to_vecs());
        agent.update_targets();
        let t1 = agent.twin.as_ref().unwrap().target.to_vecs();
        assert!((t1[0][0] - (0.95 * t0[0][0] + 0.05 * c[0][0])).abs() < 1e-6);
    }

    #[test]
    fn plain_rust_policy_matches_the_tensor_actor() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut agent = Ddpg::new(6, 4, SharedConfig::default(), DdpgConfig::default(), &mut rng);
        let b = batch(32, 6, &mut rng);
        agent.norm.update(&b.obs);
        let policy = agent.policy();
        let obs = &b.obs[..6];
        let want = tch::no_grad(|| super::super::nets::tensor_to_vec(&agent.actor.forward(&agent.norm.tensor(obs))));
        let got = policy.act(obs);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 1e-5, "{got:?} vs {want:?}");
        }
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for _ in 0..100 {
            let a = policy.explore(obs, 0.3, 0.2, &mut rng);
            assert!(a.len() == 4 && a.iter().all(|x| (-1.0..=1.0).contains(x)));
        }
    }

    #[test]
    fn first_adam_step_moves_each_weight_by_the_learning_rate() {
        let p = vec![Tensor::of_slice(&[1.0f32, -2.0, 3.0])];
        let mut params = p;
        let mut adam = Adam::new(&params, 0.01);
        adam.step(&mut params, &[0.5f32, -4.0, 1e-3]);
        let v = super::super::nets::tensor_to_vec(&params[0]);
        // m̂/√v̂ = sign(g) at the first step (up to eps)
        for (got, want) in v.iter().zip([0.99f32, -1.99, 2.99]) {
            assert!((got - want).abs() < 1e-4, "{v:?}");
        }
    }
}
