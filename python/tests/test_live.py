"""The interactive controller's live session from Python (``surfcap play``'s player without the
page): a host steps it under its own input, gets the frames that fall due with their placement
and the transitions chosen, fetches each transition's blended frames as positions (whole, or
from a frame on), and restarts it; bad arguments are refused by name."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

import surfcap


@pytest.fixture(scope="module")
def walker(surfcap_bin: Path, tmp_path_factory) -> Path:
    """The procedural mannequin walking, jogging, turning and standing, 2 s clips, 1,000 vertices."""
    out = tmp_path_factory.mktemp("live") / "walker.subject"
    args = ["make", "mannequin", "--procedural", "walk,jog,turn_left,idle", "--duration", "2", "--vertices", "1000"]
    subprocess.run([str(surfcap_bin), *args, "-o", str(out), "--quiet"], check=True, capture_output=True)
    return out


def test_a_live_session_steps_blends_and_restarts(walker, cache_dir):
    subject = surfcap.Subject.load(walker, cache_dir=cache_dir)
    session = surfcap.prepare(subject).live()
    info = session.info
    assert info["subject"] == subject.name and info["frames"] == len(subject)
    assert info["stream"]["bits"] == 16
    assert session.captured_stream()[:6] == b"SCSTRM"
    frames, blends = [], []
    for k in range(360):
        out = session.step((1.0, 0.0) if k < 180 else (0.0, 1.0), dt=1 / 60)
        frames += out["frames"]
        blends += [b["id"] for b in out["blends"]]
    assert abs(len(frames) - 180) <= 1, f"{len(frames)} frames in 6 s at 30 fps"
    assert all(("frame" in f) != ("blend" in f) and "theta" in f for f in frames)
    assert blends, "a quarter turn chose no transition"
    n = subject.n_vertices
    for b in sorted(set(blends)):
        whole = session.blend(b)
        assert whole.dtype == np.float32 and whole.ndim == 3 and whole.shape[1:] == (n, 3)
        piece, total = session.blend_from(b, 1)
        assert total == whole.shape[0] and piece.shape == (total - 1, n, 3)
        # Each stream is quantised on its own bounds (16 bits).
        assert np.abs(piece - whole[1:]).max() < 1e-3
    assert session.info["blends_made"]["count"] == len(set(blends))
    session.restart()
    again = session.step((0.0, 0.0))
    assert all(f.get("frame", info["start"]["frame"]) == info["start"]["frame"] for f in again["frames"])


def test_bad_arguments_are_refused_by_name(walker, cache_dir):
    prep = surfcap.prepare(surfcap.Subject.load(walker, cache_dir=cache_dir))
    with pytest.raises(surfcap.SurfcapError, match=r"20 bits per coordinate: expected 8 to 16"):
        prep.live(bits=20)
    session = prep.live(bits=8)
    with pytest.raises(ValueError, match=r"dt 5: expected seconds from 0 to 1"):
        session.step((1.0, 0.0), dt=5.0)
    with pytest.raises(ValueError, match=r"expected two finite numbers"):
        session.step((float("nan"), 0.0))
    with pytest.raises(RuntimeError, match=r"no blend 99"):
        session.blend(99)
