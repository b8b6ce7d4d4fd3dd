//! DDPG updates per second on random data (3×256 nets, BlocksTouch sizes).
//! Usage: cargo run --release --example update_rate [BATCH] [THREADS] [f32|bf16]
use blockpuzzle::learn::agents::ddpg::{Ddpg, DdpgConfig};
use blockpuzzle::learn::agents::replay::ReplayBuffer;
use blockpuzzle::learn::agents::shared::{Precision, SharedConfig};
use rand::{Rng, SeedableRng};
fn main() {
    blockpuzzle::learn::blas::ensure_fast_kernels();
    let batch: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(256);
    let threads: i32 = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(2);
    let bf16 = std::env::args().nth(3).is_some_and(|s| s == "bf16");
    tch::set_num_threads(threads);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let precision = if bf16 { Precision::Bf16 } else { Precision::F32 };
    let mut agent =
        Ddpg::new(48, 4, SharedConfig { precision, ..SharedConfig::default() }, DdpgConfig::default(), &mut rng);
    let mut buf = ReplayBuffer::new(48, 4, 100_000);
    for _ in 0..20_000 {
        let o: Vec<f32> = (0..48).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let a: Vec<f32> = (0..4).map(|_| rng.gen_range(-1.0..1.0)).collect();
        buf.push(&o, &a, -1.0, &o, rng.gen_bool(0.05), 0.0, 0.98);
    }
    agent.norm.update(&buf.sample(5000, &mut rng).obs);
    for _ in 0..20 {
        agent.update(&buf.sample(batch, &mut rng));
    }
    let n = 300;
    let t = std::time::Instant::now();
    for _ in 0..n {
        agent.update(&buf.sample(batch, &mut rng));
    }
    let core = blockpuzzle::learn::blas::openblas_core().unwrap_or_else(|| "?".into());
    println!(
        "batch {batch}, {threads} threads, {precision:?}, OpenBLAS {core}: {:.1} updates/s",
        n as f64 / t.elapsed().as_secs_f64()
    );
}
