"""Shared fixtures of the Python tests (run by scripts/test with tools/venv's pytest).

- ``data``: the shared real-data folder (``SURFCAP_DATA`` or ``../shared/data``). A test that
  needs it fails when it is missing under ``CI=true``; elsewhere it is skipped visibly only when
  ``SURFCAP_SKIP_REAL_DATA=1``, and fails otherwise, as the Rust tests do.
- ``cli``: runs the ``surfcap`` program built by ``cargo test --release`` (``target/release``,
  or ``SURFCAP_BIN``) and returns the completed process; a failing run fails the test.
- ``cache_dir``: a fresh cache folder per test, so no test reads or writes the user's cache.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def data() -> Path:
    d = Path(os.environ.get("SURFCAP_DATA", ROOT.parent / "shared" / "data"))
    if (d / "README.md").is_file():
        return d
    if os.environ.get("CI") == "true":
        pytest.fail(f"real data missing at {d} (CI=true: a real-data test must run)")
    if os.environ.get("SURFCAP_SKIP_REAL_DATA") == "1":
        pytest.skip(f"real data missing at {d} (SURFCAP_SKIP_REAL_DATA=1)")
    pytest.fail(f"real data missing at {d}: set SURFCAP_DATA, or SURFCAP_SKIP_REAL_DATA=1 to skip")


@pytest.fixture(scope="session")
def surfcap_bin() -> Path:
    exe = Path(os.environ.get("SURFCAP_BIN", ROOT / "target" / "release" / "surfcap"))
    if not exe.is_file():
        pytest.fail(f"{exe} is missing: build it with `cargo build --release -p surfcap-cli` (scripts/test does)")
    return exe


@pytest.fixture
def cache_dir(tmp_path: Path) -> Path:
    d = tmp_path / "cache"
    d.mkdir()
    return d


@pytest.fixture
def cli(surfcap_bin: Path, cache_dir: Path):
    """``cli(*args, json_out=False)``: runs surfcap with ``--cache-dir`` where the command takes
    it is up to the caller; returns the CompletedProcess (or the parsed ``--json`` result)."""

    def run(*args: str, json_out: bool = False, check: bool = True):
        cmd = [str(surfcap_bin), *(["--json"] if json_out else []), *map(str, args)]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if check and p.returncode != 0:
            pytest.fail(f"{' '.join(cmd)} exited {p.returncode}:\n{p.stderr}")
        return json.loads(p.stdout) if json_out else p

    return run


@pytest.fixture(scope="session")
def crane(data: Path) -> Path:
    return data / "vlasic2008" / "crane"
