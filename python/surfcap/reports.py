"""Reports: what a command writes beside its output as ``<output>.report.json``, as objects.

A report's fields are attributes (a nested object is a ``Report`` too, a list stays a list);
``to_dict()`` gives the plain dict, ``to_json()`` the JSON text. Each query's report class lists
the fields it always has, with their types.
"""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional


def _wrap(value: Any) -> Any:
    if isinstance(value, dict):
        return Report(value)
    if isinstance(value, list):
        return [_wrap(v) for v in value]
    return value


class Report:
    """A report: attribute access to the fields of the JSON the command line writes."""

    def __init__(self, fields: Dict[str, Any]):
        object.__setattr__(self, "_fields", fields)

    def __getattr__(self, name: str) -> Any:
        fields = object.__getattribute__(self, "_fields")
        if name in fields:
            return _wrap(fields[name])
        raise AttributeError(f"{type(self).__name__} has no field {name!r}; it has {', '.join(fields)}")

    def __getitem__(self, name: str) -> Any:
        return _wrap(self._fields[name])

    def __contains__(self, name: str) -> bool:
        return name in self._fields

    def __dir__(self) -> List[str]:
        return list(self._fields) + ["to_dict", "to_json"]

    def to_dict(self) -> Dict[str, Any]:
        """The report as plain dicts and lists (a copy)."""
        return json.loads(json.dumps(self._fields))

    def to_json(self, indent: int = 2) -> str:
        """The report as JSON text."""
        return json.dumps(self._fields, indent=indent)

    def __repr__(self) -> str:
        short = {k: v for k, v in self._fields.items() if not isinstance(v, (list, dict))}
        return f"{type(self).__name__}({short})"


# --- distances and interpolation (thesis chapter 2) ---

# --- transitions (thesis 3.2) ---


class TransitionReport(Report):
    """One transition, as ``surfcap transition`` writes ``<output>.transition.json``: global
    frames ``from``/``to`` (``report["from"]``: ``from`` is a Python keyword), segment lengths,
    the duration L (frames), the warp's normalised cost and the table's cost D(i, j), the slope
    (None for inf), the warp as [source frame, destination frame] pairs, and the blend time."""

    to: int
    source_length: int
    destination_length: int
    duration: int
    normalised_cost: float
    table_cost: float
    slope: Optional[int]
    warp: List[List[int]]
    blend_seconds: float


class TransitionCostsReport(Report):
    """Thesis 2.5.5, Fig. 2.15, as ``surfcap eval transitions`` writes ``transitions.json``:
    ``rows`` (per slope: ``slope``, ``pairs``, ``standard``/``dtw``/``dtw_vls`` with ``mean`` and
    ``std``, ``dtw_vls_mean_duration``), and ``plot``: the curves the command plots (``slope``,
    ``sample`` of ``standard``, ``dtw_vls``, ``duration`` per sampled pair, ``shown``: the warp
    drawn on the distance matrix, or None)."""

    subject: str
    frames: int
    fps: float
    l_min: int
    l_max: int
    fixed_length: int
    dtw_first_step: str
    rows: List[Report]
    plot: Report

    def curves(self) -> Dict[str, Any]:
        """The sampled curves of Fig. 2.15 as arrays: ``standard`` and ``dtw_vls`` (P,) float64
        normalised costs, ``duration`` (P,) uint32 frames of the variable-length transitions,
        ``fixed_length`` (int, the standard transitions' duration)."""
        import numpy as np

        sample = self._fields["plot"]["sample"]
        return {
            "standard": np.array([s["standard"] for s in sample], dtype=np.float64),
            "dtw_vls": np.array([s["dtw_vls"] for s in sample], dtype=np.float64),
            "duration": np.array([s["duration"] for s in sample], dtype=np.uint32),
            "fixed_length": self._fields["fixed_length"],
        }

# --- graphs (thesis 3.3-3.4) ---

# --- synthesis (thesis 3.5) ---


class PathReport(Report):
    """What ``synth path`` writes as ``<output>.report.json``: the curve, the search, the walk
    (``walk``: global frames; ``segments``; ``graph``), the centre's errors measured on the
    animation (``per_frame.error``, ``per_frame.centre``), the ``missed_stretches`` of the curve
    and ``constraints`` (the path, with whether it was ``missed``). Lengths in the subject's
    units."""

    constraint: str
    curve_length: float
    planar: bool
    subject: str
    fps: float
    frames: int
    original_frames: int
    synthetic_frames: int
    transitions: int
    walk: List[int]
    mean_error: float
    max_error: float
    travelled: float
    path_length: float
    net_displacement: float
    constraints: List[Report]
    missed_stretches: List[Report]


class KeyposesReport(Report):
    """What ``synth keyposes`` writes: per key (``keys``) the requested and obtained output frame,
    the timing error and the pose distance at the obtained time (thesis Fig. 3.18), with why a
    time no walk can meet is unreachable; the walk and ``constraints``."""

    constraint: str
    keys: List[Report]
    mean_abs_error_frames: float
    search_seconds: float
    subject: str
    fps: float
    frames: int
    transitions: int
    walk: List[int]
    constraints: List[Report]


