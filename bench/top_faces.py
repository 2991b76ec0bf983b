#!/usr/bin/env python3
"""A real pattern piece of a chosen size: the top faces of a garment OBJ.

    python3 bench/top_faces.py IN.obj OUT.obj FACES

Keeps the FACES faces whose centres sit highest (+Y up), with their vertices and
texture coordinates (so that UV seams still cut the piece), and nothing else.
Issue 16's speed target names a 100k-face panel; the shared skirt densified by
../shared/data/make_dense.py is one panel of 175,104 quads, and its top 100,000
faces (waist to mid-thigh) are a real, doubly curved 100k-face piece.
"""
import sys

import numpy as np


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__.strip().splitlines()[2].strip())
    src, dst, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
    v, vt, f = [], [], []
    with open(src, encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("v "):
                v.append([float(t) for t in line.split()[1:4]])
            elif line.startswith("vt "):
                vt.append(line.split()[1:3])
            elif line.startswith("f "):
                corners = [t.split("/") for t in line.split()[1:]]
                f.append([(int(c[0]) - 1, int(c[1]) - 1 if len(c) > 1 and c[1] else -1) for c in corners])
    v = np.array(v)
    height = np.array([v[[c[0] for c in face], 1].mean() for face in f])
    keep = np.sort(np.argsort(-height, kind="stable")[:count])
    used = sorted({c[0] for k in keep for c in f[k]})
    used_t = sorted({c[1] for k in keep for c in f[k] if c[1] >= 0})
    new = {o: n + 1 for n, o in enumerate(used)}
    new_t = {o: n + 1 for n, o in enumerate(used_t)}
    with open(dst, "w", encoding="utf-8") as out:
        for o in used:
            out.write("v %.6f %.6f %.6f\n" % tuple(v[o]))
        for o in used_t:
            out.write("vt %s %s\n" % tuple(vt[o]))
        for k in keep:
            out.write("f " + " ".join("%d/%d" % (new[a], new_t[b]) if b >= 0 else str(new[a]) for a, b in f[k]) + "\n")
    print("%s: %d vertices, %d faces (centres at y >= %.2f)" % (dst, len(used), len(keep), height[keep].min()))


if __name__ == "__main__":
    main()
