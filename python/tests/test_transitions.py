"""Transitions from Python equal the command line's: one transition's animation and report as
``surfcap transition`` writes them, the transition table as ``surfcap transitions`` writes its
``.npy`` files (from the same cache file), and Fig. 2.15's costs as ``surfcap eval transitions``
reports them. Run on the first frames of the real crane, saved as a subject cache that both
read."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import surfcap

from test_distances import FRAMES, crane_part  # noqa: F401  (the shared fixture)


@pytest.mark.parametrize("slope,args", [(3, []), ("inf", ["--slope", "inf", "--l-min", "3", "--l-max", "8"])])
def test_transition_table_equals_the_cli_npy_and_shares_its_cache_file(crane_part, cli, cache_dir, tmp_path, slope, args):
    s = surfcap.Subject.load(crane_part, cache_dir=cache_dir)
    kw = {} if not args else {"slope": slope, "l_min": 3, "l_max": 8}
    t = surfcap.transition_table(s, **kw)
    r = cli("transitions", crane_part, *args, "-o", tmp_path / "table", "--cache-dir", cache_dir, json_out=True)
    assert r["cached"] is True, "the command read the table the binding computed"
    assert (t["l_min"], t["l_max"]) == (r["l_min"], r["l_max"])
    assert t["slope"] == r["slope"] == (None if slope == "inf" else 3)
    for name, dtype in [("D", np.float64), ("L", np.uint32), ("li", np.uint32), ("lj", np.uint32)]:
        theirs = np.load(tmp_path / "table" / f"{name}.npy")
        assert t[name].dtype == dtype == theirs.dtype, name
        assert t[name].shape == (FRAMES, FRAMES)
        assert t[name].tobytes() == theirs.tobytes(), name
        assert not t[name].flags.writeable
    # The command computing on its own gives the same numbers.
    cli("transitions", crane_part, *args, "-o", tmp_path / "alone", "--cache-dir", tmp_path / "fresh")
    assert np.load(tmp_path / "alone" / "D.npy").tobytes() == t["D"].tobytes()
    assert np.isinf(t["D"]).any() and np.isfinite(t["D"]).any()


def test_one_transition_equals_the_clis_animation_and_report(crane_part, cli, cache_dir, tmp_path):
    s = surfcap.Subject.load(crane_part, cache_dir=cache_dir)
    anim, report = surfcap.transition(s, "crane:2", 33, l_min=4, l_max=10)
    assert isinstance(anim, surfcap.Subject) and isinstance(report, surfcap.reports.TransitionReport)
    assert anim.sequences == ["crane_2_to_33"]
    assert anim.positions.shape == (report.duration, s.n_vertices, 3)
    assert report["from"] == 2 and report.to == 33 and report.slope == 3
    assert report.warp[0][0] == 2 and report.warp[-1][1] == 33
    table = surfcap.transition_table(s, l_min=4, l_max=10)
    assert report.table_cost == table["D"][2, 33]
    assert (report.source_length, report.destination_length, report.duration) == (
        table["li"][2, 33], table["lj"][2, 33], table["L"][2, 33])
    ours = tmp_path / "py.glb"
    anim.export(ours)
    theirs = tmp_path / "cli.glb"
    cli("transition", crane_part, "--from", "crane:2", "--to", "33", "--l-min", "4", "--l-max", "10",
        "-o", theirs, "--cache-dir", cache_dir)
    assert ours.read_bytes() == theirs.read_bytes()
    written = json.loads(theirs.with_suffix(".transition.json").read_text())
    # (The file also says it is surfcap's report, so that a later run may replace it.)
    assert (written.pop("written_by"), written.pop("output_kind")) == ("surfcap", "report")
    ours_report = report.to_dict()
    for r in (written, ours_report):
        del r["blend_seconds"]
    assert ours_report == written


def test_transition_costs_equal_eval_transitions(crane_part, cli, cache_dir, tmp_path):
    s = surfcap.Subject.load(crane_part, cache_dir=cache_dir)
    r = surfcap.transition_costs(s, slopes=[2, 3], plot_pairs=30)
    assert isinstance(r, surfcap.reports.TransitionCostsReport)
    cli("eval", "transitions", crane_part, "--slopes", "2,3", "--plot-pairs", "30", "-o", tmp_path / "ev",
        "--cache-dir", cache_dir)
    written = json.loads((tmp_path / "ev" / "transitions.json").read_text())
    written.pop("plots")
    ours = r.to_dict()
    ours.pop("plot")
    assert ours == written
    assert [row.slope for row in r.rows] == [2, 3]
    c = r.curves()
    n = len(r.plot.sample)
    assert 0 < n <= 30
    assert c["standard"].shape == c["dtw_vls"].shape == c["duration"].shape == (n,)
    assert c["standard"].dtype == np.float64 and c["duration"].dtype == np.uint32
    assert c["fixed_length"] == r.fixed_length
    # Variable lengths and warping never cost more than the standard transition on average.
    assert r.rows[1].dtw_vls.mean <= r.rows[1].standard.mean
    assert r.plot.slope == 3


def test_bad_arguments_name_the_argument_and_match_the_cli(crane_part, cli, tmp_path):
    s = surfcap.Subject.load(crane_part, cache=False)
    with pytest.raises(ValueError, match=r"^slope: 0: expected a whole number >= 1 or inf$"):
        surfcap.transition_table(s, slope=0)
    with pytest.raises(ValueError, match=r"^slope: 'steep': expected a whole number >= 1 or inf$"):
        surfcap.transition(s, 0, 20, slope="steep")
    with pytest.raises(ValueError, match=r"^l_min 0: expected a whole number >= 1$"):
        surfcap.transition_table(s, l_min=0)
    with pytest.raises(ValueError, match=r"^segment lengths 9\.\.4: expected 1 <= l-min <= l-max$"):
        surfcap.transition_table(s, l_min=9, l_max=4)
    with pytest.raises(IndexError, match="frame 41"):
        surfcap.transition(s, 41, 0)
    with pytest.raises(ValueError, match=r"^slopes \[0\]: expected whole numbers >= 1$"):
        surfcap.transition_costs(s, slopes=[0])
    with pytest.raises(ValueError, match="dtw_first_step"):
        surfcap.transition_costs(s, dtw_first_step="diagonal")
    # No room for a source segment after the last frame: the command's message.
    with pytest.raises(surfcap.SurfcapError) as e:
        surfcap.transition(s, "crane:39", 5, l_min=4, l_max=10)
    p = cli("transition", crane_part, "--from", "crane:39", "--to", "5", "--l-min", "4", "--l-max", "10",
            "-o", tmp_path / "t.glb", "--cache-dir", tmp_path / "c", check=False)
    assert p.returncode != 0
    assert str(e.value).startswith("no transition from crane:39 to 5: the source needs 4 frames")
    assert str(e.value) in p.stderr
    p = cli("transitions", crane_part, "--l-min", "9", "--l-max", "4", "-o", tmp_path / "t",
            "--cache-dir", tmp_path / "c", check=False)
    assert p.returncode != 0 and "segment lengths 9..4: expected 1 <= l-min <= l-max" in p.stderr
