"""Refit for Blender: resize the selected garment(s) from body A to body B (another
object, or a shape key of body A) while keeping the shape the designer meant.

The engine is the Python package `refit` (built with Refit; Debian's Blender runs the
system Python, so the same package loads here: docs/blender.md). Each garment becomes
a new object "<garment> on <body B>": a copy of the garment (materials, UVs, vertex
groups, modifiers kept) with the resized positions. Everything is computed in the
garment's own (local) coordinates, where the feature file's coordinates are too: an
OBJ imported into Blender keeps the file's numbers there.
"""

bl_info = {
    "name": "Refit",
    "author": "Refit",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Refit",
    "description": "Resize garments from one body to another, keeping their designed shape",
    "category": "Object",
}

import os
import sys
import threading

import bpy
import numpy as np
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty


def import_refit():
    """The package refit, from sys.path or the folder set in the add-on's preferences."""
    try:
        import refit
        return refit
    except ImportError:
        addon = bpy.context.preferences.addons.get(__name__)
        folder = bpy.path.abspath(addon.preferences.package_folder) if addon else ""
        if folder and folder not in sys.path:
            sys.path.insert(0, folder)
        try:
            import refit
            return refit
        except ImportError:
            raise RuntimeError("the Python package refit is not found: run Refit's tools/setup.sh, or set its "
                               "folder (build/release/python) in the add-on's preferences") from None


# --- Blender data as arrays ---------------------------------------------------------


