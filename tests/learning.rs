//! A small but real learning check: DDPG learns GripperTouch-v0 (move the
//! blue gripper onto the green block) within a fixed budget of environment
//! steps. Random actions succeed in about 10% of episodes.

use blockpuzzle::agents::ddpg::DdpgConfig;
use blockpuzzle::policy::Policy;
use blockpuzzle::train::{train, EpochRow, TrainConfig};

struct Greedy(blockpuzzle::agents::ddpg::DdpgPolicy);

impl Policy for Greedy {
    fn act(&mut self, obs: &[f32]) -> [f32; 4] {
        let a = self.0.act(obs);
        [a[0], a[1], a[2], a[3]]
    }
}

#[test]
fn ddpg_learns_to_touch_the_block_within_a_step_budget() {
    let config = TrainConfig {
        env: "GripperTouch-v0".into(),
        workers: 2,
        epochs: 6,
        cycles: 10,
        rollouts: 2,
        batches: 40,
        batch_size: 128,
        buffer_size: 100_000,
        test_episodes: 5,
        success_threshold: 0.7,
        seed: 1,
        torch_threads: 1,
        ddpg: DdpgConfig::default(),
    };
    let dir = tempfile::tempdir().unwrap();
    let rows = train(&config, dir.path(), false, &mut |_: &EpochRow, _: &TrainConfig| {}).unwrap();
    let steps = rows.last().unwrap().env_steps;
    assert!(steps <= 6 * 10 * 2 * 2 * 50, "budget: {steps} env steps");

    let saved = blockpuzzle::train::load_policy(&dir.path().join("policy.json")).unwrap();
    let mut env = blockpuzzle::make("GripperTouch-v0").unwrap();
    let mut policy = Greedy(saved.policy);
    let episodes = 40;
    let wins = (0..episodes)
        .filter(|&k| blockpuzzle::rollout::run_episode(&mut env, &mut policy, 10_000 + k).unwrap().success)
        .count();
    assert!(wins * 100 >= episodes as usize * 40, "success {wins}/{episodes} after {steps} env steps; progress {rows:?}");
}
