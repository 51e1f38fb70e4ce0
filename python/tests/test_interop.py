"""Hand-offs to trimesh and rerun: the numbers arrive unchanged (vertex order, triangles, every
frame on its timeline), an .rrd written by ``to_rerun`` reads back with rerun's own reader, and
a missing package is named with what to install."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import surfcap

FACES = np.array([[0, 1, 2], [0, 2, 3], [1, 3, 2]])


def subject(frames: int = 5, **kw) -> surfcap.Subject:
    rng = np.random.default_rng(3)
    p = rng.random((frames, 4, 3)).astype(np.float32)
    return surfcap.Subject.from_arrays(FACES, p, cache=False, **kw)


def test_to_trimesh_keeps_every_vertex_and_triangle_of_the_frame():
    trimesh = pytest.importorskip("trimesh")
    s = subject(sequences=[("walk", 2), ("run", 3)])
    m = s.to_trimesh("run:1")
    assert isinstance(m, trimesh.Trimesh)
    assert m.vertices.dtype == np.float64 and m.vertices.shape == (4, 3)
    np.testing.assert_array_equal(m.vertices, s.frame(3).astype(np.float64))
    np.testing.assert_array_equal(m.faces, FACES)
    np.testing.assert_array_equal(surfcap.to_trimesh(s, 0).vertices, s.frame(0))
    with pytest.raises(IndexError, match="frames 0 to 4"):
        s.to_trimesh(5)


def test_to_trimesh_on_the_crane_gives_a_watertight_frame_of_the_same_size(crane):
    pytest.importorskip("trimesh")
    s = surfcap.Subject.load(crane, cache=False)
    m = s.to_trimesh("crane:100")
    assert len(m.vertices) == s.n_vertices and len(m.faces) == s.n_faces
    np.testing.assert_array_equal(m.vertices, s.frame(100))


def read_rrd(path, *, complete: bool = True):
    """The static and per-frame columns of every entity of an .rrd file, with rerun's reader
    (times as int64 nanoseconds). ``complete``: the file must have its footer (its recording
    closed); rerun warns when it reads one without."""
    import warnings

    import pyarrow as pa
    from rerun.chunk import RrdReader

    def values(col):
        if pa.types.is_duration(col.type) or pa.types.is_timestamp(col.type):
            col = col.cast(pa.int64())
        return col.to_pylist()

    out: dict = {}
    with warnings.catch_warnings():
        # A recording still open has no footer yet: rerun reads it by scanning, and says so.
        warnings.filterwarnings("error" if complete else "ignore", message="RRD file has no footer")
        chunks = RrdReader(path).stream().to_chunks()
    for c in chunks:
        rb = c.to_record_batch()
        e = out.setdefault(c.entity_path, {"static": {}, "rows": []})
        cols = {n: values(rb.column(n)) for n in rb.schema.names}
        if c.is_static:
            e["static"].update(cols)
        else:
            for i in range(c.num_rows):
                e["rows"].append({n: v[i] for n, v in cols.items()})
    return out


def test_to_rerun_writes_a_complete_rrd_with_every_frame_on_the_frame_and_time_timelines(tmp_path):
    pytest.importorskip("rerun")
    s = subject(6, fps=24.0, sequences=[("walk", 2), ("run", 4)], up_axis="+z")
    rrd = tmp_path / "s.rrd"
    s.to_rerun(path=rrd)
    got = read_rrd(rrd)
    mesh = got["/subject"]
    np.testing.assert_array_equal(np.array(mesh["static"]["Mesh3D:triangle_indices"][0]), FACES)
    rows = sorted(mesh["rows"], key=lambda r: r["frame"])
    assert [r["frame"] for r in rows] == list(range(6))
    for r in rows:
        np.testing.assert_array_equal(np.array(r["Mesh3D:vertex_positions"], dtype=np.float32), s.frame(r["frame"]))
        assert r["time"] == pytest.approx(r["frame"] / 24.0 * 1e9, abs=1)
    # The up axis as view coordinates at the root, so the viewer shows the subject upright.
    import rerun as rr

    root = got["/"]["static"]
    key = next(k for k in root if k.endswith("ViewCoordinates:xyz"))
    z_up = [d.value for d in rr.ViewCoordinates.RIGHT_HAND_Z_UP.coordinates]
    assert root[key][0] == [z_up]  # one row holding one instance


def test_log_rerun_logs_one_sequence_into_a_given_recording_at_its_global_frames(tmp_path):
    rr = pytest.importorskip("rerun")
    s = subject(5, sequences=[("walk", 2), ("run", 3)])
    rec = rr.RecordingStream("surfcap-test")
    rrd = tmp_path / "run.rrd"
    rec.save(str(rrd))
    s.log_rerun("actors/run", sequence="run", recording=rec, timeline="tick", up_axis=False)
    rec.flush()
    got = read_rrd(rrd, complete=False)  # the recording is still open
    rows = sorted(got["/actors/run"]["rows"], key=lambda r: r["tick"])
    assert [r["tick"] for r in rows] == [2, 3, 4]
    np.testing.assert_array_equal(
        np.array([r["Mesh3D:vertex_positions"] for r in rows], dtype=np.float32), s.sequence_positions("run")
    )
    assert "/" not in got or not any("ViewCoordinates" in k for k in got["/"]["static"])
    with pytest.raises(KeyError, match=r"walk \(2 frames\), run \(3 frames\)"):
        s.log_rerun(sequence="jump", recording=rec)


@pytest.mark.parametrize(
    "module, call, pip",
    [
        ("trimesh", lambda s: s.to_trimesh(0), "pip install trimesh"),
        ("rerun", lambda s: s.to_rerun(), "pip install rerun-sdk"),
        ("rerun", lambda s: s.log_rerun(), "pip install rerun-sdk"),
    ],
)
def test_a_missing_package_is_named_with_what_to_install(monkeypatch, module, call, pip):
    monkeypatch.setitem(sys.modules, module, None)  # import fails as if it were not installed
    with pytest.raises(ImportError, match=pip):
        call(subject())
