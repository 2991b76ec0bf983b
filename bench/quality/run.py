#!/usr/bin/env python3
"""The quality suite: every garment of the shared data resized to every target body
of its sex (and to F_shorter and M_shorter, body A 9 % shorter, made here), by Refit
(full pipeline), the warp alone, MakeHuman's own proxy fit (where it exists) and
Blender's Surface Deform, scored from the written files by bench/quality/meshes.py
(numpy and scipy only: nothing here comes from the code under test).

    /usr/bin/python3 bench/quality/run.py --refit build/release/tools/refit [--quick]
        [--garments skirt dress ...] [--bodies F_heavier ...] [--methods refit warp makehuman blender]
        [--data ../shared/data] [--out DIR] [--jobs 2] [--json R.json] [--refit-args "--no-collision"]
        [--assert] [--check-bodies] [--dense]

Prints one Markdown row per garment, body and method, then the worst figure of each
method against issue 13's targets. With --assert, exits 1 when Refit misses a target
listed in ASSERTED (the ones the engine holds today; CTest runs --quick --assert), and on
the shared bodies those in ASSERTED_SHARED_ONLY.
Exits 77 (CTest's skip) when the shared data is absent. --check-bodies runs the same on
bodies made here from the shared ones (CHECK: combined and stronger morphs), to see
whether what holds on the shared bodies holds off them. --dense adds the garments of
DENSE (the dress split to 135k vertices by the shared data's make_dense.py), where the
warp's folds under the arms show (about 6 minutes more: scoring is per face).
"""
import argparse
import concurrent.futures
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import meshes  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))

# Garment, body it is on, the skirt part's top and hem heights (cm), where the back
# profile ends (the dress's back slit) and whether the hem is a slice 1 cm above the
# hem edge (the dress's hem loop runs up the slit: no plane holds it).
GARMENTS = {
    "skirt": ("skirt_on_A_female.obj", "A_female", dict(y_top=10.0, y_hem=-69.6, y_back_end=-69.6, hem_slice=False)),
    "dress": ("dress_on_A_female.obj", "A_female", dict(y_top=5.0, y_hem=-29.9, y_back_end=-11.5, hem_slice=True)),
    "outfit_dress_jeans": ("outfit_dress_jeans_on_A_female.obj", "A_female",
                           dict(y_top=5.0, y_hem=-29.9, y_back_end=-11.5, hem_slice=True)),
    "jeans": ("jeans_on_A_female.obj", "A_female", None),
    "male_suit": ("male_suit_on_M_ref.obj", "M_ref", None),
    "dress_soup": ("dress_soup_on_A_female.obj", "A_female", None),
}
TARGETS = {"A_female": ["F_heavier", "F_thinner", "F_taller", "F_shorter"], "M_ref": ["M_heavier", "M_shorter"]}
# Bodies the shared data does not have, made here from body A: 9 % shorter, as wide
# (its heights scaled about the soles). The garment should follow (issue 13 item 3).
DERIVED = {"F_shorter": ("A_female", 0.91), "M_shorter": ("M_ref", 0.91)}
# Bodies to check against (--check-bodies), none of them scored in the table above:
# MakeHuman's morphs of the shared bodies combined and pushed beyond them (body A plus
# the weighted differences of the shared bodies from it; all have body A's
# triangles). The acceptance set's bodies are not here; these show whether what
# holds on the shared bodies holds off them.
CHECK = {"F_heavier_taller": ("A_female", {"F_heavier": 1.0, "F_taller": 1.0}),
         "F_thinner_taller": ("A_female", {"F_thinner": 1.0, "F_taller": 1.0}),
         "F_heaviest": ("A_female", {"F_heavier": 1.6}),
         "F_thinnest": ("A_female", {"F_thinner": 1.5}),
         "M_heaviest": ("M_ref", {"M_heavier": 1.6})}
# Dense garments (--dense), made here with the shared data's make_dense.py (midpoint
# subdivision: the same shape, faces of about 0.4 cm): the warp crumples a garment
# at a scale below body A's triangles (under the arms), which the coarse garments'
# 2 cm faces never show. Their features are the coarse garment's (planes and points).
DENSE = {"dress_dense": ("dress", 100000)}
DERIVED_DIR = None  # where main() writes them
QUICK = (["skirt", "dress"], ["F_heavier", "F_thinner"])
# Features: the hem and a front and a left profile (one side only: the garment must
# stay symmetric all the same). Held-out profiles, scored but not features: degrees
# around the body's vertical axis from the front (+Z) towards the left (+X).
FEATURE_SIDES = {"front": 0, "left": 90}
HELD_OUT = [45, 135, 180, 270]

