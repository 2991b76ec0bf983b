#!/usr/bin/env python3
"""Writes jeans.json and male_suit.json, the feature files of the shared jeans and
of the trousers of the shared male suit (issue 16), from the garments:

    /usr/bin/python3 bench/quality/features/jeans_features.py [--data ../shared/data]

For the left leg (+x), the leg's axis is the line through the middles of its
cross-sections at the top of the thigh and at the hem (the legs stand apart, so
the axis leans); the right leg's features are the mirror images of the left's.
Shape curves (they keep their shape in a resize, and are drawn on the pattern):
the front and back creases, where the plane through the axis and the body's
front direction (+Z) cuts the leg's front and back. Seam curves (where the
pattern is cut; a resize ignores them): the outseam, where the plane through
the axis and the sideways direction (+X) cuts the leg's outer side, from the
waistband to the hem. The jeans' own UV seams already cut the legs apart at the
inseam and the centre seams, so each leg becomes a front and a back piece, as
a pattern maker cuts trousers. The suit's trousers are the piece of the suit
that holds its lowest vertex (the jacket is left alone)."""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
import meshes  # noqa: E402

Y_THIGH, Y_HEM = -25.0, -72.0  # cm: just below the crotch, just above the hem edge


def section_middle(v, side, y, band=2.0):
    s = v[(np.abs(v[:, 1] - y) < band) & (side * v[:, 0] > 0)]
    return 0.5 * (s.min(0) + s.max(0))


def slice_feature(name, a, b, view, near, start, end, role):
    f = {"name": name,
         "plane": {"segment": [list(map(float, a)), list(map(float, b))], "view": list(map(float, view))},
         "curve": {"kind": "slice", "near": list(map(float, near)), "from": list(map(float, start)),
                   "to": list(map(float, end)), "control_points": 12},
         "samples": 60}
    if role != "shape":
        f["role"] = role
    return f


def extreme(v, side_mask, direction, y):
    """The vertex farthest along `direction` among those near height y."""
    s = v[side_mask & (np.abs(v[:, 1] - y) < 3.0)]
    return s[np.argmax(s @ direction)]


def lowest_piece(v, faces):
    """Vertices of the connected piece (through faces) that holds the lowest vertex."""
    parent = np.arange(len(v))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for f in faces:
        for a, b in zip(f, f[1:]):
            ra, rb = find(a), find(b)
            if ra != rb:
                parent[ra] = rb
    root = find(int(np.argmin(v[:, 1])))
    return np.array([find(i) == root for i in range(len(v))])


def mirrored(feature, leg):
    """The feature of the other leg: every point and direction mirrored in x = 0
    (a designer's symmetric pattern; the resize then pairs them as mirror images)."""
    m = json.loads(json.dumps(feature).replace("left", leg))

    def flip(p):
        return [-p[0], p[1], p[2]]
    plane = m["plane"]
    plane["segment"] = [flip(p) for p in plane["segment"]]
    plane["view"] = flip(plane["view"])
    for key in ("near", "from", "to"):
        m["curve"][key] = flip(m["curve"][key])
    return m


def features(v):
    """The left leg's features from the garment, the right leg's as their mirror images."""
    out = []
    top_y = v[:, 1].max()
    a = section_middle(v, 1, Y_THIGH)
    b = section_middle(v, 1, Y_HEM)
    mask = v[:, 0] > 0.5
    mid_y = 0.5 * (Y_THIGH + Y_HEM)
    for name, d in (("front", np.array([0.0, 0.0, 1.0])), ("back", np.array([0.0, 0.0, -1.0]))):
        out.append(slice_feature("left-%s-crease" % name, a, b, [0, 0, 1], extreme(v, mask, d, mid_y),
                                 extreme(v, mask, d, Y_THIGH + 5.0), extreme(v, mask, d, v[:, 1].min() + 1.0), "shape"))
    out_dir = np.array([1.0, 0.0, 0.0])
    out.append(slice_feature("left-outseam", a, b, [1, 0, 0], extreme(v, mask, out_dir, mid_y),
                             extreme(v, mask, out_dir, top_y - 1.0), extreme(v, mask, out_dir, v[:, 1].min()), "seam"))
    out += [mirrored(f, "right") for f in out]
    return {"units": "cm", "features": out}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=os.path.join(HERE, "..", "..", "..", "..", "shared", "data"))
    args = ap.parse_args()
    for name, file in (("jeans", "jeans_on_A_female.obj"), ("male_suit", "male_suit_on_M_ref.obj")):
        v, faces = meshes.read_obj(os.path.join(args.data, "garments", file))
        with open(os.path.join(HERE, name + ".json"), "w") as f:
            json.dump(features(v[lowest_piece(v, faces)]), f, indent=1)


if __name__ == "__main__":
    main()
