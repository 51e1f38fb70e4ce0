"""What a long call costs the rest of the program: no copy of a large position array (measured
with the process's peak resident memory, which sees Rust's allocations, and tracemalloc, which
sees numpy's), the GIL released while surfcap works, progress shown through tqdm when it is
installed and nothing printed when it is not, and the library's notes sent to the ``surfcap``
logger."""

from __future__ import annotations

import logging
import sys
import threading
import time
import tracemalloc
import types
from pathlib import Path

import numpy as np
import pytest

import surfcap

FRAMES, VERTICES = 2_000, 10_000
MB = 1 << 20


def strip_faces(n_vertices: int) -> np.ndarray:
    """A triangle strip over every vertex: (n - 2, 3)."""
    i = np.arange(n_vertices - 2)
    return np.stack([i, i + 1, i + 2], axis=1)


def large_positions(frames: int, vertices: int) -> np.ndarray:
    """(frames, vertices, 3) float32, every page written (resident), C-contiguous."""
    p = np.empty((frames, vertices, 3), dtype=np.float32)
    base = np.arange(vertices * 3, dtype=np.float32).reshape(vertices, 3) * 1e-4
    p[...] = base
    p[:, :, 1] += np.linspace(0.0, 1.0, frames, dtype=np.float32)[:, None]
    return p


