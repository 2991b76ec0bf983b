#!/usr/bin/env python3
"""The chunked mode on a garment larger than memory (issue 14): the shared
MakeHuman dress densified to --vertices (../shared/data/make_dense.py; made once
into --dense, never into the repository), resized from A_female to F_heavier
with its three features under --memory-budget, process wall time and peak
memory; with --compare, the in-memory mode on the same garment too, and whether
the two outputs are byte-identical. Both modes run with --no-collision (the
chunked mode refuses the collision step: docs/chunked.md). Wall, user CPU and
peak RSS are the process's own, measured here (wait4), beside the report's
peak_memory_mb.

    python3 bench/chunked.py [--refit build/release/tools/refit] [--vertices 10000000]
        [--dense /work/dense] [--budget 1G] [--compare] [--threads 2] [--extra ARG ...]

The 10M run makes a 2.8 GB garment (17.2M vertices: make_dense.py's rounds
overshoot) and writes as much; check the disk first. Exits 77 without the
shared data. Prints one Markdown row per mode.
"""
import argparse
import filecmp
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from dense import densified  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--refit", default="build/release/tools/refit")
    ap.add_argument("--vertices", type=int, default=10_000_000)
    ap.add_argument("--dense", default="/work/dense")
    ap.add_argument("--data", default=os.path.join(HERE, "..", "..", "shared", "data"))
    ap.add_argument("--budget", default="1G")
    ap.add_argument("--compare", action="store_true", help="also run in memory and compare the outputs")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--keep", action="store_true", help="keep the outputs")
    ap.add_argument("--extra", nargs="*", default=[], help="more `refit resize` arguments (e.g. --no-collision)")
    a = ap.parse_args()
    if not os.path.isdir(os.path.join(a.data, "garments")):
        print(f"skipped: the shared data is not at {a.data}")
        return 77
    os.makedirs(a.dense, exist_ok=True)
    garment = densified(a.data, "dress_on_A_female.obj", os.path.join(a.dense, f"dress_{a.vertices}.obj"), a.vertices,
                        quiet=False)
    body = lambda name: os.path.join(a.data, "bodies", name + ".obj")
    base = [a.refit, "resize", "--garment", garment, "--from", body("A_female"), "--to", body("F_heavier"),
            "--features", os.path.join(HERE, "quality", "features", "dress.json"), "--threads", str(a.threads),
            "--no-collision", "--quiet"] + a.extra
    modes = [("chunked", ["--memory-budget", a.budget, "--temp-dir", a.dense])]
    if a.compare:
        modes.append(("in memory", []))
    outs = {}
    print("| vertices | file MB | mode | process wall s | user CPU s | peak RSS MB | report peak MB | estimate MB | chunk vertices |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|")
    for name, extra in modes:
        out = os.path.join(a.dense, f"out_{name.replace(' ', '_')}_{a.vertices}.obj")
        report = out + ".json"
        t = time.monotonic()
        child = subprocess.Popen(base + extra + ["--out", out, "--report", report])
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.monotonic() - t
        if os.waitstatus_to_exitcode(status) != 0:
            print(f"refit failed in the {name} mode (exit {os.waitstatus_to_exitcode(status)})")
            return 1
        r = json.load(open(report))
        chunks = r.get("chunks", {})
        print(f"| {r['garment']['vertices']} | {os.path.getsize(garment) / 2**20:.0f} | {name} | {wall:.1f} | "
              f"{usage.ru_utime:.1f} | {usage.ru_maxrss / 1024:.0f} | {r['peak_memory_mb']:.0f} | "
              f"{r.get('memory_estimate_mb', 0):.0f} | {chunks.get('vertices', '')} |", flush=True)
        os.remove(report)
        outs[name] = out
    if a.compare:
        same = filecmp.cmp(outs["chunked"], outs["in memory"], shallow=False)
        print(f"\noutputs byte-identical: {same}")
    if not a.keep:
        for out in outs.values():
            os.remove(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
