"""Hand-offs to other Python tools, when they are installed: trimesh and rerun (rerun-sdk 0.41).

Neither package is a dependency of surfcap: ``pip install trimesh rerun-sdk`` (or
``pip install ./python[interop]``). Calling one of these functions without its package raises
``ImportError`` naming the package to install.

- ``to_trimesh(subject, frame)``: one frame as a ``trimesh.Trimesh`` (float64 vertices, the
  subject's triangles, vertex ``i`` kept as vertex ``i``).
- ``log_rerun(subject, ...)``: every frame as a ``rerun.Mesh3D`` over a frame timeline and a
  time timeline (seconds at the subject's fps), into the current or a given recording.
- ``to_rerun(subject, ...)``: a new recording holding the same, saved to an ``.rrd`` file when
  a path is given.
"""

from __future__ import annotations

from typing import Any, Optional, Union

Frame = Union[int, str]

# The pip package that provides each module (rerun's is not named after its module).
_PIP_NAME = {"trimesh": "trimesh", "rerun": "rerun-sdk"}

# The subject's up axis as rerun's view coordinates (right-handed, as surfcap's subjects are).
_VIEW_COORDINATES = {
    "+x": "RIGHT_HAND_X_UP",
    "-x": "RIGHT_HAND_X_DOWN",
    "+y": "RIGHT_HAND_Y_UP",
    "-y": "RIGHT_HAND_Y_DOWN",
    "+z": "RIGHT_HAND_Z_UP",
    "-z": "RIGHT_HAND_Z_DOWN",
}


def _require(module: str, what: str) -> Any:
    """Imports ``module`` or raises ImportError saying what needs it and what to install."""
    try:
        return __import__(module)
    except ImportError as e:
        pip = _PIP_NAME.get(module, module)
        raise ImportError(f"{what} needs the `{module}` package (pip install {pip}): {e}") from e


def to_trimesh(subject: Any, frame: Frame = 0) -> Any:
    """One frame (global index or ``"sequence:frame"``) as a ``trimesh.Trimesh``.

    The vertices are a ``(V, 3)`` float64 copy of the frame (trimesh works in float64); the
    faces are the subject's ``(T, 3)`` triangles (int64, trimesh's dtype). trimesh's processing
    (merging vertices, dropping unused ones) is off, so vertex ``i`` stays vertex ``i`` and the
    mesh's vertex count is the subject's.
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
    up_axis: bool = True,
) -> None:
    """Logs every frame (or one sequence's) as a ``rerun.Mesh3D`` at ``entity_path``.

    The triangles are logged once, as static data; the ``(V, 3)`` float32 positions of each
    frame are sent in one column batch (``rerun.send_columns``) over two timelines: ``timeline``
    (the global frame index, sequences back to back as ``Subject.frame_name`` counts them) and
    ``"time"`` (that index in seconds at the subject's fps). The recording's current time is
    left as it was. ``up_axis=True`` also logs the subject's up axis as static
    ``rerun.ViewCoordinates`` at the root ``"/"``, so that the 3D view shows the subject
    upright.

    Logs into ``recording``, or rerun's current recording (call ``rerun.init(...)`` and
    ``rerun.spawn()`` or ``rerun.save(...)`` first). A ``sequence`` the subject does not have
    raises ``KeyError`` listing the ones it has.
    """
    rr = _require("rerun", "Subject.log_rerun")
    import numpy as np

    names = list(subject.sequences)
    if sequence is not None:
        subject.sequence_positions(sequence)  # KeyError naming the sequences when unknown
        names = [sequence]
    kw = {"recording": recording} if recording is not None else {}
    if up_axis:
        coords = getattr(rr.ViewCoordinates, _VIEW_COORDINATES[subject.up_axis])
        rr.log("/", coords, static=True, **kw)
    faces = np.asarray(subject.faces, dtype=np.uint32)
    rr.log(entity_path, rr.Mesh3D.from_fields(triangle_indices=faces), static=True, **kw)
    n_vertices = subject.n_vertices
    offset = 0
    for name in subject.sequences:
        n = subject.sequence_frames[name]
        if name in names and n > 0:
            positions = subject.sequence_positions(name).reshape(-1, 3)
            frames = np.arange(offset, offset + n, dtype=np.int64)
            rr.send_columns(
                entity_path,
                indexes=[
                    rr.TimeColumn(timeline, sequence=frames),
                    rr.TimeColumn("time", duration=frames / subject.fps),
                ],
                columns=rr.Mesh3D.columns(vertex_positions=positions).partition([n_vertices] * n),
                **kw,
            )
        offset += n


def to_rerun(
    subject: Any,
    application_id: str = "surfcap",
    entity_path: str = "subject",
    *,
    path: Optional[str] = None,
    sequence: Optional[str] = None,
) -> Any:
    """A new ``rerun.RecordingStream`` holding every frame (or one sequence's) as
    ``log_rerun`` logs them, and returns it.

    With ``path``, the recording is written to that ``.rrd`` file and closed, so the file is
    complete (with its footer) when this returns; ``rerun <path>`` opens it. To keep logging
    into a file, make the recording yourself (``rec.save(path)``) and call ``log_rerun``.
    Without ``path``, show the recording with ``rec.spawn()`` or ``rec.notebook_show()``."""
    rr = _require("rerun", "Subject.to_rerun")
    rec = rr.RecordingStream(application_id)
    if path is not None:
        rec.save(str(path))
    log_rerun(subject, entity_path, recording=rec, sequence=sequence)
    if path is not None:
        rec.disconnect()  # flushes and writes the footer
    return rec
