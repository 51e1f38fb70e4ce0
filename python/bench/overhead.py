"""What a binding call costs over the same library call: the crane's pose distance matrix and a
path query.

Each row alternates, `--repeat` times, the binding as a user calls it and the library work that
call does, timed in Rust around the very calls the binding makes (the private hooks
`surfcap._surfcap._library_pose_distances_seconds` and `_library_path_seconds`). The overhead is
the binding's best wall time over the library's best, minus one (the medians' ratio too: on a
shared machine the best of several runs is the steadier measure): argument conversion, the
GIL released and taken back, the result handed to numpy (the matrix as a view, no copy), the
report built as a Python object.

- Distances: the crane (175 frames, 10,002 vertices), deformation metric (thesis eq. 2.13), every
  call on a fresh memory-only subject so the matrix is computed each time.
- Path: the mannequin moved by CMU 16_15, 16_17, 16_19 and 16_36 (1,000 vertices; built with the
  `surfcap` program, `SURFCAP_BIN` or `surfcap` on the PATH), its graph prepared once, the 15 m
  S-curve of examples/s_path_15m.csv followed in memory.

    tools/venv/bin/python python/bench/overhead.py --repeat 5

Prints a Markdown table (docs/results/python.md keeps the numbers of one run).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import surfcap
from surfcap import _surfcap

ROOT = Path(__file__).resolve().parents[2]


def timed(call) -> float:
    t = time.perf_counter()
    call()
    return time.perf_counter() - t


def row(name: str, binding: list, library: list) -> str:
    b, l = min(binding), min(library)
    mb, ml = statistics.median(binding), statistics.median(library)
    return (
        f"| {name} | {len(binding)} | {b:.4f} | {l:.4f} | {100 * (b / l - 1):+.2f}% "
        f"| {100 * (mb / ml - 1):+.2f}% |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--data", type=Path, default=Path(os.environ.get("SURFCAP_DATA", ROOT.parent / "shared" / "data")))
    a = ap.parse_args()
    surfcap.set_progress(False)

    crane = surfcap.Subject.load(a.data / "vlasic2008" / "crane", cache=False)
    faces, positions = crane.faces, crane.positions
    fresh = lambda: surfcap.Subject.from_arrays(faces, positions, fps=crane.fps, cache=False)  # noqa: E731
    binding, library = [], []
    for k in range(a.repeat):
        # Alternated, each going first every other run, so that neither gains from the order.
        s, t = fresh(), fresh()
        if k % 2:
            library.append(_surfcap._library_pose_distances_seconds(t))
        binding.append(timed(lambda: surfcap.pose_distances(s)))
        if not k % 2:
            library.append(_surfcap._library_pose_distances_seconds(t))

    with tempfile.TemporaryDirectory() as tmp:
        walker = Path(tmp) / "cmu.subject"
        bvh = [str(a.data / "cmu_bvh" / f"{c}.bvh") for c in ("16_15", "16_17", "16_19", "16_36")]
        exe = os.environ.get("SURFCAP_BIN", "surfcap")
        subprocess.run([exe, "--quiet", "make", "mannequin", "--bvh", *bvh, "--vertices", "1000", "-o", str(walker)], check=True, capture_output=True)
        synth = surfcap.prepare(surfcap.Subject.load(walker, cache=False))
        curve = np.loadtxt(ROOT / "examples" / "s_path_15m.csv", delimiter=",", skiprows=2)
        path_binding, path_library = [], []
        for k in range(a.repeat):
            if k % 2:
                path_library.append(_surfcap._library_path_seconds(synth, curve))
            path_binding.append(timed(lambda: synth.path(curve)))
            if not k % 2:
                path_library.append(_surfcap._library_path_seconds(synth, curve))

    print("| call | runs | binding (s, best) | library (s, best) | overhead (best) | overhead (medians) |")
    print("|---|---:|---:|---:|---:|---:|")
    print(row("pose_distances(crane), 175 x 175", binding, library))
    print(row("Synthesizer.path(15 m S-curve), CMU mannequin", path_binding, path_library))


if __name__ == "__main__":
    main()
