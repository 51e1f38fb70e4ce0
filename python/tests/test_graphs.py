"""``surfcap.graph``: the graph over a subject's frames equal to ``surfcap graph build``'s files
(edges and weights to the bit, graph.json's numbers), for every kind, sharing the command line's
cache; its options refused with the command's messages."""

from __future__ import annotations

import json
import subprocess
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


SKIP = {"seconds", "cached", "files", "edges"}


@pytest.mark.parametrize(
    "options, flags",
    [
        ({}, []),
        ({"kind": "sparse-essential", "k": 8}, ["--kind", "sparse-essential", "--k", "8"]),
        ({"kind": "motion", "alpha": 0.1, "slope": "inf"}, ["--kind", "motion", "--alpha", "0.1", "--slope", "inf"]),
        ({"l_min": 5, "l_max": 12}, ["--l-min", "5", "--l-max", "12"]),
    ],
    ids=["essential", "sparse", "motion-inf-slope", "bounds"],
)
def test_graph_equals_graph_build_to_the_bit(walker, cli, cache_dir, tmp_path, options, flags):
    out = tmp_path / "graph"
    cli("graph", "build", walker, "-o", out, "--cache-dir", cache_dir, *flags)
    theirs = json.loads((out / "graph.json").read_text())
    # A cache of its own: the binding computes the graph itself.
    s = surfcap.Subject.load(walker, cache=False)
    g = surfcap.graph(s, **options)
    assert g["edges"].dtype == np.uint32 and g["edges"].shape == (theirs["edges"], 2)
    assert g["weights"].dtype == np.float64 and g["weights"].shape == (theirs["edges"],)
    np.testing.assert_array_equal(g["edges"], np.load(out / "edges.npy"))
    assert g["weights"].tobytes() == np.load(out / "weights.npy").tobytes()
    assert {k: v for k, v in g.items() if k not in SKIP | {"weights"}} == {
        k: v for k, v in theirs.items() if k not in SKIP
    }
    assert g["cached"] is False


def test_graph_shares_the_command_lines_cache_and_writes_its_folder(walker, cli, cache_dir, tmp_path):
    theirs = tmp_path / "cli"
    cli("graph", "build", walker, "-o", theirs, "--cache-dir", cache_dir)
    s = surfcap.Subject.load(walker, cache_dir=cache_dir)
    ours = tmp_path / "py"
    g = surfcap.graph(s, output=ours)
    assert g["cached"] is True, "the command line's cache entry is read, not recomputed"
    for f in ["edges.npy", "weights.npy"]:
        assert (ours / f).read_bytes() == (theirs / f).read_bytes(), f
    mine = json.loads((ours / "graph.json").read_text())
    assert mine["files"] == ["edges.npy", "weights.npy", "graph.json"]
    assert {k: v for k, v in mine.items() if k not in {"seconds", "cached"}} == {
        k: v for k, v in json.loads((theirs / "graph.json").read_text()).items() if k not in {"seconds", "cached"}
    }
    # A folder surfcap did not write is not replaced.
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("keep")
    with pytest.raises(surfcap.SurfcapError):
        surfcap.graph(s, output=foreign)
    assert (foreign / "notes.txt").read_text() == "keep"


def test_graph_options_are_refused_with_the_command_lines_messages(walker):
    s = surfcap.Subject.load(walker, cache=False)
    with pytest.raises(ValueError, match="expected essential, sparse-essential"):
        surfcap.graph(s, kind="dense")
    with pytest.raises(surfcap.SurfcapError, match=r"--k 5: only with --kind sparse-essential \(the graph is essential\)"):
        surfcap.graph(s, k=5)
    with pytest.raises(surfcap.SurfcapError, match="the graph kind already says k = 8"):
        surfcap.graph(s, kind="sparse-essential:8", k=9)
    with pytest.raises(ValueError, match="k 0: expected a whole number >= 1"):
        surfcap.graph(s, kind="sparse-essential", k=0)
    with pytest.raises(ValueError, match="slope 0: expected a whole number >= 1 or inf"):
        surfcap.graph(s, slope=0)
    with pytest.raises(ValueError, match="alpha"):
        surfcap.graph(s, alpha=-1.0)
    with pytest.raises(surfcap.SurfcapError, match=r"segment lengths 20\.\.10: expected 1 <= l-min <= l-max"):
        surfcap.graph(s, l_min=20, l_max=10)
