//! Playing episodes for training: the behaviour policies (the algorithm's
//! exploration, AggreVaTeD's mixture, the solver's mixture with an imitation
//! learner, deterministic for tests), one episode, and all workers' episodes
//! in parallel threads.

use super::{Result, TrainError};
use crate::env::hindsight;
use crate::env::vector::VectorEnv;
use crate::env::{BlockEnv, EnvError, ObsSpec, ACTION_DIM};
use crate::episode::rollout::{play_episode, Event};
use crate::learn::agents::algorithm::{Algorithm, Explorer};
use crate::learn::agents::expert::{Actor, Mixture};
use crate::learn::agents::replay::ReplayBuffer;
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::AnyPolicy;
use crate::policy::{Policy, ScriptedPolicy};
use crate::sim::rules::{Colour, Touching};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// Who acts in an episode.
#[derive(Clone, Copy)]
pub(crate) enum Behaviour<'a> {
    /// The deterministic policy (tests and finals).
    Greedy(&'a AnyPolicy),
    /// The algorithm's exploration (DDPG: actor + noise; PGGD, SAC: sampling).
    Explore(&'a dyn Explorer),
    /// AggreVaTeD's roll-in mixture of expert and learner.
    Mixture(&'a Mixture<'a>),
    /// An imitation learner's episodes: the solver labels every step and acts
    /// on it with probability `share`, the learner's explorer otherwise.
    Imitate {
        /// The learner, frozen.
        learner: &'a dyn Explorer,
        /// The probability that the solver acts at a step.
        share: f64,
        /// Standard deviation of the Gaussian noise on the solver's action where it acts.
        noise: f64,
    },
}

impl<'a> Behaviour<'a> {
    /// What an algorithm's exploration episodes of `epoch` play: an imitation
    /// learner's ([`Algorithm::solver_share`]) the solver's mixture with
    /// `explorer`, any other's `explorer` alone.
    pub(crate) fn exploring(agent: &dyn Algorithm, explorer: &'a dyn Explorer, epoch: usize) -> Self {
        match agent.solver_share(epoch) {
            Some(share) => Self::Imitate { learner: explorer, share, noise: agent.solver_noise() },
            None => Self::Explore(explorer),
        }
    }

    /// `(action taken, whether the expert or the solver chose it)`; the
    /// environment receives it clipped to [−1, 1], and the episode stores it
    /// (an imitation episode stores `label`, the solver's action, instead).
    /// `noise` is the episode's exploration-noise state (empty at its start).
    ///
    /// # Panics
    /// [`Behaviour::Imitate`] without the solver's label (an [`Acting`] builds one).
    fn act(&self, obs: &[f32], label: Option<&[f32]>, noise: &mut Vec<f32>, rng: &mut ChaCha8Rng) -> (Vec<f32>, bool) {
        match self {
            Self::Greedy(p) => (p.act(obs), false),
            Self::Explore(e) => (e.explore(obs, noise, rng), false),
            Self::Mixture(m) => {
                let (who, a) = m.act(obs, noise, rng);
                (a, who == Actor::Expert)
            }
            Self::Imitate { learner, share, noise: sigma } => {
                use rand::Rng;
                use rand_distr::{Distribution, StandardNormal};
                let label = label.expect("the solver labels an imitation episode");
                if rng.gen_bool(share.clamp(0.0, 1.0)) {
                    if *sigma == 0.0 {
                        return (label.to_vec(), true);
                    }
                    let noisy = label.iter().map(|&a| {
                        let z: f64 = StandardNormal.sample(&mut *rng);
                        (a + (sigma * z) as f32).clamp(-1.0, 1.0)
                    });
                    (noisy.collect(), true)
                } else {
                    (learner.explore(obs, noise, rng), false)
                }
            }
        }
    }
}

/// A finished episode's transitions and outcome.
pub(crate) struct Episode {
    pub(crate) obs: Vec<Vec<f32>>,
    /// Actions as the behaviour produced them (PGGD: before clipping).
    pub(crate) act: Vec<Vec<f32>>,
    pub(crate) rew: Vec<f32>,
    pub(crate) terminated: bool,
    pub(crate) success: bool,
    /// Steps on which the expert (or the solver, for an imitation learner) acted.
    pub(crate) expert_steps: usize,
    /// Seconds spent in the policy (forward passes and noise).
    pub(crate) forward_seconds: f64,
    /// What hindsight colour relabelling needs, where the environment records
    /// its substeps' contacts ([`BlockEnv::record_substeps`]).
    pub(crate) contacts: Option<Contacts>,
}

/// An episode's rule objects' colours and the contacts of every substep of every step.
pub(crate) struct Contacts {
    /// Colours of the rule objects (gripper, table, blocks, floor) in this episode.
    pub(crate) colours: Vec<Colour>,
    /// `steps[t]`: the contacts of step t's substeps, in order.
    pub(crate) steps: Vec<Vec<Touching>>,
}

impl Episode {
    /// Environment steps taken.
    pub(crate) fn len(&self) -> usize {
        self.rew.len()
    }

    /// Appends the transitions to `replay` and feeds the observations to the
    /// normaliser. Transition t holds the `n_step`-step return (m = min(n_step,
    /// steps left) rewards, discounted), the observation m steps later, done
    /// when that is the terminal state, the bootstrap discount γᵐ, and the
    /// discounted return-to-go as the extra column (PGGD's weight).
    pub(crate) fn store(&self, replay: &mut ReplayBuffer, norm: &mut Normalizer, gamma: f64, n_step: usize) {
        self.store_transitions(replay, gamma, n_step);
        norm.update(&self.obs.concat());
    }

    /// The same episode under up to `k` other colourings of its blocks
    /// ([`crate::env::hindsight::alternatives`]: a block blue touched becomes green,
    /// the greens take its colour; with `pairs`, also a block that touched green
    /// becomes blue): the observations' colour one-hots
    /// rewritten, the rewards and terminations replayed by the colour rules
    /// over the recorded contacts (cut at the first terminal step under the
    /// new colours; an episode that does not end under them ends unterminated,
    /// as at a time limit). None without recorded contacts.
    pub(crate) fn relabelled(
        &self,
        spec: &ObsSpec,
        k: usize,
        strategy: hindsight::Strategy,
        max_steps: usize,
    ) -> Vec<Episode> {
        let Some(c) = &self.contacts else { return Vec::new() };
        let mut out = Vec::new();
        // The gripper's and table's colours are relabelled where the observation shows them.
        let fixtures = spec.mode.is_entities();
        for colours in hindsight::alternatives(&c.colours, &c.steps, k, strategy, fixtures) {
            let Ok(replayed) = hindsight::replay(&colours, &c.steps, max_steps) else { continue };
            let n = replayed.len();
            let obs = self.obs[..=n]
                .iter()
                .map(|o| {
                    let mut o = o.clone();
                    hindsight::recolour_obs(spec, &mut o, &colours);
                    o
                })
                .collect();
            out.push(Episode {
                obs,
                act: self.act[..n].to_vec(),
                rew: replayed.iter().map(|r| r.reward).collect(),
                terminated: replayed.last().is_some_and(|r| r.terminated),
                success: replayed.last().is_some_and(|r| r.terminated && r.reward == 0.0),
                expert_steps: 0,
                forward_seconds: 0.0,
                contacts: None,
            });
        }
        out
    }

    /// Stores the episode's transitions (n-step where `n_step` > 1); the
    /// normaliser is updated by the caller, from every rank's observations.
    pub(crate) fn store_transitions(&self, replay: &mut ReplayBuffer, gamma: f64, n_step: usize) {
        let n = self.rew.len();
        let g32 = gamma as f32;
        let mut ret = vec![0.0f32; n];
        let mut g = 0.0;
        for t in (0..n).rev() {
            g = self.rew[t] + g32 * g;
            ret[t] = g;
        }
        for (t, ret_t) in ret.iter().enumerate() {
            let m = n_step.max(1).min(n - t);
            // One step: the reward itself, as the paper's target has it.
            let (mut rew, mut discount) = (self.rew[t], g32);
            for k in 1..m {
                rew += discount * self.rew[t + k];
                discount *= g32;
            }
            let done = self.terminated && t + m == n;
            replay.push(&self.obs[t], &self.act[t], rew, &self.obs[t + m], done, *ret_t, discount);
        }
    }
}

/// Mixes the run seed with counters into an independent stream seed.
pub(crate) fn stream_seed(seed: u64, parts: &[u64]) -> u64 {
    // SplitMix64 steps over the parts: cheap and well distributed.
    let mut z = seed ^ 0x9E37_79B9_7F4A_7C15;
    for &p in parts {
        z = z.wrapping_add(p).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    z
}

/// Which level and distribution each exploration episode plays. The
/// paper's curriculum plays the current level only (`level_replay` and
/// `challenge_share` 0); these options are this project's, for the headline study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Draw {
    /// The curriculum's current level.
    pub(crate) level: usize,
    /// The task's maximum level.
    pub(crate) max_level: usize,
    /// Probability that an episode plays a uniformly drawn lower level instead.
    pub(crate) level_replay: f64,
    /// At the maximum level: probability that an episode plays the challenge distribution.
    pub(crate) challenge_share: f64,
}

impl Draw {
    /// (level, challenge) of the episode of `seed`, from a stream of its own.
    pub(crate) fn pick(&self, seed: u64) -> (usize, bool) {
        use rand::Rng;
        let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, &[6]));
        let (u, v): (f64, f64) = (rng.gen(), rng.gen());
        if self.level == self.max_level && u < self.challenge_share {
            (self.level, true)
        } else if self.level > 0 && v < self.level_replay {
            (rng.gen_range(0..self.level), false)
        } else {
            (self.level, false)
        }
    }
}