# What issue 13 asks (the targets), and which of them CTest asserts today.
TARGET_TEXT = {
    "flipped": "new flipped faces 0",
    "inside_vertices": "vertices inside body B 0",
    "inside_faces": "face interiors inside body B 0",
    "near_body_change": "near-body distance change <= 0.5 cm",
    "mirror": "mirror error <= warp + 0.1 cm",
    "height": "height ratio within 2 % of the warp's",
    "feature_gain": "feature profiles >= 10x better than the warp",
    "held_out_gain": "profiles between features >= 3x better than the warp",
    "feature_gap": "feature gap <= 0.05 cm",
    "hem_level": "hem height spread <= the warp's",
    # Beyond issue 13's list (2026-11-30): a garment of several pieces keeps them in order.
    "layers": "no more vertices through the layer over them than the warp",
}
# Face interiors since the collision step probes a coarse face's points over body B's
# vertices (2026-11-27): 0 in all 22 cases, scored at 21 points per fan triangle; and
# with the points over body B's vertices too since the rounds over what is left inside.
# The mirror error, the height ratio and the level hem since 2026-11-28 (held in all 22
# cases and on the CHECK bodies since the symmetric pushes twice and the level hems).
ASSERTED = ["flipped", "inside_vertices", "inside_faces", "mirror", "height", "hem_level"]
# The written feature gap holds in all 22 shared cases (since the snap after the
# symmetrisation) but not on the CHECK bodies (6 of 21, up to 0.11 cm: a coarse face
# cannot bend with a curve the clearance pushed out), so it is asserted on the shared ones only.
ASSERTED_SHARED_ONLY = ["feature_gap"]
# A face of the input this far inside body A (cm) marks its corners: see input_sunk.
INPUT_SUNK_CM = 0.1
# Creases: a change of the angle between two neighbouring faces above this
# (degrees). The dense dress's ripples along its side profiles on a heavier body
# are 5-20 degrees between 0.1-0.3 cm faces (bench/README.md, "Creases").
CREASE_DEGREES = 10.0


def body_centre(body_vertices, y):
    sel = (np.abs(body_vertices[:, 1] - y) < 2.0) & (np.abs(body_vertices[:, 0]) < 18.0)
    v = body_vertices[sel]
    return 0.5 * (v.min(0) + v.max(0))


def outer(positions, centre, y, direction):
    """The garment's outermost point at height y along a horizontal direction, on the
    vertical plane through the centre along that direction."""
    d = np.array([direction[0], 0.0, direction[2]])
    normal = np.array([d[2], 0.0, -d[0]])
    q = positions - centre
    sel = (np.abs(q[:, 1] - (y - centre[1])) <= 2.0) & (np.abs(q @ normal) <= 4.0)
    reach = max(0.0, float((q[sel] @ d).max())) if sel.any() else 0.0
    return [centre[0] + d[0] * reach, y, centre[2] + d[2] * reach]


def profile(positions, centre, spec, degrees, name, end_y=None):
    t = np.radians(degrees)
    d = np.array([np.sin(t), 0.0, np.cos(t)])
    normal = [float(np.cos(t)), 0.0, float(-np.sin(t))]
    y_mid = 0.5 * (spec["y_top"] + spec["y_hem"])
    end = spec["y_hem"] if end_y is None else end_y
    return {"name": name, "plane": {"point": [float(c) for c in centre], "normal": normal},
            "curve": {"kind": "slice", "near": outer(positions, centre, y_mid, d),
                      "from": outer(positions, centre, spec["y_top"], d), "to": outer(positions, centre, end, d),
                      "control_points": 12}, "samples": 60}


