//! Hindsight colour relabelling against the environment: replaying an
//! episode's recorded substep contacts under its own colours gives exactly
//! the rewards and terminations the environment reported, and an episode in
//! which blue touched grey is a success of the task in which grey is green.

use blockpuzzle::env::hindsight::{alternatives, recolour_obs, replay, Replayed, Strategy};
use blockpuzzle::env::{registry, BlockEnv, EnvConfig};
use blockpuzzle::policy::{Policy, RandomPolicy, ScriptedPolicy};
use blockpuzzle::sim::rules::{Colour, Touching};

/// One episode: the rule objects' colours, each step's substep contacts, what the env reported, the observations.
fn episode(env: &mut BlockEnv, policy: &mut dyn Policy, seed: u64) -> (Vec<Colour>, Vec<Vec<Touching>>, Vec<Replayed>) {
    env.record_substeps(true);
    let (mut obs, _) = env.reset(Some(seed)).unwrap();
    policy.reset();
    let colours = env.objects().iter().map(|o| o.colour).collect();
    let (mut steps, mut reported) = (Vec::new(), Vec::new());
    loop {
        let s = env.step(&policy.act(&obs)).unwrap();
        steps.push(env.substep_contacts().to_vec());
        reported.push(Replayed { reward: s.reward, terminated: s.terminated });
        obs = s.obs;
        if s.terminated || s.truncated {
            return (colours, steps, reported);
        }
    }
}

#[test]
fn replaying_the_recorded_contacts_gives_what_the_environment_reported() {
    for (id, scripted) in [("BlocksChoose-v0", true), ("ReachAvoid-v0", false), ("BlocksAvoid-v0", true)] {
        let mut env = BlockEnv::new(EnvConfig::new(registry::task(id).unwrap())).unwrap();
        let max_steps = env.config().task.spec.max_episode_steps;
        let mut policy: Box<dyn Policy> =
            if scripted { Box::new(ScriptedPolicy::for_env(env.config())) } else { Box::new(RandomPolicy::new(1)) };
        let mut ends = [0usize; 3];
        for seed in 0..12 {
            let (colours, steps, reported) = episode(&mut env, policy.as_mut(), seed);
            assert_eq!(replay(&colours, &steps, max_steps).unwrap(), reported, "{id} seed {seed}");
            let last = reported.last().unwrap();
            ends[if !last.terminated {
                2
            } else if last.reward == 0.0 {
                0
            } else {
                1
            }] += 1;
        }
        if scripted {
            assert!(ends[0] > 0, "{id}: some episode succeeded ({ends:?})");
        } else {
            assert!(ends[1] > 0, "{id}: some episode failed ({ends:?})");
        }
    }
}

/// The scripted controller shown the observation with two blocks' colours swapped: it pushes
/// blue to the block it believes green.
struct Misled {
    inner: ScriptedPolicy,
    spec: blockpuzzle::env::ObsSpec,
    believed: Vec<Colour>,
}

impl Policy for Misled {
    fn reset(&mut self) {
        self.inner.reset();
    }
    fn act(&mut self, obs: &[f32]) -> [f32; 4] {
        let mut seen = obs.to_vec();
        recolour_obs(&self.spec, &mut seen, &self.believed);
        self.inner.act(&seen)
    }
}

#[test]
fn blue_pushed_into_grey_succeeds_once_grey_is_green() {
    // BlocksChoose-v0: gripper, table, blue, green, grey. Pushed into grey, blue never reaches
    // green; relabelled with grey as the goal, the same contacts are a success.
    let mut env = BlockEnv::new(EnvConfig::new(registry::task("BlocksChoose-v0").unwrap())).unwrap();
    use Colour::{Blue, Green, Grey};
    let believed = vec![Grey, Grey, Blue, Grey, Green];
    let spec = env.obs_spec();
    let mut policy = Misled { inner: ScriptedPolicy::for_env(env.config()), spec, believed: believed.clone() };
    let (mut episodes, mut relabelled_successes) = (0, 0);
    for seed in 0..20 {
        let (colours, steps, reported) = episode(&mut env, &mut policy, seed);
        let alt = alternatives(&colours, &steps, 2, Strategy::BlueTouched, false);
        if !alt.contains(&believed) {
            continue; // blue never touched grey in this episode
        }
        episodes += 1;
        let r = replay(&believed, &steps, 50).unwrap();
        assert!(r.len() <= reported.len());
        relabelled_successes += usize::from(r.last().is_some_and(|s| s.terminated && s.reward == 0.0));
        // The relabelled observation says the new colours.
        let mut obs = env.reset(Some(seed)).unwrap().0;
        recolour_obs(&spec, &mut obs, &believed);
        for (k, row) in spec.objects(&obs).enumerate() {
            assert_eq!(blockpuzzle::env::ObsSpec::colour(row), &believed[2 + k].one_hot());
        }
    }
    assert!(episodes >= 10, "blue touched grey in {episodes} of 20 episodes");
    assert!(relabelled_successes >= episodes / 2, "{relabelled_successes} of {episodes} relabelled successes");
}
