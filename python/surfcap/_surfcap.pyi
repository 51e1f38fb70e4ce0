"""Type stubs of the extension module (crates/surfcap-python). Shapes and dtypes are in the
docstrings: F frames, V vertices, T triangles."""

from __future__ import annotations

from os import PathLike
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import reports

__version__: str

Frame = Union[int, str]
"""A frame: a global index, or ``"sequence:frame"`` (0-based frame in that sequence)."""
Path = Union[str, PathLike]
FloatArray = npt.ArrayLike
"""float32 or float64 numbers, any order or strides (copied once unless C-contiguous float32)."""
IntArray = npt.ArrayLike

class SurfcapError(Exception):
    """A surfcap error with the command line's message (the file, line or frame at fault and
    what was expected). ``causes``: the lower-level causes, outermost first."""

    causes: List[str]

class ConstraintsMissedWarning(UserWarning):
    """A synthesis missed a constraint; its report says which, by how much and why."""

def set_progress(enabled: bool) -> None:
    """Show (default) or hide tqdm progress bars of long calls."""

class Subject:
    """One topology, named sequences of vertex positions, frame rate, up axis and units, with
    its derived products (distances, tables, graphs, walk models) cached under the same keys as
    the command line's (``cache_dir``: default ``$XDG_CACHE_HOME/surfcap`` or
    ``~/.cache/surfcap``; ``cache=False``: memory only; ``refresh=True``: recompute)."""

    @staticmethod
    def load(
        path: Path,
        *,
        fps: Optional[float] = None,
        up_axis: Optional[str] = None,
        units: Optional[str] = None,
        cache_dir: Optional[Path] = None,
        cache: bool = True,
        refresh: bool = False,
    ) -> Subject:
        """Opens a subject cache or any source the command line reads."""
    @staticmethod
    def import_(
        paths: Union[Path, Sequence[Path]],
        *,
        name: Optional[str] = None,
        fps: Optional[float] = None,
        up_axis: Optional[str] = None,
        units: Optional[str] = None,
        cache_dir: Optional[Path] = None,
        cache: bool = True,
        refresh: bool = False,
    ) -> Subject:
        """Imports one or several sources into one subject (``surfcap import``)."""
    @staticmethod
    def from_arrays(
        faces: IntArray,
        positions: FloatArray,
        *,
        fps: float = 30.0,
        name: str = "subject",
        sequences: Optional[Sequence[Tuple[str, int]]] = None,
        up_axis: str = "+y",
        units: str = "m",
        copy: bool = False,
        cache_dir: Optional[Path] = None,
        cache: bool = True,
        refresh: bool = False,
    ) -> Subject:
        """A subject from ``faces`` (T, 3) integers and ``positions`` (F, V, 3) or (V, 3) floats.
        A C-contiguous float32 ``positions`` is read in place (no copy: do not change it while
        the subject lives) unless ``copy=True``. ``sequences``: ``(name, frames)`` pairs that
        split the frames (default: one sequence named ``name``)."""
    name: str
    fps: float
    up_axis: str
    """``"+x"``, ``"+y"``, ``"+z"``, ``"-x"``, ``"-y"`` or ``"-z"``."""
    units: str
    metres_per_unit: Optional[float]
    n_frames: int
    n_vertices: int
    n_faces: int
    sequences: List[str]
    sequence_frames: Dict[str, int]
    cache_dir: Optional[str]
    faces: npt.NDArray[np.uint32]
    """(T, 3) uint32, read-only view."""
    positions: npt.NDArray[np.float32]
    """(F, V, 3) float32 in global frame order: a read-only view with one sequence, a joined copy
    with several."""
    def __len__(self) -> int: ...
    def sequence_positions(self, name: str) -> npt.NDArray[np.float32]:
        """(F_seq, V, 3) float32, read-only view of one sequence."""
    def frame(self, frame: Frame) -> npt.NDArray[np.float32]:
        """(V, 3) float32, read-only view of one frame."""
    def resolve_frame(self, frame: Frame) -> int:
        """The global index of ``frame``."""
    def frame_name(self, frame: int) -> str:
        """``"sequence:frame"`` of a global index."""
    def export(
        self,
        path: Path,
        format: Optional[str] = None,
        *,
        sequences: Optional[Sequence[str]] = None,
        ascii: bool = False,
        force: bool = False,
    ) -> List[str]:
        """Writes the subject as ``surfcap export`` does (glb, obj, ply, pc2, npy, usda, abc;
        default from the extension); returns the paths written."""
    def save(self, path: Path, *, force: bool = False) -> None:
        """Writes a subject cache (``surfcap import -o x.subject``)."""
    # interop (surfcap/interop.py)
    def to_trimesh(self, frame: Frame = 0) -> object:
        """One frame as a ``trimesh.Trimesh`` (needs trimesh)."""
    def to_rerun(self, application_id: str = "surfcap", entity_path: str = "subject", *, path: Optional[Path] = None) -> object:
        """A rerun recording with every frame as ``Mesh3D`` (needs rerun-sdk)."""
    def log_rerun(self, entity_path: str = "subject", *, timeline: str = "frame", sequence: Optional[str] = None, recording: object = None) -> None:
        """Logs every frame as ``rerun.Mesh3D`` over a timeline (needs rerun-sdk)."""

