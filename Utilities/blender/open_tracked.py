"""Opens a DynamicPoints .glb (tracked.glb of the main job, or PCA Compress / the glTF writer's
output) in Blender ready to play: imported with smooth shading, the scene's frame range set to
the animation's frames and its rate to the file's 24 frames per second. With --save, writes a
.blend that any Blender opens and plays as it is.

  blender -P open_tracked.py -- tracked.glb                      (the GUI, ready to play)
  blender -b -P open_tracked.py -- tracked.glb --save tracked.blend  (no display)

It imports through the add-on beside it (dynamicpoints_import.py, File > Import >
DynamicPoints animation (.glb) once installed), which says why the plain glTF import is not
enough in Debian 12's Blender 3.4.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from dynamicpoints_import import FPS, import_animation  # noqa: E402 (beside this file)


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


def main():
    path, save = arguments()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    try:
        import_animation(bpy.context, path)
    except RuntimeError as error:
        sys.exit(str(error))
    scene = bpy.context.scene
    print(f"{path}: {len(scene.objects)} objects, frames {scene.frame_start}-{scene.frame_end} "
          f"at {FPS} frames per second")
    if save:
        bpy.ops.wm.save_as_mainfile(filepath=save)
        print(f"saved {save}")


main()
