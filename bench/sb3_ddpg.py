#!/usr/bin/env python3
"""Time stable-baselines3 DDPG on gymnasium-robotics FetchPush-v4, on CPU.

Usage: sb3_ddpg.py --steps N --updates M --threads K --seed S

Builds DDPG("MultiInputPolicy", FetchPush-v4) with actor and critic [256, 256, 256],
batch_size 256, buffer_size 1e6, lr 1e-3, gamma 0.98, tau 0.05, Gaussian action noise
(sigma 0.1), a plain DictReplayBuffer (no HER), device "cpu", torch.set_num_threads(K).

Two separate measurements:
  env_steps_per_s  N steps of model.learn() with learning_starts=0, train_freq=1 and
                   gradient_steps=0: every step is SB3's real collection path (actor
                   forward + noise, env step, Monitor/VecEnv wrappers, replay insert),
                   only the gradient updates are left out. Timed after a warm-up.
  updates_per_s    one model.train(gradient_steps=M, batch_size=256) call (M updates:
                   replay sample, critic + actor step, Polyak update of both targets),
                   after a warm-up call, with at least MIN_FILL transitions in the buffer.

Prints one JSON line:
  {"impl": "sb3", "sb3": ..., "torch": ..., "threads": K, "batch_size": 256,
   "env_steps_per_s": ..., "updates_per_s": ..., ...}
"""
import argparse
import json
import time

ENV_ID = "FetchPush-v4"
BATCH_SIZE = 256
WARMUP_STEPS = 200     # collection steps before the timed collection
WARMUP_UPDATES = 20    # gradient updates before the timed train() call
MIN_FILL = 2000        # transitions in the replay buffer before timing train()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, required=True, help="timed env steps")
    ap.add_argument("--updates", type=int, required=True, help="timed gradient updates")
    ap.add_argument("--threads", type=int, default=1, help="torch.set_num_threads")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if args.steps < 1 or args.updates < 1 or args.threads < 1:
        ap.error("--steps, --updates and --threads must be >= 1")

    # Imports after argument parsing so that --help is quick.
    import gymnasium
    import gymnasium_robotics
    import numpy as np
    import stable_baselines3
    import torch
    from stable_baselines3 import DDPG
    from stable_baselines3.common.noise import NormalActionNoise

    torch.set_num_threads(args.threads)
    gymnasium.register_envs(gymnasium_robotics)
    env = gymnasium.make(ENV_ID)
    n_act = env.action_space.shape[0]

    model = DDPG(
        "MultiInputPolicy",
        env,
        learning_rate=1e-3,
        buffer_size=1_000_000,
        learning_starts=0,      # use the actor from the first step (no random warm-up phase)
        batch_size=BATCH_SIZE,
        tau=0.05,
        gamma=0.98,
        train_freq=1,
        gradient_steps=0,       # collection only; updates are timed separately below
        action_noise=NormalActionNoise(np.zeros(n_act), 0.1 * np.ones(n_act)),
        policy_kwargs=dict(net_arch=dict(pi=[256, 256, 256], qf=[256, 256, 256])),
        device="cpu",
        seed=args.seed,
        verbose=0,
    )

    # --- env steps/s, SB3 collection path ---------------------------------------------
    model.learn(total_timesteps=WARMUP_STEPS)
    t0 = time.perf_counter()
    model.learn(total_timesteps=args.steps, reset_num_timesteps=False)
    collect_s = time.perf_counter() - t0
    collected = model.num_timesteps - WARMUP_STEPS

    # --- gradient updates/s -----------------------------------------------------------
    short = MIN_FILL - model.replay_buffer.size()
    if short > 0:
        model.learn(total_timesteps=short, reset_num_timesteps=False)
    buffer_size = model.replay_buffer.size()
    model.train(gradient_steps=WARMUP_UPDATES, batch_size=BATCH_SIZE)
    t0 = time.perf_counter()
    model.train(gradient_steps=args.updates, batch_size=BATCH_SIZE)
    train_s = time.perf_counter() - t0
    env.close()

    print(json.dumps({
        "impl": "sb3",
        "sb3": stable_baselines3.__version__,
        "torch": torch.__version__,
        "threads": args.threads,
        "batch_size": BATCH_SIZE,
        "env_steps_per_s": round(collected / collect_s, 1),
        "updates_per_s": round(args.updates / train_s, 1),
        "env": ENV_ID,
        "steps": collected,
        "collect_seconds": round(collect_s, 4),
        "updates": args.updates,
        "train_seconds": round(train_s, 4),
        "buffer_transitions": buffer_size,
        "seed": args.seed,
    }))


if __name__ == "__main__":
    main()
