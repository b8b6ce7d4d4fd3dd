use blockpuzzle::env::make;
fn main() {
    let mut env = make("BlocksTouch-v0").unwrap();
    let (obs, info) = env.reset(Some(1)).unwrap();
    println!("grip0 {:?}", env.initial_gripper_position());
    println!("obs {} {:?}\n{:?}", obs.len(), &obs[..10], info);
    println!("blocks {:?}", env.block_positions());
    let t = std::time::Instant::now();
    let mut n = 0;
    for ep in 0..20 {
        env.reset(Some(ep)).unwrap();
        loop {
            let s = env.step(&[0.3, -0.2, -0.5, 0.0]).unwrap();
            n += 1;
            if s.terminated || s.truncated { if ep < 3 { println!("{:?} r={} {:?}", s.info, s.reward, env.gripper_position()); } break; }
        }
    }
    println!("{} steps/s", n as f64 / t.elapsed().as_secs_f64());
}
