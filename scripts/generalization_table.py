#!/usr/bin/env python3
"""The summary tables of results/generalization.md from results/generalization/mujoco-M/*.json
(written by scripts/generalization.sh, one folder per engine): per zoo policy and suite, train and
test mean success, the gap, and the rows skipped. Numbers of two engines are never in one table.

Usage: python3 scripts/generalization_table.py [--engine 3.11.0]   # default: 2.2.2
       python3 scripts/generalization_table.py --agents   # issue 31's training snapshots
                                                         # (results/generalization/mujoco-2.2.2/agents/RUN-epochE.SUITE.json)
       python3 scripts/generalization_table.py --agents-summary [EPOCH]   # one row per snapshot
       python3 scripts/generalization_table.py --generated [--engine 3.11.0]   # issue 46's suites of
                                                         # generated tasks: mean success (rows taken / rows)
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
SUITES = ["colour", "layout", "cross-task", "count", "obstacles"]
GENERATED = ["procgen", "compose", "cross-task-v2"]
BASELINES = ["baseline-scripted", "baseline-obs-hash"]
ENGINE = sys.argv[sys.argv.index("--engine") + 1] if "--engine" in sys.argv else "2.2.2"
DIR = ROOT / "results" / "generalization" / f"mujoco-{ENGINE}"


def applies(r):
    """A suite applies to a policy trained on one of its train split's tasks."""
    train = next(s for s in r["splits"] if s["name"] == "train")
    return r["policy_task"] in {row["task"] for row in train["rows"]}


def main():
    files = sorted(DIR.glob("*.json"))
    policies = sorted({f.name.split(".")[0] for f in files} - set(BASELINES))
    results = {
        p: {s: json.loads((DIR / f"{p}.{s}.json").read_text()) for s in SUITES}
        for p in policies
    }
    for title, keep in [("Where the suite applies (the policy was trained on a task of its train split)", True),
                        ("Elsewhere, for reference (the train split is not the policy's training task)", False)]:
        print(f"**{title}**")
        print()
        print("| zoo policy | trained on | suite | train | test | gap | rows skipped |")
        print("|---|---|---|---:|---:|---:|---:|")
        for p in policies:
            for s in SUITES:
                r = results[p][s]
                if applies(r) != keep:
                    continue
                means = {sp["name"]: sp["mean_success"] for sp in r["splits"]}
                skipped = sum(row["skipped"] is not None for sp in r["splits"] for row in sp["rows"])
                total = sum(len(sp["rows"]) for sp in r["splits"])
                f = lambda v: "–" if v is None else f"{v:.3f}"
                print(f"| {p} | {r['policy_task']} | {s} | {f(means.get('train'))} | {f(means.get('test'))} | "
                      f"{f(r['gap'])} | {skipped} of {total} |")
        print()
    print("**Baselines (no training): the scripted controllers, and pseudo-random actions (obs-hash)**")
    print()
    print("| baseline | suite | train | test | gap |")
    print("|---|---|---:|---:|---:|")
    for b in BASELINES:
        for s in SUITES:
            r = json.loads((DIR / f"{b}.{s}.json").read_text())
            means = {sp["name"]: sp["mean_success"] for sp in r["splits"]}
            f = lambda v: "–" if v is None else f"{v:.3f}"
            print(f"| {b.removeprefix('baseline-')} | {s} | {f(means.get('train'))} | {f(means.get('test'))} | {f(r['gap'])} |")
    print()
    shas = {s: results[policies[0]][s]["suite"]["sha256"][:12] for s in SUITES}
    print("Suite versions (sha256, first 12 hex digits): " + ", ".join(f"{s} `{h}`" for s, h in shas.items()) + ".")
    engines = {results[p][s]["provenance"]["mujoco"] for p in policies for s in SUITES}
    assert engines == {ENGINE}, f"{DIR} holds results of MuJoCo {engines}"
    print(f"All on MuJoCo {ENGINE} (each file's `provenance`).")


def wilson(k, n, z=1.96):
    """The Wilson score interval of k successes in n episodes."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def split_cell(split):
    """Mean success of a split's evaluated rows and the Wilson interval of their pooled episodes."""
    rows = [r["evaluation"] for r in split["rows"] if r["skipped"] is None]
    if not rows:
        return "–"
    k, n = sum(r["successes"] for r in rows), sum(r["episodes"] for r in rows)
    lo, hi = wilson(k, n)
    return f"{split['mean_success']:.3f} [{lo:.2f}, {hi:.2f}]"


