"""The Subject class: arrays in (dtypes, orders, strides, zero-copy), views out, errors that name
what is wrong, and the real crane read as the command line reads it."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import surfcap

FACES = np.array([[0, 1, 2], [0, 2, 3]])


def positions(frames: int = 5) -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.random((frames, 4, 3)).astype(np.float32)


def test_version():
    assert surfcap.__version__ == "0.1.0"


def test_c_contiguous_float32_is_used_in_place_and_views_share_memory():
    p = positions()
    s = surfcap.Subject.from_arrays(FACES, p, cache=False)
    v = s.positions
    assert v.__array_interface__["data"][0] == p.__array_interface__["data"][0]
    assert not v.flags.writeable
    assert s.frame(2).__array_interface__["data"][0] == p[2].__array_interface__["data"][0]
    # copy=True makes the subject its own numbers.
    c = surfcap.Subject.from_arrays(FACES, p, cache=False, copy=True)
    assert not np.shares_memory(c.positions, p)
    np.testing.assert_array_equal(c.positions, p)


def test_a_view_keeps_the_numbers_alive_after_the_subject_is_gone():
    p = positions()
    s = surfcap.Subject.from_arrays(FACES, p, cache=False, copy=True)
    v = s.frame(4)
    del s
    np.testing.assert_array_equal(v, p[4])


@pytest.mark.parametrize(
    "make",
    [
        lambda p: p.astype(np.float64),
        lambda p: np.asfortranarray(p),
        lambda p: np.asfortranarray(p.astype(np.float64)),
        lambda p: np.concatenate([p, p], axis=2)[:, :, ::2][:, :, :3] if False else p[:, :, [0, 1, 2]],
        lambda p: np.stack([p, p], axis=-1)[..., 0],  # strided: every other number
        lambda p: p.tolist(),
    ],
    ids=["float64", "f-order", "f-order-float64", "fancy-copy", "strided", "list"],
)
def test_every_dtype_order_and_stride_gives_the_same_subject(make):
    p = positions()
    s = surfcap.Subject.from_arrays(FACES, make(p), cache=False)
    np.testing.assert_array_equal(s.positions, p)


def test_sequences_split_the_frames_and_frames_are_named_sequence_frame():
    p = positions(5)
    s = surfcap.Subject.from_arrays(FACES, p, cache=False, sequences=[("walk", 2), ("run", 3)])
    assert s.sequences == ["walk", "run"]
    assert s.sequence_frames == {"walk": 2, "run": 3}
    assert s.resolve_frame("run:1") == 3
    assert s.frame_name(3) == "run:1"
    np.testing.assert_array_equal(s.sequence_positions("run"), p[2:])
    assert np.shares_memory(s.sequence_positions("run"), p)
    np.testing.assert_array_equal(s.positions, p)  # joined: a copy
    np.testing.assert_array_equal(s.frame("walk:1"), p[1])


def test_bad_inputs_say_what_is_wrong():
    p = positions()
    with pytest.raises(ValueError, match=r"triangle 1 has vertex index 7, expected 0 to 3"):
        surfcap.Subject.from_arrays([[0, 1, 2], [0, 2, 7]], p, cache=False)
    with pytest.raises(TypeError, match="integer"):
        surfcap.Subject.from_arrays(FACES.astype(float), p, cache=False)
    with pytest.raises(ValueError, match=r"expected \(frames, vertices, 3\)"):
        surfcap.Subject.from_arrays(FACES, p[:, :, :2], cache=False)
    with pytest.raises(ValueError, match="positions hold 5"):
        surfcap.Subject.from_arrays(FACES, p, cache=False, sequences=[("a", 2)])
    bad = p.copy()
    bad[3, 1, 2] = np.nan
    with pytest.raises(surfcap.SurfcapError, match=r"frame 3.*vertex 1|vertex 1.*frame 3"):
        surfcap.Subject.from_arrays(FACES, bad, cache=False)
    s = surfcap.Subject.from_arrays(FACES, p, cache=False, sequences=[("a", 2), ("b", 3)])
    with pytest.raises(surfcap.SurfcapError, match='no sequence "c"'):
        s.resolve_frame("c:1")
    with pytest.raises(IndexError, match="frames 0 to 4"):
        s.frame(5)
    with pytest.raises(KeyError, match="a \\(2 frames\\), b \\(3 frames\\)"):
        s.sequence_positions("c")
    with pytest.raises(surfcap.SurfcapError, match="no such file"):
        surfcap.Subject.load("/nonexistent/walk.obj")


def test_load_names_the_file_at_fault(tmp_path):
    obj = tmp_path / "bad.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(surfcap.SurfcapError) as e:
        surfcap.Subject.load(obj, fps=30, cache=False)
    assert "bad.obj" in str(e.value) and "line 4" in str(e.value) + " ".join(getattr(e.value, "causes", []))


def test_crane_loads_as_the_cli_reads_it_and_exports_the_same_bytes(crane, cli, tmp_path):
    s = surfcap.Subject.load(crane, cache=False)
    assert s.n_frames == 175 and s.sequences == ["crane"]
    assert s.positions.dtype == np.float32 and s.positions.shape == (175, s.n_vertices, 3)
    np.testing.assert_array_equal(s.positions, np.load(crane / "positions.npy"))
    ours = tmp_path / "py.glb"
    s.export(ours)
    theirs = tmp_path / "cli.glb"
    cli("export", crane, "--format", "glb", "-o", theirs)
    assert ours.read_bytes() == theirs.read_bytes()
    # A folder surfcap did not write is not replaced (a file output is, as with the CLI's -o).
    other = tmp_path / "mine"
    other.mkdir()
    (other / "notes.txt").write_text("not surfcap's")
    with pytest.raises(surfcap.SurfcapError, match="mine"):
        s.export(other, "obj")
    assert (other / "notes.txt").read_text() == "not surfcap's"


def test_save_and_load_a_subject_cache(tmp_path):
    p = positions()
    s = surfcap.Subject.from_arrays(FACES, p, cache=False, fps=24, units="cm", up_axis="+z", name="cube")
    s.save(tmp_path / "cube.subject")
    t = surfcap.Subject.load(tmp_path / "cube.subject", cache=False)
    assert (t.name, t.fps, t.units, t.up_axis) == ("cube", 24.0, "cm", "+z")
    np.testing.assert_array_equal(t.positions, p)
