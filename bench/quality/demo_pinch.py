#!/usr/bin/env python3
"""The pinch at the centre-front waist of `refit demo` (issue 13: "refit demo shows no
pinch at the centre-front waist"), measured from the written files with numpy only
(bench/quality/meshes.py: nothing here comes from the code under test).

    /usr/bin/python3 bench/quality/demo_pinch.py --refit build/release/tools/refit [--out-dir DIR]
        [--refit-args "..."]

Runs `refit demo` (procedural mannequin pair and 40k-vertex dress; the front profile
starts at the waist, where body B's belly makes the warp bulge), then scores the warp
alone and Refit against the dress on body A: per edge two faces share, the change of
the angle between their normals (meshes.dihedral_change). A groove or a fold the
result adds shows as edges whose angle changes by many degrees; the warp's own smooth
bend of this fine mesh changes each edge by little. Printed per method: the edges
over 12 degrees within 4 cm of the front profile's top end (the waist at the centre
front), the largest change there, and the same over the whole dress.

With --assert the exit status is 1 when Refit leaves any edge there over the threshold
(issue 13: "refit demo shows no pinch at the centre-front waist"; CTest runs it).

With --refit-args the demo's dress is resized again with those options (same files),
to compare switches, e.g. --refit-args="--feature-zone 0".
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import meshes  # noqa: E402

THRESHOLD_DEG = 12.0
RADIUS_CM = 4.0


def front_waist(features_path):
    """The front profile's top end (its `from` point): the centre-front waist."""
    with open(features_path, encoding="utf-8") as f:
        spec = json.load(f)
    for feat in spec["features"]:
        if feat["name"] == "front-profile":
            return np.asarray(feat["curve"]["from"], dtype=float)
    raise SystemExit("demo_pinch: %s has no front-profile feature" % features_path)


def score(original, result, faces, centre):
    change = meshes.dihedral_change(original, result, faces)
    # Each edge placed at its first face's centre on body A.
    mid = np.asarray([original[faces[p[0]]].mean(axis=0) for p in meshes.face_pairs(faces)])
    near = np.linalg.norm(mid - centre, axis=1) <= RADIUS_CM
    return {
        "waist_edges_over": int((change[near] > THRESHOLD_DEG).sum()),
        "waist_max_deg": float(change[near].max()) if near.any() else 0.0,
        "all_edges_over": int((change > THRESHOLD_DEG).sum()),
        "all_max_deg": float(change.max()),
        "waist_edges": int(near.sum()),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--refit", default="build/release/tools/refit")
    ap.add_argument("--out-dir", default=None, help="where the demo writes (default: a temporary folder)")
    ap.add_argument("--refit-args", default="", help="resize the demo's dress again with these options")
    ap.add_argument("--assert", dest="check", action="store_true",
                    help="exit 1 when Refit bends an edge near the centre-front waist by more than the threshold")
    args = ap.parse_args()
    out = args.out_dir or tempfile.mkdtemp(prefix="refit-demo-pinch-")
    subprocess.run([args.refit, "demo", "--out-dir", out, "--quiet"], check=True, stdout=subprocess.DEVNULL)
    refit_out = os.path.join(out, "dress_on_B.obj")
    if args.refit_args:
        refit_out = os.path.join(out, "dress_on_B_args.obj")
        subprocess.run([args.refit, "resize", "--garment", os.path.join(out, "dress_on_A.obj"), "--from",
                        os.path.join(out, "body_A.obj"), "--to", os.path.join(out, "body_B.obj"), "--features",
                        os.path.join(out, "dress_features.json"), "--out", refit_out, "--quiet"]
                       + args.refit_args.split(), check=True)
    original, faces = meshes.read_obj(os.path.join(out, "dress_on_A.obj"))
    centre = front_waist(os.path.join(out, "dress_features.json"))
    print("| method | edges > %.0f deg within %.0f cm of the centre-front waist | largest there, deg "
          "| edges > %.0f deg, whole dress | largest, deg |" % (THRESHOLD_DEG, RADIUS_CM, THRESHOLD_DEG))
    print("|---|---:|---:|---:|---:|")
    for name, path in (("warp", os.path.join(out, "dress_on_B_warp_only.obj")), ("refit", refit_out)):
        s = score(original, meshes.read_positions(path), faces, centre)
        print("| %s | %d (of %d) | %.1f | %d | %.1f |" % (name, s["waist_edges_over"], s["waist_edges"],
                                                         s["waist_max_deg"], s["all_edges_over"], s["all_max_deg"]))
    if args.check:
        if s["waist_edges"] == 0:
            sys.exit("demo_pinch: no edge of the demo dress lies near the centre-front waist")
        if s["waist_edges_over"] > 0:
            sys.exit("demo_pinch: Refit bends %d edges within %.0f cm of the centre-front waist by more than %.0f "
                     "degrees (largest %.1f): a pinch" % (s["waist_edges_over"], RADIUS_CM, THRESHOLD_DEG,
                                                          s["waist_max_deg"]))


if __name__ == "__main__":
    main()