/// A behaviour acting in one episode, as a [`Policy`]: its exploration
/// noise state and generator, the solver that labels an imitation episode,
/// and what it spent.
struct Acting<'a> {
    behaviour: &'a Behaviour<'a>,
    rng: ChaCha8Rng,
    noise: Vec<f32>,
    /// For [`Behaviour::Imitate`]: the solver, following the episode whoever acts.
    solver: Option<ScriptedPolicy>,
    /// The solver's label of each step so far (with a solver).
    labels: Vec<Vec<f32>>,
    /// Actions the expert chose.
    expert_steps: usize,
    forward_seconds: f64,
}

impl Policy for Acting<'_> {
    fn reset(&mut self) {
        self.noise.clear();
        self.labels.clear();
        if let Some(s) = &mut self.solver {
            s.reset();
        }
    }

    /// The action taken (the environment clips it to [−1, 1] itself); the
    /// episode stores it, or the solver's label where there is one.
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        let t = Instant::now();
        let label = self.solver.as_mut().map(|s| s.act(obs).to_vec());
        let (a, by_expert) = self.behaviour.act(obs, label.as_deref(), &mut self.noise, &mut self.rng);
        self.forward_seconds += t.elapsed().as_secs_f64();
        self.expert_steps += by_expert as usize;
        self.labels.extend(label);
        std::array::from_fn(|k| a.get(k).copied().unwrap_or(0.0))
    }
}

