"""Opens a .glb in Blender (batch mode; imported as a user would with smooth shading, see
Utilities/blender/open_tracked.py) or a saved .blend, and prints what Blender made of it as one
JSON line after the marker "DP-REPORT ": the mesh objects, vertex count, morph targets (shape
keys), the colour attributes (a glTF COLOR_0 becomes one), the animation's frame range, the scene's frame range and frame rate, and the vertex
positions Blender evaluates at the frames asked for, in glTF axes (Y up) so they compare directly
with the file.

Usage: blender -b --factory-startup --python-exit-code 1 -P blender_glb_report.py --
           FILE.glb|FILE.blend [FRAME ...]
"""
import json
import sys

import bpy  # only inside Blender

args = sys.argv[sys.argv.index("--") + 1:]
path, frames = args[0], [int(a) for a in args[1:]]
if path.endswith(".blend"):
    bpy.ops.wm.open_mainfile(filepath=path)
else:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
scene = bpy.context.scene
# The animated mesh first (a scene may hold others, e.g. Blender's default cube).
meshes = sorted((o for o in scene.objects if o.type == "MESH"),
                key=lambda o: o.data.shape_keys is None)
report = {"file": path, "mesh_objects": len(meshes)}
if meshes:
    obj = meshes[0]
    keys = obj.data.shape_keys
    action = keys.animation_data.action if keys and keys.animation_data else None
    report["vertices"] = len(obj.data.vertices)
    report["morph_targets"] = len(keys.key_blocks) - 1 if keys else 0  # minus the basis
    report["colour_attributes"] = [a.name for a in obj.data.color_attributes]
    report["fps"] = scene.render.fps / scene.render.fps_base
    report["scene_frames"] = [scene.frame_start, scene.frame_end]
    if action:
        first, last = action.frame_range
        report["frame_range"] = [first, last]
        report["frames"] = int(round(last - first)) + 1
    positions = {}
    for frame in frames:
        scene.frame_set(frame)
        evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mesh = evaluated.to_mesh()
        world = obj.matrix_world
        # Blender is Z up; the importer maps glTF (x, y, z) to Blender (x, -z, y).
        positions[frame] = [[v.x, v.z, -v.y] for v in (world @ p.co for p in mesh.vertices)]
        evaluated.to_mesh_clear()
    report["positions"] = positions
print("DP-REPORT " + json.dumps(report))
