"""How fast Pixar's USD (usd-core) loads USD files: for each file, its size, the time
Usd.Stage.Open takes, and the time to then read every time sample of every mesh's points and
velocities (what a renderer or DCC tool playing the animation reads), every coordinate
summed through numpy so that a memory-mapped file is really read. Each measurement runs in
a fresh Python process (so no layer is cached), after `import pxr`; the median of --repeat runs
is printed, as a markdown table.

    tools/venv/bin/python tools/usd-load-time.py --repeat 5 crane.usda crane.usdc
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

CHILD = r"""
import json, sys, time
import numpy
from pxr import Usd, UsdGeom
t0 = time.perf_counter()
stage = Usd.Stage.Open(sys.argv[1])
t1 = time.perf_counter()
values = 0
frames = 0
total = 0.0
for prim in stage.Traverse():
    if not prim.IsA(UsdGeom.Mesh):
        continue
    mesh = UsdGeom.Mesh(prim)
    for attr in (mesh.GetPointsAttr(), mesh.GetVelocitiesAttr()):
        for t in attr.GetTimeSamples():
            # Every coordinate is touched (summed), so a lazily mapped file is really read.
            a = numpy.asarray(attr.Get(t))
            total += float(a.sum(dtype=numpy.float64))
            values += len(a)
            frames += 1
t2 = time.perf_counter()
json.dump({"open": t1 - t0, "read": t2 - t1, "vectors": values, "samples": frames}, sys.stdout)
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", help="also write the measurements here")
    a = ap.parse_args()
    rows = []
    for f in a.files:
        runs = []
        for _ in range(a.repeat):
            o = subprocess.run([sys.executable, "-c", CHILD, f], capture_output=True, text=True)
            if o.returncode != 0:
                sys.exit(f"usd-core could not read {f}:\n{o.stderr}")
            runs.append(json.loads(o.stdout))
        row = {
            "file": f,
            "bytes": os.path.getsize(f),
            "open_s": statistics.median(r["open"] for r in runs),
            "read_s": statistics.median(r["read"] for r in runs),
            "samples": runs[0]["samples"],
            "vectors": runs[0]["vectors"],
            "runs": runs,
        }
        row["total_s"] = statistics.median(r["open"] + r["read"] for r in runs)
        rows.append(row)
    print("| file | size (MB) | open (s) | read all points + velocities (s) | open + read (s) | samples |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in rows:
        print(
            f"| {os.path.basename(r['file'])} | {r['bytes'] / 1e6:.1f} | {r['open_s']:.3f} | {r['read_s']:.3f} "
            f"| {r['total_s']:.3f} | {r['samples']} |"
        )
    if a.json:
        with open(a.json, "w") as out:
            json.dump(rows, out, indent=1)


if __name__ == "__main__":
    main()
