"""Reads an Alembic (.abc) archive with the reference library (PyPI `alembic3d`, the PyAlembic
bindings) and prints what a test compares, as JSON: the archive's metadata and time samplings,
and for every PolyMesh (at any depth) its path, schema metadata, sample count, sample times,
topology variance, every sample's face counts, face indices, positions and velocities (None
when absent), its UVs and normals
(values, indices, scope) and its arbitrary geometry parameters (name, scope, values); and every Xform's local matrix
(Imath's row-vector layout) by path."""
import json
import sys

import alembic3d as A

Abc = A.Abc
G = A.AbcGeom
SCOPES = {G.GeometryScope.kConstantScope: "constant", G.GeometryScope.kUniformScope: "uniform",
          G.GeometryScope.kVaryingScope: "varying", G.GeometryScope.kVertexScope: "vertex",
          G.GeometryScope.kFacevaryingScope: "facevarying", G.GeometryScope.kUnknownScope: "unknown"}


def vec(v):
    return [[float(x) for x in p] for p in v]


def at(ts, n, k):
    """A selector for sample k. PyAlembic's ISampleSelector(int) resolves to the float-time
    overload (sample k would be the one nearest time k seconds), so select by the sample's own
    time and check that it resolves to index k."""
    sel = Abc.ISampleSelector(ts.getSampleTime(k), Abc.ISampleSelector.TimeIndexType.kNearIndex)
    assert sel.getIndex(ts, n) == k, (k, sel.getIndex(ts, n))
    return sel


def geom_param(p, n):
    if not p.valid():
        return None
    out = {"scope": SCOPES.get(p.getScope(), str(p.getScope())), "indexed": p.isIndexed(),
           "samples": p.getNumSamples(), "values": [], "indices": []}
    for i in range(p.getNumSamples()):
        s = p.getIndexedValue(at(p.getTimeSampling(), p.getNumSamples(), i))
        vals = s.getVals()
        try:
            out["values"].append(vec(vals))
        except TypeError:
            out["values"].append([float(x) for x in vals])
        ind = s.getIndices()
        out["indices"].append([int(x) for x in ind] if ind is not None else None)
    return out


archive = Abc.IArchive(sys.argv[1])
out = {"archive_metadata": archive.getTop().getMetaData().serialize(), "time_samplings": [], "meshes": [],
       "xforms": {}}
for i in range(archive.getNumTimeSamplings()):
    ts = archive.getTimeSampling(i)
    tst = ts.getTimeSamplingType()
    out["time_samplings"].append({
        "uniform": tst.isUniform(), "time_per_cycle": tst.getTimePerCycle(),
        "start": ts.getSampleTime(0),
        "max_samples": archive.getMaxNumSamplesForTimeSamplingIndex(i)})

stack = [archive.getTop()]
while stack:
    obj = stack.pop()
    for c in reversed(list(obj.children)):
        stack.append(c)
    if G.IXform.matches(obj.getHeader()):
        xs = G.IXform(obj, Abc.WrapExistingFlag.kWrapExisting).getSchema()
        v = xs.getValue()
        m = v.getMatrix()
        out["xforms"][obj.getFullName()] = {
            "samples": xs.getNumSamples(), "inherits": v.getInheritsXforms(),
            "matrix": [[m[i][j] for j in range(4)] for i in range(4)]}
    if not G.IPolyMesh.matches(obj.getHeader()):
        continue
    schema = G.IPolyMesh(obj, Abc.WrapExistingFlag.kWrapExisting).getSchema()
    n = schema.getNumSamples()
    ts = schema.getTimeSampling()
    mesh = {"path": obj.getFullName(), "metadata": obj.getMetaData().serialize(), "samples": n,
            "times": [ts.getSampleTime(k) for k in range(n)],
            "topology_variance": str(schema.getTopologyVariance()),
            "face_counts": [], "face_indices": [], "positions": [], "self_bounds": [], "velocities": [],
            "uvs": geom_param(schema.getUVsParam(), n), "normals": geom_param(schema.getNormalsParam(), n),
            "arb_geom_params": {}}
    for k in range(n):
        s = schema.getValue(at(ts, n, k))
        mesh["face_counts"].append([int(x) for x in s.getFaceCounts()])
        mesh["face_indices"].append([int(x) for x in s.getFaceIndices()])
        mesh["positions"].append(vec(s.getPositions()))
        v = s.getVelocities()
        mesh["velocities"].append(vec(v) if v is not None and len(v) else None)
        b = s.getSelfBounds()
        mesh["self_bounds"].append([[b.min().x, b.min().y, b.min().z], [b.max().x, b.max().y, b.max().z]])
    arb = schema.getArbGeomParams()
    if arb.valid():
        for j in range(arb.getNumProperties()):
            h = arb.getPropertyHeader(j)
            name = h.getName()
            prop = arb.getProperty(name) if hasattr(arb, "getProperty") else None
            entry = {"metadata": h.getMetaData().serialize(), "array": h.isArray(), "samples": [], "pod": str(h.getDataType().getPod())}
            if h.isArray():
                p = Abc.IArrayProperty(arb, name)
                for k in range(p.getNumSamples()):
                    entry["samples"].append([float(x) if not isinstance(x, (int, bool)) else int(x) for x in p.getValue(at(p.getTimeSampling(), p.getNumSamples(), k))])
            elif h.isScalar():
                p = Abc.IScalarProperty(arb, name)
                for k in range(p.getNumSamples()):
                    v = p.getValue(at(p.getTimeSampling(), p.getNumSamples(), k))
                    entry["samples"].append(v if isinstance(v, (int, float, bool)) else str(v))
            mesh["arb_geom_params"][name] = entry
    out["meshes"].append(mesh)
json.dump(out, sys.stdout)