/// Plays one episode with `behaviour` from the layout of `seed`; with a
/// `draw`, at the level and in the distribution it picks for that seed
/// (without, at the environment's current settings).
fn play(env: &mut BlockEnv, behaviour: &Behaviour, seed: u64, draw: Option<&Draw>) -> Result<Episode, EnvError> {
    if let Some(d) = draw {
        let (level, challenge) = d.pick(seed);
        env.set_level(level)?;
        env.set_challenge(challenge)?;
    }
    // The layout comes from `seed`; the exploration noise from a stream derived from it.
    let rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, &[5]));
    // The solver reads the entities observation, which an imitation learner's environment presents.
    let solver =
        matches!(behaviour, Behaviour::Imitate { .. }).then(|| ScriptedPolicy::solver(env.obs_spec().max_objects));
    let mut acting =
        Acting { behaviour, rng, noise: Vec::new(), solver, labels: Vec::new(), expert_steps: 0, forward_seconds: 0.0 };
    let mut ep = Episode {
        obs: vec![],
        act: vec![],
        rew: vec![],
        terminated: false,
        success: false,
        expert_steps: 0,
        forward_seconds: 0.0,
        contacts: None,
    };
    play_episode(env, &mut acting, seed, |event| match event {
        Event::Reset { env, .. } => {
            ep.contacts = env
                .records_substeps()
                .then(|| Contacts { colours: env.objects().iter().map(|o| o.colour).collect(), steps: Vec::new() });
        }
        Event::Step { env, obs, action, step } => {
            if let Some(c) = &mut ep.contacts {
                c.steps.push(env.substep_contacts().to_vec());
            }
            ep.obs.push(obs.to_vec());
            ep.act.push(action.to_vec());
            ep.rew.push(step.reward);
            ep.success |= step.info.is_success;
            if step.terminated || step.truncated {
                ep.terminated = step.terminated;
                ep.obs.push(step.obs.clone());
            }
        }
    })?;
    (ep.expert_steps, ep.forward_seconds) = (acting.expert_steps, acting.forward_seconds);
    if acting.solver.is_some() {
        // What an imitation learner learns: the solver's action in every state visited.
        debug_assert_eq!(acting.labels.len(), ep.act.len());
        ep.act = acting.labels;
    }
    Ok(ep)
}

