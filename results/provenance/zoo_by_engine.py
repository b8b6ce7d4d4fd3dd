"""Each zoo entry's recorded evaluations side by side per engine (results/provenance.md).

Usage: python3 results/provenance/zoo_by_engine.py   (from the checkout)"""
import json
import pathlib

ZOO = pathlib.Path(__file__).resolve().parents[2] / "zoo"
print("| entry | task | distribution | episodes | MuJoCo 2.2.2 | MuJoCo 3.11.0 |")
print("|---|---|---|---:|---:|---:|")
for path in sorted(ZOO.glob("*.json")):
    meta = json.loads(path.read_text())
    cells = {}
    for e in meta["evaluations"]:
        engine = (e.get("provenance") or {}).get("mujoco", "none")
        key = (e["env"], e["distribution"] + (", grey removed" if e["grey_blind"] else ""), e["episodes"])
        cells.setdefault(key, {})[engine] = e["success_rate"]
    for (env, dist, n), by in cells.items():
        show = lambda m: f"{by[m]:.3f}" if m in by else "–"
        print(f"| {meta['name']} | {env} | {dist} | {n} | {show('2.2.2')} | {show('3.11.0')} |")
