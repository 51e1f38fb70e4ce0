"""The surface motion graph (Huang et al. 2009) from Python: ``smg_query`` on a subject and on a
frame set gives the animation ``surfcap smg query`` writes, to the bit; ``smg_build`` gives the
similarity matrix the command caches; a missed constraint warns; bad arguments are named."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import surfcap

CONNECT = "horse_gallop:horse_gallop"
# 16 frames at 10 fps with a self-transition: 4 s needs the loop (as the command's test asks).
QUERY = dict(from_="horse_gallop:0", to="horse_gallop:15", time=4.0, distance=0.0, distance_weight=0.0001,
             windows="3-4", tolerance=1000.0)


def cli_query(cli, source: Path, out: Path, cache: Path, *extra: str, time: str = "4"):
    return cli("smg", "query", source, "--connect", CONNECT, "--from", "horse_gallop:0", "--to", "horse_gallop:15",
               "--time", time, "--distance", "0", "--distance-weight", "0.0001", "--windows", "3-4",
               "--cache-dir", cache, "-o", out, *extra)


def report_of(out: Path) -> dict:
    return json.loads(out.with_name(out.stem + ".report.json").read_text())


def same_files(a: Path, b: Path):
    """Every file under folder `a` has the same bytes under folder `b`, and they hold the same
    names."""
    names = sorted(str(p.relative_to(a)) for p in a.rglob("*") if p.is_file())
    assert names and names == sorted(str(p.relative_to(b)) for p in b.rglob("*") if p.is_file())
    for n in names:
        assert (a / n).read_bytes() == (b / n).read_bytes(), n


# The report's fields that do not depend on how long a run took or where it wrote.
STABLE = ["engine", "fps", "from", "to", "connections", "frames", "distance", "unit", "transition_cost", "cost",
          "path", "loops", "graph", "ilp_solves", "constraints", "target_distance", "target_seconds", "seconds",
          "transition_frames", "tolerance", "within_tolerance", "unreachable", "unconverged_subproblems",
          "loop_rule", "excluded_loops"]


@pytest.fixture
def horse(data: Path) -> Path:
    return data / "threejs_morph_animals" / "horse_gallop"


def test_a_query_on_a_subject_plays_the_commands_animation_to_the_bit(cli, horse, tmp_path, cache_dir):
    cli_out = tmp_path / "cli"
    cli_query(cli, horse, cli_out, cache_dir, "--tolerance", "1000", "--format", "npy")
    subject = surfcap.Subject.load(horse, cache=False)
    anim, report = surfcap.smg_query(subject, connect=CONNECT, **QUERY)
    assert isinstance(anim, surfcap.Subject) and isinstance(report, surfcap.reports.SmgQueryReport)
    assert anim.sequences == ["smg"] and anim.n_frames == report.frames
    py_out = tmp_path / "py"
    anim.export(py_out, "npy")
    same_files(cli_out, py_out)
    want = report_of(cli_out)
    got = report.to_dict()
    for k in STABLE:
        assert got[k] == want[k], k
    assert len(report.path) >= 2, "the loop was taken"
    assert report.outputs == []
    # output= writes what the command writes, the same bytes.
    again = tmp_path / "again"
    _, r = surfcap.smg_query(subject, connect=[CONNECT], output=again, format="npy", **QUERY)
    same_files(cli_out, again)
    assert report_of(again)["frames"] == want["frames"] and r.outputs == [str(again)]


def test_a_query_on_a_frame_set_plays_a_frame_set_equal_to_the_commands(cli, horse, tmp_path, cache_dir):
    frames = tmp_path / "horse.frames"
    cli("--quiet", "remesh-frames", horse, "--seed", "2", "-o", frames)
    cli_out = tmp_path / "cli.frames"
    cli_query(cli, frames, cli_out, cache_dir, "--tolerance", "1000")
    want = surfcap.FrameSet.load(cli_out, cache=False)
    fs = surfcap.FrameSet.load(frames, cache=False)
    assert len(set(fs.vertex_counts)) > 1, "frames keep their own meshes"
    anim, report = surfcap.smg_query(fs, connect=CONNECT, **QUERY)
    assert isinstance(anim, surfcap.FrameSet)
    assert anim.n_frames == want.n_frames == report.frames
    for f in range(anim.n_frames):
        (p, t), (wp, wt) = anim.frame(f), want.frame(f)
        assert p.dtype == np.float32 and t.dtype == np.uint32
        np.testing.assert_array_equal(p.view(np.uint32), wp.view(np.uint32))
        np.testing.assert_array_equal(t, wt)
    w = report_of(cli_out)
    for k in ["frames", "distance", "path", "transition_frames", "cost"]:
        assert report.to_dict()[k] == w[k], k


def test_build_returns_the_similarity_the_command_caches_to_the_bit(cli, horse, tmp_path, cache_dir):
    graph = tmp_path / "graph.json"
    cli("smg", "build", horse, "--connect", CONNECT, "--keys", "horse_gallop:0,horse_gallop:15", "--windows", "3-4",
        "--cache-dir", cache_dir, "-o", graph)
    cached = list(cache_dir.glob("smg-similarity-*.npy"))
    assert len(cached) == 1, cached
    subject = surfcap.Subject.load(horse, cache=False)
    sim, report = surfcap.smg_build(subject, connect=CONNECT, keys=["horse_gallop:0", "horse_gallop:15"],
                                    windows="3-4")
    assert sim.shape == (16, 16) and sim.dtype == np.float64
    np.testing.assert_array_equal(sim.view(np.uint64), np.load(cached[0]).view(np.uint64))
    want = json.loads(graph.read_text())
    for k in ["frames", "sequences", "connections", "key_frames", "nodes", "edges", "transitions",
              "missing_transitions"]:
        assert report.to_dict()[k] == want[k], k
    assert report.similarity_cached is False
    # A subject cached in the command's folder reads the command's matrix back.
    shared = surfcap.Subject.load(horse, cache_dir=cache_dir)
    sim2, r2 = surfcap.smg_build(shared, connect=CONNECT, windows="3-4", output=tmp_path / "g.json")
    assert r2.similarity_cached is True
    np.testing.assert_array_equal(sim2, sim)
    assert json.loads((tmp_path / "g.json").read_text())["nodes"] == r2.nodes


def test_a_missed_time_warns_and_reports_it(horse):
    subject = surfcap.Subject.load(horse, cache=False)
    q = dict(QUERY, time=4.5)  # 45 frames: the gallop's loop cannot meet it exactly
    del q["tolerance"]
    with pytest.warns(surfcap.ConstraintsMissedWarning, match="constraint time missed"):
        _, report = surfcap.smg_query(subject, connect=CONNECT, frame_tolerance=0, **q)
    missed = [c.name for c in report.constraints if c.missed]
    assert "time" in missed
    # Within the tolerance: no warning.
    with warnings.catch_warnings():
        warnings.simplefilter("error", surfcap.ConstraintsMissedWarning)
        surfcap.smg_query(subject, connect=CONNECT, **QUERY)


def test_frame_sets_from_arrays_keep_each_frames_mesh():
    rng = np.random.default_rng(1)
    tri = np.array([[0, 1, 2]])
    quad = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
    pos = [rng.random((3, 3)), rng.random((4, 3)).astype(np.float32), np.asfortranarray(rng.random((4, 3)))]
    fs = surfcap.FrameSet.from_arrays(pos, [tri, quad, quad], fps=10, sequences=[("a", 1), ("b", 2)], cache=False)
    assert (fs.n_frames, fs.sequences, fs.vertex_counts) == (3, ["a", "b"], [3, 4, 4])
    p, t = fs.frame("b:1")
    np.testing.assert_array_equal(p, pos[2].astype(np.float32))
    assert t.dtype == np.uint32 and not p.flags.writeable
    assert fs.frame_name(2) == "b:1" and fs.resolve_frame("b:0") == 1
    with pytest.raises(ValueError, match=r"faces\[1\]: triangle 1 has vertex index 3"):
        surfcap.FrameSet.from_arrays([pos[0], pos[0]], [tri, quad], cache=False)
    with pytest.raises(ValueError, match="faces: 1 arrays for 2 frames"):
        surfcap.FrameSet.from_arrays(pos[:2], [tri], cache=False)
    with pytest.raises(ValueError, match="sequences: 5 frames in all"):
        surfcap.FrameSet.from_arrays(pos, [tri, quad, quad], sequences=[("a", 5)], cache=False)


def test_bad_arguments_are_named(horse, tmp_path):
    subject = surfcap.Subject.load(horse, cache=False)
    with pytest.raises(TypeError, match="input: expected a Subject or a FrameSet"):
        surfcap.smg_query(str(horse), connect=CONNECT, **QUERY)
    with pytest.raises(surfcap.SurfcapError, match='--connect: no sequence "nope"'):
        surfcap.smg_query(subject, connect="nope:horse_gallop", **QUERY)
    with pytest.raises(surfcap.SurfcapError, match="--windows"):
        surfcap.smg_query(subject, connect=CONNECT, **dict(QUERY, windows="1-4"))
    with pytest.raises(surfcap.SurfcapError, match="--to"):
        surfcap.smg_query(subject, connect=CONNECT, **dict(QUERY, to="horse_gallop:16"))
    with pytest.raises(ValueError, match="time: 0"):
        surfcap.smg_query(subject, connect=CONNECT, **dict(QUERY, time=0.0))
    with pytest.raises(ValueError, match="resolution: 4"):
        surfcap.smg_build(subject, connect=CONNECT, resolution=4)
    with pytest.raises(ValueError, match="format: given without output"):
        surfcap.smg_query(subject, connect=CONNECT, format="npy", **QUERY)
    with pytest.raises(ValueError, match="reads as a subject"):
        surfcap.FrameSet.load(horse)