/// One episode to play: by worker `worker` on task `task` of the run, from the layout of `seed`,
/// at the level and in the distribution `draw` picks (without: at the environment's settings).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Planned {
    pub(crate) worker: usize,
    pub(crate) task: usize,
    pub(crate) seed: u64,
    pub(crate) draw: Option<Draw>,
}

/// Plays `plan` on `envs`, which hold one environment per worker and task of `tasks` (worker-major:
/// environment `worker × tasks.len() + k` plays the run's task `tasks[k]`), in parallel over
/// environments, each playing its episodes in plan order. Returns the episodes in plan order: what
/// each one plays depends on its seed and draw alone, so the result is the same for any split over threads.
pub(crate) fn play_plan(
    envs: &mut VectorEnv,
    tasks: &[usize],
    behaviour: &Behaviour,
    plan: &[Planned],
) -> Result<Vec<Episode>> {
    let results: Vec<Result<Vec<(usize, Episode)>, EnvError>> = envs.each(|i, env| {
        let (worker, task) = (i / tasks.len(), tasks[i % tasks.len()]);
        plan.iter()
            .enumerate()
            .filter(|(_, p)| p.worker == worker && p.task == task)
            .map(|(j, p)| Ok((j, play(env, behaviour, p.seed, p.draw.as_ref())?)))
            .collect()
    });
    let mut out: Vec<Option<Episode>> = (0..plan.len()).map(|_| None).collect();
    for r in results {
        for (j, ep) in r? {
            out[j] = Some(ep);
        }
    }
    out.into_iter().enumerate().map(|(j, ep)| ep.ok_or(TrainError::Unplayed(j))).collect()
}

