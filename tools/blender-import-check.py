# Imports a .glb with Blender's glTF importer, headless, and prints what it made (shape keys,
# the action, the weights at Blender frame 6). A manual check, not part of scripts/test:
#   blender -b --python tools/blender-import-check.py -- file.glb
# On Debian 12 (blender 3.4 + python3-numpy 1.24) the importer uses np.bool, removed from numpy:
# the alias is restored below.
import bpy, sys, json
import numpy
numpy.bool = bool  # Debian 12: Blender 3.4's glTF importer uses np.bool, removed in numpy 1.24
path = sys.argv[sys.argv.index('--') + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
mesh = next(o for o in bpy.data.objects if o.type == 'MESH')
keys = mesh.data.shape_keys
acts = [a.name for a in bpy.data.actions]
act = keys.animation_data.action if keys and keys.animation_data else None
scene = bpy.context.scene
res = {"vertices": len(mesh.data.vertices), "shape_keys": len(keys.key_blocks) if keys else 0, "actions": acts}
if act:
    res["fcurves"] = len(act.fcurves)
    res["frame_range"] = list(act.frame_range)
    # Evaluate at frame 6 (key 5 at 30 fps -> frame 6 in Blender, 1-based)
    scene.frame_set(6)
    on = [(k.name, round(k.value, 3)) for k in keys.key_blocks[1:] if abs(k.value) > 1e-6]
    res["nonzero_at_frame_6"] = on[:5]
print("RESULT " + json.dumps(res))
