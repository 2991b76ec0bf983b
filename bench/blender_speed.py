#!/usr/bin/env python3
"""Refit against Blender's Surface Deform on the same dense real garment, side by side
(issue 14): the shared MakeHuman dress densified by ../shared/data/make_dense.py, body
A_female to F_heavier. Blender binds the garment to body A and evaluates it on body B's
positions (bench/quality/blender_surface_deform.py, `blender -b`); Refit runs the full
pipeline with the quality suite's three dress features. The two take turns run by run,
so a slow spell of the shared machine hits both alike.

    /usr/bin/python3 bench/blender_speed.py [--refit build/release/tools/refit]
        [--vertices 1000000] [--repeat 3] [--threads 2] [--workdir /work/dense]
        [--data ../shared/data]

Prints per run and as medians: Blender's bind + evaluate seconds (its own clock, the
OBJ reading left out) and its process wall; Refit's bind + resize seconds (the
report's timings without load and write) and its process wall; peak memory of both
(each process's own maximum resident set); and the ratios Blender / Refit. Exits 77 (CTest's skip)
with a message when Blender or the shared data is absent.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from dense import densified  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def timed(cmd):
    """Runs cmd; returns (wall seconds, peak RSS MB of that process)."""
    t0 = time.perf_counter()
    child = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - t0
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        raise SystemExit(f"failed ({child.returncode}): {' '.join(cmd)}")
    return wall, usage.ru_maxrss / 1024.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--refit", default="build/release/tools/refit")
    ap.add_argument("--vertices", type=int, default=1000000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--workdir", default="/tmp/refit-blender-speed")
    ap.add_argument("--data", default=os.path.join(HERE, "..", "..", "shared", "data"))
    a = ap.parse_args()
    blender = shutil.which("blender")
    if not blender:
        print("skipped: Blender is not installed (apt-get install blender)")
        return 77
    if not os.path.isdir(os.path.join(a.data, "garments")):
        print(f"skipped: the shared data is not at {a.data}")
        return 77
    os.makedirs(a.workdir, exist_ok=True)
    garment = densified(a.data, "dress_on_A_female.obj", os.path.join(a.workdir, f"dress_{a.vertices}.obj"), a.vertices)
    body_a, body_b = (os.path.join(a.data, "bodies", b + ".obj") for b in ("A_female", "F_heavier"))
    features = os.path.join(HERE, "quality", "features", "dress.json")
    out_b, out_r = os.path.join(a.workdir, "blender_out.obj"), os.path.join(a.workdir, "refit_out.obj")
    times_b, report_r = os.path.join(a.workdir, "blender_times.json"), os.path.join(a.workdir, "refit_report.json")
    blender_cmd = [blender, "-b", "--factory-startup", "--python",
                   os.path.join(HERE, "quality", "blender_surface_deform.py"), "--", garment, body_a, body_b, out_b, times_b]
    refit_cmd = [a.refit, "resize", "--garment", garment, "--from", body_a, "--to", body_b, "--features", features,
                 "--out", out_r, "--report", report_r, "--threads", str(a.threads), "--quiet"]
    rows = []
    print(f"dress of {a.vertices}+ vertices ({garment}), A_female -> F_heavier, Refit with {a.threads} threads")
    print("| run | Blender bind+evaluate s | Blender wall s | Blender peak MB | Refit bind+resize s | Refit wall s "
          "| Refit peak MB | bind+evaluate / bind+resize | wall / wall |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for run in range(a.repeat):
        bw, bpeak = timed(blender_cmd)
        bt = json.load(open(times_b))
        rw, rpeak = timed(refit_cmd)
        t = json.load(open(report_r))["timings_ms"]
        refit_work = (t["total"] - t.get("load", 0.0) - t.get("write", 0.0)) / 1000.0
        row = (bt["bind_s"] + bt["evaluate_s"], bw, bpeak, refit_work, rw, rpeak)
        rows.append(row)
        print(f"| {run + 1} | {row[0]:.2f} | {row[1]:.2f} | {row[2]:.0f} | {row[3]:.2f} | {row[4]:.2f} | {row[5]:.0f} "
              f"| {row[0] / row[3]:.1f}x | {row[1] / row[4]:.1f}x |")
    med = [statistics.median(r[i] for r in rows) for i in range(6)]
    ratio_work = statistics.median(r[0] / r[3] for r in rows)
    ratio_wall = statistics.median(r[1] / r[4] for r in rows)
    print(f"| median | {med[0]:.2f} | {med[1]:.2f} | {med[2]:.0f} | {med[3]:.2f} | {med[4]:.2f} | {med[5]:.0f} "
          f"| {ratio_work:.1f}x | {ratio_wall:.1f}x |")
    print("(runs alternate Blender, Refit; peak memory: each process's own maximum resident set)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
