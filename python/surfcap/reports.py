"""Reports: what a command writes beside its output as ``<output>.report.json``, as objects.

A report's fields are attributes (a nested object is a ``Report`` too, a list stays a list);
``to_dict()`` gives the plain dict, ``to_json()`` the JSON text. Each query's report class lists
the fields it always has, with their types.
"""

from __future__ import annotations

import json
from typing import Any, Dict, List


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

# --- graphs (thesis 3.3-3.4) ---

# --- synthesis (thesis 3.5) ---

# --- surface motion graph (Huang et al. 2009) ---

# --- transfer (thesis chapter 5) ---

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
