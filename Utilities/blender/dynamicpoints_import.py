"""Blender add-on: File > Import > DynamicPoints animation (.glb). Imports a DynamicPoints .glb
(tracked.glb of the main job, or the glTF writer's output) ready to play: the mesh with smooth
shading, and the scene's frame range and rate set to the animation's.

Install once: Edit > Preferences > Add-ons > Install..., choose this file, tick the box.
Blender's own glTF importer does the reading; this add-on only chooses its shading and sets the
scene, because:
- Debian 12's Blender 3.4 fails on every glTF mesh with the importer's default shading ("Use
  Normal Data" calls numpy.bool, which Debian's numpy 1.24 no longer has), whatever the file
  holds; "Smooth Shading" takes another path and suits the tracked surface.
- The importer never sets the scene's frame range from a file (it stays 1-250, and the
  animation starts at frame 0).
open_tracked.py uses the same function from the command line.
"""
import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ImportHelper

bl_info = {
    "name": "DynamicPoints animation (.glb)",
    "description": "Imports a DynamicPoints .glb ready to play (smooth shading, the scene's "
                   "frame range and rate set to the animation's)",
    "blender": (3, 4, 0),
    "location": "File > Import > DynamicPoints animation (.glb)",
    "category": "Import-Export",
}

FPS = 24  # the rate DynamicPoints writes its keys at (t / 24 s)


def animated_frames(objects):
    """The first and last frame any shape-key animation of OBJECTS has keys at, or None."""
    ranges = [o.data.shape_keys.animation_data.action.frame_range for o in objects
              if o.type == "MESH" and o.data.shape_keys and o.data.shape_keys.animation_data
              and o.data.shape_keys.animation_data.action]
    if not ranges:
        return None
    return int(round(min(r[0] for r in ranges))), int(round(max(r[1] for r in ranges)))


def import_animation(context, path):
    """Imports PATH into the current scene and sets the scene to play its animation. Returns
    (objects imported, (first, last) frame or None); raises RuntimeError if Blender cannot."""
    before = set(context.scene.objects)
    result = bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
    if "FINISHED" not in result:
        raise RuntimeError(f"Blender could not import {path}")
    imported = [o for o in context.scene.objects if o not in before]
    scene = context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    frames = animated_frames(imported)
    if frames:
        scene.frame_start, scene.frame_end = frames
        scene.frame_set(frames[0])
    return imported, frames


class ImportDynamicPointsAnimation(bpy.types.Operator, ImportHelper):
    """Import a DynamicPoints .glb ready to play"""
    bl_idname = "import_scene.dynamicpoints_glb"
    bl_label = "Import DynamicPoints animation"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".glb"
    filter_glob: StringProperty(default="*.glb;*.gltf", options={"HIDDEN"})

    def execute(self, context):
        try:
            imported, frames = import_animation(context, self.filepath)
        except RuntimeError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if frames:
            self.report({"INFO"}, f"{len(imported)} objects, frames {frames[0]}-{frames[1]} at "
                                  f"{FPS} frames per second")
        else:
            self.report({"WARNING"}, f"{self.filepath} holds no shape-key animation")
        return {"FINISHED"}


def menu_entry(self, _context):
    self.layout.operator(ImportDynamicPointsAnimation.bl_idname,
                         text="DynamicPoints animation (.glb)")


def register():
    bpy.utils.register_class(ImportDynamicPointsAnimation)
    bpy.types.TOPBAR_MT_file_import.append(menu_entry)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_entry)
    bpy.utils.unregister_class(ImportDynamicPointsAnimation)
