#!/usr/bin/env python3
"""End-to-end scalability driver: runs `refit resize` (load to write) on dresses of
several sizes with 1 and 2 threads and prints a Markdown table of the report's stage
timings (ms), the process wall time and peak memory, median of --repeat runs.

    python3 bench/scalability.py [--refit build/release/tools/refit]
        [--sizes 100000 1000000 4000000] [--threads 1 2] [--stage warp|full] [--repeat 3]
        [--garment procedural|dress|outfit] [--data ../shared/data]

--garment procedural (default): the generated A-line dress and mannequins, with its
generated features. --garment dress / outfit: the shared MakeHuman dress / dress over
jeans densified by ../shared/data/make_dense.py to at least each size, body A_female to
F_heavier, the quality suite's features (bench/quality/features/); exits 77 without the
shared data.

Runs alternate between the thread counts. After each size's rows, the ratio of
the first thread count's median total to each other's.

--warm-up runs each size once, unmeasured, before its measured runs: on this project's
virtual machine memory the process has not touched for a few seconds costs about 10
ms/MB at its first touch (the host backs it again) against 0.3-0.6 ms/MB right after
another process freed it, so a 4M run right after a 1M run pays for the 2 GB the 1M
run did not use (bench/README.md, "4M against 1M, warm and cold").
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from dense import densified  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REAL = {"dress": ("dress_on_A_female.obj", "dress.json"), "outfit": ("outfit_dress_jeans_on_A_female.obj",
                                                                   "outfit_dress_jeans.json")}


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--refit", default="build/release/tools/refit")
    ap.add_argument("--sizes", type=int, nargs="+", default=[100000, 1000000, 4000000])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--stage", default="full")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workdir", default=None)
    ap.add_argument("--garment", default="procedural", choices=["procedural"] + sorted(REAL))
    ap.add_argument("--data", default=os.path.join(HERE, "..", "..", "shared", "data"))
    ap.add_argument("--warm-up", action="store_true", help="one unmeasured run of each size before its measured runs")
    a = ap.parse_args()
    work = a.workdir or tempfile.mkdtemp(prefix="refit-scal-")
    os.makedirs(work, exist_ok=True)
    if a.garment == "procedural":
        A, B = os.path.join(work, "A.obj"), os.path.join(work, "B.obj")
        run([a.refit, "generate", "--body-out", A])
        run([a.refit, "generate", "--belly", "6", "--hip", "104", "--waist", "76", "--bust", "92", "--body-out", B])
    else:
        if not os.path.isdir(os.path.join(a.data, "garments")):
            print(f"skipped: the shared data is not at {a.data}")
            return 77
        A, B = (os.path.join(a.data, "bodies", b + ".obj") for b in ("A_female", "F_heavier"))
    stages = ["load", "bind", "warp", "features", "surface", "collision", "write", "total"]
    print(f"garment: {a.garment}; stage: {a.stage}; medians of {a.repeat} runs; ms except memory")
    print("| vertices | threads | " + " | ".join(stages) + " | process wall | peak MB | bytes/vertex |")
    print("|" + "---:|" * (len(stages) + 5))
    ratios = []
    for n in a.sizes:
        g = os.path.join(work, f"{a.garment}_{n}.obj")
        f = os.path.join(work, f"{a.garment}_{n}.json")
        if a.garment != "procedural":
            f = os.path.join(HERE, "quality", "features", REAL[a.garment][1])
            densified(a.data, REAL[a.garment][0], g, n)
        elif not (os.path.exists(g) and os.path.exists(f)):  # a --workdir kept from an earlier run has them
            run([a.refit, "generate", "--vertices", str(n), "--garment-out", g, "--features-out", f])
        # Thread counts take turns run by run, so a slow spell of the shared
        # machine hits them alike and their ratio stays meaningful.
        reports = {t: [] for t in a.threads}
        walls = {t: [] for t in a.threads}
        rep = os.path.join(work, "report.json")

        def command(t):
            cmd = [a.refit, "resize", "--garment", g, "--from", A, "--to", B, "--out", os.path.join(work, "out.obj"),
                   "--report", rep, "--threads", str(t), "--quiet", "--stage", a.stage]
            return cmd + (["--features", f] if a.stage != "warp" else [])
        if a.warm_up:
            run(command(a.threads[-1]))
        for _ in range(a.repeat):
            for t in a.threads:
                cmd = command(t)
                start = time.monotonic()
                run(cmd)
                walls[t].append(time.monotonic() - start)
                reports[t].append(json.load(open(rep)))
        for t in a.threads:
            rows = reports[t]
            def med(key):
                vals = []
                for r in rows:
                    v = r["timings_ms"].get(key, 0.0)
                    vals.append(sum(v.values()) if isinstance(v, dict) else v)
                return statistics.median(vals)
            verts = rows[0]["garment"]["vertices"]
            mem = statistics.median(r["peak_memory_mb"] for r in rows)
            cells = " | ".join(f"{med(s):.0f}" for s in stages)
            wall = statistics.median(walls[t])
            print(f"| {verts} | {t} | {cells} | {wall:.2f} s | {mem:.0f} | {mem * 1048576 / verts:.0f} |", flush=True)
            totals = [r["timings_ms"]["total"] for r in rows]
            if t == a.threads[0]:
                base = statistics.median(totals)
            else:
                ratios.append(f"{verts} vertices, {a.threads[0]} -> {t} threads: {base / statistics.median(totals):.2f}x "
                              f"(totals ms: {', '.join(f'{v:.0f}' for v in totals)})")
    print()
    for line in ratios:
        print(line)


if __name__ == "__main__":
    sys.exit(main())
