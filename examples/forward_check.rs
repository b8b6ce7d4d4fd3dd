use blockpuzzle::env::{registry::config, BlockEnv};
use blockpuzzle::policy::{Policy, RandomPolicy};
fn traj(full: bool) -> (Vec<Vec<f64>>, Vec<Vec<f32>>, f64, f64) {
    let mut c = config("BlocksChoose-v0").unwrap();
    c.full_forward = full;
    let mut env = BlockEnv::new(c).unwrap();
    let mut p = RandomPolicy::new(3);
    let mut qs = vec![];
    let mut os = vec![];
    let t = std::time::Instant::now();
    for ep in 0..30 {
        let mut obs = env.reset(Some(ep)).unwrap().0;
        loop {
            let s = env.step(&p.act(&obs)).unwrap();
            qs.push(env.data().qpos().to_vec());
            qs.push(env.data().qvel().to_vec());
            os.push(s.obs.clone());
            obs = s.obs;
            if s.terminated || s.truncated {
                break;
            }
        }
    }
    let el = t.elapsed().as_secs_f64();
    (qs, os, el, env.physics_seconds())
}
fn main() {
    let a = traj(true);
    let b = traj(false);
    println!("identical qpos/qvel: {} obs: {}", a.0 == b.0, a.1 == b.1);
    if let Some(i) = (0..a.0.len()).find(|&i| a.0[i] != b.0[i]) {
        let d: Vec<f64> = a.0[i].iter().zip(&b.0[i]).map(|(x, y)| x - y).collect();
        println!("first qpos/qvel diff at record {i} (step {}): {:?}", i / 2, d);
    }
    if let Some(i) = (0..a.1.len()).find(|&i| a.1[i] != b.1[i]) {
        println!("first obs diff at step {i}");
    }
    println!("overhead full {:.3} partial {:.3}", 1.0 - a.3 / a.2, 1.0 - b.3 / b.2);
}
#[allow(dead_code)]
fn unused() {}
