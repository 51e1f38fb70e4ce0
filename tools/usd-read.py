"""Reads a .usda stage with Pixar's USD (usd-core) and prints what a test compares, as JSON:
the stage's time codes, up axis and metres per unit, and for every mesh its path, face
counts and indices, every time sample of its points and of its velocities, and the samples of its frame labels."""
import json
import sys

from pxr import Usd, UsdGeom

stage = Usd.Stage.Open(sys.argv[1])
out = {
    "time_codes_per_second": stage.GetTimeCodesPerSecond(),
    "frames_per_second": stage.GetFramesPerSecond(),
    "start": stage.GetStartTimeCode(),
    "end": stage.GetEndTimeCode(),
    "up_axis": UsdGeom.GetStageUpAxis(stage),
    "meters_per_unit": UsdGeom.GetStageMetersPerUnit(stage),
    "default_prim": str(stage.GetDefaultPrim().GetPath()),
    "meshes": [],
}
for prim in stage.Traverse():
    if not prim.IsA(UsdGeom.Mesh):
        continue
    mesh = UsdGeom.Mesh(prim)
    points = mesh.GetPointsAttr()
    times = points.GetTimeSamples()
    labels = prim.GetAttribute("primvars:surfcap:synthetic")
    out["meshes"].append({
        "path": str(prim.GetPath()),
        "face_vertex_counts": list(mesh.GetFaceVertexCountsAttr().Get()),
        "face_vertex_indices": list(mesh.GetFaceVertexIndicesAttr().Get()),
        "times": list(times),
        "points": [[c for p in points.Get(t) for c in p] for t in times],
        "velocities": [[c for p in mesh.GetVelocitiesAttr().Get(t) for c in p] for t in mesh.GetVelocitiesAttr().GetTimeSamples()],
        "labels": [int(labels.Get(t)) for t in labels.GetTimeSamples()] if labels else None,
    })
json.dump(out, sys.stdout)