class ReachReport(Report):
    """What ``synth reach`` writes: the distance and duration asked and obtained (frames shown,
    start included), the realism and total cost, whether both were ``met`` and, if the graph
    proves it, why not (``unreachable_why``); the walk and ``constraints``."""

    constraint: str
    target_distance: float
    distance: float
    distance_error: float
    target_seconds: float
    seconds: float
    target_frames: int
    obtained_frames: int
    time_error_frames: int
    realism_cost: float
    total_cost: float
    met: bool
    subject: str
    fps: float
    frames: int
    transitions: int
    walk: List[int]
    constraints: List[Report]

# --- surface motion graph (Huang et al. 2009) ---


class SmgQueryReport(Report):
    """The report of ``smg_query`` (``surfcap smg query``'s ``.report.json``): the path found,
    its cost, the distance covered and the frames played, each constraint asked and achieved,
    and why no path meets the targets when none does (``unreachable``)."""

    input: str
    engine: str
    fps: float
    frames: int
    distance: float
    unit: str
    transition_cost: float
    cost: float
    path: List[str]
    """The path's runs, ``sequence:first-last``."""
    loops: List[Report]
    graph: Report
    similarity_cached: bool
    ilp_solves: int
    constraints: List[Report]
    outputs: List[str]
    target_distance: float
    target_seconds: float
    seconds: float
    transition_frames: List[int]
    within_tolerance: Optional[bool]
    unreachable: Optional[Report]
    excluded_loops: List[Report]


class SmgGraphReport(Report):
    """The report of ``smg_build`` (``surfcap smg build``'s JSON): the two-level graph's nodes,
    edges and transitions."""

    input: str
    frames: int
    sequences: List[str]
    connections: List[str]
    key_frames: List[str]
    similarity_cached: bool
    nodes: List[str]
    edges: List[Report]
    transitions: List[Report]
    missing_transitions: List[str]

# --- transfer (thesis chapter 5) ---


class TransferTrainReport(Report):
    """The report of ``TransferModel.train`` (``report.json`` of the model folder): the pairs
    trained on, and for the GP method the parts, their components and fits."""

    model: Optional[str]
    method: str
    source: str
    target: str
    pairs: int
    key_pairs: int
    densified: bool
    fit_seconds: float
    total_seconds: float
    cached: bool


class TransferApplyReport(Report):
    """The report of ``TransferModel.apply`` (``surfcap transfer apply``'s ``.report.json``):
    the error against the true motion when one was given (``accuracy``, None otherwise) and the
    edge-length change, per-frame displacements and stitching cuts."""

    model: str
    method: str
    motion: str
    source: str
    target: str
    frames: int
    reconstruction: str
    correction: bool
    nearest: int
    parts: List[str]
    accuracy: Optional[Report]
    edge_length_distortion: Report
    setup_seconds: float
    transfer_seconds: float
    total_seconds: float
    per_frame: Report
    written: List[str]

# --- variation (thesis chapter 6) ---


class VariationTrainReport(Report):
    """What ``surfcap vary train`` writes as the model folder's ``report.json``: the learnt
    sequences (``name``, ``origin``, ``frames``) and every part's GPDM fit (``part``,
    ``vertices``, ``dimensions``, ``iterations``, ``converged``, ``objective_start``,
    ``objective``, ``alpha`` (eq. 6.4), ``beta`` (eq. 6.6), ``seconds``). ``model`` (the folder)
    is there once the model is saved."""

    subject: str
    subject_path: str
    vertices: int
    reference: str
    frames: int
    latent_dim: int
    max_iterations: int
    sequences: List[Report]
    parts: List[Report]
    train_seconds: float
    total_seconds: float
    threads: int


class VariationSampleReport(Report):
    """What ``surfcap vary sample`` writes as ``report.json``: the HMC chains (one per part:
    ``acceptance_rate``, ``step_size``, ``leapfrog_steps``, ``divergences``), the learnt motion
    varied, and per variant its ``sequence``, ``frames``, ``body_frame_distance`` (mean
    per-vertex distance from the learnt motion, body frame), ``end_distance``, ``path_length``
    and ``cleanup`` (the foot-skate clean-up's numbers, or None). ``sequence`` or ``blend`` says
    what was varied. ``model``, each variant's ``file`` and ``view`` are there once written."""

    subject: str
    units: str
    seed: int
    count: int
    options: Report
    chains: List[Report]
    learnt: Report
    variants: List[Report]
    load_seconds: float
    sample_seconds: float
    write_seconds: float
    total_seconds: float


# --- appearance (thesis chapter 4) ---


class AppearanceBuildReport(Report):
    """What ``surfcap appearance build --json`` prints of a built model: the reference frame and
    the medoid shift's path (``medoid_references``, ``medoid_errors``), the eigen maps kept and
    the share of the variance they explain, the stages' seconds. ``model`` (the folder) is there
    when it was written."""

    frames: int
    size: List[int]
    active_texels: int
    reference: str
    medoid_references: List[str]
    medoid_errors: List[float]
    eigen_textures: int
    eigen_warps: int
    texture_explained_variance: float
    warp_explained_variance: float
    stages: Report
    seconds: float