/// Runs `per_worker` episodes on every worker's environment in parallel (one task).
pub(crate) fn play_all(
    envs: &mut VectorEnv,
    behaviour: &Behaviour,
    per_worker: usize,
    seed_of: impl Fn(usize, usize) -> u64,
) -> Result<Vec<Episode>> {
    let plan: Vec<Planned> = (0..envs.num_envs())
        .flat_map(|w| (0..per_worker).map(move |k| (w, k)))
        .map(|(worker, k)| Planned { worker, task: 0, seed: seed_of(worker, k), draw: None })
        .collect();
    play_plan(envs, &[0], behaviour, &plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn episode(rew: Vec<f32>, terminated: bool) -> Episode {
        let n = rew.len();
        Episode {
            obs: (0..=n).map(|t| vec![t as f32, 0.0]).collect(),
            act: (0..n).map(|t| vec![t as f32]).collect(),
            rew,
            terminated,
            success: false,
            expert_steps: 0,
            forward_seconds: 0.0,
            contacts: None,
        }
    }

    #[test]
    fn n_step_transitions_sum_rewards_and_bootstrap_m_steps_later() {
        let g = 0.5f32;
        let ep = episode(vec![-1.0, -2.0, -4.0, -8.0, 0.0], true);
        let mut replay = ReplayBuffer::new(2, 1, 100);
        ep.store(&mut replay, &mut Normalizer::new(2, 0.01, 5.0), 0.5, 3);
        let (d, _) = replay.parts();
        assert_eq!(d.rew, vec![-1.0 - 1.0 - 1.0, -2.0 - 2.0 - 2.0, -4.0 - 4.0, -8.0, 0.0]);
        let next: Vec<f32> = d.next_obs.chunks(2).map(|o| o[0]).collect();
        assert_eq!(next, vec![3.0, 4.0, 5.0, 5.0, 5.0]);
        assert_eq!(d.discount, vec![g * g * g, g * g * g, g * g * g, g * g, g]);
        assert_eq!(d.terminated, vec![0.0, 0.0, 1.0, 1.0, 1.0], "the terminal state ends the last three returns");
        assert_eq!(d.return_to_go[3], -8.0, "return-to-go");
        // One step: the paper's transitions.
        let mut replay = ReplayBuffer::new(2, 1, 100);
        episode(vec![-1.0, -2.0], false).store(&mut replay, &mut Normalizer::new(2, 0.01, 5.0), 0.5, 1);
        let (d, _) = replay.parts();
        assert_eq!(
            (d.rew.clone(), d.discount.clone(), d.terminated.clone()),
            (vec![-1.0, -2.0], vec![g, g], vec![0.0, 0.0])
        );
    }

    #[test]
    fn relabelled_episodes_take_the_rules_verdict_and_the_new_colours() {
        use crate::env::{ObsMode, COLOUR_FEATURE};
        use Colour::{Blue, Green, Grey, Red};
        // Rule objects: gripper, table, blue, green, grey, red (four blocks); the `objects` observation.
        let colours = vec![Grey, Grey, Blue, Green, Grey, Red];
        let spec = ObsSpec::new(ObsMode::Objects, 4);
        let touch = |pairs: &[(usize, usize)]| vec![Touching::from_pairs(6, pairs)];
        // Step 0: gripper–blue; step 1: blue–grey; step 2: blue–red (the original episode's failure).
        let steps = vec![touch(&[(0, 2)]), touch(&[(2, 4)]), touch(&[(2, 5)])];
        let obs: Vec<Vec<f32>> = (0..4)
            .map(|t| {
                let mut o = vec![t as f32; spec.dim()];
                for (k, c) in colours[2..].iter().enumerate() {
                    let at = spec.robot_dim() + k * spec.object_dim() + COLOUR_FEATURE;
                    o[at..at + 4].copy_from_slice(&c.one_hot());
                }
                o
            })
            .collect();
        let ep = Episode {
            obs,
            act: (0..3).map(|t| vec![t as f32; 4]).collect(),
            rew: vec![-1.0, -1.0, -48.0],
            terminated: true,
            success: false,
            expert_steps: 0,
            forward_seconds: 0.0,
            contacts: Some(Contacts { colours: colours.clone(), steps }),
        };
        let others = ep.relabelled(&spec, 4, hindsight::Strategy::BlueTouched, 50);
        // Grey (touched at step 1) as the goal: success at step 1, the episode cut there. Red (step 2)
        // as the goal: success at step 2, nothing red having touched blue before.
        assert_eq!(others.len(), 2);
        let (grey, red) = (&others[0], &others[1]);
        assert_eq!((grey.rew.clone(), grey.terminated, grey.success), (vec![-1.0, 0.0], true, true));
        assert_eq!((grey.obs.len(), grey.act.len()), (3, 2));
        assert_eq!((red.rew.clone(), red.terminated, red.success), (vec![-1.0, -1.0, 0.0], true, true));
        let colour_of = |o: &[f32], k: usize| {
            let at = spec.robot_dim() + k * spec.object_dim() + COLOUR_FEATURE;
            o[at..at + 4].to_vec()
        };
        // Block 2 (grey) now reads green and block 1 (green) grey, in every observation.
        for o in &grey.obs {
            assert_eq!((colour_of(o, 2), colour_of(o, 1)), (Green.one_hot().to_vec(), Grey.one_hot().to_vec()));
        }
        // The terminal transition of a relabelled success is done; the original's colours are untouched.
        let mut replay = ReplayBuffer::new(spec.dim(), 4, 10);
        grey.store_transitions(&mut replay, 0.98, 1);
        assert_eq!(replay.parts().0.terminated, vec![0.0, 1.0]);
        assert_eq!(colour_of(&ep.obs[0], 2), Grey.one_hot().to_vec());
        assert!(
            Episode { contacts: None, ..ep }.relabelled(&spec, 4, hindsight::Strategy::BlueTouched, 50).is_empty(),
            "nothing recorded, nothing relabelled"
        );
    }

    #[test]
    fn an_entities_episode_also_relabels_the_gripper_and_recolours_its_row() {
        use crate::env::{Fixture, ObsMode, COLOUR_FEATURE};
        use Colour::{Blue, Green, Grey, Red};
        let colours = vec![Grey, Grey, Blue, Green, Grey, Red];
        let touch = |pairs: &[(usize, usize)]| vec![Touching::from_pairs(6, pairs)];
        // Step 0: nothing; step 1: gripper–blue; step 2: blue–grey; step 3: blue–red.
        let steps = vec![touch(&[]), touch(&[(0, 2)]), touch(&[(2, 4)]), touch(&[(2, 5)])];
        let episode = |spec: &ObsSpec| {
            let row = |k: usize| spec.robot_dim() + k * spec.object_dim() + COLOUR_FEATURE;
            let mut o = vec![0.5; spec.dim()];
            for (k, c) in colours[2..].iter().enumerate() {
                o[row(k)..row(k) + 4].copy_from_slice(&c.one_hot());
            }
            for (f, c) in [(Fixture::Gripper, colours[0]), (Fixture::Table, colours[1])] {
                if let Some(k) = spec.fixture_row(f) {
                    o[row(k)..row(k) + 4].copy_from_slice(&c.one_hot());
                }
            }
            Episode {
                obs: vec![o; 5],
                act: vec![vec![0.0; 4]; 4],
                rew: vec![-1.0, -1.0, -1.0, -47.0],
                terminated: true,
                success: false,
                expert_steps: 0,
                forward_seconds: 0.0,
                contacts: Some(Contacts { colours: colours.clone(), steps: steps.clone() }),
            }
        };
        let objects = ObsSpec::new(ObsMode::Objects, 4);
        assert_eq!(episode(&objects).relabelled(&objects, 4, hindsight::Strategy::BlueTouched, 50).len(), 2);
        let entities = ObsSpec::new(ObsMode::Entities, 4);
        let others = episode(&entities).relabelled(&entities, 4, hindsight::Strategy::BlueTouched, 50);
        // The gripper as the goal first (blue touched it at step 1), then the grey and red blocks.
        assert_eq!(others.len(), 3);
        assert_eq!((others[0].rew.clone(), others[0].success), (vec![-1.0, 0.0], true));
        let gripper = entities.fixture_row(Fixture::Gripper).unwrap();
        let at = entities.robot_dim() + gripper * entities.object_dim() + COLOUR_FEATURE;
        assert!(others[0].obs.iter().all(|o| o[at..at + 4] == Green.one_hot()), "the gripper's row reads green");
        assert!(others[1].obs.iter().all(|o| o[at..at + 4] == Grey.one_hot()), "only where the gripper is relabelled");
    }

    #[test]
    fn an_imitation_episode_stores_the_solvers_labels_whoever_acts() {
        use crate::env::{EnvConfig, ObsMode};
        struct Still;
        impl Explorer for Still {
            fn explore(&self, _: &[f32], _: &mut Vec<f32>, _: &mut ChaCha8Rng) -> Vec<f32> {
                vec![0.0; ACTION_DIM]
            }
        }
        let task = crate::env::registry::task("BlocksTouch-v0").unwrap();
        let mut env = BlockEnv::new(EnvConfig { obs_mode: ObsMode::Entities, ..EnvConfig::new(task) }).unwrap();
        for share in [0.0, 1.0] {
            let ep = play(&mut env, &Behaviour::Imitate { learner: &Still, share, noise: 0.0 }, 3, None).unwrap();
            assert_eq!(ep.expert_steps, if share == 1.0 { ep.len() } else { 0 });
            // A fresh solver over the recorded observations gives the stored actions.
            let mut solver = ScriptedPolicy::solver(env.obs_spec().max_objects);
            solver.reset();
            let labels: Vec<Vec<f32>> = ep.obs[..ep.len()].iter().map(|o| solver.act(o).to_vec()).collect();
            assert_eq!(ep.act, labels, "share {share}");
            assert!(ep.act.iter().any(|a| a.iter().any(|&x| x != 0.0)), "the solver moves, whoever acts");
        }
        // Noise on the solver's actions (BC's DART): other states, the labels still the solver's clean actions.
        let clean = play(&mut env, &Behaviour::Imitate { learner: &Still, share: 1.0, noise: 0.0 }, 3, None).unwrap();
        let noisy = play(&mut env, &Behaviour::Imitate { learner: &Still, share: 1.0, noise: 0.3 }, 3, None).unwrap();
        assert_ne!(noisy.obs[1..].to_vec(), clean.obs[1..clean.obs.len().min(noisy.obs.len())].to_vec());
        assert_eq!(noisy.obs[0], clean.obs[0], "the same reset");
        let mut solver = ScriptedPolicy::solver(env.obs_spec().max_objects);
        solver.reset();
        let labels: Vec<Vec<f32>> = noisy.obs[..noisy.len()].iter().map(|o| solver.act(o).to_vec()).collect();
        assert_eq!(noisy.act, labels);
        assert_eq!(noisy.expert_steps, noisy.len());
    }

    #[test]
    fn draws_replay_lower_levels_and_the_challenge_at_the_stated_rates() {
        let draw = Draw { level: 4, max_level: 10, level_replay: 0.25, challenge_share: 0.5 };
        let picks: Vec<(usize, bool)> = (0..4000).map(|s| draw.pick(s)).collect();
        assert_eq!(picks, (0..4000).map(|s| draw.pick(s)).collect::<Vec<_>>(), "seeded");
        let lower = picks.iter().filter(|p| p.0 < 4).count() as f64 / 4000.0;
        assert!((lower - 0.25).abs() < 0.03 && picks.iter().all(|p| !p.1 && p.0 <= 4), "{lower}");
        let top = Draw { level: 10, ..draw };
        let picks: Vec<(usize, bool)> = (0..4000).map(|s| top.pick(s)).collect();
        let challenge = picks.iter().filter(|p| p.1).count() as f64 / 4000.0;
        let lower = picks.iter().filter(|p| p.0 < 10).count() as f64 / 4000.0;
        assert!((challenge - 0.5).abs() < 0.03 && (lower - 0.125).abs() < 0.03, "{challenge} {lower}");
        let paper = Draw { level_replay: 0.0, challenge_share: 0.0, ..top };
        assert!((0..100).all(|s| paper.pick(s) == (10, false)));
    }
}
