use blockpuzzle::env::{make, registry::config, BlockEnv};
use rand::{Rng, SeedableRng};
fn run(mut env: BlockEnv) -> f64 {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    env.reset(Some(0)).unwrap();
    let t = std::time::Instant::now();
    let mut n = 0;
    while n < 4000 {
        let a: Vec<f32> = (0..4).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let s = env.step(&a).unwrap();
        n += 1;
        if s.terminated || s.truncated {
            env.reset(None).unwrap();
        }
    }
    n as f64 / t.elapsed().as_secs_f64()
}
fn main() {
    for _ in 0..2 {
        let mut c = config("BlocksChoose-v0").unwrap();
        c.collision_filter = false;
        let off = run(BlockEnv::new(c.clone()).unwrap());
        let on = run(make("BlocksChoose-v0").unwrap());
        println!("steps/s off {off:.0} on {on:.0} ratio {:.2}", on / off);
    }
}
