"""Reads a surfcap tile work folder with zarr-python (the reference Zarr implementation numpy and
xarray users have) and saves every array it holds as .npy into an output folder, for the tests to
compare to the bit with surfcap's own products. Prints a JSON summary (shape, chunks, dtype,
dimension names per array).

usage: zarr-read.py WORK OUT_DIR
"""
import json
import os
import sys

import numpy as np
import zarr


def main():
    work, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    root = zarr.open_group(work, mode="r")
    summary = {}
    for name in ["distances.zarr", "table/cost.zarr", "table/len.zarr", "table/li.zarr", "table/lj.zarr", "paths/costs.zarr"]:
        a = zarr.open_array(os.path.join(work, name), mode="r")
        values = a[:]
        np.save(os.path.join(out, name.replace("/", "_").replace(".zarr", "") + ".npy"), values)
        summary[name] = {
            "shape": list(a.shape),
            "chunks": list(a.chunks),
            "dtype": str(a.dtype),
            "dimension_names": list(a.metadata.dimension_names or []),
        }
    summary["groups"] = sorted(k for k, _ in root.groups())
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
