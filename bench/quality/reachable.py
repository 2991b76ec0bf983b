#!/usr/bin/env python3
"""Is a missed shape target of the quality suite reachable at all? (issue 13)

For every feature curve and held-out profile of the suite's garments with features, on
every body of a finished suite run (`run.py --out DIR --methods refit warp`), this finds
a placement of the curve's *original* shape (a similarity: a turn within the curve's plane,
as the warp turned that plane, a move and a scale; --any-rotation: any turn in 3D, which
can turn a profile's bulge sideways out of its plane) such that
  - every sample stays within --reach cm of where the warp alone puts it (a curve cannot
    slide around the body: the garment around it goes with it),
  - every sample is at least --clearance cm outside body B,
  - every sample that sat within 1 cm outside body A (on faces clear of it) keeps its
    distance to the body within --band cm (issue 13's near-body target),
and prints the least shape error found, against the target (the warp's error / 10 for
features, / 3 for held-out profiles) and Refit's. A placement found with no violation is a
witness: that curve alone can meet its target without giving up the near-body one (the
search is local, so a miss here proves nothing). Each curve is placed on its own: where
curves meet, their placements need not agree. Computed with numpy and scipy from the OBJ
files, as every score of the suite.

    /usr/bin/python3 bench/quality/reachable.py --dir OUT [--reach 0.5 1 2] [--json R.json] [--any-rotation]
"""
import argparse
import json
import os
import sys

import numpy as np
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import meshes  # noqa: E402
import run  # noqa: E402

NEAR_CM = 1.0  # as the suite's near-body change


def plane_normal(x):
    """The normal of the plane that fits the samples x best (their least spread)."""
    return np.linalg.svd(x - x.mean(0))[2][-1]


def placement(x, warped, in_plane):
    """place(p): the samples x under a similarity with parameters p, and the parameters of the
    similarity that fits x onto y (for a start). Any similarity: p = rotation vector,
    translation, log scale. In the plane (in_plane): the fit onto the warp's curve (which turns
    the curve's plane as the warp does) followed by a turn about that plane's normal, a move
    and a scale: p = angle, move, log scale; a curve is not turned out of its plane."""
    if not in_plane:
        def place(p):
            return np.exp(p[6]) * x @ Rotation.from_rotvec(p[:3]).as_matrix().T + p[3:6]

        def start(y):
            r, s, mx, my = meshes.umeyama(x, y)
            return np.concatenate([Rotation.from_matrix(r).as_rotvec(), my - s * r @ mx, [np.log(s)]])
        return place, start
    r0, s0, mx, my = meshes.umeyama(x, warped)
    n = r0 @ plane_normal(x)
    base = s0 * (x - mx) @ r0.T  # about the warp's centroid

    def place(p):
        return np.exp(p[4]) * base @ Rotation.from_rotvec(p[0] * n).as_matrix().T + my + p[1:4]

    def start(y):
        r, s, _, my1 = meshes.umeyama(x, y)
        turn = Rotation.from_matrix(r @ r0.T).as_rotvec()
        return np.concatenate([[turn @ n], my1 - my, [np.log(s / s0)]])
    return place, start


def least_error(x, warped, starts, body_b, near, lo, hi, clearance, reach, in_plane=True):
    """Least shape error of the original samples x placed by a similarity under the constraints
    (and the placement's parameters, see placement())."""
    length = np.linalg.norm(np.diff(x, axis=0), axis=1).sum()
    place, start = placement(x, warped, in_plane)

    def violation(p):
        z = place(p)
        d = body_b.signed_distance(z)
        v = np.where(near, np.maximum(0.0, lo - d) + np.maximum(0.0, d - hi), np.maximum(0.0, clearance - d))
        v = v + np.maximum(0.0, np.linalg.norm(z - warped, axis=1) - reach)
        return v

    best = None
    for y in starts:
        res = minimize(lambda p: float((violation(p) ** 2).sum()), start(y), method="Powell",
                       options={"xtol": 1e-7, "ftol": 1e-14, "maxfev": 40000})
        if best is None or res.fun < best.fun:
            best = res
    v = violation(best.x)
    # Moving each violating sample by its violation meets the constraints; the curve's
    # shape error is then at most that RMS over its length (scale of the placement undone).
    scale = float(np.linalg.norm(np.diff(place(best.x), axis=0), axis=1).sum() / length)
    error = float(np.sqrt((v ** 2).mean()) / length / scale)
    return error, float(v.max()), scale, best.x


