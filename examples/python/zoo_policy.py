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


FORMATS = ("blockpuzzle-zoo/1", "blockpuzzle-zoo/2", "blockpuzzle-zoo/3")
#: Where an object row's colour one-hot (red, blue, green, grey) begins.
COLOUR_FEATURE = 15


class ZooPolicy:
    """The deterministic action of a zoo entry: normalise, the network, tanh (DDPG) or clip(mu) (PGGD).

    The network is an MLP (ReLU layers) or, where the metadata gives a `set` layout, a set network
    over the `objects` observation (robot | object rows | mask): a per-object encoder, optionally a
    self-attention block, masked mean and max pooling, and a head. A set network takes any number of
    object slots: the slot count is read from the observation's length.
    """

    def __init__(self, json_path):
        json_path = pathlib.Path(json_path).with_suffix(".json")
        self.meta = json.loads(json_path.read_text())
        if self.meta["format"] not in FORMATS:
            raise ValueError(f"{json_path}: unknown format {self.meta['format']!r}")
        self.tensors = load_file(str(json_path.with_suffix(".safetensors")))
        self.layers = len(self.meta["actor"]["sizes"]) - 1
        self.set = self.meta["actor"].get("set")

    def _dense(self, i, x, relu):
        y = x @ self.tensors[f"actor.{i}.weight"].T + self.tensors[f"actor.{i}.bias"]
        return np.maximum(y, 0.0) if relu else y

    def _normalise(self, x):
        t, clip = self.tensors, self.meta["norm_clip"]
        mean, std = t["obs_norm.mean"], t["obs_norm.std"]
        if self.set is not None:
            # Object rows share one mean and std per feature (slot 0's); the mask passes unchanged.
            r, f = self.set["robot"], self.set["object"]
            slots = (len(x) - r) // (f + 1)
            mean = np.concatenate([mean[:r], np.tile(mean[r:r + f], slots), np.zeros(slots, np.float32)])
            std = np.concatenate([std[:r], np.tile(std[r:r + f], slots), np.ones(slots, np.float32)])
        return np.clip((x - mean) / std, -clip, clip)

    def _pool(self, x):
        """A set network's head input: robot features, masked mean and max of the encoded rows."""
        r, f, e = self.set["robot"], self.set["object"], self.set["encoder_layers"]
        slots = (len(x) - r) // (f + 1)
        rows = x[r:r + slots * f].reshape(slots, f)
        present = x[r + slots * f:r + slots * f + slots] > 0.5
        h, rows = rows[present], rows[present]
        for i in range(e):
            h = self._dense(i, h, relu=True)
        first = e
        if self.set.get("attention", False):
            q, k, v = (self._dense(e + j, h, relu=False) for j in range(3))
            scores = q @ k.T / np.sqrt(q.shape[1], dtype=np.float32)
            w = np.exp(scores - scores.max(axis=1, keepdims=True)) if len(h) else scores
            w = w / w.sum(axis=1, keepdims=True) if len(h) else w
            h = np.maximum(h + self._dense(e + 3, w @ v, relu=False), 0.0)
            first = e + 4
        width = self.tensors[f"actor.{e - 1}.bias"].shape[0]
        if self.set.get("by_colour", False):
            # One group per colour (red, blue, green, grey): the row's one-hot, passed by the normaliser.
            groups = [rows[:, COLOUR_FEATURE + c] > 0.5 for c in range(4)]
        else:
            groups = [np.ones(len(h), bool)]
        means = [h[g].mean(axis=0) if g.any() else np.zeros(width, np.float32) for g in groups]
        peaks = [h[g].max(axis=0) if g.any() else np.zeros(width, np.float32) for g in groups]
        return np.concatenate([x[:r], *means, *peaks]), first

    def act(self, obs):
        x = self._normalise(np.asarray(obs, np.float32))
        first = 0
        if self.set is not None:
            x, first = self._pool(x)
        for i in range(first, self.layers):
            x = self._dense(i, x, relu=i < self.layers - 1)
        if self.meta["actor"]["tanh_out"]:
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
