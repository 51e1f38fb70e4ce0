"""Path, key-pose and reach synthesis from Python: the walk, the positions and the report's
numbers equal ``surfcap synth path | keyposes | reach``'s on the same inputs (positions to the
bit through the npy export); a prepared subject answers several queries; ``output=`` writes what
the command writes; a missed constraint warns; bad arguments are refused by name."""

from __future__ import annotations

import json
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest

import surfcap


@pytest.fixture(scope="session")
def walker(surfcap_bin: Path, tmp_path_factory) -> Path:
    """The procedural walker of the CLI tests: walk and jog clips of 2 s, 1,000 vertices."""
    out = tmp_path_factory.mktemp("walker") / "walker.subject"
    args = ["make", "mannequin", "--procedural", "walk,jog", "--duration", "2", "--vertices", "1000", "-o", out, "--quiet"]
    subprocess.run([str(surfcap_bin), *map(str, args)], check=True, capture_output=True)
    return out


# The fields that time the run or name its files: everything else must be equal.
TIMES = {"seconds", "prepare_seconds", "blend_seconds", "search_seconds", "outputs"}


def numbers(report: dict) -> dict:
    """A report without its timings and file names (nested ones too)."""
    if isinstance(report, dict):
        return {k: numbers(v) for k, v in report.items() if k not in TIMES | {"written_by", "output_kind"}}
    if isinstance(report, list):
        return [numbers(v) for v in report]
    return report


def same_npy_folders(ours: Path, theirs: Path) -> None:
    """The same files with the same bytes (the npy export: meta.json, <sequence>/positions.npy and
    template.obj), surfcap's hidden output marker aside."""

    def files(d: Path) -> list:
        return sorted(str(p.relative_to(d)) for p in d.rglob("*") if p.is_file() and not p.name.startswith("."))

    names = files(theirs)
    assert "path/positions.npy" in names or any(n.endswith("positions.npy") for n in names), names
    assert names == files(ours)
    for n in names:
        assert (ours / n).read_bytes() == (theirs / n).read_bytes(), n


def cli_synth(cli, *args) -> dict:
    """Runs ``surfcap --json synth ...`` (a missed constraint is not a failure without --strict)."""
    return cli("synth", *args, json_out=True)


@pytest.fixture
def line(tmp_path) -> Path:
    f = tmp_path / "line.csv"
    f.write_text("# 5 m on the ground\n0,0\n5,0\n")
    return f


def test_path_equals_synth_path_walk_positions_and_report(walker, cli, cache_dir, line, tmp_path):
    theirs = tmp_path / "cli"
    r = cli_synth(cli, "path", walker, "--curve", line, "-o", theirs, "--format", "npy", "--cache-dir", cache_dir)
    s = surfcap.Subject.load(walker, cache_dir=cache_dir)
    anim, report = surfcap.synth_path(s, line)
    assert isinstance(report, surfcap.reports.PathReport)
    assert report.walk == r["walk"] and len(report.walk) > 10
    assert anim.sequences == ["path"] and anim.n_frames == r["frames"] == report.frames
    assert anim.positions.dtype == np.float32 and anim.positions.shape == (r["frames"], s.n_vertices, 3)
    assert numbers(report.to_dict()) == numbers(r)
    assert report.outputs == [], "nothing written without output="
    ours = tmp_path / "py"
    anim.export(ours, "npy")
    same_npy_folders(ours, theirs)


def test_a_prepared_subject_answers_several_queries_with_an_array_curve(walker, cli, cache_dir, line, tmp_path):
    s = surfcap.Subject.load(walker, cache_dir=cache_dir)
    syn = surfcap.prepare(s)
    assert syn.kind == "essential" and syn.n_edges > 0 and syn.subject.name == s.name
    from_file, r1 = syn.path(line)
    curve = np.array([[0.0, 0.0], [5.0, 0.0]])
    for c in [curve, curve.astype(np.float32), np.asfortranarray(curve)]:
        from_array, r2 = syn.path(c)
        assert r2.walk == r1.walk and r2.mean_error == r1.mean_error
        np.testing.assert_array_equal(from_array.positions, from_file.positions)
    # Another query on the same graph, the same numbers as the command line's.
    theirs = tmp_path / "cli"
    r = cli_synth(
        cli, "path", walker, "--curve", line, "--start", "walk:10", "--window", "2", "-o", theirs, "--format", "npy",
        "--cache-dir", cache_dir,
    )
    anim, report = syn.path(curve, start="walk:10", window=2.0)
    assert report.walk == r["walk"] and numbers(report.to_dict()) == numbers(r)
    anim.export(tmp_path / "py", "npy")
    same_npy_folders(tmp_path / "py", theirs)


def test_output_writes_what_synth_path_writes(walker, cli, cache_dir, line, tmp_path):
    theirs = tmp_path / "cli"
    cli("synth", "path", walker, "--curve", line, "-o", theirs, "--format", "npy", "--cache-dir", cache_dir)
    s = surfcap.Subject.load(walker, cache_dir=cache_dir)
    ours = tmp_path / "py"
    _, report = surfcap.prepare(s).path(line, output=ours, format="npy")
    same_npy_folders(ours, theirs)
    written = json.loads((tmp_path / "py.report.json").read_text())
    assert numbers(written) == numbers(json.loads((tmp_path / "cli.report.json").read_text()))
    assert numbers(written) == numbers(report.to_dict())
    assert [Path(p).name for p in report.outputs] == [Path(p).name for p in written["outputs"]]