def closest_approach(x, y):
    """The closest points of polylines x and y: (distance, (segment of x, t), (segment of y, t))."""
    best = (np.inf, None, None)
    for i in range(len(x) - 1):
        for t in np.linspace(0.0, 1.0, 21):
            p = (1 - t) * x[i] + t * x[i + 1]
            a, d = y[:-1], np.diff(y, axis=0)
            u = np.clip(((p - a) * d).sum(1) / np.maximum((d * d).sum(1), 1e-30), 0.0, 1.0)
            dist = np.linalg.norm(a + u[:, None] * d - p, axis=1)
            j = int(dist.argmin())
            if dist[j] < best[0]:
                best = (float(dist[j]), (i, t), (j, float(u[j])))
    return best


def joint_least(curves, warped, starts, body_b, bands, clearance, reach, gap, in_plane=True):
    """The feature curves placed together: as least_error, plus every pair of curves that
    meets in the original (closest approach under 0.1 cm) meeting within `gap`."""
    names = list(curves)
    meets = []
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            d, sa, sb = closest_approach(curves[names[b]], curves[names[a]])
            if d < 0.1:
                meets.append((names[b], sa, names[a], sb))

    placers = {k: placement(curves[k], warped[k], in_plane)[0] for k in names}
    size = 5 if in_plane else 7

    def place(k, p):
        return placers[k](p)

    def at(z, seg):
        i, t = seg
        return (1 - t) * z[i] + t * z[i + 1]

    def violation(params):
        z, parts = {}, []
        for n, k in enumerate(names):
            z[k] = place(k, params[size * n:size * n + size])
            near, lo, hi = bands[k]
            d = body_b.signed_distance(z[k])
            v = np.where(near, np.maximum(0.0, lo - d) + np.maximum(0.0, d - hi), np.maximum(0.0, clearance - d))
            parts.append(v + np.maximum(0.0, np.linalg.norm(z[k] - warped[k], axis=1) - reach))
        for kb, sa, ka, sb in meets:
            parts.append(np.array([max(0.0, np.linalg.norm(at(z[kb], sa) - at(z[ka], sb)) - gap)]))
        return parts

    params = []
    for k in names:  # each curve's own least placement first
        near, lo, hi = bands[k]
        _, _, _, p = least_error(curves[k], warped[k], [s[k] for s in starts], body_b, near, lo, hi, clearance, reach,
                                 in_plane)
        params.append(p)
    res = minimize(lambda p: float(sum((v ** 2).sum() for v in violation(p))), np.concatenate(params),
                   method="Powell", options={"xtol": 1e-7, "ftol": 1e-14, "maxfev": 400000})
    parts = violation(res.x)
    out = {}
    for n, k in enumerate(names):
        length = np.linalg.norm(np.diff(curves[k], axis=0), axis=1).sum()
        scale = np.linalg.norm(np.diff(place(k, res.x[size * n:size * n + size]), axis=0), axis=1).sum() / length
        out[k] = float(np.sqrt((parts[n] ** 2).mean()) / length / scale)
    return out, [float(v[0]) for v in parts[len(names):]]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dir", required=True, help="a run.py --out folder with the refit and warp results")
    ap.add_argument("--data", default=os.path.join(run.HERE, "..", "..", "..", "shared", "data"))
    ap.add_argument("--reach", type=float, nargs="+", default=[1.0])
    ap.add_argument("--clearance", type=float, default=0.25, help="cm (the engine's curves: 0.2 + 0.05)")
    ap.add_argument("--band", type=float, default=0.5)
    ap.add_argument("--gap", type=float, default=0.05, help="cm: how far meeting curves may end apart (issue 13)")
    ap.add_argument("--garments", nargs="+", default=["skirt", "dress", "outfit_dress_jeans"])
    ap.add_argument("--all", action="store_true", help="every curve, not only Refit's misses")
    ap.add_argument("--joint", action="store_true",
                    help="also place each case's feature curves together, meeting where they meet (slow: minutes a case)")
    ap.add_argument("--bodies", nargs="+", help="only these target bodies")
    ap.add_argument("--any-rotation", action="store_true",
                    help="let a placement turn a curve out of its plane (a front profile's bulge turned sideways "
                         "meets the band, but is no longer the designer's profile); default: only within it")
    ap.add_argument("--json")
    args = ap.parse_args()
    if not os.path.isdir(args.dir):
        sys.exit("reachable.py: %s: no such folder (a run.py --out folder)" % args.dir)
    out = []
    print("| garment | body | curve | near-body samples | warp | target | Refit | Refit outside the band cm | " +
          " | ".join("least found, reach %g cm" % r for r in args.reach) + " |")
    print("|---|---|---|---:|---:|---:|---:|---:|" + "---:|" * len(args.reach))
    for g in args.garments:
        fname, body_a_name, spec = run.GARMENTS[g]
        pos, faces = meshes.read_obj(os.path.join(args.data, "garments", fname))[:2]
        ids = meshes.weld_ids(pos)
        body_a = meshes.Body(os.path.join(args.data, "bodies", body_a_name + ".obj"))
        sunk = run.input_sunk(pos, faces, ids, body_a)
        features = json.load(open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "features", g + ".json")))
        curves = {f["name"]: run.carried_curve(pos, faces, ids, f) for f in features["features"]}
        for h in run.feature_specs(pos, body_a.vertices, spec)[1]:
            c = run.carried_curve(pos, faces, ids, h)
            if c is not None and len(c) >= 5:
                curves[h["name"]] = c
        for body in args.bodies or run.TARGETS[body_a_name]:
            b_path = os.path.join(args.dir, body + ".obj")
            if not os.path.exists(b_path):
                b_path = os.path.join(args.data, "bodies", body + ".obj")
            paths = {m: os.path.join(args.dir, "%s__%s__%s.obj" % (g, body, m)) for m in ("warp", "refit")}
            if not all(os.path.exists(p) for p in paths.values()):
                continue
            body_b = meshes.Body(b_path)
            res = {m: meshes.read_positions(p) for m, p in paths.items()}
            feature_case = {}
            for name, c in curves.items():
                x = c.on(pos)
                da = body_a.signed_distance(x)
                near = (da >= 0) & (da <= NEAR_CM) & ~sunk[c.i] & ~sunk[c.j]
                lo, hi = np.maximum(args.clearance, da - args.band), da + args.band
                warped, refit = c.on(res["warp"]), c.on(res["refit"])
                if not name.startswith("held"):
                    feature_case[name] = (x, warped, refit, (near, lo, hi))
                e_warp, e_refit = meshes.shape_error(warped, x), meshes.shape_error(refit, x)
                target = e_warp / (3.0 if name.startswith("held") else 10.0)
                d_refit = body_b.signed_distance(refit)
                outside = np.where(near, np.maximum(0, lo - d_refit) + np.maximum(0, d_refit - hi),
                                   np.maximum(0, args.clearance - d_refit)).max()
                row = dict(garment=g, body=body, curve=name, near=int(near.sum()), samples=len(x), warp=e_warp,
                           target=target, refit=e_refit, refit_outside_band=float(outside), least={})
                if not args.all and e_refit <= target:
                    out.append(row)
                    continue
                for reach in args.reach:
                    e, worst, scale, _ = least_error(x, warped, [warped, refit], body_b, near, lo, hi, args.clearance,
                                                     reach, not args.any_rotation)
                    row["least"][str(reach)] = dict(error=e, worst_violation=worst, scale=scale)
                out.append(row)
                print("| %s | %s | %s | %d/%d | %.5f | %.5f | %.5f%s | %.2f | %s |" % (
                    g, body, name, near.sum(), len(x), e_warp, target, e_refit, "" if e_refit <= target else " (miss)",
                    outside,
                    " | ".join("%.5f%s" % (row["least"][str(r)]["error"],
                                           " (witness)" if row["least"][str(r)]["worst_violation"] == 0.0 else "")
                               for r in args.reach)), flush=True)
            if args.joint and feature_case:
                for reach in args.reach:
                    least, gaps = joint_least({k: v[0] for k, v in feature_case.items()},
                                              {k: v[1] for k, v in feature_case.items()},
                                              [{k: v[1] for k, v in feature_case.items()},
                                               {k: v[2] for k, v in feature_case.items()}],
                                              body_b, {k: v[3] for k, v in feature_case.items()}, args.clearance,
                                              reach, args.gap, not args.any_rotation)
                    out.append(dict(garment=g, body=body, joint=True, reach=reach, least=least, meeting_misses=gaps))
                    print("| %s | %s | together, reach %g cm | %s; meetings missed by %s cm |" % (
                        g, body, reach, ", ".join("%s %.5f" % kv for kv in least.items()),
                        " ".join("%.3f" % v for v in gaps)), flush=True)
    if not out:
        sys.exit("reachable.py: %s: no refit and warp results of the garments with features" % args.dir)
    if args.json:
        json.dump(out, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