def feature_specs(positions, body_a, spec):
    """The feature file for a garment (hem, front and left profiles) and the held-out profiles."""
    centre = body_centre(body_a, spec["y_top"])
    if spec["hem_slice"]:
        y = spec["y_hem"] + 1.0
        hem = {"name": "hem", "plane": {"point": [float(centre[0]), y, float(centre[2])], "normal": [0, 1, 0]},
               "curve": {"kind": "slice", "near": outer(positions, centre, y, (0, 0, 1)), "control_points": 24},
               "samples": 120}
    else:
        hem = {"name": "hem", "curve": {"kind": "boundary", "near": outer(positions, centre, spec["y_hem"], (0, 0, 1))},
               "samples": 120}
    features = [hem] + [profile(positions, centre, spec, deg, name) for name, deg in FEATURE_SIDES.items()]
    held = [profile(positions, centre, spec, deg, "held_%d" % deg,
                    spec["y_back_end"] if 90 < deg < 270 else None) for deg in HELD_OUT]
    return {"units": "cm", "features": features}, held


def carried_curve(positions, faces, ids, f):
    c = f["curve"]
    if c["kind"] == "boundary":
        return meshes.boundary_curve(positions, faces, ids, c["near"])
    return meshes.slice_curve(positions, faces, ids, f["plane"]["point"], f["plane"]["normal"], c["near"],
                              c.get("from"), c.get("to"))


class Case:
    """One garment on body A going to body B: everything scored against the input."""

    def __init__(self, data, garment, target):
        self.garment = garment
        self.target = target
        source = DENSE[garment][0] if garment in DENSE else garment
        file, self.body_a_name, self.spec = GARMENTS[source]
        self.garment_path = (os.path.join(DERIVED_DIR, garment + ".obj") if garment in DENSE
                             else os.path.join(data, "garments", file))
        self.a_path = os.path.join(data, "bodies", self.body_a_name + ".obj")
        made = target in DERIVED or target in CHECK
        self.b_path = os.path.join(DERIVED_DIR if made else os.path.join(data, "bodies"), target + ".obj")
        self.peer_path = os.path.join(data, "peer_makehuman", "%s__%s.obj" % (garment, target))
        self.features_path = os.path.join(HERE, "features", source + ".json") if self.spec else None


def write_derived_bodies(data, out_dir):
    for name, (source, height) in DERIVED.items():
        lines = open(os.path.join(data, "bodies", source + ".obj")).read().splitlines()
        floor = min(float(l.split()[2]) for l in lines if l.startswith("v "))
        with open(os.path.join(out_dir, name + ".obj"), "w") as f:
            for l in lines:
                if l.startswith("v "):
                    x, y, z = (float(t) for t in l.split()[1:4])
                    l = "v %.6f %.6f %.6f" % (x, floor + (y - floor) * height, z)
                f.write(l + "\n")
    for name, (base, weights) in CHECK.items():
        pos, faces = meshes.read_obj(os.path.join(data, "bodies", base + ".obj"))
        out = pos.copy()
        for other, w in weights.items():
            out += w * (meshes.read_obj(os.path.join(data, "bodies", other + ".obj"))[0] - pos)
        with open(os.path.join(out_dir, name + ".obj"), "w") as f:
            f.writelines("v %.6f %.6f %.6f\n" % tuple(v) for v in out)
            f.writelines("f " + " ".join(str(i + 1) for i in face) + "\n" for face in faces)


def input_sunk(original, faces, ids, body_a, depth=INPUT_SUNK_CM):
    """Per vertex: a face of it (coincident vertices of a soup count as one) has a
    point more than `depth` inside body A in the input."""
    pts, owner = meshes.face_samples(original, faces)
    sunk_faces = np.unique(owner[body_a.signed_distance(pts) < -depth])
    marked = np.zeros(ids.max() + 1, dtype=bool)
    for f in sunk_faces:
        marked[ids[list(faces[f])]] = True
    return marked[ids]


