"""Runs inside Blender (run_blender_test.py starts it): install and enable the add-on,
import the float32-exact shared files, resize the dress (with features) and the jeans
to F_heavier, as an object and as a shape key, and check the new objects."""
import os
import sys

import bpy
import numpy as np

folder, addon, features = sys.argv[sys.argv.index("--") + 1:]

bpy.ops.preferences.addon_install(filepath=addon)
bpy.ops.preferences.addon_enable(module="refit_blender")
assert hasattr(bpy.types, "VIEW3D_PT_refit") and hasattr(bpy.context.scene, "refit"), "the add-on did not register"

bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()


def load(name):
    bpy.ops.wm.obj_import(filepath=os.path.join(folder, name + ".obj"))
    return bpy.context.selected_objects[0]


def positions(obj):
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def cli_positions(name):
    """The command line's output, as Blender stores it (float32)."""
    path = os.path.join(folder, "cli_" + name + ".obj")
    return np.float32([[float(t) for t in line.split()[1:4]] for line in open(path) if line.startswith("v ")])


def select(*objs):
    bpy.ops.object.select_all(action="DESELECT")
    for o in objs:
        o.select_set(True)
    bpy.context.view_layer.objects.active = objs[0]


a, b, dress, jeans = load("A_female"), load("F_heavier"), load("dress"), load("jeans")
fabric = bpy.data.materials.new("fabric")
dress.data.materials.append(fabric)
hem = dress.vertex_groups.new(name="hem")
hem.add([0, 1, 2], 0.5, "REPLACE")
jeans["refit_features"] = ""  # the panel's feature file is the dress's

s = bpy.context.scene.refit
s.body_a, s.body_b, s.features, s.units = a, b, features, "cm"
select(dress, jeans)
assert bpy.ops.object.refit_resize() == {"FINISHED"}

for garment, name in ((dress, "dress"), (jeans, "jeans")):
    new = bpy.data.objects["%s on F_heavier" % garment.name]
    got, want = positions(new), cli_positions(name)
    assert got.shape == want.shape, (got.shape, want.shape)
    differ = int(np.count_nonzero(np.any(got != want, axis=1)))
    assert differ == 0, "%s: %d of %d vertices differ from refit resize (max %g)" % (
        name, differ, len(got), np.abs(got - want).max())
    assert new.matrix_world == garment.matrix_world
    assert new.data.uv_layers.keys() == garment.data.uv_layers.keys() and new.data.uv_layers
    uv_new = np.empty(len(new.data.loops) * 2, dtype=np.float32)
    uv_old = np.empty_like(uv_new)
    new.data.uv_layers[0].data.foreach_get("uv", uv_new)
    garment.data.uv_layers[0].data.foreach_get("uv", uv_old)
    assert np.array_equal(uv_new, uv_old)
    print("refit add-on: %s on F_heavier equals refit resize (%d vertices)" % (name, len(got)))
new_dress = bpy.data.objects["dress on F_heavier"]
assert [m.name for m in new_dress.data.materials] == ["fabric"]
assert new_dress.vertex_groups.keys() == ["hem"] and new_dress.vertex_groups["hem"].weight(1) == 0.5
assert "feature_shape_error" in new_dress["refit_report"]
assert np.array_equal(positions(dress), np.float32(positions(dress)))  # the garment itself is untouched

# Body B as a shape key of body A: the same result.
a.shape_key_add(name="Basis")
key = a.shape_key_add(name="heavier")
key.data.foreach_set("co", positions(b).reshape(-1))
s.body_b, s.shape_key = None, "heavier"
select(dress)
assert bpy.ops.object.refit_resize() == {"FINISHED"}
assert np.array_equal(positions(bpy.data.objects["dress on heavier"]), cli_positions("dress"))
print("refit add-on: body B as a shape key of body A: the same positions")

# Errors are Blender reports (from a script: a RuntimeError with refit's message).
bpy.ops.mesh.primitive_cube_add()
s.body_b = bpy.context.active_object
select(dress)
try:
    bpy.ops.object.refit_resize()
    raise AssertionError("a cube as body B was accepted")
except RuntimeError as e:
    assert "vertices" in str(e), str(e)
    print("refit add-on: error reported: %s" % str(e).strip())
print("refit add-on: all checks passed")
