"""Type stubs of the extension module (crates/surfcap-python). Shapes and dtypes are in the
docstrings: F frames, V vertices, T triangles."""

from __future__ import annotations

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

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
    def to_rerun(self, application_id: str = "surfcap", entity_path: str = "subject", *, path: Optional[Path] = None, sequence: Optional[str] = None) -> object:
        """A new rerun recording with every frame as ``Mesh3D`` over the timelines ``frame`` and
        ``time``; with ``path``, written to that ``.rrd`` file and closed (needs rerun-sdk)."""
    def log_rerun(self, entity_path: str = "subject", *, timeline: str = "frame", sequence: Optional[str] = None, recording: object = None, up_axis: bool = True) -> None:
        """Logs the triangles once (static) and every frame's ``(V, 3)`` float32 positions as
        ``rerun.Mesh3D`` over ``timeline`` (global frame index) and ``time`` (seconds), with the
        subject's up axis as view coordinates at ``/`` (needs rerun-sdk)."""

# --- distances and interpolation (thesis chapter 2) ---

def pose_distances(subject: Subject, *, metric: str = "deformation", w: float = 0.01) -> npt.NDArray[np.float64]:
    """All-pairs pose distances (F, F) float64 in global frame order, as ``surfcap distance``
    writes them (same cache file, same bits): ``metric`` "deformation" (eq. 2.13),
    "deformation-log" (eq. 2.14), "euclidean" (eq. 2.2) or "deformation-literal" (eq. 2.13 with
    eq. 2.6 read literally, A^-1 B); ``w`` the stretch weight. A read-only
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

def graph(
    subject: Subject,
    *,
    kind: str = "essential",
    k: Optional[int] = None,
    alpha: float = 0.05,
    slope: Union[int, str, float] = 3,
    l_min: Optional[int] = None,
    l_max: Optional[int] = None,
    output: Optional[Path] = None,
    force: bool = False,
) -> Dict[str, object]:
    """The graph over the subject's frames, as ``surfcap graph build`` (``kind``: essential,
    sparse-essential (``k`` transitions kept per frame), motion; ``slope``: int >= 1 or "inf";
    segment bounds default from the subject's clips). Returns ``edges`` (E, 2) uint32 (from, to
    global frames), ``weights`` (E,) float64 and graph.json's numbers (``nodes``,
    ``frames_in_graph``, ``original_edges``, ``transition_edges``, ``density``, ``kind``,
    ``alpha``, ``l_min``, ``l_max``, ``slope``, ``seconds``, ``cached``, ``subject``).
    ``output``: writes edges.npy, weights.npy and graph.json there."""

# --- synthesis (thesis 3.5) ---

Curve = Union[Path, npt.ArrayLike]
"""A CSV file, or an (N, 3) x,y,z / (N, 2) ground-plane array of float32 or float64 in the
subject's units."""
Keys = Union[Path, Sequence[Tuple[Frame, Union[float, str]]]]
"""A key file (``frame,time`` lines), or ``(frame, time)`` pairs: time in seconds (a number) or
a str as in the file (``"90"``/``"90f"``: output frame, ``"3s"``: seconds)."""

class LiveSession:
    """The interactive controller played live (``Synthesizer.live``): ``step`` advances it under
    an input and returns what falls due as a dict (``frames`` with their placement ``theta``,
    ``t`` and ``centre``, each a captured ``frame`` or a ``blend`` id and its frame ``k``;
    ``decisions``, ``blends``, ``cannot_follow``, ``predicted``, ``desired``); ``blend`` and
    ``blend_from`` give a chosen transition's blended frames as (F, V, 3) float32 positions."""

    info: Dict[str, Any]
    def step(self, direction: Tuple[float, float], *, run: bool = False, dt: float = 1 / 60) -> Dict[str, Any]:
        """Advances the controller by ``dt`` seconds (0 to 1): ``direction`` on the subject's two
        ground axes, of length 0 (stop) to 1 (the gait's full speed); ``run`` rather than walk."""
    def blend(self, id: int) -> npt.NDArray[np.float32]:
        """Blend ``id``'s frames, once made: (F, V, 3) float32 positions."""
    def blend_from(self, id: int, frame: int) -> Tuple[npt.NDArray[np.float32], int]:
        """Blend ``id``'s frames from ``frame`` on that are made so far, and its frame count."""
    def captured_stream(self) -> bytes:
        """Every captured frame as one compact stream (the play page's format)."""
    def restart(self) -> None:
        """Starts the controller again from its start frame."""