def score(case, original, faces, ids, crease_edges, body_a, body_b, dist_a, sunk_a, result, warp, curves, held,
          report):
    s = {}
    s["flipped"] = meshes.flipped_faces(original, result, faces)
    dist_b = body_b.signed_distance(result)
    s["inside_vertices"] = int((dist_b < 0).sum())
    pts, owner = meshes.face_samples(result, faces)
    probes, probe_owner = meshes.face_probes(result, faces, body_b.vertices)
    inside = np.concatenate([owner[body_b.signed_distance(pts) < 0], probe_owner[body_b.signed_distance(probes) < 0]])
    s["inside_faces"] = int(len(np.unique(inside)))
    near = (dist_a >= 0) & (dist_a <= 1.0)
    s["near_body_change"] = float(np.abs(dist_b[near] - dist_a[near]).max()) if near.any() else 0.0
    # The same without the vertices of faces the input already sinks into body A:
    # those must move for the face interiors to clear body B.
    clear = near & ~sunk_a
    s["near_body_change_input_clear"] = float(np.abs(dist_b[clear] - dist_a[clear]).max()) if clear.any() else 0.0
    edges = np.array([(f[k], f[(k + 1) % len(f)]) for f in faces for k in range(len(f))])
    l0 = np.linalg.norm(original[edges[:, 0]] - original[edges[:, 1]], axis=1)
    l1 = np.linalg.norm(result[edges[:, 0]] - result[edges[:, 1]], axis=1)
    ok = l0 > 1e-9
    strain = np.abs(np.log(np.maximum(l1[ok], 1e-12) / l0[ok]))
    s["strain_p95"] = float(np.percentile(strain, 95))
    s["strain_max"] = float(strain.max())
    # Creases: edges between two faces whose angle changed by more than
    # CREASE_DEGREES from the input (a fold line, a groove, a crumple or a ripple
    # along a curve; a smooth bend of the whole garment spreads small changes).
    welded, pairs, clear_edges = crease_edges
    creased = meshes.dihedral_change(original, result, welded, pairs) > CREASE_DEGREES
    s["creases"] = int(creased.sum())
    # The same on edges none of whose faces has a corner on a face the input sinks
    # into body A: such faces must move for their interiors to clear body B.
    s["creases_input_clear"] = int((creased & clear_edges).sum()) if len(creased) else 0
    # Layers: vertices another piece covered in the input that lie beyond it here.
    s["layers_crossed"], s["layers_crossed_depth"] = (
        meshes.layers_crossed(result, faces, case.pieces, body_b, case.covers) if case.covers else (0, 0.0))
    partners = meshes.mirror_partners(original)
    has = partners >= 0
    mirrored = result[has].copy()
    mirrored[:, 0] = -mirrored[:, 0]
    s["mirror"] = float(np.linalg.norm(mirrored - result[partners[has]], axis=1).max()) if has.any() else 0.0
    height = lambda p: p[:, 1].max() - p[:, 1].min()
    s["height_ratio"] = float(height(result) / height(original))
    # Curves carried by their edge parameters from the input to the result.
    feature_errors, held_errors = {}, {}
    for name, c in curves.items():
        feature_errors[name] = meshes.shape_error(c.on(result), c.on(original))
    for name, c in held.items():
        held_errors[name] = meshes.shape_error(c.on(result), c.on(original))
    s["feature_errors"] = feature_errors
    s["held_errors"] = held_errors
    if "hem" in curves:
        hem = curves["hem"].on(result)
        s["hem_spread"] = float(hem[:, 1].max() - hem[:, 1].min())
    if report and "surface" in report:
        # On the written garment (after the collision step) where the report has it.
        s["feature_gap"] = report["surface"].get("feature_gap_written", report["surface"].get("feature_gap"))
    return s


def run_refit(refit, case, out_dir, method, extra):
    out = os.path.join(out_dir, "%s__%s__%s.obj" % (case.garment, case.target, method))
    rep = out[:-4] + ".json"
    cmd = [refit, "resize", "--garment", case.garment_path, "--from", case.a_path, "--to", case.b_path,
           "--out", out, "--report", rep, "--quiet", "--threads", "1"]
    if method == "warp":
        cmd += ["--stage", "warp"]
    else:
        if case.features_path:
            cmd += ["--features", case.features_path]
        cmd += extra
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError("refit failed on %s -> %s: %s" % (case.garment, case.target, r.stderr.strip()))
    return out, json.load(open(rep))


def run_blender(case, out_dir):
    out = os.path.join(out_dir, "%s__%s__blender.obj" % (case.garment, case.target))
    times = out[:-4] + ".json"
    r = subprocess.run(["blender", "-b", "--factory-startup", "--python", os.path.join(HERE, "blender_surface_deform.py"),
                        "--", case.garment_path, case.a_path, case.b_path, out, times], capture_output=True, text=True)
    if r.returncode != 0 or not os.path.exists(out):
        return None, None
    return out, json.load(open(times))


