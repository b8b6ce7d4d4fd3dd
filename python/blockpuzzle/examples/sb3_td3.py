"""Stable-Baselines3 TD3 on BlockPuzzle/BlocksTouch-v0 through the Python package, with the paper's
curriculum (the test success at the current level reaching 0.7 moves it up a level), logging the
success rate against environment steps as the Rust trainer's progress.csv does, so the two
trainers' curves on the same environment can be drawn side by side.

    pip install stable-baselines3             # SB3 and torch (the package itself needs neither)
    python -m blockpuzzle.examples.sb3_td3 --timesteps 600000 --run-dir runs/sb3-td3-s0
    (again with --resume to continue a stopped run from its last save)
    python -m blockpuzzle.examples.sb3_td3 --run-dir runs/sb3-td3-s0 --evaluate 1000
    (the saved model on 1000 episodes at the top level, seeds 1,000,000+: the episodes
    `blockpuzzle eval --episodes 1000` plays, so the two trainers' policies meet the same layouts)

Hyperparameters follow the paper's DDPG where TD3 has them: 3 × 256 ReLU layers, batch 256,
lr 1e-3, gamma 0.98, tau 0.05, Gaussian action noise 0.2, buffer 1e6; two environments, as
`blockpuzzle train --workers 2`: SB3's DummyVecEnv of two `gym.make` environments (`--vec-env
dummy`, the default, which made the numbers of results/python.md), or the Rust vector
environment through `blockpuzzle.sb3.SB3VecEnv` (`--vec-env rust`: the curriculum level set with
`set_attr("level", L)`).

The run directory holds progress.csv and, every --save-every env steps, the model, its replay
buffer and the curriculum state; --resume continues from them (SB3 does not save every random
stream, so a resumed run is not bit-identical to an uninterrupted one).
"""
import argparse
import csv
import json
import os
import sys

import gymnasium as gym
import numpy as np

import blockpuzzle  # registers the ids


class Curriculum(gym.Wrapper):
    """Resets at the curriculum's current level (shared by all copies through `state`)."""

    def __init__(self, env, state):
        super().__init__(env)
        self.state = state

    def reset(self, **kwargs):
        options = dict(kwargs.pop("options", None) or {})
        options.setdefault("level", self.state["level"])
        return self.env.reset(options=options, **kwargs)


def success_rate(model, env_id, level, episodes, seed):
    env = gym.make(env_id)
    wins = 0
    for k in range(episodes):
        obs, _ = env.reset(seed=seed + k, options={"level": level})
        done = False
        while not done:
            action, _ = model.predict(obs, deterministic=True)
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
        wins += bool(info["is_success"])
    env.close()
    return wins / episodes


#: What to install where SB3 is missing.
NEEDS_SB3 = ("this example needs Stable-Baselines3 and torch, which the blockpuzzle package does not install: "
             "pip install stable-baselines3 (for torch's smaller CPU-only build first: pip install torch "
             "--index-url https://download.pytorch.org/whl/cpu)")


