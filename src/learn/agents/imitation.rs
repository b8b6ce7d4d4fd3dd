//! Imitation of the solver: the learner behind `--algo bc` and `--algo dagger`
//! (each declared in its own file, `bc.rs` and `dagger.rs`).
//!
//! * The policy is a deterministic actor π(s) = tanh(net(s̄)), s̄ the normalised
//!   observation, with the shared shape (`--net entity`: the set network over
//!   the entities rows).
//! * Every step of an exploration episode is labelled with the solver's action
//!   for that observation ([`crate::policy::ScriptedPolicy::solver`], which
//!   reads the same entities observation and nothing else), and the replay
//!   buffer stores that label in place of the action taken.
//! * The loss is ‖π(s̄) − a*‖², a* the label, averaged over the batch and the
//!   action's components; one Adam step at `--lr-actor` per batch. No critic.
//! * Who acts is where the two differ ([`Cloner::solver_share`]): in behaviour
//!   cloning the solver always acts, so the learner sees the solver's states
//!   only (or states near them, with Gaussian noise on the solver's actions:
//!   `--bc-noise`, DART, Laskey et al. 2017); in DAgger (Ross, Gordon and Bagnell 2011) the solver acts at each
//!   step with probability β, which decays from 1 epoch by epoch, and the
//!   learner's own action is taken otherwise, so the solver labels the states
//!   the learner visits.

use super::algorithm::{param_count, Algorithm, Explorer, Part, Spec, StartError, UpdateStats};
use super::nets::{append_grads, Adam, Net};
use super::replay::Batch;
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::AnyPolicy;
use crate::policy::actor::DeterministicPolicy;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use tch::Tensor;

/// The shared settings an imitation learner reads: the network's shape, its learning rate, the
/// normaliser and the precision (no critic, no discount, no targets).
pub const READS: &[&str] = &["--layers", "--hidden", "--lr-actor", "--norm-eps", "--norm-clip", "--precision"];

/// Who acts in an epoch's exploration episodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Schedule {
    /// The solver, always (behaviour cloning).
    Solver,
    /// The solver with probability β = β0 + (1 − β0)·exp(−epoch / t0), else the learner (DAgger).
    Decay {
        /// The share the solver keeps in the end.
        beta0: f64,
        /// The decay's time constant, in epochs (0: β0 from the first epoch).
        t0: f64,
    },
}

impl Schedule {
    /// The probability that the solver acts at a step of `epoch`'s exploration episodes.
    pub fn share(self, epoch: usize) -> f64 {
        match self {
            Self::Solver => 1.0,
            Self::Decay { beta0, t0 } => super::expert::beta(epoch, beta0, t0),
        }
    }
}

/// The imitation learner: an actor, its optimiser and the normaliser.
pub struct Cloner {
    /// Its registration's name ("bc" or "dagger").
    name: &'static str,
    /// Who acts in exploration episodes.
    pub schedule: Schedule,
    /// The noise on the solver's actions where it acts ([`Algorithm::solver_noise`]).
    pub noise: f64,
    /// Observation normaliser.
    pub norm: Normalizer,
    /// The actor π.
    pub actor: Net,
    /// Its optimiser.
    pub opt: Adam,
    act_dim: usize,
}

impl Cloner {
    /// A fresh learner with the networks of `spec`, `noise` on the solver's actions;
    /// `rng` fixes the initial weights.
    pub fn new(name: &'static str, spec: &Spec, schedule: Schedule, noise: f64, rng: &mut impl Rng) -> Self {
        let s = spec.shared;
        let actor = spec.arch.net((s.hidden, s.layers), 0, spec.act_dim, true, rng).with_bf16(s.bf16());
        let opt = Adam::new(&actor.params, s.lr_actor);
        let norm = spec.arch.normalizer(s.norm_eps, s.norm_clip);
        Self { name, schedule, noise, norm, actor, opt, act_dim: spec.act_dim }
    }

    /// The frozen deterministic policy.
    pub fn deterministic(&self) -> DeterministicPolicy {
        DeterministicPolicy { net: self.actor.to_plain(), norm: self.norm.clone() }
    }

    /// One update on `batch` (gradient and Adam step); the statistics.
    pub fn update(&mut self, batch: &Batch) -> UpdateStats {
        let (g, stats) = Algorithm::gradient(self, batch, 0, None);
        self.apply_gradient(&g);
        stats
    }
}

impl Algorithm for Cloner {
    super::algorithm::learner_basics!(field name);

    fn gradient(&mut self, batch: &Batch, _shard: u64, _weights: Option<&[f32]>) -> (Vec<f32>, UpdateStats) {
        let n = batch.len() as i64;
        let obs = self.norm.tensor(&batch.obs);
        // The labels are the solver's actions, which the environment would clip to [−1, 1].
        let label = Tensor::of_slice(&batch.act).view([n, self.act_dim as i64]).clamp(-1.0, 1.0);
        let loss = (self.actor.forward(&obs) - label).square().mean(tch::Kind::Float);
        self.actor.zero_grad();
        loss.backward();
        let mut flat = Vec::new();
        append_grads(&self.actor.params, &mut flat);
        let stats = UpdateStats { critic_loss: f64::NAN, actor_loss: loss.double_value(&[]), mean_q: f64::NAN };
        (flat, stats)
    }

