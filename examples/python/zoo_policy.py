"""Run a BlockPuzzle zoo policy with numpy alone (no blockpuzzle, no torch).

An entry is zoo/NAME.safetensors (float32 tensors) + zoo/NAME.json (metadata);
the format is described in zoo/README.md. With --check, every entry in the
folder is loaded and must reproduce the actions recorded at export ("probes")
to within 1e-5; the exit status says whether all did.

    python examples/python/zoo_policy.py --check zoo/
    python examples/python/zoo_policy.py zoo/ReachAvoid-v0-ddpg.json
"""

import argparse
import json
import pathlib
import sys

import numpy as np
from safetensors.numpy import load_file


class ZooPolicy:
    """The deterministic action of a zoo entry: normalise, ReLU layers, tanh (DDPG) or clip(mu) (PGGD)."""

    def __init__(self, json_path):
        json_path = pathlib.Path(json_path).with_suffix(".json")
        self.meta = json.loads(json_path.read_text())
        if self.meta["format"] not in ("blockpuzzle-zoo/1", "blockpuzzle-zoo/2"):
            raise ValueError(f"{json_path}: unknown format {self.meta['format']!r}")
        self.tensors = load_file(str(json_path.with_suffix(".safetensors")))
        self.layers = len(self.meta["actor"]["sizes"]) - 1

    def act(self, obs):
        t, m = self.tensors, self.meta
        x = (np.asarray(obs, np.float32) - t["obs_norm.mean"]) / t["obs_norm.std"]
        x = np.clip(x, -m["norm_clip"], m["norm_clip"])
        for i in range(self.layers):
            x = t[f"actor.{i}.weight"] @ x + t[f"actor.{i}.bias"]
            if i < self.layers - 1:
                x = np.maximum(x, 0.0)
        if m["actor"]["tanh_out"]:
            return np.tanh(x)
        return np.clip(x[: len(x) // 2], -1.0, 1.0)  # PGGD: [mu | sigma pre-activation]


def check(folder):
    entries = sorted(pathlib.Path(folder).glob("*.safetensors"))
    worst = 0.0
    for entry in entries:
        policy = ZooPolicy(entry)
        for probe in policy.meta["probes"]:
            err = float(np.max(np.abs(policy.act(probe["obs"]) - np.asarray(probe["action"], np.float32))))
            worst = max(worst, err)
        print(f"{entry.stem}: {policy.meta['task']['id']} {policy.meta['algo']} epoch {policy.meta['epoch']}, "
              f"{len(policy.meta['probes'])} probes reproduced")
    print(f"{len(entries)} entries, largest action difference {worst:.2e}")
    return len(entries) > 0 and worst < 1e-5


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("path", help="a zoo entry (.json or .safetensors), or a zoo folder with --check")
    parser.add_argument("--check", action="store_true", help="check every entry of the folder against its probes")
    args = parser.parse_args()
    if args.check:
        sys.exit(0 if check(args.path) else 1)
    policy = ZooPolicy(args.path)
    obs = policy.meta["probes"][0]["obs"]
    print(f"{policy.meta['name']} on {policy.meta['task']['id']}: action {policy.act(obs)} for probe 0")


if __name__ == "__main__":
    main()