def evaluate(args, case, out_dir):
    original, faces = meshes.read_obj(case.garment_path)
    # The faces on welded vertices and their edges, for the creases of every method's result.
    ids, welded, pairs = meshes.welded_face_pairs(original, faces)
    body_a = meshes.Body(case.a_path)
    body_b = meshes.Body(case.b_path)
    dist_a = body_a.signed_distance(original)
    sunk_a = input_sunk(original, faces, ids, body_a)
    case.pieces = meshes.components(original, faces, ids)
    case.covers = meshes.layer_covers(original, faces, case.pieces, body_a) if case.pieces.max() > 0 else []
    face_by_sunk = np.array([bool(sunk_a[list(f)].any()) for f in faces], dtype=bool)
    clear_edges = ~(face_by_sunk[pairs[:, 0]] | face_by_sunk[pairs[:, 1]]) if len(pairs) else np.zeros(0, dtype=bool)
    crease_edges = (welded, pairs, clear_edges)
    curves, held = {}, {}
    if case.spec:
        spec = json.load(open(case.features_path))
        for f in spec["features"]:
            curves[f["name"]] = carried_curve(original, faces, ids, f)
        _, held_specs = feature_specs(original, body_a.vertices, case.spec)
        for f in held_specs:
            c = carried_curve(original, faces, ids, f)
            if c is not None and len(c) >= 5:
                held[f["name"]] = c
    rows = {}
    warp = None
    for method in args.methods:
        report = None
        if method in ("refit", "warp"):
            path, report = run_refit(args.refit, case, out_dir, method, args.refit_args)
        elif method == "makehuman":
            path = case.peer_path if os.path.exists(case.peer_path) else None
        elif method == "blender":
            path, _ = run_blender(case, out_dir) if shutil.which("blender") else (None, None)
        if not path:
            continue
        result = meshes.read_positions(path)
        if len(result) != len(original):
            raise RuntimeError("%s: %d vertices, expected %d" % (path, len(result), len(original)))
        rows[method] = score(case, original, faces, ids, crease_edges, body_a, body_b, dist_a, sunk_a, result, warp,
                             curves, held, report)
        if method == "warp":
            warp = rows[method]
    return case, rows


def verdicts(rows):
    """Each method's figures against issue 13's targets (the warp alone as the reference)."""
    w = rows.get("warp")
    out = {}
    for m, s in rows.items():
        v = {"flipped": s["flipped"] == 0, "inside_vertices": s["inside_vertices"] == 0,
             "inside_faces": s["inside_faces"] == 0, "near_body_change": s["near_body_change"] <= 0.5}
        if w:
            v["mirror"] = s["mirror"] <= w["mirror"] + 0.1
            v["height"] = abs(s["height_ratio"] / w["height_ratio"] - 1) <= 0.02
            if s["feature_errors"]:
                v["feature_gain"] = min(w["feature_errors"][k] / max(e, 1e-12) for k, e in s["feature_errors"].items()) >= 10
            if s["held_errors"]:
                v["held_out_gain"] = min(w["held_errors"][k] / max(e, 1e-12) for k, e in s["held_errors"].items()) >= 3
            if "hem_spread" in s:
                v["hem_level"] = s["hem_spread"] <= w["hem_spread"] + 1e-6
            if "layers_crossed" in s and "layers_crossed" in w:
                v["layers"] = s["layers_crossed"] <= w["layers_crossed"]
        if s.get("feature_gap") is not None:
            v["feature_gap"] = s["feature_gap"] <= 0.05
        out[m] = v
    return out


