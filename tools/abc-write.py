"""Writes an Alembic (.abc, Ogawa) archive with the reference library (PyPI `alembic3d`, the
PyAlembic bindings) from a JSON description, for surfcap's import tests
(crates/surfcap-cli/tests/abc_import.rs): `abc-write.py spec.json out.abc`.

The description: {"metadata": {key: value} (archive metadata), "objects": [...]} where each
object, parents before children, is one of
  {"type": "xform", "path": "/walk", "translate": [x, y, z] (optional)}
  {"type": "mesh", "path": "/walk/mesh", "subd": false,
   "fps": 30 | "time_per_cycle": t (uniform, with "start") | "times": [...] (acyclic),
   "samples": [{"P": [[x, y, z], ...], "faceIndices": [...], "faceCounts": [...]}, ...]
       (faceIndices/faceCounts only where the topology is given, else the previous repeats),
   "uv": {"vals": [[u, v], ...], "indices": [...] | null, "scope": "facevarying" | "vertex"},
   "normals": [[x, y, z], ...], "labels": [0 | 1, ...] (uint8 surfcap_synthetic, one per sample)}
  {"type": "points" | "curves", "path": ...}
Positions are given as the doubles of float32 values, so the archive holds them exactly."""
import json
import sys

import alembic3d as A
import imath

Abc = A.Abc
G = A.AbcGeom
T = A.AbcCoreAbstract


def v3f(points):
    a = imath.V3fArray(len(points))
    for i, (x, y, z) in enumerate(points):
        a[i] = imath.V3f(x, y, z)
    return a


def ints(values, kind=imath.IntArray):
    a = kind(len(values))
    for i, v in enumerate(values):
        a[i] = v
    return a


def time_sampling(archive, obj):
    if "times" in obj:
        tst = T.TimeSamplingType(T.TimeSamplingType.AcyclicNumSamples(), T.TimeSamplingType.AcyclicTimePerCycle())
        times = T.TimeVector()
        times[:] = obj["times"]
        ts = T.TimeSampling(tst, times)
    elif "time_per_cycle" in obj:
        ts = T.TimeSampling(obj["time_per_cycle"], obj.get("start", 0.0))
    elif "fps" in obj:
        ts = T.TimeSampling(1.0 / obj["fps"], obj.get("start", 0.0))
    else:
        return None
    return archive.addTimeSampling(ts)


spec = json.load(open(sys.argv[1]))
if spec.get("metadata"):
    md = T.MetaData()
    for k, v in spec["metadata"].items():
        md.set(k, v)
    archive = Abc.CreateArchiveWithInfo(sys.argv[2], "surfcap tests", "", Abc.Argument(md))
else:
    archive = Abc.OArchive(sys.argv[2])
made = {"": archive.getTop()}
for obj in spec["objects"]:
    parent_path, name = obj["path"].rsplit("/", 1)
    parent = made[parent_path]
    kind = obj["type"]
    if kind == "xform":
        x = G.OXform(parent, name)
        s = G.XformSample()
        if "translate" in obj:
            s.setTranslation(imath.V3d(*obj["translate"]))
        x.getSchema().set(s)
        made[obj["path"]] = x
    elif kind == "points":
        p = G.OPoints(parent, name)
        p.getSchema().set(G.OPointsSchemaSample(v3f([[0, 0, 0], [1, 0, 0]]), ints([0, 1], imath.IntArray)))
        made[obj["path"]] = p
    elif kind == "curves":
        c = G.OCurves(parent, name)
        c.getSchema().set(G.OCurvesSchemaSample(v3f([[0, 0, 0], [1, 0, 0], [1, 1, 0]]), ints([3])))
        made[obj["path"]] = c
    elif kind == "mesh":
        m = (G.OSubD if obj.get("subd") else G.OPolyMesh)(parent, name)
        schema = m.getSchema()
        tsi = time_sampling(archive, obj)
        if tsi is not None:
            schema.setTimeSampling(tsi)
        labels = None
        if "labels" in obj:
            arb = schema.getArbGeomParams()
            labels = G.OUcharGeomParam(arb, "surfcap_synthetic", False, G.GeometryScope.kConstantScope, 1)
            if tsi is not None:
                labels.setTimeSampling(tsi)
        for k, smp in enumerate(obj["samples"]):
            P = v3f(smp["P"])
            uv = obj.get("uv")
            if "faceIndices" in smp:
                fi, fc = ints(smp["faceIndices"]), ints(smp["faceCounts"])
                if obj.get("subd"):
                    sample = G.OSubDSchemaSample(P, fi, fc)
                else:
                    sample = G.OPolyMeshSchemaSample(P, fi, fc)
                if uv is not None and k == 0:
                    scope = G.GeometryScope.kVertexScope if uv.get("scope") == "vertex" else G.GeometryScope.kFacevaryingScope
                    vals = imath.V2fArray(len(uv["vals"]))
                    for i, (a, b) in enumerate(uv["vals"]):
                        vals[i] = imath.V2f(a, b)
                    if uv.get("indices") is not None:
                        gs = G.OV2fGeomParamSample(vals, ints(uv["indices"], imath.UnsignedIntArray), scope)
                    else:
                        gs = G.OV2fGeomParamSample(vals, scope)
                    sample.setUVs(gs)
                if "normals" in obj and k == 0 and not obj.get("subd"):
                    sample.setNormals(G.ON3fGeomParamSample(v3f(obj["normals"]), G.GeometryScope.kVertexScope))
            elif obj.get("subd"):
                sample = G.OSubDSchemaSample()
                sample.setPositions(P)
            else:
                sample = G.OPolyMeshSchemaSample(P)
            schema.set(sample)
            if labels is not None:
                labels.set(G.OUcharGeomParamSample(ints([obj["labels"][k]], imath.UnsignedCharArray), G.GeometryScope.kConstantScope))
        made[obj["path"]] = m
    else:
        raise SystemExit(f"unknown object type {kind}")
