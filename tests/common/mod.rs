#![allow(dead_code)]
//! Helpers shared by the integration tests.

use blockpuzzle::env::{BlockEnv, EnvError};
use blockpuzzle::policy::Policy;

/// One recorded step: (qpos, qvel, obs, reward, terminated, truncated).
pub type Frame = (Vec<f64>, Vec<f64>, Vec<f32>, f32, bool, bool);

/// Runs one episode; returns the reset frame and one frame per step.
pub fn trajectory(env: &mut BlockEnv, policy: &mut dyn Policy, seed: u64) -> Result<Vec<Frame>, EnvError> {
    let (mut obs, _) = env.reset(Some(seed))?;
    policy.reset();
    let mut out = vec![(env.data().qpos().to_vec(), env.data().qvel().to_vec(), obs.clone(), 0.0, false, false)];
    loop {
        let s = env.step(&policy.act(&obs))?;
        out.push((
            env.data().qpos().to_vec(),
            env.data().qvel().to_vec(),
            s.obs.clone(),
            s.reward,
            s.terminated,
            s.truncated,
        ));
        obs = s.obs;
        if s.terminated || s.truncated {
            return Ok(out);
        }
    }
}