def vertex_positions(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def shape_key_positions(obj, name):
    keys = obj.data.shape_keys
    if keys is None or name not in keys.key_blocks:
        raise ValueError("%s has no shape key '%s'" % (obj.name, name))
    block = keys.key_blocks[name]
    co = np.empty(len(block.data) * 3, dtype=np.float32)
    block.data.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def faces_of(mesh):
    """Each polygon's vertex indices one after another, and each polygon's size."""
    sizes = np.empty(len(mesh.polygons), dtype=np.int64)
    starts = np.empty(len(mesh.polygons), dtype=np.int64)
    mesh.polygons.foreach_get("loop_total", sizes)
    mesh.polygons.foreach_get("loop_start", starts)
    loops = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", loops)
    if len(sizes) and not np.array_equal(starts, np.concatenate(([0], np.cumsum(sizes)[:-1]))):
        loops = np.concatenate([loops[s:s + n] for s, n in zip(starts, sizes)])  # polygons out of loop order
    return loops, sizes


def loose_edges(mesh):
    """Edges of no polygon (hanging threads): the garment's 2-vertex lines."""
    loose = np.zeros(len(mesh.edges), dtype=bool)
    mesh.edges.foreach_get("is_loose", loose)
    ends = np.empty(len(mesh.edges) * 2, dtype=np.int64)
    mesh.edges.foreach_get("vertices", ends)
    ends = ends.reshape(-1, 2)[loose]
    return ends.reshape(-1), np.full(len(ends), 2, dtype=np.int64)


def triangles_of(mesh):
    """Polygons fan-split a-b-c, a-c-d (as refit's OBJ reader does)."""
    loops, sizes = faces_of(mesh)
    tris, at = [], 0
    for n in sizes:
        a = loops[at]
        tris.extend((a, loops[at + k], loops[at + k + 1]) for k in range(1, n - 1))
        at += n
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def in_frame_of(garment, obj, positions):
    """`obj`'s local positions in `garment`'s local coordinates (unchanged, bit for bit,
    when both objects have the same transform)."""
    if obj.matrix_world == garment.matrix_world:
        return positions
    m = np.array(garment.matrix_world.inverted() @ obj.matrix_world)
    return positions @ m[:3, :3].T + m[:3, 3]


# --- the work -------------------------------------------------------------------------


class Task:
    """One garment: what is read from Blender (main thread), the engine's work (any
    thread, GIL released), and the result put back into Blender (main thread)."""

    def __init__(self, garment, settings, body_b_positions, body_b_name):
        self.garment = garment
        self.name = garment.name
        self.body_b_name = body_b_name
        a = settings.body_a
        self.body_a_name = a.name
        self.positions = vertex_positions(garment.data)
        self.faces = faces_of(garment.data)
        self.lines = loose_edges(garment.data)
        self.body_a = in_frame_of(garment, a, vertex_positions(a.data))
        self.triangles = triangles_of(a.data)
        self.body_b = in_frame_of(garment, a if settings.body_b is None else settings.body_b, body_b_positions)
        if len(self.body_b) != len(self.body_a):
            raise ValueError("body B (%s) has %d vertices, body A (%s) %d: body B must be body A's mesh in "
                             "another shape" % (body_b_name, len(self.body_b), a.name, len(self.body_a)))
        features = garment.get("refit_features", settings.features)  # per garment, else the panel's
        self.features = bpy.path.abspath(features) if features else ""
        self.options = dict(units=units_of(settings), stage=settings.stage, symmetry=settings.symmetry,
                            collision=settings.collision, threads=settings.threads,
                            clearance=round(settings.clearance, 6),  # Blender keeps float32: 0.2 is 0.2000000030
                            follow_body=round(settings.follow_body, 6))
        self.result = None

    def run(self, refit, progress):
        g = refit.Garment(self.positions, self.faces[0], self.faces[1],
                          *(self.lines if len(self.lines[1]) else (None, None)))
        features = refit.read_features(self.features, units=self.options["units"]) if self.features else None
        a = refit.Body(self.body_a, self.triangles, name=self.body_a_name)
        binding = refit.Binding(g, a, features=features, progress=progress, **self.options)
        self.result = binding.resize(refit.Body(self.body_b, self.triangles, name=self.body_b_name), progress=progress)

    def make_object(self, context):
        """A copy of the garment at the resized positions, beside it in its collections."""
        obj = self.garment.copy()
        obj.data = self.garment.data.copy()
        obj.name = "%s on %s" % (self.name, self.body_b_name)
        obj.data.name = obj.name
        if obj.data.shape_keys:
            obj.shape_key_clear()  # they would override the new positions
        obj.data.vertices.foreach_set("co", self.result.positions.astype(np.float32).reshape(-1))
        obj.data.update()
        obj["refit_report"] = {"warnings": list(self.result.warnings),
                               "feature_shape_error": {c["name"]: c.get("shape_error_output", 0.0)
                                                       for c in self.result.report.get("features", [])}}
        for collection in self.garment.users_collection:
            collection.objects.link(obj)
        if not obj.users_collection:
            context.scene.collection.objects.link(obj)
        return obj


def units_of(settings):
    if settings.units != "SCENE":
        return settings.units
    unit = bpy.context.scene.unit_settings
    if unit.system == "IMPERIAL":
        return "in"
    scale = unit.scale_length  # metres per Blender unit
    for name, metres in (("mm", 0.001), ("cm", 0.01), ("m", 1.0)):
        if abs(scale - metres) <= 1e-9 * metres:
            return name
    return "m"


def garments_of(context, settings):
    bodies = {settings.body_a, settings.body_b}
    return [o for o in context.selected_objects if o.type == "MESH" and o not in bodies]


def body_b_of(settings):
    """Body B's positions (local to its object) and its name."""
    if settings.body_a is None:
        raise ValueError("choose body A")
    if settings.body_b is not None:
        return vertex_positions(settings.body_b.data), settings.body_b.name
    if settings.shape_key:
        return shape_key_positions(settings.body_a, settings.shape_key), settings.shape_key
    raise ValueError("choose body B, or a shape key of body A")


# --- Blender's classes --------------------------------------------------------------


def is_mesh(_, obj):
    return obj.type == "MESH"


class RefitSettings(bpy.types.PropertyGroup):
    body_a: PointerProperty(type=bpy.types.Object, poll=is_mesh, name="Body A",
                            description="The body the garment was made around")
    body_b: PointerProperty(type=bpy.types.Object, poll=is_mesh, name="Body B",
                            description="The new body (same vertices and faces as body A)")
    shape_key: StringProperty(name="Shape key", description="Body B as this shape key of body A (when no body B)")
    features: StringProperty(name="Features", subtype="FILE_PATH",
                             description="Feature file (JSON) whose curves keep their shape; a garment's custom "
                                         "property refit_features overrides it")
    units: EnumProperty(name="Units", default="SCENE", items=[
        ("SCENE", "Scene", "From the scene's unit settings"), ("cm", "cm", ""), ("mm", "mm", ""), ("m", "m", ""),
        ("in", "in", "")])
    stage: EnumProperty(name="Stage", default="full", items=[
        ("full", "Full", "All three steps"), ("features", "Features", "Warp and feature curves"),
        ("warp", "Warp", "The warp alone")])
    symmetry: EnumProperty(name="Symmetry", default="auto", items=[
        ("auto", "Auto", "Mirror one-sided features when garment and body are symmetric"),
        ("x", "X", "Always about x"), ("none", "None", "Never")])
    collision: BoolProperty(name="Collision", default=True, description="Push the garment out of body B")
    clearance: FloatProperty(name="Clearance (cm)", default=0.2, min=0.0, max=10.0)
    follow_body: FloatProperty(name="Follow body (cm)", default=0.0, min=0.0, max=10.0,
                               description="Feature samples that sat within this of body A follow body B "
                                           "(a fitted part; 0: the curves keep their shape there too)")
    threads: IntProperty(name="Threads", default=0, min=0, max=1024, description="0: every core")


class REFIT_OT_resize(bpy.types.Operator):
    """Resize the selected garment(s) from body A to body B into new objects"""

    bl_idname = "object.refit_resize"
    bl_label = "Resize Garment"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def prepare(self, context):
        settings = context.scene.refit
        refit = import_refit()
        body_b, body_b_name = body_b_of(settings)
        garments = garments_of(context, settings)
        if not garments:
            raise ValueError("select the garment object(s) to resize")
        return refit, [Task(g, settings, body_b, body_b_name) for g in garments]

    def finish(self, context, tasks):
        made = [t.make_object(context) for t in tasks]
        for o in context.selected_objects:
            o.select_set(False)
        for o in made:
            o.select_set(True)
        context.view_layer.objects.active = made[-1]
        warnings = sum(len(t.result.warnings) for t in tasks)
        self.report({"WARNING"} if warnings else {"INFO"},
                    "Refit: %d garment(s) resized%s" % (len(made), ", %d warning(s)" % warnings if warnings else ""))

    def execute(self, context):
        """From scripts: the whole work here, blocking."""
        try:
            refit, tasks = self.prepare(context)
            for t in tasks:
                t.run(refit, None)
        except (ValueError, RuntimeError) as e:  # refit.Error is a RuntimeError
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.finish(context, tasks)
        return {"FINISHED"}

    def invoke(self, context, event):
        """From the UI: the engine in a thread (it releases the GIL), the stage in the status bar."""
        try:
            self.refit, self.tasks = self.prepare(context)
        except (ValueError, RuntimeError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.stage, self.error, self.done = "starting", None, 0
        self.thread = threading.Thread(target=self.work, daemon=True)
        self.thread.start()
        wm = context.window_manager
        self.timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, len(self.tasks))
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def work(self):
        try:
            for k, t in enumerate(self.tasks):
                t.run(self.refit, lambda stage, k=k: setattr(self, "stage", "%s: %s" % (self.tasks[k].name, stage)))
                self.done = k + 1
        except Exception as e:  # reported on the main thread
            self.error = e

    def modal(self, context, event):
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        text = "Refit %d/%d: %s" % (self.done, len(self.tasks), self.stage)
        context.workspace.status_text_set(text)
        context.window_manager.progress_update(self.done)
        if self.thread.is_alive():
            return {"RUNNING_MODAL"}
        context.window_manager.event_timer_remove(self.timer)
        context.window_manager.progress_end()
        context.workspace.status_text_set(None)
        if self.error is not None:
            self.report({"ERROR"}, str(self.error))
            return {"CANCELLED"}
        self.finish(context, self.tasks)
        return {"FINISHED"}


class VIEW3D_PT_refit(bpy.types.Panel):
    bl_label = "Refit"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Refit"

    def draw(self, context):
        s = context.scene.refit
        col = self.layout.column()
        col.prop(s, "body_a")
        col.prop(s, "body_b")
        if s.body_b is None and s.body_a is not None and s.body_a.data.shape_keys:
            col.prop_search(s, "shape_key", s.body_a.data.shape_keys, "key_blocks")
        col.prop(s, "features")
        col.prop(s, "units")
        col.prop(s, "stage")
        col.prop(s, "symmetry")
        row = col.row()
        row.prop(s, "collision")
        row.prop(s, "clearance")
        col.prop(s, "follow_body")
        col.prop(s, "threads")
        col.operator(REFIT_OT_resize.bl_idname, icon="MOD_CLOTH")


class RefitPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    package_folder: StringProperty(name="Folder of the refit package", subtype="DIR_PATH",
                                   description="Where `import refit` finds it when it is not installed "
                                               "(Refit's build/release/python)")

    def draw(self, context):
        self.layout.prop(self, "package_folder")


classes = (RefitSettings, REFIT_OT_resize, VIEW3D_PT_refit, RefitPreferences)


def register():
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.refit = PointerProperty(type=RefitSettings)


def unregister():
    del bpy.types.Scene.refit
    for c in reversed(classes):
        bpy.utils.unregister_class(c)
