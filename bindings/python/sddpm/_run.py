"""``sddpm.run``: the main job of ``sddpm run`` (polycube, hex mesh, spline, every
export and the report) into a folder, with the command's own option names."""

from __future__ import annotations

import ctypes as C
import difflib
import json
import numbers
import os
from typing import Callable, Optional

import numpy as np

from ._capi import _check, _json, _progress, load_library

_ARGUMENTS: Optional[list] = None


def run_arguments() -> list[dict]:
    """The options :func:`run` takes: those of ``sddpm run --help``, each a dict with
    "name" (the command line's, e.g. "no-spline"; the keyword is "no_spline"), "kind"
    ("flag": True or False, "value": one value, "list": a str or a list of them,
    "positional": the mesh), "type" ("bool", "int", "number", "string", "path"),
    "required", "default" and "help"."""
    global _ARGUMENTS
    if _ARGUMENTS is None:
        _ARGUMENTS = _json(load_library().sddpm_run_arguments_json)
    return [dict(a) for a in _ARGUMENTS]


def _keywords() -> dict:
    return {a["name"].replace("-", "_"): a for a in run_arguments() if a["kind"] != "positional" and a["name"] != "output"}


def _fspath(value, what: str) -> str:
    try:
        return os.fsdecode(os.fspath(value))
    except TypeError:
        raise TypeError(f"{what} must be a str or os.PathLike, not {type(value).__name__}") from None


def _word(key: str, arg: dict, value) -> str:
    """One value of option ``key`` as the command line writes it (TypeError for a value
    of another type; the parser refuses bad values with a ValueError)."""
    t = arg["type"]
    if t == "path":
        p = _fspath(value, f"option {key}")
        if not os.path.exists(p):
            raise FileNotFoundError(2, f"option {key}: no such file", p)
        return p
    if t == "int":
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Integral, np.integer)):
            raise TypeError(f"option {key} takes an int, not {type(value).__name__}")
        return str(int(value))
    if t == "number":
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.floating, np.integer)):
            raise TypeError(f"option {key} takes a number, not {type(value).__name__}")
        return repr(float(value))
    if not isinstance(value, str):
        raise TypeError(f"option {key} takes a str, not {type(value).__name__}")
    return value


def _arguments(path, out, options: dict) -> list[str]:
    """The arguments of ``sddpm run`` for a call of :func:`run`."""
    mesh = _fspath(path, "path")
    if not os.path.exists(mesh):
        raise FileNotFoundError(2, "mesh file: no such file", mesh)
    args = ["--output=" + _fspath(out, "out")]
    known = _keywords()
    for key, value in options.items():
        arg = known.get(key)
        if arg is None:
            close = difflib.get_close_matches(key, list(known), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise TypeError(f"run() got an unexpected keyword argument {key!r}{hint}; sddpm.run_arguments() lists the options")
        flag = "--" + arg["name"]
        if value is None:
            continue
        if arg["kind"] == "flag":
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"option {key} is a flag: True or False, not {type(value).__name__}")
            if value:
                args.append(flag)
        elif arg["kind"] == "list":
            values = [value] if isinstance(value, str) else value
            if not isinstance(values, (list, tuple)):
                raise TypeError(f"option {key} takes a str or a list of str, not {type(value).__name__}")
            args += [f"{flag}={_word(key, arg, v)}" for v in values]
        else:
            args.append(f"{flag}={_word(key, arg, value)}")
    return args + ["--", mesh]


def run(path, out, *, progress: Optional[Callable[[float, str], bool]] = None, **options) -> dict:
    """The main job, as ``sddpm run PATH -o OUT [options]``: polycube, all-hex mesh,
    spline, every export, report.json and report.html in the folder ``out`` (new or
    empty, unless ``force=True``). The options are those of ``sddpm run --help`` with
    underscores for the dashes: ``level=2``, ``no_spline=True``, ``labels="THC+Z,0,..."``
    (or a list of contexts), ``goal_hausdorff=0.02``, ``strict=True``, ...
    (:func:`run_arguments` lists them); None leaves an option at its default.
    ``progress(fraction, stage)`` returning False cancels. Returns report.json's content.

    FileNotFoundError for a missing mesh (or constraints / weights) file, TypeError for an
    unknown option or a value of the wrong type, SddpmValueError (a ValueError) for a
    value the command refuses, SddpmError when the job fails (a mesh that cannot be
    meshed, a genus mismatch, cancellation, ...)."""
    args = _arguments(path, out, options)
    lib = load_library()
    argv = (C.c_char_p * len(args))(*[os.fsencode(a) for a in args])
    cb, box = _progress(progress)
    st = lib.sddpm_run(argv, len(args), cb, None)
    if box["error"] is not None:
        raise box["error"]
    _check(st)
    with open(os.path.join(_fspath(out, "out"), "report.json"), encoding="utf-8") as f:
        return json.load(f)
