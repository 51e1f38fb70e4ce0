"""surfcap from Python: 4D surface capture (sequences of meshes sharing one topology) turned
into new animations.

Plain numpy in and out: ``(T, 3)`` integer faces, ``(F, V, 3)`` float positions (float32 or
float64, any order or strides), float64 matrices; frames as a global index or
``"sequence:frame"``. Every function mirrors a command of the ``surfcap`` program and gives the
same numbers for the same inputs and seed. Long calls release the GIL; progress shows with
``tqdm`` when it is installed (``set_progress(False)`` hides it). Errors are ``SurfcapError``
with the command line's message. The user guide's Python chapter is docs/src/python.md.
"""

from ._surfcap import __version__, Subject, SurfcapError, ConstraintsMissedWarning, set_progress
from . import reports
from ._surfcap import *  # noqa: F401,F403  (every binding of every area)
from .interop import to_trimesh, to_rerun, log_rerun  # noqa: F401

Subject.to_trimesh = to_trimesh
Subject.to_rerun = to_rerun
Subject.log_rerun = log_rerun

__all__ = [n for n in dir() if not n.startswith("_")]
