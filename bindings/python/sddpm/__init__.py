"""libsddpm for Python: a thin ctypes layer over the library's C ABI.

Objects (Options, Mesh, Contexts, Model, Polycube, HexMesh, Spline) own their C handle and
free it when collected (or explicitly with ``close()`` / a ``with`` block). Arrays go in and
come out as numpy arrays. :func:`run` is the command line's main job (``sddpm run``)
with its option names. Errors: FileNotFoundError for a missing file, TypeError for a
value of the wrong type, :class:`SddpmValueError` (a ValueError) for a value the
library refuses, :class:`SddpmError` (a RuntimeError) when a method fails; the last
two carry the status number, its name and the library's message.

Options are the library's named options ("hex.quality.pillow"; every one with its
type, default and documentation: ``Options().describe()``), given to the build calls
as keyword arguments with underscores for the dots (``hex_quality_pillow=False``), as
a dict (``options={"hex.quality.pillow": False}``) or as an :class:`Options`.

The shared library is found, in order, in this package (``pip install`` builds it
into the package), at ``$SDDPM_LIBRARY``, in ``$CARGO_TARGET_DIR/release`` or
``target/release`` of the source tree this file sits in, then by the system's
loader (``libsddpm.so``); :func:`library_path` says which.
"""

from __future__ import annotations

from ._capi import (HEX_FORMATS, STATUS, SddpmError, SddpmValueError, abi_version, library_path, load_library,
                    version)
from ._objects import STAGES, Contexts, HexMesh, Mesh, Model, Options, Polycube, Spline
from ._run import run, run_arguments

__all__ = [
    "run",
    "run_arguments",
    "work",
    "SddpmError",
    "SddpmValueError",
    "Options",
    "Mesh",
    "Contexts",
    "Context",
    "Model",
    "Polycube",
    "HexMesh",
    "Spline",
    "HEX_FORMATS",
    "STAGES",
    "load_library",
    "library_path",
    "abi_version",
    "version",
    "STATUS",
]

from . import work  # noqa: E402  (the scale-out work unit; imports this module lazily)

#: Another name for the context object (a stack of one or more contexts).
Context = Contexts
