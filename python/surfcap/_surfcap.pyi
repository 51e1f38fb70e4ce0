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

# --- transitions (thesis 3.2) ---

# --- graphs (thesis 3.3-3.4) ---

# --- synthesis (thesis 3.5) ---

# --- surface motion graph (Huang et al. 2009) ---

# --- transfer (thesis chapter 5) ---

# --- variation (thesis chapter 6) ---

class VariationModel:
    """A motion variation model (thesis 6.4-6.7): one GPDM per body part over sequences of one
    motion type, as ``surfcap vary train`` learns it. ``save`` writes the folder the command
    writes; ``load`` reads it."""

    @staticmethod
    def train(
        subject: Subject,
        sequences: Optional[Sequence[str]] = None,
        *,
        reference: Optional[str] = None,
        parts: Optional[Path] = None,
        blend: Optional[Sequence[Tuple[str, str]]] = None,
        blend_weights: Sequence[float] = (0.5,),
        latent_dim: int = 3,
        iterations: int = 400,
        output: Optional[Path] = None,
        force: bool = False,
    ) -> VariationModel:
        """Learns the model as ``surfcap vary train`` (default: every sequence, the first the
        reference, five proposed parts). ``blend``: pairs ``(A, B)`` blended at each of
        ``blend_weights`` (strictly between 0 and 1). ``output``: also write the model folder.
        The training's report is ``.report``."""
    @staticmethod
    def load(path: Path, *, cache_dir: Optional[Path] = None, cache: bool = True) -> VariationModel:
        """Reads a model folder written by ``surfcap vary train`` or ``save``."""
    def save(self, path: Path, *, force: bool = False) -> None:
        """Writes the model folder as ``surfcap vary train`` does (``surfcap vary sample`` reads it)."""
    report: Optional[reports.VariationTrainReport]
    subject: str
    sequences: List[str]
    reference: str
    frames: int
    parts: List[str]
    n_vertices: int
    fps: float
    path: Optional[str]
    def sample(
        self,
        sequence: Optional[str] = None,
        *,
        blend: Optional[Tuple[str, str, float]] = None,
        count: int = 5,
        seed: int = 0,
        start: str = "learnt",
        path: str = "source",
        smoothing: int = 2,
        warmup: int = 100,
        thin: int = 5,
        max_leapfrog: int = 30,
        no_foot_skate_cleanup: bool = False,
        move_root: bool = False,
        output: Optional[Path] = None,
        force: bool = False,
    ) -> Tuple[List[Subject], reports.VariationSampleReport]:
        """``count`` variants of the learnt ``sequence`` or of ``blend`` = ``(A, B, W)``, as
        ``surfcap vary sample`` (same seed, same variants as the command, to the bit). Each
        variant is a ``Subject`` of one sequence ``<name>~<k>`` ((F, V, 3) float32 positions).
        ``output``: also write the folder (one glb per variant and ``report.json``)."""

# --- appearance (thesis chapter 4) ---

class AppearanceModel:
    """Eigen textures and eigen warps of per-frame texture maps (thesis 4.4), as ``surfcap
    appearance build`` makes them. Maps out are ``(H, W, 3)`` uint8, the command's PNG bytes."""

    @staticmethod
    def build(
        maps: Union[Path, npt.NDArray[np.uint8]],
        mesh: Union[Path, Subject, None] = None,
        *,
        names: Optional[Sequence[str]] = None,
        components: Optional[int] = None,
        lambda_: float = 0.02,
        warping: str = "poisson",
        search_warping: str = "direct",
        medoid_iterations: int = 5,
        keep_holed: bool = False,
        dilation: int = 1,
        flow_scale: int = 1,
        no_preprocess: bool = False,
        output: Optional[Path] = None,
        force: bool = False,
        cache_dir: Optional[Path] = None,
        cache: bool = True,
        refresh: bool = False,
    ) -> AppearanceModel:
        """``maps``: a folder as the command reads it, or (F, H, W, 3) uint8. ``mesh``: the
        UV-mapped mesh (OBJ path, subject source or ``Subject``; default the folder's
        ``template.obj``). ``output``: also write the model folder. The summary is ``.report``."""
    @staticmethod
    def load(path: Path, *, cache_dir: Optional[Path] = None, cache: bool = True, refresh: bool = False) -> AppearanceModel:
        """Reads a model folder written by ``surfcap appearance build`` or ``save``."""
    def save(self, path: Path, *, force: bool = False) -> None:
        """Writes the model folder as ``surfcap appearance build`` does."""
    report: Optional[reports.AppearanceBuildReport]
    names: List[str]
    reference: str
    n_frames: int
    n_textures: int
    n_warps: int
    shape: Tuple[int, int]
    """(height, width) of the maps."""
    mask: npt.NDArray[np.bool_]
    """(H, W) bool: the active texels."""
    def reconstruct(self, frame: Union[int, str], *, components: Optional[int] = None, output: Optional[Path] = None) -> npt.NDArray[np.uint8]:
        """(H, W, 3) uint8: a training frame rebuilt from its coefficients (``appearance reconstruct``)."""
    def interpolate(self, frames: Sequence[Union[int, str]], weights: Optional[Sequence[float]] = None, *, output: Optional[Path] = None) -> npt.NDArray[np.uint8]:
        """(H, W, 3) uint8 blended in the eigen spaces (``appearance interpolate``; equal weights by default)."""
    def complete(
        self,
        texture: Union[Path, npt.NDArray[np.uint8]],
        observed: Union[Path, npt.ArrayLike, None] = None,
        *,
        keep_observed: bool = False,
        flow_scale: int = 1,
        no_preprocess: bool = False,
        output: Optional[Path] = None,
    ) -> npt.NDArray[np.uint8]:
        """(H, W, 3) uint8: an incomplete map completed by projection (``appearance complete``);
        ``observed`` (H, W) bool or an image (default: the texels that are not pure black)."""