class Synthesizer:
    """A subject prepared for synthesis (``prepare``): its graph and walk model, built once."""

    subject: Subject
    kind: str
    n_edges: int
    n_transitions: int
    prepare_seconds: float
    def live(self, *, bits: int = 16) -> LiveSession:
        """Starts a live session of the interactive controller on this subject (``surfcap
        play``'s player without the page); ``bits``: 8 to 16 per coordinate of the streams."""
    def path(
        self,
        curve: Curve,
        *,
        planar: bool = False,
        tags: Union[None, str, Sequence[str]] = None,
        start: Optional[Frame] = None,
        window: Optional[float] = None,
        max_transitions: Optional[int] = None,
        branching: int = 8,
        tolerance: Optional[float] = None,
        frame_tolerance: Optional[int] = None,
        output: Optional[Path] = None,
        format: Optional[str] = None,
        force: bool = False,
    ) -> Tuple[Subject, reports.PathReport]:
        """Follows ``curve`` with the centre of mass (``surfcap synth path``). Returns the
        animation ((F, V, 3) float32 in one sequence ``path``) and its report; ``output``
        writes both as the command does."""
    def keyposes(
        self,
        keys: Keys,
        *,
        tolerance: Optional[float] = None,
        frame_tolerance: Optional[int] = None,
        output: Optional[Path] = None,
        format: Optional[str] = None,
        force: bool = False,
    ) -> Tuple[Subject, reports.KeyposesReport]:
        """Moves key poses to new times (``surfcap synth keyposes``)."""
    def reach(
        self,
        from_: Frame,
        to: Frame,
        distance: float,
        time: Union[float, str],
        *,
        distance_scale: float = 0.3,
        time_scale: float = 10.0,
        tolerance: Optional[float] = None,
        frame_tolerance: Optional[int] = None,
        output: Optional[Path] = None,
        format: Optional[str] = None,
        force: bool = False,
    ) -> Tuple[Subject, reports.ReachReport]:
        """From one frame to another covering ``distance`` (subject units) in ``time`` (seconds,
        or ``"90f"`` frames shown) (``surfcap synth reach``)."""

def prepare(
    subject: Subject,
    *,
    kind: str = "essential",
    k: Optional[int] = None,
    alpha: float = 0.05,
    slope: Union[int, str, float] = 3,
    l_min: Optional[int] = None,
    l_max: Optional[int] = None,
    track: Optional[Sequence[int]] = None,
) -> Synthesizer:
    """Reads or builds (and caches) the subject's graph and walk model once."""

def synth_path(subject: Subject, curve: Curve, *, kind: str = "essential", k: Optional[int] = None, alpha: float = 0.05, slope: Union[int, str, float] = 3, l_min: Optional[int] = None, l_max: Optional[int] = None, track: Optional[Sequence[int]] = None, planar: bool = False, tags: Union[None, str, Sequence[str]] = None, start: Optional[Frame] = None, window: Optional[float] = None, max_transitions: Optional[int] = None, branching: int = 8, tolerance: Optional[float] = None, frame_tolerance: Optional[int] = None, output: Optional[Path] = None, format: Optional[str] = None, force: bool = False) -> Tuple[Subject, reports.PathReport]:
    """``prepare(subject, ...).path(curve, ...)`` in one call (the request checked first)."""

def synth_keyposes(subject: Subject, keys: Keys, *, kind: str = "essential", k: Optional[int] = None, alpha: float = 0.05, slope: Union[int, str, float] = 3, l_min: Optional[int] = None, l_max: Optional[int] = None, tolerance: Optional[float] = None, frame_tolerance: Optional[int] = None, output: Optional[Path] = None, format: Optional[str] = None, force: bool = False) -> Tuple[Subject, reports.KeyposesReport]:
    """``prepare(subject, ...).keyposes(keys, ...)`` in one call (the keys checked first)."""

def synth_reach(subject: Subject, from_: Frame, to: Frame, distance: float, time: Union[float, str], *, kind: str = "essential", k: Optional[int] = None, alpha: float = 0.05, slope: Union[int, str, float] = 3, l_min: Optional[int] = None, l_max: Optional[int] = None, distance_scale: float = 0.3, time_scale: float = 10.0, tolerance: Optional[float] = None, frame_tolerance: Optional[int] = None, output: Optional[Path] = None, format: Optional[str] = None, force: bool = False) -> Tuple[Subject, reports.ReachReport]:
    """``prepare(subject, ...).reach(from_, to, distance, time, ...)`` in one call."""

# --- surface motion graph (Huang et al. 2009) ---

