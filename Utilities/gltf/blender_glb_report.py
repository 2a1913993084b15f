"""Imports a .glb into Blender (batch mode) and prints what Blender made of it as one JSON line
after the marker "DP-REPORT ": the mesh objects, vertex count, morph targets (shape keys), the
animation's frame range and frame rate, and the vertex positions Blender evaluates at the frames
asked for, in glTF axes (Y up) so they compare directly with the file.

Usage: blender -b --factory-startup --python-exit-code 1 -P blender_glb_report.py -- FILE.glb
           [FRAME ...]
"""
import json
import sys

import numpy

# Debian's Blender 3.4 glTF importer still uses numpy.bool, which numpy 1.24 removed.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

import bpy  # noqa: E402  (only inside Blender)

args = sys.argv[sys.argv.index("--") + 1:]
path, frames = args[0], [int(a) for a in args[1:]]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
scene = bpy.context.scene
meshes = [o for o in scene.objects if o.type == "MESH"]
report = {"file": path, "mesh_objects": len(meshes)}
if meshes:
    obj = meshes[0]
    keys = obj.data.shape_keys
    action = keys.animation_data.action if keys and keys.animation_data else None
    report["vertices"] = len(obj.data.vertices)
    report["morph_targets"] = len(keys.key_blocks) - 1 if keys else 0  # minus the basis
    report["fps"] = scene.render.fps / scene.render.fps_base
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
