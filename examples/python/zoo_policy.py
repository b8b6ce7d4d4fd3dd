"""Run a BlockPuzzle zoo policy with numpy alone (no blockpuzzle installed, no torch).

The reader is the package's own ``blockpuzzle/zoo.py``, loaded here by path; the format is
zoo/README.md's. With --check, every entry in the folder is loaded and must reproduce the
actions recorded at export ("probes") to within 1e-5; the exit status says whether all did.

    python examples/python/zoo_policy.py --check zoo/
    python examples/python/zoo_policy.py zoo/ReachAvoid-v0-ddpg.json
"""

import argparse
import importlib.util
import pathlib
import sys

ZOO_PY = pathlib.Path(__file__).resolve().parents[2] / "python" / "blockpuzzle" / "zoo.py"
_spec = importlib.util.spec_from_file_location("blockpuzzle_zoo", ZOO_PY)
zoo = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(zoo)


def check(folder):
    entries = sorted(pathlib.Path(folder).glob("*.safetensors"))
    worst = 0.0
    for entry in entries:
        policy = zoo.load(entry)
        error = policy.probe_error()
        worst = max(worst, error)
        verdict = "reproduced" if error < 1e-5 else f"NOT reproduced (action difference {error:.2e})"
        print(f"{entry.stem}: {policy.task_id} {policy.algo or 'algorithm unrecorded'} epoch {policy.meta['epoch']}, "
              f"{len(policy.meta['probes'])} probes {verdict}")
    print(f"{len(entries)} entries, largest action difference {worst:.2e}")
    return len(entries) > 0 and worst < 1e-5


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("path", help="a zoo entry (.json or .safetensors), or a zoo folder with --check")
    parser.add_argument("--check", action="store_true", help="check every entry of the folder against its probes")
    args = parser.parse_args()
    if args.check:
        sys.exit(0 if check(args.path) else 1)
    policy = zoo.load(args.path)
    obs = policy.meta["probes"][0]["obs"]
    print(f"{policy.name} on {policy.task_id}: action {policy(obs)} for probe 0")


if __name__ == "__main__":
    main()