class FrameSet:
    """A frame set: named sequences of frames, each frame its own mesh (``(V_i, 3)`` float32
    positions, ``(T_i, 3)`` uint32 triangles), with frame rate, up axis and units."""

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
    ) -> FrameSet:
        """Opens a ``.frames`` folder or any source the command line reads as a frame set."""
    @staticmethod
    def from_arrays(
        positions: Sequence[FloatArray],
        faces: Sequence[IntArray],
        *,
        fps: float = 30.0,
        name: str = "frames",
        sequences: Optional[Sequence[Tuple[str, int]]] = None,
        up_axis: str = "+y",
        units: str = "m",
        cache_dir: Optional[Path] = None,
        cache: bool = True,
        refresh: bool = False,
    ) -> FrameSet:
        """One ``(V_i, 3)`` position array and one ``(T_i, 3)`` integer face array per frame."""
    name: str
    fps: float
    up_axis: str
    units: str
    n_frames: int
    sequences: List[str]
    sequence_frames: Dict[str, int]
    vertex_counts: List[int]
    """The vertex count of every frame, in global frame order."""
    cache_dir: Optional[str]
    def __len__(self) -> int: ...
    def frame(self, frame: Frame) -> Tuple[np.ndarray, np.ndarray]:
        """``(positions (V_i, 3) float32, faces (T_i, 3) uint32)``, read-only views."""
    def resolve_frame(self, frame: Frame) -> int: ...
    def frame_name(self, frame: int) -> str: ...
    def export(self, path: Path, format: Optional[str] = None, *, force: bool = False) -> List[str]:
        """A ``.frames`` folder, or glb (a mesh per frame), abc or obj; returns the paths written."""

def smg_query(
    input: Union[Subject, FrameSet],
    *,
    connect: Union[str, Sequence[str]],
    from_: str,
    to: str,
    distance: float,
    time: float,
    windows: str = "3-30",
    transitions: int = 1,
    separation: int = 15,
    resolution: int = 64,
    distance_weight: float = 1.0 / 0.3,
    time_weight: float = 0.1,
    paper_cost: bool = False,
    min_loop: int = 10,
    loop_variation_floor: float = 1.0,
    tolerance: Optional[float] = None,
    frame_tolerance: Optional[int] = None,
    output: Optional[Path] = None,
    format: Optional[str] = None,
    force: bool = False,
) -> Tuple[Union[Subject, FrameSet], reports.SmgQueryReport]:
    """``surfcap smg query``: the path between two key frames (``"sequence:frame"``) covering
    ``distance`` (subject units) in ``time`` seconds. Returns a ``Subject`` (one sequence
    ``smg``, ``(F, V, 3)`` float32) for a subject, a ``FrameSet`` for a frame set, and the
    report; a missed constraint issues ``ConstraintsMissedWarning``."""

def smg_build(
    input: Union[Subject, FrameSet],
    *,
    connect: Union[str, Sequence[str]],
    keys: Sequence[str] = (),
    windows: str = "3-30",
    transitions: int = 1,
    separation: int = 15,
    resolution: int = 64,
    output: Optional[Path] = None,
) -> Tuple[np.ndarray, reports.SmgGraphReport]:
    """``surfcap smg build``: the shape similarity ``(F, F)`` float64 (the matrix cached as
    ``smg-similarity-*.npy``) and the graph's report."""

# --- transfer (thesis chapter 5) ---

class TransferModel:
    """A motion transfer from a source subject to a target subject (GP regression on body
    parts, thesis chapter 5, or Baran et al. 2009); its folder is the one ``surfcap transfer
    train`` writes and ``surfcap transfer apply`` reads."""

    @staticmethod
    def train(
        source: Subject,
        target: Subject,
        pairs: Union[Path, Sequence[Tuple[Frame, Frame]]],
        *,
        method: str = "gp",
        source_parts: Optional[Path] = None,
        target_parts: Optional[Path] = None,
        whole_body: bool = False,
        components: int = 20,
        kernel: str = "nn",
        seed: int = 0,
        no_densify: bool = False,
        max_straight: int = 3,
        output: Optional[Path] = None,
        force: bool = False,
    ) -> TransferModel:
        """``surfcap transfer train``: ``pairs`` a CSV path or ``(source frame, target frame)``
        pairs; ``method`` gp or baran; ``kernel`` nn, se or linear."""
    @staticmethod
    def load(dir: Path) -> TransferModel:
        """Reads a model folder written by ``surfcap transfer train`` or ``save``."""
    def save(self, dir: Path, *, force: bool = False) -> None:
        """Writes the model folder as ``surfcap transfer train -o dir`` does."""
    method: str
    source_name: str
    target_name: str
    report: Optional[reports.TransferTrainReport]
    def apply(
        self,
        source: Subject,
        sequence: str,
        *,
        reconstruction: str = "stitch",
        truth: Optional[Tuple[Subject, str]] = None,
        correction: bool = False,
        nearest: int = 3,
        output: Optional[Path] = None,
        format: Optional[str] = None,
        force: bool = False,
    ) -> Tuple[Subject, reports.TransferApplyReport]:
        """``surfcap transfer apply``: the target playing ``source``'s sequence (one sequence
        ``<sequence>-as-<target>``, ``(F, V, 3)`` float32) and the report."""

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
        deviation_smoothing: int = 4,
        warmup: int = 20,
        thin: int = 2,
        max_leapfrog: int = 30,
        no_foot_skate_cleanup: bool = False,
        hold_hips: bool = False,
        no_learnt_stretch: bool = False,
        carry_pins: bool = False,
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