def test_keyposes_equal_synth_keyposes_from_a_file_and_from_a_list(walker, cli, cache_dir, tmp_path):
    keys = tmp_path / "keys.csv"
    keys.write_text("frame,time\nwalk:0,0\njog:10,40\nwalk:30,3s\n")
    theirs = tmp_path / "cli"
    r = cli_synth(cli, "keyposes", walker, "--keys", keys, "-o", theirs, "--format", "npy", "--cache-dir", cache_dir)
    s = surfcap.Subject.load(walker, cache_dir=cache_dir)
    anim, report = surfcap.synth_keyposes(s, keys)
    assert report.walk == r["walk"] and numbers(report.to_dict()) == numbers(r)
    anim.export(tmp_path / "py", "npy")
    same_npy_folders(tmp_path / "py", theirs)
    # The same keys as a list: seconds as numbers, frames as in the file, frames by global index.
    jog10 = s.resolve_frame("jog:10")
    _, listed = surfcap.prepare(s).keyposes([("walk:0", 0), (jog10, "40"), ("walk:30", 3.0)])
    assert listed.walk == r["walk"]
    assert [k.obtained_time for k in listed.keys] == [k["obtained_time"] for k in r["keys"]]


def test_reach_equals_synth_reach(walker, cli, cache_dir, tmp_path):
    theirs = tmp_path / "cli"
    r = cli_synth(
        cli, "reach", walker, "--from", "walk:0", "--to", "jog:20", "--distance", "3", "--time", "3", "-o", theirs,
        "--format", "npy", "--cache-dir", cache_dir,
    )
    s = surfcap.Subject.load(walker, cache_dir=cache_dir)
    anim, report = surfcap.synth_reach(s, "walk:0", "jog:20", 3.0, 3)
    assert report.walk == r["walk"] and numbers(report.to_dict()) == numbers(r)
    anim.export(tmp_path / "py", "npy")
    same_npy_folders(tmp_path / "py", theirs)
    # Frames as global indices, the time as frames shown: the same query.
    frames = round(3 * s.fps)
    _, again = surfcap.prepare(s).reach(0, s.resolve_frame("jog:20"), 3.0, f"{frames}f")
    assert again.walk == r["walk"] and again.obtained_frames == r["obtained_frames"]


def test_a_missed_constraint_warns_and_the_report_says_it(walker, cache_dir, line):
    s = surfcap.Subject.load(walker, cache_dir=cache_dir)
    with pytest.warns(surfcap.ConstraintsMissedWarning, match="constraint path missed"):
        _, report = surfcap.synth_path(s, line, tolerance=0.0)
    assert report.constraints[0].missed is True and report.constraints[0].tolerance == 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, report = surfcap.synth_path(s, line, tolerance=100.0)
    assert report.constraints[0].missed is False


def test_bad_arguments_are_refused_by_name(walker, tmp_path, line):
    s = surfcap.Subject.load(walker, cache=False)
    with pytest.raises(ValueError, match=r"curve: shape \[2, 4\], expected \(points, 2\)"):
        surfcap.synth_path(s, np.zeros((2, 4)))
    with pytest.raises(surfcap.SurfcapError, match="curve: point 1: NaN is not a finite number"):
        surfcap.synth_path(s, np.array([[0.0, 0.0], [np.nan, 1.0]]))
    with pytest.raises(surfcap.SurfcapError, match="missing.csv: cannot read: No such file"):
        surfcap.synth_path(s, tmp_path / "missing.csv")
    with pytest.raises(ValueError, match="branching 0: expected a whole number >= 1"):
        surfcap.synth_path(s, line, branching=0)
    with pytest.raises(ValueError, match="window -1: expected a finite number > 0"):
        surfcap.synth_path(s, line, window=-1.0)
    with pytest.raises(ValueError, match="tolerance -1: expected a finite number >= 0"):
        surfcap.synth_path(s, line, tolerance=-1.0)
    with pytest.raises(surfcap.SurfcapError, match='--tags "fly:0-2"'):
        surfcap.synth_path(s, line, tags=["fly:0-2"])
    with pytest.raises(surfcap.SurfcapError, match='no sequence "swim"'):
        surfcap.synth_path(s, line, start="swim:3")
    with pytest.raises(surfcap.SurfcapError, match=rf"--track 5000: the subject has vertices 0 to {s.n_vertices - 1}"):
        surfcap.prepare(s, track=[5000])
    with pytest.raises(surfcap.SurfcapError, match=r"keys:2: time 0 is not after the previous key's 5"):
        surfcap.synth_keyposes(s, [("walk:0", "5"), ("walk:3", "0")])
    with pytest.raises(TypeError, match=r"keys: expected a key file or a list of \(frame, time\) pairs"):
        surfcap.synth_keyposes(s, 3)
    with pytest.raises(ValueError, match=r"time -3: expected a duration > 0"):
        surfcap.synth_reach(s, 0, 10, 1.0, "-3")
    with pytest.raises(ValueError, match="distance -1: expected a finite number >= 0"):
        surfcap.synth_reach(s, 0, 10, -1.0, 2)
    with pytest.raises(surfcap.SurfcapError, match=r"--time 1f: expected a duration of at least two frames"):
        surfcap.synth_reach(s, 0, 10, 1.0, "1f")
    with pytest.raises(ValueError, match="format: only with output"):
        surfcap.synth_path(s, line, format="npy")