# --- distances and interpolation (thesis chapter 2) ---

def pose_distances(subject: Subject, *, metric: str = "deformation", w: float = 0.01) -> npt.NDArray[np.float64]:
    """All-pairs pose distances (F, F) float64 in global frame order, as ``surfcap distance``
    writes them (same cache file, same bits): ``metric`` "deformation" (eq. 2.13),
    "deformation-log" (eq. 2.14) or "euclidean" (eq. 2.2); ``w`` the stretch weight. A read-only
    view of the cached matrix."""

def pose_distance(subject: Subject, a: Frame, b: Frame, *, metric: str = "deformation", w: float = 0.01) -> float:
    """One pose distance: entry (a, b) of ``pose_distances`` to the bit, computed for the pair
    alone unless the matrix is at hand."""

def interpolate(
    subject: Subject,
    from_: Frame,
    to: Frame,
    *,
    steps: int = 10,
    method: str = "nonlinear",
    stretch: str = "linear",
    output: Optional[Path] = None,
    format: Optional[str] = None,
    force: bool = False,
) -> Subject:
    """``steps`` poses (>= 2, both ends included) from ``from_`` to ``to`` as ``surfcap
    interpolate`` makes them: ``method`` "nonlinear" (eq. 2.45-2.49; ``stretch`` "linear" or
    "log") or "linear" (eq. 2.23). A Subject of one sequence ``<from>_to_<to>``, positions
    (steps, V, 3) float32. ``output=`` also writes it (``format`` as ``--format``)."""

# --- transitions (thesis 3.2) ---

Slope = Union[int, str, float]
"""A slope constraint p (eq. 2.53): a whole number >= 1, or ``"inf"`` / ``float("inf")`` for none."""

def transition(
    subject: Subject,
    from_: Frame,
    to: Frame,
    *,
    slope: Slope = 3,
    l_min: Optional[int] = None,
    l_max: Optional[int] = None,
) -> Tuple[Subject, reports.TransitionReport]:
    """One optimal transition from ``from_`` (source segment starts there) to ``to`` (destination
    segment ends there), as ``surfcap transition``: the animation (duration, V, 3) float32 and
    the report ``<output>.transition.json`` holds."""

def transition_table(
    subject: Subject,
    *,
    slope: Slope = 3,
    l_min: Optional[int] = None,
    l_max: Optional[int] = None,
) -> Dict[str, Union[npt.NDArray[np.float64], npt.NDArray[np.uint32], int, None]]:
    """The all-pairs transition table as ``surfcap transitions`` writes it (same cache file,
    same numbers), read-only (F, F) views: ``"D"`` float64 normalised cost (inf where none fits),
    ``"L"`` uint32 duration, ``"li"``, ``"lj"`` uint32 segment lengths; plus the parameters used,
    ``"l_min"``, ``"l_max"``, ``"slope"`` (None for inf)."""

def transition_costs(
    subject: Subject,
    *,
    slopes: Sequence[int] = (2, 3, 4, 5),
    fixed: Optional[int] = None,
    plot_pairs: int = 100,
    dtw_first_step: str = "surfcap",
) -> reports.TransitionCostsReport:
    """Thesis Fig. 2.15 as ``surfcap eval transitions`` computes it: per slope, mean and std of
    the normalised costs of standard, DTW and DTW + variable-length transitions, and the sampled
    cost and duration curves (``report.curves()``)."""

# --- graphs (thesis 3.3-3.4) ---

# --- synthesis (thesis 3.5) ---

# --- surface motion graph (Huang et al. 2009) ---

# --- transfer (thesis chapter 5) ---

# --- variation (thesis chapter 6) ---

# --- appearance (thesis chapter 4) ---
