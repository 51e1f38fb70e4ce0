"""The tour notebook (examples/notebooks/tour.ipynb) runs from top to bottom on the real data,
with the surfcap program of this checkout and a fresh cache folder; the stored copy keeps its
outputs (a reader sees them without running it)."""

from __future__ import annotations

import os
from pathlib import Path

import nbformat
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[2]
TOUR = ROOT / "examples" / "notebooks" / "tour.ipynb"


def test_the_stored_tour_keeps_its_outputs():
    nb = nbformat.read(TOUR, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(c.get("outputs") for c in code), "every code cell has its output stored"
    assert not any(o.output_type == "error" for c in code for o in c.outputs)
    images = sum("image/png" in o.get("data", {}) for c in code for o in c.outputs)
    assert images >= 5, f"{images} figures stored"


def test_the_tour_runs(data, surfcap_bin, tmp_path, monkeypatch):
    monkeypatch.setenv("SURFCAP_DATA", str(data))
    monkeypatch.setenv("SURFCAP_BIN", str(surfcap_bin))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    nb = nbformat.read(TOUR, as_version=4)
    client = NotebookClient(nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(TOUR.parent)}})
    client.execute()  # raises CellExecutionError naming the cell and the error
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert "crane" in text and "mean error" in text and "16_15~1" in text, text
