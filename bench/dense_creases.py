#!/usr/bin/env python3
"""The quality suite's creases (bench/quality/meshes.py, without the engine) for
garments too large for the suite's other scores: edges whose two faces' angle changed
from the original's by more than each threshold (degrees), over the whole garment and
inside an optional box (of edge midpoints, in the result's coordinates). Every result
must have the original's vertices and faces (Refit keeps them).

  /usr/bin/python3 bench/dense_creases.py ORIGINAL.obj RESULT.obj [RESULT.obj ...]
      [--degrees 10 20] [--box XMIN XMAX YMIN YMAX ZMIN ZMAX]
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "quality"))
import meshes  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("original")
    ap.add_argument("results", nargs="+")
    ap.add_argument("--degrees", type=float, nargs="+", default=[10.0, 20.0])
    ap.add_argument("--box", type=float, nargs=6, metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"))
    args = ap.parse_args()
    original, faces = meshes.read_obj(args.original)
    # As the suite does: faces on welded vertices, so split seams count as edges.
    _, welded, pairs = meshes.welded_face_pairs(original, faces)
    # An edge's ends: the corners its two faces share.
    shared = [sorted(set(welded[a]) & set(welded[b]))[:2] for a, b in pairs]
    ends = np.asarray(shared, dtype=np.int64).reshape(-1, 2)
    head = "file | " + " | ".join("> %g deg" % t for t in args.degrees)
    if args.box:
        head += " | " + " | ".join("> %g deg in box" % t for t in args.degrees)
    print(head)
    for path in args.results:
        result, result_faces = meshes.read_obj(path)
        if result.shape != original.shape or result_faces != faces:
            sys.exit("dense_creases: %s: not the original's vertices and faces" % path)
        change = meshes.dihedral_change(original, result, welded, pairs)
        row = ["%d" % (change > t).sum() for t in args.degrees]
        if args.box:
            mid = 0.5 * (result[ends[:, 0]] + result[ends[:, 1]])
            lo, hi = np.array(args.box[0::2]), np.array(args.box[1::2])
            inside = np.all((mid > lo) & (mid < hi), axis=1)
            row += ["%d" % ((change > t) & inside).sum() for t in args.degrees]
        print(path + " | " + " | ".join(row))


if __name__ == "__main__":
    main()