def main(argv=None):
    # The description is the docstring's first paragraph, whole.
    ap = argparse.ArgumentParser(prog="python -m blockpuzzle.examples.sb3_td3",
                                 description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--env", default="BlockPuzzle/BlocksTouch-v0",
                    help="a built-in id, with or without the BlockPuzzle/ namespace (default: %(default)s)")
    ap.add_argument("--timesteps", type=int, default=600_000)
    ap.add_argument("--eval-every", type=int, default=5_000, help="env steps between evaluations (one 'epoch')")
    ap.add_argument("--episodes", type=int, default=20, help="test and finals episodes per evaluation")
    ap.add_argument("--threshold", type=float, default=0.7)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--save-every", type=int, default=50_000, help="env steps between saves (model + replay buffer)")
    ap.add_argument("--run-dir", default="runs/sb3-td3-s0")
    ap.add_argument("--resume", action="store_true")
    ap.add_argument("--evaluate", type=int, metavar="N",
                    help="only evaluate the run's saved model on N episodes at the top level (seeds 1,000,000+)")
    ap.add_argument("--vec-env", choices=["dummy", "rust"], default="dummy",
                    help="dummy: SB3's DummyVecEnv of two gym.make environments; rust: blockpuzzle.sb3.SB3VecEnv")
    args = ap.parse_args(argv)
    if args.env in blockpuzzle.env_ids():
        args.env = f"{blockpuzzle.NAMESPACE}/{args.env}"
    try:
        from stable_baselines3 import TD3
        from stable_baselines3.common.callbacks import BaseCallback
        from stable_baselines3.common.noise import NormalActionNoise
        from stable_baselines3.common.vec_env import DummyVecEnv
    except ImportError:
        sys.exit(NEEDS_SB3)

    if args.evaluate:
        model_path = os.path.join(args.run_dir, "model.zip")
        if not os.path.exists(model_path):
            ap.error(f"--evaluate: no saved model in {args.run_dir}")
        model = TD3.load(model_path, device="cpu")
        top = gym.make(args.env).get_wrapper_attr("max_level")
        n = args.evaluate
        p = success_rate(model, args.env, top, n, 1_000_000)
        # Wilson score interval, 95%.
        z = 1.959964
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
        # The saved model's own count of the env steps behind it (whatever --eval-every the run used).
        steps = int(model.num_timesteps)
        print(json.dumps({"env": args.env, "level": top, "episodes": n, "first_seed": 1_000_000, "success": p,
                          "wilson95": [round(centre - half, 4), round(centre + half, 4)], "env_steps": steps}))
        return

    os.makedirs(args.run_dir, exist_ok=True)
    paths = {k: os.path.join(args.run_dir, k) for k in ("model.zip", "replay.pkl", "state.json", "progress.csv")}
    if args.resume and not os.path.exists(paths["state.json"]):
        ap.error(f"--resume: no saved run in {args.run_dir}")
    if not args.resume and os.path.exists(paths["progress.csv"]):
        ap.error(f"{args.run_dir} already holds a run; pass --resume or choose another --run-dir")
    state = {"level": 0, "epoch": 0, "next_eval": args.eval_every}
    if args.resume:
        with open(paths["state.json"]) as f:
            state.update(json.load(f))
    max_level = gym.make(args.env).get_wrapper_attr("max_level")
    if args.vec_env == "rust":
        from blockpuzzle.sb3 import SB3VecEnv
        envs = SB3VecEnv(args.env, num_envs=2, threads=2)
        envs.set_attr("level", state["level"])
    else:
        envs = DummyVecEnv([lambda: Curriculum(gym.make(args.env), state) for _ in range(2)])
    if args.resume:
        model = TD3.load(paths["model.zip"], env=envs, device="cpu")
        model.load_replay_buffer(paths["replay.pkl"])
    else:
        model = TD3("MlpPolicy", envs, learning_rate=1e-3, buffer_size=1_000_000, batch_size=256, tau=0.05,
                    gamma=0.98, action_noise=NormalActionNoise(np.zeros(4), 0.2 * np.ones(4)),
                    policy_kwargs={"net_arch": [256, 256, 256]}, seed=args.seed, device="cpu")

    # Rows after the last save are dropped on resume: they will be measured again.
    rows = []
    if args.resume and os.path.exists(paths["progress.csv"]):
        with open(paths["progress.csv"]) as f:
            rows = [r for r in csv.reader(f)][1:]
        rows = [r for r in rows if int(r[0]) < state["epoch"]]
    with open(paths["progress.csv"], "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["epoch", "curriculum/level", "test/success", "finals/success", "time/env_steps"])
        out.writerows(rows)

        def save():
            model.save(paths["model.zip"])
            model.save_replay_buffer(paths["replay.pkl"])
            with open(paths["state.json"] + ".tmp", "w") as s:
                json.dump(state, s)
            os.replace(paths["state.json"] + ".tmp", paths["state.json"])

        class Evaluate(BaseCallback):
            def __init__(self):
                super().__init__()
                self.next_save = model.num_timesteps + args.save_every

            def _on_step(self):
                if self.num_timesteps < state["next_eval"]:
                    return True
                state["next_eval"] += args.eval_every
                epoch = state["epoch"]
                seed = 3_000_000 + 1000 * epoch
                test = success_rate(self.model, args.env, state["level"], args.episodes, seed)
                finals = success_rate(self.model, args.env, max_level, args.episodes, seed + 500)
                out.writerow([epoch, state["level"], test, finals, self.num_timesteps])
                f.flush()
                print(f"epoch {epoch} steps {self.num_timesteps} level {state['level']} test {test:.2f} finals {finals:.2f}")
                if test >= args.threshold and state["level"] < max_level:
                    state["level"] += 1
                    if args.vec_env == "rust":
                        envs.set_attr("level", state["level"])  # each environment's next episode
                state["epoch"] += 1
                if self.num_timesteps >= self.next_save:
                    self.next_save += args.save_every
                    save()
                return True

        model.learn(total_timesteps=args.timesteps - model.num_timesteps, callback=Evaluate(),
                    reset_num_timesteps=not args.resume)
        save()


if __name__ == "__main__":
    main()
