"""Opens a DynamicPoints .glb (tracked.glb of the main job, or PCA Compress / the glTF writer's
output) in Blender ready to play: imported with smooth shading, the scene's frame range set to
the animation's frames and its rate to the file's 24 frames per second. With --save, writes a
.blend that any Blender opens and plays as it is.

  blender -P open_tracked.py -- tracked.glb                      (the GUI, ready to play)
  blender -b -P open_tracked.py -- tracked.glb --save tracked.blend  (no display)

Why a script: Blender's glTF importer never sets the scene's frame range (it stays 1-250, and
our animation starts at frame 0), and Debian 12's Blender 3.4 fails on every glTF mesh with the
importer's default shading ("Use Normal Data": numpy.bool, which Debian's numpy 1.24 no longer
has, whatever the file holds); "Smooth Shading", chosen here, takes another path and suits the
tracked surface. In the import dialog, choose Shading: Smooth Shading to do the same by hand.
"""
import sys

import bpy

FPS = 24  # the rate DynamicPoints writes its keys at (t / 24 s)


def arguments():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not args or args[0].startswith("-"):
        sys.exit("usage: blender [-b] -P open_tracked.py -- FILE.glb [--save FILE.blend]")
    save = None
    if "--save" in args:
        at = args.index("--save")
        if at + 1 >= len(args):
            sys.exit("--save needs the .blend file to write")
        save = args[at + 1]
    return args[0], save


def animated_frames(objects):
    """The first and last frame any imported shape-key animation has keys at."""
    ranges = [o.data.shape_keys.animation_data.action.frame_range for o in objects
              if o.type == "MESH" and o.data.shape_keys and o.data.shape_keys.animation_data
              and o.data.shape_keys.animation_data.action]
    if not ranges:
        return None
    return int(round(min(r[0] for r in ranges))), int(round(max(r[1] for r in ranges)))


def main():
    path, save = arguments()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
    if "FINISHED" not in result:
        sys.exit(f"Blender could not import {path}")
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    frames = animated_frames(scene.objects)
    if frames:
        scene.frame_start, scene.frame_end = frames
        scene.frame_set(frames[0])
    print(f"{path}: {len(scene.objects)} objects, frames {scene.frame_start}-{scene.frame_end} "
          f"at {FPS} frames per second")
    if save:
        bpy.ops.wm.save_as_mainfile(filepath=save)
        print(f"saved {save}")


main()
