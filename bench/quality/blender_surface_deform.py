"""Blender's Surface Deform as a peer: bind a garment to body A, give body A body B's
vertex positions (same connectivity), evaluate, and write the garment's new `v`
positions in the file's vertex order.

    blender -b --factory-startup --python bench/quality/blender_surface_deform.py -- \
        GARMENT.obj BODY_A.obj BODY_B.obj OUT.obj [TIMES.json]

Meshes are built from the OBJ's own `v` and `f` lines (not Blender's importer, which
may split or reorder vertices), so vertex i of OUT is vertex i of GARMENT. `l` and
`p` elements are not meshes in Blender: their vertices are kept as loose vertices.
"""
import json
import sys
import time

import bpy


def read(path):
    verts, faces = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                verts.append(tuple(float(x) for x in line.split()[1:4]))
            elif line.startswith("f "):
                idx = []
                for tok in line.split()[1:]:
                    i = int(tok.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                if len(set(idx)) == len(idx):  # Blender rejects faces with a repeated vertex
                    faces.append(idx)
    return verts, faces


def make_object(name, verts, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def main():
    args = sys.argv[sys.argv.index("--") + 1:]
    garment_path, a_path, b_path, out_path = args[:4]
    times_path = args[4] if len(args) > 4 else None
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    t0 = time.perf_counter()
    gv, gf = read(garment_path)
    av, af = read(a_path)
    bv, _ = read(b_path)
    garment = make_object("garment", gv, gf)
    body = make_object("body", av, af)
    t_load = time.perf_counter()
    mod = garment.modifiers.new("refit_peer", "SURFACE_DEFORM")
    mod.target = body
    bpy.context.view_layer.objects.active = garment
    garment.select_set(True)
    result = bpy.ops.object.surfacedeform_bind(modifier=mod.name)
    if "FINISHED" not in result or not mod.is_bound:
        print("blender_surface_deform: bind failed", file=sys.stderr)
        sys.exit(1)
    t_bind = time.perf_counter()
    flat = [c for v in bv for c in v]
    body.data.vertices.foreach_set("co", flat)
    body.data.update()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    evaluated = garment.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    if len(mesh.vertices) != len(gv):
        print("blender_surface_deform: vertex count changed", file=sys.stderr)
        sys.exit(1)
    co = [0.0] * (3 * len(gv))
    mesh.vertices.foreach_get("co", co)
    t_eval = time.perf_counter()
    with open(out_path, "w") as f:
        for i in range(len(gv)):
            f.write("v %.6f %.6f %.6f\n" % (co[3 * i], co[3 * i + 1], co[3 * i + 2]))
    evaluated.to_mesh_clear()
    if times_path:
        with open(times_path, "w") as f:
            json.dump({"load_s": t_load - t0, "bind_s": t_bind - t_load, "evaluate_s": t_eval - t_bind}, f)


main()
