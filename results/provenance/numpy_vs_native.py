import json, blockpuzzle
from blockpuzzle import zoo
name = "BlocksChoose-v0-ddpg-ours"
for native in (False, True):
    p = zoo.load(name, native=native)
    r = blockpuzzle.evaluate(lambda o: p(o), suite="layout", threads=2, name=f"{name} native={native}")
    print(f"native={native}:", [(row["distribution"], row["evaluation"]["successes"], row["evaluation"]["outcomes"]) for s in r["splits"] for row in s["rows"]])
r = blockpuzzle.evaluate(zoo.load(name), suite="layout", threads=2)
print("zoo policy (the CLI's evaluator):", [(row["distribution"], row["evaluation"]["successes"], row["evaluation"]["outcomes"]) for s in r["splits"] for row in s["rows"]])
