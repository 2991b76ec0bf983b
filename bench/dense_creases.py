#!/usr/bin/env python3
"""Creases of dense written garments, counted without the engine: edges whose two
triangles' angle changed from the original's by more than each threshold (degrees),
over the whole garment and inside an optional box (of edge midpoints, in the result's
coordinates). Every file must have the original's vertices and faces (Refit keeps them).

  /usr/bin/python3 bench/dense_creases.py ORIGINAL.obj RESULT.obj [RESULT.obj ...]
      [--degrees 10 20] [--box XMIN XMAX YMIN YMAX ZMIN ZMAX]
"""
import argparse
import sys

import numpy as np


def read_obj(path):
    """Vertex positions and faces fanned into triangles (0-based)."""
    verts, tris = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                verts.append(line.split()[1:4])
            elif line.startswith("f "):
                ids = [int(t.split("/")[0]) for t in line.split()[1:]]
                ids = [i - 1 if i > 0 else len(verts) + i for i in ids]
                tris.extend((ids[0], ids[k], ids[k + 1]) for k in range(1, len(ids) - 1))
    return np.asarray(verts, float), np.asarray(tris, np.int64).reshape(-1, 3)


def edge_pairs(tris, n):
    """Edges with exactly two triangles: (triangle a, triangle b, vertex 0, vertex 1)."""
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    owner = np.tile(np.arange(len(tris)), 3)
    key = np.minimum(e[:, 0], e[:, 1]) * n + np.maximum(e[:, 0], e[:, 1])
    order = np.argsort(key, kind="stable")
    k = key[order]
    starts = np.r_[0, np.nonzero(k[1:] != k[:-1])[0] + 1]
    counts = np.diff(np.r_[starts, len(k)])
    two = starts[counts == 2]
    return owner[order[two]], owner[order[two + 1]], e[order[two]]


def dihedral(x, tris, fa, fb):
    a, b, c = x[tris[:, 0]], x[tris[:, 1]], x[tris[:, 2]]
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = normal / np.where(length > 0, length, 1.0)
    return np.degrees(np.arccos(np.clip((normal[fa] * normal[fb]).sum(1), -1.0, 1.0)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("original")
    ap.add_argument("results", nargs="+")
    ap.add_argument("--degrees", type=float, nargs="+", default=[10.0, 20.0])
    ap.add_argument("--box", type=float, nargs=6, metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"))
    args = ap.parse_args()
    x0, tris = read_obj(args.original)
    fa, fb, ev = edge_pairs(tris, len(x0))
    d0 = dihedral(x0, tris, fa, fb)
    head = "file | " + " | ".join("> %g deg" % t for t in args.degrees)
    if args.box:
        head += " | " + " | ".join("> %g deg in box" % t for t in args.degrees)
    print(head)
    for path in args.results:
        x, t = read_obj(path)
        if x.shape != x0.shape or not np.array_equal(t, tris):
            sys.exit("dense_creases: %s: not the original's vertices and faces" % path)
        change = np.abs(dihedral(x, tris, fa, fb) - d0)
        row = ["%d" % (change > th).sum() for th in args.degrees]
        if args.box:
            mid = 0.5 * (x[ev[:, 0]] + x[ev[:, 1]])
            lo, hi = np.array(args.box[0::2]), np.array(args.box[1::2])
            inside = np.all((mid > lo) & (mid < hi), axis=1)
            row += ["%d" % ((change > th) & inside).sum() for th in args.degrees]
        print(path + " | " + " | ".join(row))


if __name__ == "__main__":
    main()
