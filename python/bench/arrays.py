"""What an input array's dtype, order and strides cost `Subject.from_arrays`.

Each row passes the same `(F, V, 3)` positions in another layout and times the call (the best of
`--repeat` runs, progress hidden, no cache). The reference is numpy's own single pass over the
numbers: `np.ascontiguousarray(x, dtype=np.float32)` on the same input, the cheapest way to turn
it into what surfcap stores. A ratio near 1 means the layout costs one pass and no slow path;
the C-contiguous float32 row is read in place (no copy) and costs only surfcap's check of the
numbers (every position finite), which every other row pays too. So the expected cost of a
copied layout is numpy's pass plus that check; the last column is the ratio of the call to it.

    PYTHONPATH=target/pylib tools/venv/bin/python python/bench/arrays.py --frames 500 --vertices 10000

Then, with `--memory-frames` (default 2,000) frames of the same vertices, how much the process's
peak resident memory (Linux's VmHWM, reset through /proc/self/clear_refs; it sees Rust's
allocations) and numpy's traced memory (tracemalloc) grow during `from_arrays` on a C-contiguous
float32 array, read in place, and with `copy=True`. python/tests/test_memory_and_threads.py
asserts the same at 2,000 x 10,000.

Prints Markdown tables (docs/results/python.md keeps the numbers of one run).
"""

from __future__ import annotations

import argparse
import platform
import time
import tracemalloc
from pathlib import Path

import numpy as np

import surfcap


def best_of(repeat: int, call) -> float:
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        out = call()
        best = min(best, time.perf_counter() - t)
        del out
    return best


def layouts(frames: int, vertices: int) -> list[tuple[str, np.ndarray]]:
    rng = np.random.default_rng(0)
    p = rng.random((frames, vertices, 3), dtype=np.float32)
    wide = np.empty((frames, vertices, 6), dtype=np.float32)
    wide[..., ::2] = p
    wide[..., 1::2] = 0
    return [
        ("float32, C order (in place)", p),
        ("float32, F order", np.asfortranarray(p)),
        ("float32, strided (every other number)", wide[..., ::2]),
        ("float32, frames reversed (negative stride)", p[::-1]),
        ("float64, C order", p.astype(np.float64)),
        ("float64, F order", np.asfortranarray(p.astype(np.float64))),
    ]


def vm_hwm_bytes() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    raise RuntimeError("no VmHWM in /proc/self/status")


def peak_growth(call) -> tuple[int, int]:
    """(bytes the peak resident memory grew, numpy's traced peak in bytes) during ``call()``."""
    Path("/proc/self/clear_refs").write_text("5")
    before = vm_hwm_bytes()
    tracemalloc.start()
    out = call()
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    grown = vm_hwm_bytes() - before
    del out
    return grown, traced


def memory_table(frames: int, vertices: int, faces: np.ndarray) -> None:
    p = np.empty((frames, vertices, 3), dtype=np.float32)
    p[...] = np.arange(vertices * 3, dtype=np.float32).reshape(vertices, 3) * 1e-4  # resident
    mb = 1 << 20
    print(f"\n{frames} frames x {vertices} vertices float32: {p.nbytes / mb:.1f} MiB\n")
    print("| from_arrays | peak resident memory grew (MiB) | numpy's traced peak (MiB) |")
    print("|---|---:|---:|")
    for name, copy in (("in place (default)", False), ("copy=True", True)):
        grown, traced = peak_growth(lambda: surfcap.Subject.from_arrays(faces, p, cache=False, copy=copy))
        print(f"| {name} | {grown / mb:.1f} | {traced / mb:.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=500)
    ap.add_argument("--vertices", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--memory-frames", type=int, default=2_000, help="0 skips the memory table")
    a = ap.parse_args()
    surfcap.set_progress(False)
    i = np.arange(a.vertices - 2)
    faces = np.stack([i, i + 1, i + 2], axis=1)
    print(f"surfcap {surfcap.__version__}, numpy {np.__version__}, Python {platform.python_version()}; "
          f"{a.frames} frames x {a.vertices} vertices, best of {a.repeat}\n")
    print("| input | copied | from_arrays (ms) | numpy's one pass (ms) | pass + check (ms) | ratio |")
    print("|---|---|---:|---:|---:|---:|")
    check = None
    for name, x in layouts(a.frames, a.vertices):
        t_surfcap = best_of(a.repeat, lambda: surfcap.Subject.from_arrays(faces, x, cache=False))
        s = surfcap.Subject.from_arrays(faces, x, cache=False)
        if np.shares_memory(s.positions, x):
            check = t_surfcap  # the in-place row: surfcap's check of the numbers alone
            print(f"| {name} | no | {t_surfcap * 1e3:.1f} | - | {t_surfcap * 1e3:.1f} | 1.00 |")
            continue
        t_numpy = best_of(a.repeat, lambda: np.ascontiguousarray(x, dtype=np.float32))
        expected = t_numpy + (check or 0.0)
        print(f"| {name} | yes | {t_surfcap * 1e3:.1f} | {t_numpy * 1e3:.1f} | {expected * 1e3:.1f} | "
              f"{t_surfcap / expected:.2f} |")
    if a.memory_frames > 0:
        memory_table(a.memory_frames, a.vertices, faces)


if __name__ == "__main__":
    main()
