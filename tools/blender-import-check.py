# Imports a file with real Blender, headless, and prints what it made as one line
# `RESULT {json}`.
#
# - `.abc` (Alembic, through Blender's own importer): the mesh objects, the frame range the
#   importer set, and for each frame asked for, every vertex of each mesh as Blender evaluates it
#   at that frame (its MeshSequenceCache modifier), given back in the file's Y-up coordinates
#   (Blender converts Alembic's Y-up points to Z-up: (x, y, z) -> (x, -z, y)), plus the
#   velocities Blender read from `.velocities` (its `velocity` attribute, units per second, in the
#   same coordinates), so a test compares them with what surfcap wrote.
#       tools/venv-blender/bin/python tools/blender-import-check.py file.abc --fps 30 --frames 0,5,9
#   (Blender as a Python module, PyPI `bpy` 5.0.1 in its own environment tools/venv-blender,
#   installed by scripts/setup; crates/surfcap-cli/tests/blender.rs runs it.)
# - `.glb` (glTF, through Blender's glTF importer): shape keys, the action, the weights at Blender
#   frame 6. A manual check with a Blender program:
#       blender -b --python tools/blender-import-check.py -- file.glb
#   On Debian 12 (blender 3.4 + python3-numpy 1.24) the importer uses np.bool, removed from
#   numpy: the alias is restored below. Debian's Blender has no Alembic: use `bpy` for `.abc`.
import json
import sys

import bpy
import numpy

if not hasattr(numpy, "bool"):
    numpy.bool = bool  # Debian 12: Blender 3.4's glTF importer uses np.bool, removed in numpy 1.24

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
path = args[0]
opts = {args[i]: args[i + 1] for i in range(1, len(args) - 1, 2)}
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def glb():
    bpy.ops.import_scene.gltf(filepath=path)
    mesh = next(o for o in bpy.data.objects if o.type == 'MESH')
    keys = mesh.data.shape_keys
    acts = [a.name for a in bpy.data.actions]
    act = keys.animation_data.action if keys and keys.animation_data else None
    res = {"vertices": len(mesh.data.vertices), "shape_keys": len(keys.key_blocks) if keys else 0, "actions": acts}
    if act:
        res["fcurves"] = len(act.fcurves)
        res["frame_range"] = list(act.frame_range)
        # Evaluate at frame 6 (key 5 at 30 fps -> frame 6 in Blender, 1-based)
        scene.frame_set(6)
        on = [(k.name, round(k.value, 3)) for k in keys.key_blocks[1:] if abs(k.value) > 1e-6]
        res["nonzero_at_frame_6"] = on[:5]
    return res


def abc():
    fps = float(opts.get("--fps", "24"))
    # Blender's rate is a whole fps over a base: 29.97 is 30 / 1.001.
    scene.render.fps = max(1, round(fps))
    scene.render.fps_base = scene.render.fps / fps
    bpy.ops.wm.alembic_import(filepath=path, as_background_job=False, set_frame_range=True)
    frames = [int(f) for f in opts.get("--frames", "0").split(",")]
    meshes = sorted((o for o in bpy.data.objects if o.type == 'MESH'), key=lambda o: o.name)
    res = {"blender": bpy.app.version_string, "frame_start": scene.frame_start, "frame_end": scene.frame_end,
           "fps": scene.render.fps / scene.render.fps_base, "meshes": []}
    for o in meshes:
        m = {"name": o.name, "parent": o.parent.name if o.parent else None,
             "modifiers": [md.type for md in o.modifiers], "frames": {}}
        for f in frames:
            scene.frame_set(f)
            ev = o.evaluated_get(bpy.context.evaluated_depsgraph_get())
            me = ev.to_mesh()
            co = numpy.empty(len(me.vertices) * 3, dtype=numpy.float32)
            me.vertices.foreach_get("co", co)
            co = co.reshape(-1, 3)
            entry = {"vertices": len(me.vertices), "polygons": len(me.polygons),
                     "positions": numpy.stack([co[:, 0], co[:, 2], -co[:, 1]], 1).ravel().tolist(),
                     "attributes": sorted(a.name for a in me.attributes)}
            vel = me.attributes.get("velocity")
            if vel is not None:
                v = numpy.empty(len(me.vertices) * 3, dtype=numpy.float32)
                vel.data.foreach_get("vector", v)
                v = v.reshape(-1, 3)
                entry["velocities"] = numpy.stack([v[:, 0], v[:, 2], -v[:, 1]], 1).ravel().tolist()
            ev.to_mesh_clear()
            m["frames"][str(f)] = entry
        res["meshes"].append(m)
    return res


res = abc() if path.lower().endswith(".abc") else glb()
print("RESULT " + json.dumps(res))
