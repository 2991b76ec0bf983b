#!/usr/bin/env python3
"""What each extra body costs on the shared garments (issue 14, item 4: with
`--to B1 ... Bn` the time per extra body is the apply cost only; the batch use of
garment CAD teams, thousands of bodies per garment).

    /usr/bin/python3 bench/per_body.py --refit build/release/tools/refit [--vs OTHER_REFIT] \\
        [--threads 1] [--repeat 3]

Every garment of ../shared/data (its feature file from bench/quality/features when
there is one) resized in one process to every shared target body of its sex
(`--out-dir`). Printed per garment: the process wall time (median of --repeat), and
per body the medians over bodies and runs of the report's apply stages (warp,
features, surface, collision, write, ms; the body's own set-up is in `total`). With
--vs the two binaries take turns and their outputs are compared byte for byte.
Exits 77 (CTest's skip) when the shared data is absent.
"""
import argparse
import filecmp
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
GARMENTS = {"skirt": "A_female", "dress": "A_female", "jeans": "A_female", "outfit_dress_jeans": "A_female",
            "dress_soup": "A_female", "male_suit": "M_ref"}
BODIES = {"A_female": ["F_heavier", "F_thinner", "F_taller"], "M_ref": ["M_heavier"]}
STAGES = ["warp", "features", "surface", "collision", "write", "total"]


def run(refit, data, garment, out_dir, threads):
    a = GARMENTS[garment]
    cmd = [refit, "resize", "--garment", os.path.join(data, "garments", "%s_on_%s.obj" % (garment, a)),
           "--from", os.path.join(data, "bodies", a + ".obj"), "--to"]
    cmd += [os.path.join(data, "bodies", b + ".obj") for b in BODIES[a]]
    features = os.path.join(HERE, "quality", "features", garment + ".json")
    if os.path.exists(features):
        cmd += ["--features", features]
    report = os.path.join(out_dir, "report.json")
    cmd += ["--out-dir", out_dir, "--report", report, "--threads", str(threads), "--quiet"]
    start = time.monotonic()
    subprocess.run(cmd, check=True)
    wall = time.monotonic() - start
    r = json.load(open(report))
    bodies = r["bodies"] if "bodies" in r else [r]  # one body: the report is that body's
    return wall, [{s: b["timings_ms"].get(s, 0.0) for s in STAGES} for b in bodies]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--refit", default="build/release/tools/refit")
    ap.add_argument("--vs", default=None, help="a second refit binary, run in turn with the first")
    ap.add_argument("--data", default=os.path.join(HERE, "..", "..", "shared", "data"))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    data = os.path.abspath(a.data)
    if not os.path.isdir(os.path.join(data, "garments")):
        print("per_body: %s is absent: skipped" % data)
        return 77
    binaries = [a.refit] + ([a.vs] if a.vs else [])
    work = tempfile.mkdtemp(prefix="refit-per-body-")
    print("| garment | binary | process wall s | " + " | ".join("%s ms/body" % s for s in STAGES) + " |")
    print("|---|---|---:|" + "---:|" * len(STAGES))
    same = True
    for garment in GARMENTS:
        walls = {b: [] for b in binaries}
        stages = {b: [] for b in binaries}
        for _ in range(a.repeat):
            for k, b in enumerate(binaries):
                out = os.path.join(work, "%s_%d" % (garment, k))
                wall, per_body = run(b, data, garment, out, a.threads)
                walls[b].append(wall)
                stages[b] += per_body
        if a.vs:
            out0, out1 = os.path.join(work, garment + "_0"), os.path.join(work, garment + "_1")
            for name in os.listdir(out0):
                if name.endswith(".obj") and not filecmp.cmp(os.path.join(out0, name), os.path.join(out1, name), shallow=False):
                    same = False
                    print("outputs differ: %s %s" % (garment, name))
        for b in binaries:
            med = [statistics.median(r[s] for r in stages[b]) for s in STAGES]
            print("| %s | %s | %.2f | %s |" % (garment, b, statistics.median(walls[b]), " | ".join("%.0f" % m for m in med)))
    if a.vs:
        print("outputs byte-identical" if same else "OUTPUTS DIFFER")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