def status_kb(field: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise AssertionError(f"{field} missing from /proc/self/status")


def reset_peak_rss() -> None:
    """Sets the peak resident size (VmHWM) back to the current one (Linux's clear_refs 5)."""
    Path("/proc/self/clear_refs").write_text("5")


def peak_growth(call):
    """(result, bytes the peak resident memory grew, bytes of numpy/Python peak) of ``call()``."""
    reset_peak_rss()
    before = status_kb("VmHWM")
    tracemalloc.start()
    try:
        result = call()
        _, traced_peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return result, (status_kb("VmHWM") - before) * 1024, traced_peak


@pytest.fixture(scope="module")
def large():
    if not Path("/proc/self/clear_refs").exists():
        pytest.skip("the peak resident size is measured through Linux's /proc/self/clear_refs")
    return strip_faces(VERTICES), large_positions(FRAMES, VERTICES)


def test_a_large_float32_array_is_passed_in_without_a_copy(large):
    faces, p = large
    size = p.nbytes
    assert size == FRAMES * VERTICES * 3 * 4  # 240 MB
    s, rss, traced = peak_growth(lambda: surfcap.Subject.from_arrays(faces, p, cache=False))
    # Nothing of the array's size was allocated, by Rust (peak resident memory) or numpy
    # (tracemalloc); the subject reads the caller's memory.
    assert rss < size / 20, f"peak resident memory grew by {rss / MB:.1f} MB for a {size / MB:.0f} MB array"
    assert traced < size / 100, f"numpy allocated {traced / MB:.1f} MB"
    assert np.shares_memory(s.positions, p)
    assert s.n_frames == FRAMES and s.n_vertices == VERTICES
    # The measure sees a copy: copy=True allocates the array's size.
    c, rss_copy, _ = peak_growth(lambda: surfcap.Subject.from_arrays(faces, p, cache=False, copy=True))
    assert rss_copy > 0.9 * size, f"a copy grew the peak by only {rss_copy / MB:.1f} MB"
    assert not np.shares_memory(c.positions, p)


@pytest.mark.parametrize(
    "layout",
    [
        lambda p: np.asfortranarray(p),
        lambda p: np.stack([p, p], axis=-1)[..., 0],
        lambda p: p[::-1],
        lambda p: p.astype(np.float64),
    ],
    ids=["f-order", "strided", "reversed", "float64"],
)
def test_any_other_layout_is_copied_once_by_numpy_into_what_the_subject_reads(layout, large):
    faces, p = large
    x = layout(p[:200])
    size = x.size * 4  # the float32 copy
    s, rss, traced = peak_growth(lambda: surfcap.Subject.from_arrays(faces, x, cache=False))
    # One float32 copy, made by numpy's one-pass conversion (tracemalloc sees numpy's
    # allocations, not Rust's), and nothing more of its size.
    assert 0.99 * size < traced < 1.2 * size, f"numpy allocated {traced / MB:.1f} MB for a {size / MB:.1f} MB copy"
    assert rss < 1.2 * size, f"peak resident memory grew by {rss / MB:.1f} MB for a {size / MB:.1f} MB copy"
    np.testing.assert_array_equal(s.positions, x.astype(np.float32))


def ticks_during(call, *, middle: float = 0.5):
    """Runs ``call()`` while another Python thread counts, and returns how many of its counts
    fell in the middle ``middle`` fraction of the call: none when the call holds the GIL (the
    other thread cannot run), many when it releases it."""
    stamps: list[float] = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            stamps.append(time.perf_counter())

    t = threading.Thread(target=count)
    t.start()
    try:
        while not stamps:  # the counting thread runs before the call starts
            time.sleep(0.001)
        t0 = time.perf_counter()
        call()
        t1 = time.perf_counter()
    finally:
        stop.set()
        t.join()
    margin = (1.0 - middle) / 2 * (t1 - t0)
    return sum(1 for s in stamps if t0 + margin < s < t1 - margin)


def test_the_thread_measure_sees_a_call_that_holds_the_gil():
    # sum() over a range runs in C without letting another Python thread in.
    assert ticks_during(lambda: sum(range(10_000_000))) == 0


def test_another_thread_runs_while_a_subject_is_exported_and_loaded(tmp_path, large):
    faces, p = large
    s = surfcap.Subject.from_arrays(faces, p[:300], cache=False)
    out = tmp_path / "big"
    assert ticks_during(lambda: s.export(out, "npy")) > 100
    assert ticks_during(lambda: surfcap.Subject.load(out, cache=False)) > 100
    np.testing.assert_array_equal(surfcap.Subject.load(out, cache=False).positions, p[:300])


class FakeTqdm:
    """Records what a tqdm bar is told."""

    bars: list["FakeTqdm"] = []

    def __init__(self, *args, total=None, desc=None, **kw):
        self.total, self.desc, self.updates, self.closed = total, desc, [], False
        self.thread = threading.get_ident()
        FakeTqdm.bars.append(self)

    def update(self, n=1):
        assert threading.get_ident() == self.thread, "a bar was updated from another thread"
        self.updates.append(n)

    def close(self):
        self.closed = True


@pytest.fixture
def fake_tqdm(monkeypatch):
    FakeTqdm.bars = []
    for name in ("tqdm", "tqdm.auto"):
        m = types.ModuleType(name)
        m.tqdm = FakeTqdm
        monkeypatch.setitem(sys.modules, name, m)
    return FakeTqdm.bars


def small_subject(frames: int = 24) -> surfcap.Subject:
    return surfcap.Subject.from_arrays(strip_faces(50), large_positions(frames, 50), cache=False)


def test_a_long_call_shows_its_progress_through_tqdm(fake_tqdm, tmp_path):
    small_subject(24).export(tmp_path / "frames", "obj")
    bars = [b for b in fake_tqdm if b.desc == "writing obj frames"]
    assert len(bars) == 1, [b.desc for b in fake_tqdm]
    (bar,) = bars
    assert bar.total == 24 and sum(bar.updates) == 24 and bar.closed
    assert all(b.closed for b in fake_tqdm)


def test_set_progress_false_hides_the_bars(fake_tqdm, tmp_path):
    surfcap.set_progress(False)
    try:
        small_subject().export(tmp_path / "frames", "obj")
    finally:
        surfcap.set_progress(True)
    assert fake_tqdm == []


def test_without_tqdm_a_long_call_prints_nothing(monkeypatch, capfd, tmp_path):
    for name in ("tqdm", "tqdm.auto"):
        monkeypatch.setitem(sys.modules, name, None)  # as if tqdm were not installed
    s = small_subject()
    s.export(tmp_path / "frames", "obj")
    surfcap.Subject.load(tmp_path / "frames" / "subject", fps=30, up_axis="+y", units="m", cache=False)
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert len(list((tmp_path / "frames" / "subject").glob("*.obj"))) == 24


def test_the_library_notes_go_to_the_surfcap_logger(tmp_path, caplog):
    folder = tmp_path / "walk"
    folder.mkdir()
    for f in range(3):
        (folder / f"frame_{f:03}.obj").write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 {f * 0.1}\nf 1 2 3\n")
    with caplog.at_level(logging.WARNING, logger="surfcap"):
        s = surfcap.Subject.load(folder, fps=30, cache=False)
    notes = [r.getMessage() for r in caplog.records if r.name == "surfcap"]
    assert any("no up axis in the sources: assumed +y" in n for n in notes), notes
    assert s.n_frames == 3
    # Told what they are, the sources leave nothing to note.
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="surfcap"):
        surfcap.Subject.load(folder, fps=30, up_axis="+y", units="m", cache=False)
    assert [r for r in caplog.records if r.name == "surfcap"] == []