def agent_results():
    """(agent, suite, result) of every results/generalization/mujoco-2.2.2/agents/AGENT.SUITE.json, by file name."""
    for f in sorted((DIR / "agents").glob("*-epoch*.*.json")):
        agent, suite = f.name.removesuffix(".json").rsplit(".", 1)
        yield agent, suite, json.loads(f.read_text())


def agents():
    """One row per (snapshot, suite) of results/generalization/mujoco-2.2.2/agents/: train and test success with
    95% intervals (pooled over the split's evaluated rows), the gap, test / train, rows skipped."""
    print("| agent (run, epoch) | trained on | suite | train [95%] | test [95%] | gap | test / train | rows skipped |")
    print("|---|---|---|---:|---:|---:|---:|---:|")
    for agent, suite, r in agent_results():
        splits = {sp["name"]: sp for sp in r["splits"]}
        means = {k: sp["mean_success"] for k, sp in splits.items()}
        skipped = sum(row["skipped"] is not None for sp in r["splits"] for row in sp["rows"])
        total = sum(len(sp["rows"]) for sp in r["splits"])
        train, test = means.get("train"), means.get("test")
        ratio = "–" if not train or test is None else f"{test / train:.2f}"
        gap = "–" if r["gap"] is None else f"{r['gap']:.3f}"
        where = "" if applies(r) else " (elsewhere)"
        print(f"| {agent} | {r['policy_task']}{where} | {suite} | {split_cell(splits['train'])} | "
              f"{split_cell(splits['test'])} | {gap} | {ratio} | {skipped} of {total} |")


def agents_summary(epoch=None):
    """One row per snapshot evaluated on every suite (of `epoch` only, if given): each suite's
    train -> test mean success, `(el.)` where the train split is not the policy's training task."""
    found = {}
    for agent, suite, r in agent_results():
        found.setdefault(agent, {})[suite] = r
    print("| agent (run, epoch) | " + " | ".join(SUITES) + " |")
    print("|---|" + "---:|" * len(SUITES))
    for agent, results in found.items():
        if set(results) != set(SUITES) or (epoch and not agent.endswith(f"-epoch{epoch}")):
            continue
        cells = []
        for s in SUITES:
            r = results[s]
            means = {sp["name"]: sp["mean_success"] for sp in r["splits"]}
            if means.get("train") is None or means.get("test") is None:
                cells.append("skipped")
                continue
            where = "" if applies(r) else " (el.)"
            cells.append(f"{means['train']:.3f} → {means['test']:.3f}{where}")
        print(f"| {agent} | " + " | ".join(cells) + " |")


def generated():
    """Issue 46's suites: per baseline and zoo policy, each split's mean success over the rows it
    takes, with (rows taken / rows); then the suites' versions and the engine."""
    subjects = BASELINES[::-1] + sorted({f.name.split(".")[0] for f in DIR.glob("*.json")} - set(BASELINES))
    head = " | ".join(f"{s} {sp}" for s in GENERATED for sp in ("train", "test"))
    print(f"| policy | {head} |")
    print("|---|" + "---:|" * (2 * len(GENERATED)))
    shas, engines = {}, set()
    for p in subjects:
        cells = []
        for s in GENERATED:
            f = DIR / f"{p}.{s}.json"
            if not f.exists():
                cells += ["–", "–"]
                continue
            r = json.loads(f.read_text())
            shas.setdefault(s, set()).add(r["suite"]["sha256"][:12])
            engines.add(r["provenance"]["mujoco"])
            for sp in r["splits"]:
                taken = sum(row["skipped"] is None for row in sp["rows"])
                mean = "–" if sp["mean_success"] is None else f"{sp['mean_success']:.3f}"
                cells.append(f"{mean} ({taken}/{len(sp['rows'])})")
        print(f"| {p} | " + " | ".join(cells) + " |")
    print()
    assert all(len(v) == 1 for v in shas.values()), f"results of several versions of a suite: {shas}"
    assert engines == {ENGINE}, f"{DIR} holds results of MuJoCo {engines}"
    print("Suite versions (sha256, first 12 hex digits): "
          + ", ".join(f"{s} `{next(iter(v))}`" for s, v in shas.items()) + f". All on MuJoCo {ENGINE}.")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--generated"]:
        generated()
    elif sys.argv[1:2] == ["--agents"]:
        agents()
    elif sys.argv[1:2] == ["--agents-summary"]:
        agents_summary(sys.argv[2] if len(sys.argv) > 2 else None)
    else:
        main()
