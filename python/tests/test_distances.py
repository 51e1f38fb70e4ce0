"""Pose distances and interpolation from Python equal the command line's: the distance matrix of
every metric to the bit and from the same cache file as ``surfcap distance``, one distance
alone equal to its matrix entry, and ``interpolate`` writing the same files as ``surfcap
interpolate``. Run on the first frames of the real crane, saved as a subject cache that both
read."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import surfcap

FRAMES = 40


@pytest.fixture(scope="session")
def crane_part(crane: Path, tmp_path_factory) -> Path:
    """The crane's first FRAMES frames as a subject cache (the same input for both sides)."""
    full = surfcap.Subject.load(crane, cache=False)
    part = surfcap.Subject.from_arrays(
        full.faces,
        full.positions[:FRAMES],
        fps=full.fps,
        name=full.name,
        up_axis=full.up_axis,
        units=full.units,
        copy=True,
        cache=False,
    )
    path = tmp_path_factory.mktemp("crane") / "crane.subject"
    part.save(path)
    return path


def files_of(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize(
    "metric,w", [("deformation", 0.01), ("deformation-log", 0.01), ("euclidean", 0.01), ("deformation", 0.5)]
)
def test_pose_distances_equal_the_cli_npy_to_the_bit_and_share_its_cache_file(crane_part, cli, cache_dir, tmp_path, metric, w):
    s = surfcap.Subject.load(crane_part, cache_dir=cache_dir)
    d = surfcap.pose_distances(s, metric=metric, w=w)
    assert d.dtype == np.float64 and d.shape == (FRAMES, FRAMES)
    # The CLI computing on its own (a fresh cache) gives the same bits...
    alone = tmp_path / "alone.npy"
    cli("distance", crane_part, "--metric", metric, "--w", w, "-o", alone, "--cache-dir", tmp_path / "fresh")
    theirs = np.load(alone)
    assert theirs.dtype == np.float64
    assert d.tobytes() == theirs.tobytes()
    # ...and in the binding's cache folder it reads the file the binding wrote.
    shared = tmp_path / "shared.npy"
    r = cli("distance", crane_part, "--metric", metric, "--w", w, "-o", shared, "--cache-dir", cache_dir, json_out=True)
    assert r["cached"] is True
    assert Path(r["cache_file"]).parent == cache_dir
    assert np.load(shared).tobytes() == d.tobytes()


def test_the_binding_reads_the_matrix_the_cli_cached(crane_part, cli, cache_dir, tmp_path):
    cli("distance", crane_part, "-o", tmp_path / "d.npy", "--cache-dir", cache_dir)
    files = sorted(p.name for p in cache_dir.iterdir())
    s = surfcap.Subject.load(crane_part, cache_dir=cache_dir)
    d = surfcap.pose_distances(s)
    assert sorted(p.name for p in cache_dir.iterdir()) == files, "nothing new computed or written"
    assert d.tobytes() == np.load(tmp_path / "d.npy").tobytes()


def test_the_matrix_is_a_read_only_view_of_the_pipelines_matrix(crane_part):
    s = surfcap.Subject.load(crane_part, cache=False)
    a = surfcap.pose_distances(s, metric="euclidean")
    b = surfcap.pose_distances(s, metric="euclidean")
    assert np.shares_memory(a, b), "asked twice, the matrix is made once"
    assert not a.flags.writeable
    with pytest.raises(ValueError):
        a[0, 1] = 1.0
    del s
    assert np.isfinite(a).all() and (np.diag(a) == 0).all()


@pytest.mark.parametrize("metric", ["deformation", "deformation-log", "euclidean"])
def test_one_pose_distance_is_its_matrix_entry_to_the_bit(crane_part, metric):
    pairs = [(3, 17), (17, 3), (0, 39), ("crane:12", "crane:5"), (8, 8)]
    fresh = surfcap.Subject.load(crane_part, cache=False)
    alone = [surfcap.pose_distance(fresh, a, b, metric=metric) for a, b in pairs]
    d = surfcap.pose_distances(fresh, metric=metric)
    for (a, b), x in zip(pairs, alone):
        i, j = fresh.resolve_frame(a), fresh.resolve_frame(b)
        assert x == d[i, j] and np.float64(x).tobytes() == d[i, j].tobytes(), (a, b)
        # With the matrix at hand it is read from it: the same number.
        assert surfcap.pose_distance(fresh, a, b, metric=metric) == x
    assert alone[-1] == 0.0


@pytest.mark.parametrize(
    "method,stretch", [("nonlinear", "linear"), ("nonlinear", "log"), ("linear", "linear")]
)
def test_interpolate_writes_what_the_cli_writes(crane_part, cli, tmp_path, method, stretch):
    s = surfcap.Subject.load(crane_part, cache=False)
    out = surfcap.interpolate(s, "crane:4", 30, steps=6, method=method, stretch=stretch)
    assert isinstance(out, surfcap.Subject)
    assert out.positions.shape == (6, s.n_vertices, 3) and out.positions.dtype == np.float32
    assert out.sequences == ["crane_4_to_30"]
    np.testing.assert_array_equal(out.faces, s.faces)
    np.testing.assert_array_equal(out.frame(0), s.frame("crane:4"))
    ours = tmp_path / "py"
    out.export(ours, "npy")
    theirs = tmp_path / "cli"
    cli(
        "interpolate", crane_part, "--from", "crane:4", "--to", "30", "--steps", "6",
        "--method", method, "--stretch", stretch, "--format", "npy", "-o", theirs,
    )
    assert files_of(ours) == files_of(theirs)
    # output= writes the same as the command.
    written = tmp_path / "written"
    surfcap.interpolate(s, "crane:4", 30, steps=6, method=method, stretch=stretch, output=written, format="npy")
    assert files_of(written) == files_of(theirs)


def test_bad_arguments_name_the_argument(crane_part, cli, tmp_path):
    s = surfcap.Subject.load(crane_part, cache=False)
    with pytest.raises(ValueError, match=r'^metric: "cosine": expected deformation, deformation-log, deformation-literal or euclidean$'):
        surfcap.pose_distances(s, metric="cosine")
    with pytest.raises(ValueError, match=r"^w -1: expected a finite number >= 0$"):
        surfcap.pose_distances(s, w=-1.0)
    with pytest.raises(ValueError, match=r"^w NaN: expected a finite number >= 0$"):
        surfcap.pose_distance(s, 0, 1, w=float("nan"))
    with pytest.raises(IndexError, match="frame 40: the subject has frames 0 to 39"):
        surfcap.pose_distance(s, 0, 40)
    with pytest.raises(surfcap.SurfcapError, match='no sequence "walk"'):
        surfcap.pose_distance(s, "walk:1", 0)
    with pytest.raises(ValueError, match=r"^steps 1: expected a whole number >= 2$"):
        surfcap.interpolate(s, 0, 1, steps=1)
    with pytest.raises(ValueError, match=r'^method: "cubic": expected nonlinear or linear$'):
        surfcap.interpolate(s, 0, 1, method="cubic")
    with pytest.raises(ValueError, match=r'^stretch: "exp": expected linear or log$'):
        surfcap.interpolate(s, 0, 1, stretch="exp")
    # The command refuses the same values with the same words.
    p = cli("interpolate", crane_part, "--from", "0", "--to", "1", "--method", "cubic", "-o", tmp_path / "x.glb", check=False)
    assert p.returncode != 0 and '"cubic": expected nonlinear or linear' in p.stderr
    p = cli("distance", crane_part, "--metric", "cosine", "-o", tmp_path / "d.npy", check=False)
    assert p.returncode != 0 and '"cosine": expected deformation, deformation-log, deformation-literal or euclidean' in p.stderr