    fn apply_gradient(&mut self, gradient: &[f32]) {
        self.opt.step(&mut self.actor.params, gradient);
    }

    fn gradient_len(&self) -> usize {
        param_count(&[&self.actor])
    }

    fn policy(&self) -> AnyPolicy {
        AnyPolicy::Deterministic(self.deterministic())
    }

    /// The learner's own action, without noise: DAgger runs the learner's policy as it is.
    fn explorer(&self) -> Box<dyn Explorer> {
        Box::new(Greedy(self.deterministic()))
    }

    fn solver_share(&self, epoch: usize) -> Option<f64> {
        Some(self.schedule.share(epoch))
    }

    fn solver_noise(&self) -> f64 {
        self.noise
    }

    fn parts(&mut self) -> Vec<(&'static str, Part<'_>)> {
        vec![("actor", Part::Net(&mut self.actor)), ("actor_adam", Part::Adam(&mut self.opt))]
    }

    /// The actor and the normaliser from a trained policy: imitation then goes on from it (a
    /// generalist specialised on one task by DAgger, say), with a fresh optimiser.
    fn init_from(&mut self, policy: &DeterministicPolicy) -> Result<(), StartError> {
        let fitted = super::algorithm::fit_actor(&self.actor.to_plain(), &self.norm, policy)?;
        self.actor.load_vecs(&super::algorithm::plain_vecs(&fitted.net))?;
        self.norm = fitted.norm;
        Ok(())
    }
}

/// A deterministic policy as an [`Explorer`] that adds nothing.
struct Greedy(DeterministicPolicy);

impl Explorer for Greedy {
    fn explore(&self, obs: &[f32], _noise: &mut Vec<f32>, _rng: &mut ChaCha8Rng) -> Vec<f32> {
        self.0.act(obs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learn::agents::arch::Arch;
    use crate::learn::agents::shared::SharedConfig;
    use rand::SeedableRng;

    fn learner(schedule: Schedule) -> Cloner {
        let shared = SharedConfig { hidden: 32, layers: 2, lr_actor: 3e-3, ..SharedConfig::default() };
        let spec = Spec { arch: Arch::mlp(3), act_dim: 2, shared: &shared };
        Cloner::new("bc", &spec, schedule, 0.0, &mut ChaCha8Rng::seed_from_u64(0))
    }

    #[test]
    fn the_actor_regresses_onto_the_labels_and_clips_them_first() {
        let mut c = learner(Schedule::Solver);
        // Labels: a fixed function of the observation; the second component beyond 1 (clipped to 1).
        let obs: Vec<f32> = (0..64 * 3).map(|k| ((k * 37 % 101) as f32 / 50.0) - 1.0).collect();
        let act: Vec<f32> = obs.chunks(3).flat_map(|o| [0.5 * o[0] - 0.3 * o[2], 3.0]).collect();
        c.norm.update(&obs);
        let n = obs.len() / 3;
        let batch = Batch {
            obs: obs.clone(),
            act,
            rew: vec![0.0; n],
            next_obs: obs.clone(),
            terminated: vec![0.0; n],
            return_to_go: vec![0.0; n],
            discount: vec![0.98; n],
        };
        let first = c.update(&batch);
        assert!(first.critic_loss.is_nan() && first.mean_q.is_nan(), "no critic");
        let last = (0..400).map(|_| c.update(&batch)).last().unwrap();
        assert!(last.actor_loss < 0.05 * first.actor_loss, "{first:?} -> {last:?}");
        let p = c.deterministic();
        for o in obs.chunks(3).take(8) {
            let a = p.act(o);
            assert!((a[0] - (0.5 * o[0] - 0.3 * o[2])).abs() < 0.1, "{a:?} for {o:?}");
            assert!(a[1] > 0.9 && a[1] <= 1.0, "the label 3 counts as 1: {a:?}");
        }
        // The explorer is the policy itself, noise and generator untouched.
        let (mut noise, mut rng) = (Vec::new(), ChaCha8Rng::seed_from_u64(1));
        assert_eq!(c.explorer().explore(&obs[..3], &mut noise, &mut rng), p.act(&obs[..3]));
        assert!(noise.is_empty());
    }

    #[test]
    fn bc_always_hands_over_to_the_solver_and_dagger_decays() {
        assert!((0..50).all(|e| learner(Schedule::Solver).solver_share(e) == Some(1.0)));
        let d = learner(Schedule::Decay { beta0: 0.1, t0: 2.0 });
        assert_eq!(d.solver_share(0), Some(1.0));
        assert!((d.solver_share(2).unwrap() - (0.1 + 0.9 * (-1.0f64).exp())).abs() < 1e-12);
        assert!(d.solver_share(60).unwrap() - 0.1 < 1e-9);
    }
}
