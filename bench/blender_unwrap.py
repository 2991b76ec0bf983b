#!/usr/bin/env python3
"""Is issue 16's stretch target (95th percentile of per-face |log singular value| at most
0.02) reachable on the shared garments' panels at all? Blender as a peer: its own UV
unwrappers, cut along the same seams, scored with numpy (nothing from Refit's code).

    /usr/bin/python3 bench/blender_unwrap.py GARMENT.obj [GARMENT.obj ...] [--refit build/release/tools/refit]

For each garment, Blender (3.4, `blender -b`) builds the mesh from the OBJ's `v`, `vt`
and `f` lines, marks seams where the file's texture coordinates are cut (Blender's
"Seams from Islands", the same panels `refit flatten` cuts from UV seams), and unwraps
every island with its angle-based (ABF++) and conformal (LSCM) unwrappers, then
ABF++ followed by its "Minimize Stretch" relaxation. The garment's own texture layout
is scored too. Every layout is scaled per island to the island's 3D area (which
favours the peers: Refit's ARAP is measured at its own scale), and each triangle of the
faces' fans gets |log| of its larger deviating singular value of the 3D -> 2D map, as
Refit's `triangle_p95`. With --refit, `refit flatten` runs on the same file and its
report's figures are printed beside. Skips with a message when Blender is absent.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

try:
    import bpy  # inside Blender: the unwrapping half
except ImportError:
    bpy = None


def read_obj(path):
    v, vt, faces, fuv = [], [], [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                v.append(tuple(float(x) for x in line.split()[1:4]))
            elif line.startswith("vt "):
                vt.append(tuple(float(x) for x in line.split()[1:3]))
            elif line.startswith("f "):
                idx, uv = [], []
                for tok in line.split()[1:]:
                    parts = tok.split("/")
                    i = int(parts[0])
                    idx.append(i - 1 if i > 0 else len(v) + i)
                    t = int(parts[1]) if len(parts) > 1 and parts[1] else 0
                    uv.append(t - 1 if t > 0 else (len(vt) + t if t < 0 else -1))
                if len(set(idx)) == len(idx):
                    faces.append(idx)
                    fuv.append(uv)
    return v, vt, faces, fuv


def blender_main(argv):
    garment, out = argv
    v, vt, faces, fuv = read_obj(garment)
    bpy.ops.object.select_all(action="SELECT")
    bpy.ops.object.delete()
    mesh = bpy.data.meshes.new("garment")
    mesh.from_pydata(v, [], faces)
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new("garment", mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    layer = mesh.uv_layers.new(name="file")
    for poly in mesh.polygons:
        for k, li in enumerate(poly.loop_indices):
            t = fuv[poly.index][k]
            layer.data[li].uv = vt[t] if t >= 0 else (0.0, 0.0)
    result = {"file": [list(layer.data[i].uv) for i in range(len(mesh.loops))]}
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.select_all(action="SELECT")
    bpy.ops.uv.seams_from_islands(mark_seams=True)
    for name, method, relax in (("abf", "ANGLE_BASED", False), ("lscm", "CONFORMAL", False),
                                ("abf_minimize_stretch", "ANGLE_BASED", True)):
        bpy.ops.uv.unwrap(method=method, fill_holes=False, correct_aspect=False, margin=0.0)
        if relax:
            bpy.ops.uv.minimize_stretch(iterations=2000, blend=0.0, fill_holes=False)
        bpy.ops.object.mode_set(mode="OBJECT")
        result[name] = [list(obj.data.uv_layers.active.data[i].uv) for i in range(len(obj.data.loops))]
        bpy.ops.object.mode_set(mode="EDIT")
    result["faces"] = [list(p.vertices) for p in obj.data.polygons]
    with open(out, "w") as f:
        json.dump(result, f)


def islands(faces, loop_uv):
    """Faces joined where they share an edge with the same texture coordinates on both sides."""
    import numpy as np
    parent = list(range(len(faces)))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a
    edge_owner = {}
    li = 0
    for fi, f in enumerate(faces):
        n = len(f)
        for k in range(n):
            a, b = f[k], f[(k + 1) % n]
            ua, ub = tuple(np.round(loop_uv[li + k], 6)), tuple(np.round(loop_uv[li + (k + 1) % n], 6))
            key = (min(a, b), max(a, b))
            sides = (ua, ub) if a < b else (ub, ua)
            if key in edge_owner:
                other, osides = edge_owner[key]
                if osides == sides:
                    parent[find(fi)] = find(other)
            else:
                edge_owner[key] = (fi, sides)
        li += n
    return [find(i) for i in range(len(faces))]


def score(v, faces, loop_uv, island):
    import numpy as np
    x = np.asarray(v)
    tri3, tri2, owner, face_of_triangle = [], [], [], []
    li = 0
    for fi, f in enumerate(faces):
        for k in range(1, len(f) - 1):
            face_of_triangle.append(fi)
            tri3.append([x[f[0]], x[f[k]], x[f[k + 1]]])
            tri2.append([loop_uv[li], loop_uv[li + k], loop_uv[li + k + 1]])
            owner.append(island[fi])
        li += len(f)
    t3, t2, owner = np.asarray(tri3), np.asarray(tri2, dtype=float), np.asarray(owner)
    e1, e2 = t3[:, 1] - t3[:, 0], t3[:, 2] - t3[:, 0]
    n = np.cross(e1, e2)
    a3 = 0.5 * np.linalg.norm(n, axis=1)
    u1, u2 = t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0]
    a2 = 0.5 * (u1[:, 0] * u2[:, 1] - u1[:, 1] * u2[:, 0])
    for o in np.unique(owner):  # each island to its 3D area (and its winding)
        sel = owner == o
        s = np.sqrt(a3[sel].sum() / max(abs(a2[sel].sum()), 1e-30))
        t2[sel] *= s * (1.0 if a2[sel].sum() >= 0 else np.array([1.0, -1.0]))
    u1, u2 = t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0]
    # The triangle in its own plane: x along e1, y in the plane.
    ex = e1 / np.maximum(np.linalg.norm(e1, axis=1, keepdims=True), 1e-30)
    ey = np.cross(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30), ex)
    X = np.stack([np.stack([(e1 * ex).sum(1), (e2 * ex).sum(1)], 1), np.stack([(e1 * ey).sum(1), (e2 * ey).sum(1)], 1)], 1)
    U = np.stack([np.stack([u1[:, 0], u2[:, 0]], 1), np.stack([u1[:, 1], u2[:, 1]], 1)], 1)
    ok = a3 > 0
    J = U[ok] @ np.linalg.inv(X[ok])
    sv = np.linalg.svd(J, compute_uv=False)
    flipped = int((np.linalg.det(J) < 0).sum())
    stretch = np.abs(np.log(np.maximum(sv, 1e-12))).max(1)
    faces_of = {o: len(set(f for f, w in zip(face_of_triangle, owner) if w == o)) for o in np.unique(owner)}
    per_island = {o: float(np.percentile(stretch[owner[ok] == o], 95)) for o in np.unique(owner)}
    return {"triangles": int(ok.sum()), "p50": float(np.percentile(stretch, 50)),
            "p95": float(np.percentile(stretch, 95)), "max": float(stretch.max()), "flipped": flipped,
            "islands": sorted((faces_of[o], per_island[o]) for o in per_island)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("garments", nargs="+")
    ap.add_argument("--refit", default=None)
    a = ap.parse_args()
    if not shutil.which("blender"):
        print("blender_unwrap: Blender is not installed (apt-get install blender): skipped")
        return 0
    refit_rows = []
    print("| garment | layout | islands | triangles | stretch p50 | p95 | max | flipped |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for g in a.garments:
            out = os.path.join(tmp, "uv.json")
            r = subprocess.run(["blender", "-b", "--factory-startup", "--python", os.path.abspath(__file__), "--", g, out],
                               capture_output=True, text=True)
            if r.returncode != 0 or not os.path.exists(out):
                print("blender_unwrap: %s: Blender failed:\n%s" % (g, r.stdout[-2000:] + r.stderr[-2000:]), file=sys.stderr)
                return 1
            res = json.load(open(out))
            v = read_obj(g)[0]
            faces = res.pop("faces")
            island = islands(faces, res["file"])
            name = os.path.basename(g)
            scores = {}
            for layout, uv in res.items():
                s = scores[layout] = score(v, faces, uv, island)
                print("| %s | %s | %d | %d | %.4f | %.4f | %.4f | %d |" % (
                    name, "file's texture layout" if layout == "file" else "Blender " + layout, len(set(island)),
                    s["triangles"], s["p50"], s["p95"], s["max"], s["flipped"]))
            if a.refit:
                rep = os.path.join(tmp, "refit")
                subprocess.run([a.refit, "flatten", "--garment", g, "--out-dir", rep, "--quiet"], check=True,
                               capture_output=True)
                j = json.load(open(os.path.join(rep, os.path.splitext(name)[0] + ".json")))
                refit_rows.extend((name, p["faces"], p["stretch"]["triangle_p95"],
                                   [scores[k]["islands"] for k in ("abf", "lscm", "abf_minimize_stretch")])
                                  for p in j["panels"])
    if refit_rows:
        # Panels matched to islands by their face count (Refit cuts the same UV seams).
        print()
        print("| garment | panel faces | triangle stretch p95: Refit ARAP | Blender abf | lscm | abf + minimize stretch |")
        print("|---|---:|---:|---:|---:|---:|")
        used = {}
        for name, nf, p95, peers in refit_rows:
            k = used[(name, nf)] = used.get((name, nf), -1) + 1
            cells = []
            for isl in peers:
                same = [q for f, q in isl if f == nf]
                cells.append("%.4f" % same[k] if k < len(same) else "-")
            print("| %s | %d | %.4f | %s |" % (name, nf, p95, " | ".join(cells)))
    return 0


if __name__ == "__main__":
    if bpy is not None:
        blender_main(sys.argv[sys.argv.index("--") + 1:])
    else:
        sys.exit(main())