def gains(s, w, key):
    if not s.get(key) or not w:
        return ""
    g = [w[key][k] / max(e, 1e-12) for k, e in s[key].items()]
    fmt = lambda x: ">1000x" if x > 1000 else "%.1fx" % x
    return fmt(min(g)) if len(g) == 1 else "%s-%s" % (fmt(min(g)).rstrip("x"), fmt(max(g)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--refit", default="build/release/tools/refit")
    ap.add_argument("--data", default=os.path.join(HERE, "..", "..", "..", "shared", "data"))
    ap.add_argument("--garments", nargs="+", default=list(GARMENTS))
    ap.add_argument("--bodies", nargs="+", default=None)
    ap.add_argument("--methods", nargs="+", default=["warp", "refit", "makehuman", "blender"])
    ap.add_argument("--quick", action="store_true", help="skirt and dress on F_heavier and F_thinner")
    ap.add_argument("--check-bodies", action="store_true",
                    help="the bodies of CHECK instead (blends of the shared bodies, made here)")
    ap.add_argument("--dense", action="store_true",
                    help="also the garments of DENSE (the dress subdivided to 135k vertices; slower to score)")
    ap.add_argument("--out", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", default=None)
    ap.add_argument("--refit-args", default="", help="extra options for the full pipeline")
    ap.add_argument("--write-features", action="store_true", help="(re)write features/*.json from the garments")
    ap.add_argument("--assert", dest="check", action="store_true")
    args = ap.parse_args()
    args.refit_args = args.refit_args.split()
    if "warp" in args.methods:
        args.methods = ["warp"] + [m for m in args.methods if m != "warp"]
    data = os.path.abspath(args.data)
    if not os.path.isdir(os.path.join(data, "garments")):
        print("quality suite: %s is absent: skipped" % data)
        return 77
    if args.write_features:
        for g, (file, body, spec) in GARMENTS.items():
            if spec:
                pos, _ = meshes.read_obj(os.path.join(data, "garments", file))
                feats, _ = feature_specs(pos, meshes.read_obj(os.path.join(data, "bodies", body + ".obj"))[0], spec)
                with open(os.path.join(HERE, "features", g + ".json"), "w") as f:
                    json.dump(feats, f, indent=1)
    global DERIVED_DIR
    out_dir = args.out or tempfile.mkdtemp(prefix="refit-quality-")
    os.makedirs(out_dir, exist_ok=True)
    DERIVED_DIR = out_dir
    write_derived_bodies(data, out_dir)
    garments, bodies = (QUICK if args.quick else (args.garments, args.bodies))
    if args.dense:
        for name, (source, vertices) in DENSE.items():
            subprocess.run([sys.executable, os.path.join(data, "make_dense.py"), os.path.join(data, "garments", GARMENTS[source][0]),
                            os.path.join(out_dir, name + ".obj"), "--min-vertices", str(vertices)], check=True,
                           capture_output=True)
        garments = list(garments) + [name for name in DENSE if name not in garments]  # once, if named too
    targets = TARGETS
    if args.check_bodies:
        targets = {a: [t for t, (base, _) in CHECK.items() if base == a] for a in TARGETS}
    body_a = lambda g: GARMENTS[DENSE[g][0] if g in DENSE else g][1]
    cases = [Case(data, g, t) for g in garments for t in targets[body_a(g)] if not bodies or t in bodies]
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for case, rows in pool.map(lambda c: evaluate(args, c, out_dir), cases):
            results.append((case, rows))

    print("| garment | body | method | flipped | inside v / faces | near-body change cm | strain p95 / max | creases | "
          "mirror cm | height ratio | features vs warp | between vs warp | hem spread cm | feature gap cm |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    failures = {}
    dump = []
    for case, rows in results:
        w = rows.get("warp")
        v = verdicts(rows)
        for m, s in rows.items():
            gap = s.get("feature_gap")
            print("| %s | %s | %s | %d | %d / %d | %.2f | %.3f / %.2f | %d | %.2f | %.3f | %s | %s | %s | %s |" % (
                case.garment, case.target, m, s["flipped"], s["inside_vertices"], s["inside_faces"],
                s["near_body_change"], s["strain_p95"], s["strain_max"], s["creases"], s["mirror"], s["height_ratio"],
                gains(s, w, "feature_errors") if m != "warp" else "", gains(s, w, "held_errors") if m != "warp" else "",
                "%.2f" % s["hem_spread"] if "hem_spread" in s else "", "%.3f" % gap if gap is not None else ""))
            for k, ok in v[m].items():
                if not ok:
                    failures.setdefault(m, {}).setdefault(k, []).append("%s/%s" % (case.garment, case.target))
            dump.append({"garment": case.garment, "body": case.target, "method": m, "scores": s,
                         "targets": {k: bool(ok) for k, ok in v[m].items()}})
    print()
    print("Summary over the cases (worst / median):")
    print()
    print("| method | flipped | inside v / faces | near-body change cm | mirror - warp's cm | height ratio / warp's | "
          "features vs warp (least) | between vs warp (least) | feature gap cm |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for m in args.methods:
        got = [(rows[m], rows.get("warp")) for _, rows in results if m in rows]
        if not got:
            continue
        col = lambda f: [f(s, w) for s, w in got if f(s, w) is not None]
        wm = lambda xs, worst=max: "%.2f / %.2f" % (worst(xs), float(np.median(xs))) if xs else ""
        least = lambda key: lambda s, w: (min(w[key][k] / max(e, 1e-12) for k, e in s[key].items())
                                          if s.get(key) and w and m != "warp" else None)
        print("| %s | %d | %d / %d | %s | %s | %s | %s | %s | %s |" % (
            m, max(s["flipped"] for s, _ in got), max(s["inside_vertices"] for s, _ in got),
            max(s["inside_faces"] for s, _ in got), wm(col(lambda s, w: s["near_body_change"])),
            wm(col(lambda s, w: s["mirror"] - w["mirror"] if w else None)),
            wm(col(lambda s, w: abs(s["height_ratio"] / w["height_ratio"] - 1) + 1 if w else None)),
            wm(col(least("feature_errors")), min), wm(col(least("held_errors")), min),
            wm(col(lambda s, w: s.get("feature_gap")))))
    print()
    print("Near-body change (worst / median, cm; cases over 0.5) over every vertex within 1 cm of body A, and over")
    print("those none of whose faces the input already has more than %.1f cm inside body A (such faces must move" % INPUT_SUNK_CM)
    print("for their interiors to clear body B):")
    print()
    print("| method | all | cases > 0.5 | where the input clears body A | cases > 0.5 |")
    print("|---|---:|---:|---:|---:|")
    for m in args.methods:
        got = [rows[m] for _, rows in results if m in rows]
        if not got:
            continue
        a = [s["near_body_change"] for s in got]
        c = [s["near_body_change_input_clear"] for s in got]
        print("| %s | %.2f / %.2f | %d | %.2f / %.2f | %d |" % (m, max(a), float(np.median(a)), sum(x > 0.5 for x in a),
                                                        max(c), float(np.median(c)), sum(x > 0.5 for x in c)))
    print()
    print("Creases: edges whose two faces' angle changed by more than %g degrees from the input (worst / median" % CREASE_DEGREES)
    print("over the cases), and the cases with more such edges than the warp's; then the same over the edges")
    print("none of whose faces has a corner on a face the input sinks more than %.1f cm into body A:" % INPUT_SUNK_CM)
    print()
    print("| method | creases | cases above the warp's | where the input clears body A | cases above the warp's |")
    print("|---|---:|---:|---:|---:|")
    for m in args.methods:
        got = [(rows[m], rows.get("warp")) for _, rows in results if m in rows]
        if not got:
            continue
        cells = []
        for key in ("creases", "creases_input_clear"):
            c = [s[key] for s, _ in got]
            above = sum(1 for s, w in got if w is not None and s[key] > w[key]) if m != "warp" else 0
            cells.append("%d / %d | %s" % (max(c), int(np.median(c)), above if m != "warp" else ""))
        print("| %s | %s |" % (m, " | ".join(cells)))
    print()
    print("Layers: vertices of one piece that another piece covered in the input (the line out from body A")
    print("through the vertex crosses it just beyond) and that lie beyond that piece in the result: an inner")
    print("layer through an outer one. Over the cases of garments of several pieces: the sum, the deepest (cm)")
    print("and the cases with more than the warp's:")
    print()
    print("| method | vertices through | deepest cm | cases above the warp's |")
    print("|---|---:|---:|---:|")
    for m in args.methods:
        got = [(rows[m], rows.get("warp"), case) for case, rows in results if m in rows and case.covers]
        if not got:
            continue
        above = sum(1 for s, w, _ in got if w is not None and s["layers_crossed"] > w["layers_crossed"])
        print("| %s | %d | %.2f | %s |" % (m, sum(s["layers_crossed"] for s, _, _ in got),
                                          max(s["layers_crossed_depth"] for s, _, _ in got), above if m != "warp" else ""))
    print()
    print("Targets of issue 13 missed (cases):")
    methods = [m for m in args.methods if any(m in rows for _, rows in results)]
    for m in methods:
        missed = failures.get(m, {})
        text = "; ".join("%s: %d (%s)" % (TARGET_TEXT[k], len(c), ", ".join(c[:4]) + (", ..." if len(c) > 4 else ""))
                         for k, c in missed.items())
        print("- %s: %s" % (m, text or "none"))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(dump, f, indent=1)
    if args.check:
        asserted = ASSERTED + ([] if args.check_bodies else ASSERTED_SHARED_ONLY)
        bad = [k for k in asserted if k in failures.get("refit", {})]
        if bad:
            print("quality suite: Refit misses asserted targets: " + ", ".join(TARGET_TEXT[k] for k in bad))
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
