"""The browser app's two latency targets (issue 77), measured from outside as a browser sees them.

- startup: from starting `blockpuzzle serve` to the first page (GET /) answered whole, REPEAT times;
- play: from asking for an episode (GET /api/play, the solver, seed 0, 320-pixel frames) to its
  first frame arriving, and to its last, for every built-in task, on a server already started.

Usage: python3 bench/serve_latency.py BLOCKPUZZLE [--repeat N]  (prints a Markdown table; the
standard library only). Quote the CPU beside the figures (`lscpu`).
"""

import argparse
import http.client
import json
import statistics
import subprocess
import tempfile
import time


def start(binary, folder):
    t0 = time.perf_counter()
    proc = subprocess.Popen([binary, "serve", "--port", "0", "--dir", folder], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL)
    line = proc.stdout.readline().decode()
    port = int(line.rsplit(":", 1)[1].split("/")[0])
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    c.request("GET", "/")
    r = c.getresponse()
    body = r.read()
    assert r.status == 200 and b"BlockPuzzle" in body
    return proc, port, time.perf_counter() - t0


def get_json(port, path):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    c.request("GET", path)
    return json.loads(c.getresponse().read())


def play(port, task):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
    t0 = time.perf_counter()
    c.request("GET", f"/api/play?task={task}&policy=solver&seed=0&side=320")
    r = c.getresponse()
    assert r.status == 200, r.read()
    first = None
    end = None
    for line in r:
        msg = json.loads(line)
        if first is None:
            first = time.perf_counter() - t0
        if msg["type"] == "end":
            end = msg
    return first, time.perf_counter() - t0, end


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        starts = []
        for _ in range(a.repeat):
            proc, _, seconds = start(a.binary, folder)
            starts.append(seconds)
            proc.kill()
            proc.wait()
        proc, port, _ = start(a.binary, folder)
        engine = get_json(port, "/api/health")["engine"]
        print(f"MuJoCo {engine}; startup to the first page over {a.repeat} starts: median "
              f"{statistics.median(starts):.3f} s, max {max(starts):.3f} s\n")
        print("| task | first frame (s) | whole episode (s) | steps | outcome |")
        print("|---|---:|---:|---:|---|")
        firsts = []
        for t in get_json(port, "/api/tasks"):
            first, whole, end = play(port, t["id"])
            firsts.append(first)
            print(f"| {t['id']} | {first:.2f} | {whole:.2f} | {end['steps']} | {end['outcome']} |")
        print(f"\nfirst frame: median {statistics.median(firsts):.2f} s, max {max(firsts):.2f} s")
        proc.kill()


if __name__ == "__main__":
    main()
