"""Hand-offs to other Python tools, when they are installed: trimesh and rerun."""

from __future__ import annotations

from typing import Any, Optional, Union

Frame = Union[int, str]


def _require(module: str, what: str) -> Any:
    try:
        return __import__(module)
    except ImportError as e:  # pragma: no cover - message only
        raise ImportError(f"{what} needs the `{module}` package (pip install {module.replace('_', '-')}): {e}") from e


def to_trimesh(subject: Any, frame: Frame = 0) -> Any:
    """One frame (global index or ``"sequence:frame"``) as a ``trimesh.Trimesh``.

    The vertices are a float64 copy of the frame (trimesh works in float64); the faces are the
    subject's triangles. trimesh's processing (merging vertices) is off, so vertex ``i`` stays
    vertex ``i``.
    """
    trimesh = _require("trimesh", "Subject.to_trimesh")
    import numpy as np

    return trimesh.Trimesh(
        vertices=np.asarray(subject.frame(frame), dtype=np.float64),
        faces=np.asarray(subject.faces, dtype=np.int64),
        process=False,
    )


def log_rerun(
    subject: Any,
    entity_path: str = "subject",
    *,
    timeline: str = "frame",
    sequence: Optional[str] = None,
    recording: Any = None,
) -> None:
    """Logs every frame (or one sequence's) as a ``rerun.Mesh3D`` at ``entity_path`` over the
    timeline ``timeline`` (frame numbers) and ``time`` (seconds at the subject's fps).

    Each frame logs its positions with the subject's triangles. Call
    ``rerun.init(...)`` and ``rerun.spawn()``/``rerun.save(...)`` first, or pass ``recording``.
    """
    rr = _require("rerun", "Subject.log_rerun")
    import numpy as np

    names = [sequence] if sequence is not None else subject.sequences
    faces = np.asarray(subject.faces, dtype=np.uint32)
    kw = {"recording": recording} if recording is not None else {}
    offset = 0
    for name in subject.sequences:
        n = subject.sequence_frames[name]
        if name not in names:
            offset += n
            continue
        positions = subject.sequence_positions(name)
        for f in range(n):
            g = offset + f
            rr.set_time(timeline, sequence=g, **kw)
            rr.set_time("time", duration=g / subject.fps, **kw)
            rr.log(
                entity_path,
                rr.Mesh3D(vertex_positions=positions[f], triangle_indices=faces),
                **kw,
            )
        offset += n


def to_rerun(subject: Any, application_id: str = "surfcap", entity_path: str = "subject", *, path: Optional[str] = None) -> Any:
    """A new rerun recording holding every frame (``log_rerun``); saved to ``path`` (an ``.rrd``
    file) when given. Returns the recording."""
    rr = _require("rerun", "Subject.to_rerun")
    rec = rr.RecordingStream(application_id)
    if path is not None:
        rec.save(path)
    log_rerun(subject, entity_path, recording=rec)
    return rec
