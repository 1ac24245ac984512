"""The C side of the package: the library's declarations, how it is found and
loaded, errors, and the handle base class."""

from __future__ import annotations

import ctypes as C
import errno
import json
import os
import pathlib
from typing import Callable, Iterable, Optional

# Fixed status numbers (include/sddpm.h, docs/errors.md).
STATUS = {
    0: "OK",
    1: "INVALID_ARGUMENT",
    2: "IO",
    3: "PARSE",
    4: "INVALID_MESH",
    5: "INVALID_CONTEXT",
    6: "GENUS_MISMATCH",
    7: "VERIFICATION_FAILED",
    8: "MODEL",
    9: "MESHING_FAILED",
    10: "SPLINE_FAILED",
    11: "CANCELLED",
    12: "BUFFER_TOO_SMALL",
    13: "LIMIT_EXCEEDED",
    14: "INTERNAL",
}

# A bad argument or a bad context text: the caller's value, not the method, is wrong.
_VALUE_STATUSES = {1, 5}


class _StatusInfo:
    """``status`` (int), ``name`` (e.g. "INVALID_MESH") and ``message`` of a failed call."""

    def __init__(self, status: int, message: str):
        self.status = status
        self.name = STATUS.get(status, "UNKNOWN")
        self.message = message
        super().__init__(f"{self.name}: {message}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(status={self.status}, name={self.name!r}, message={self.message!r})"


class SddpmError(_StatusInfo, RuntimeError):
    """The library's method failed on valid arguments (an input that cannot be meshed,
    a genus mismatch, a polycube that fails verification, cancellation, ...):
    ``status``, ``name`` and ``message``."""


class SddpmValueError(_StatusInfo, ValueError):
    """The library refused a value (an option out of range, a bad context, an argument
    of ``run`` the command line refuses): a ValueError with ``status``, ``name`` and
    ``message``."""


# ---------------------------------------------------------------- C declarations

class _Struct(C.Structure):
    """A C struct whose repr shows its fields."""

    def __repr__(self) -> str:
        fields = ", ".join(f"{n}={_plain(getattr(self, n))!r}" for n, *_ in self._fields_)
        return f"{type(self).__name__}({fields})"


def _plain(v):
    return list(v) if isinstance(v, C.Array) else v


class LoadOptions(_Struct):
    _fields_ = [("weld_tolerance", C.c_double), ("remove_unreferenced", C.c_bool), ("repair_orientation", C.c_bool)]


class MeshReport(_Struct):
    _fields_ = [
        ("vertices", C.c_size_t), ("triangles", C.c_size_t), ("edges", C.c_size_t), ("components", C.c_size_t),
        ("boundary_edges", C.c_size_t), ("boundary_loops", C.c_size_t), ("non_manifold_edges", C.c_size_t),
        ("non_manifold_vertices", C.c_size_t), ("inconsistent_edges", C.c_size_t), ("collapsed_triangles", C.c_size_t),
        ("degenerate_triangles", C.c_size_t), ("self_intersecting_pairs", C.c_size_t), ("unreferenced_vertices", C.c_size_t),
        ("non_finite_vertices", C.c_size_t), ("euler_characteristic", C.c_int64), ("genus", C.c_int64),
        ("closed", C.c_bool), ("manifold", C.c_bool), ("orientation_consistent", C.c_bool), ("oriented_outward", C.c_bool),
        ("can_proceed", C.c_bool), ("volume", C.c_double), ("area", C.c_double), ("bbox_min", C.c_double * 3),
        ("bbox_max", C.c_double * 3), ("bbox_diagonal", C.c_double),
    ]

    def as_dict(self) -> dict:
        d = {}
        for name, _ in self._fields_:
            v = getattr(self, name)
            d[name] = list(v) if isinstance(v, C.Array) else v
        return d


class ModelInfo(_Struct):
    _fields_ = [("parameters", C.c_size_t), ("base_width", C.c_size_t), ("diffusion_steps", C.c_size_t),
                ("trained_epochs", C.c_size_t), ("training_seed", C.c_uint64), ("final_loss", C.c_double)]


class Constraints(_Struct):
    _fields_ = [("cube", C.c_int32), ("thc", C.c_int32), ("bhc", C.c_int32), ("per_label", C.c_int32 * 11),
                ("allowed_mask", C.c_uint16), ("required_mask", C.c_uint16), ("genus", C.c_int64)]


class CandidateReport(_Struct):
    _fields_ = [("labels", C.c_int32 * 12), ("stage", C.c_int32), ("in_empty_fraction", C.c_double), ("fit", C.c_double),
                ("mean_target_pcd", C.c_double), ("score", C.c_double), ("chosen", C.c_bool)]


class HexQuality(_Struct):
    _fields_ = [("elements", C.c_size_t), ("nodes", C.c_size_t), ("min_scaled_jacobian", C.c_double),
                ("mean_scaled_jacobian", C.c_double), ("max_scaled_jacobian", C.c_double), ("inverted", C.c_size_t),
                ("hausdorff_relative", C.c_double), ("level", C.c_int32), ("volume", C.c_double), ("input_volume", C.c_double),
                ("verified_polycube", C.c_bool)]


HEX_FORMATS = {"vtu": 0, "vtk": 1, "mesh": 2, "k": 3}

PROGRESS = C.CFUNCTYPE(C.c_int, C.c_double, C.c_char_p, C.c_void_p)
_P = C.c_void_p
_S = C.c_int32
_SZ = C.c_size_t
_DP = C.POINTER(C.c_double)
_U32P = C.POINTER(C.c_uint32)
_I32P = C.POINTER(C.c_int32)
_F32P = C.POINTER(C.c_float)

_SIGNATURES = {
    "sddpm_abi_version": (C.c_uint32, []),
    "sddpm_version_string": (C.c_char_p, []),
    "sddpm_status_name": (C.c_char_p, [C.c_int32]),
    "sddpm_last_error_message": (_S, [C.c_char_p, _SZ, C.POINTER(_SZ)]),
    "sddpm_options_new": (_S, [C.POINTER(_P)]),
    "sddpm_options_free": (None, [_P]),
    "sddpm_options_set_number": (_S, [_P, C.c_char_p, C.c_double]),
    "sddpm_options_set_bool": (_S, [_P, C.c_char_p, C.c_bool]),
    "sddpm_options_set_string": (_S, [_P, C.c_char_p, C.c_char_p]),
    "sddpm_options_unset": (_S, [_P, C.c_char_p]),
    "sddpm_options_get_number": (_S, [_P, C.c_char_p, C.POINTER(C.c_double)]),
    "sddpm_options_get_bool": (_S, [_P, C.c_char_p, C.POINTER(C.c_bool)]),
    "sddpm_options_get_string": (_S, [_P, C.c_char_p, C.c_char_p, _SZ, C.POINTER(_SZ)]),
    "sddpm_options_describe_json": (_S, [_P, C.c_char_p, _SZ, C.POINTER(_SZ)]),
    "sddpm_load_options_default": (_S, [C.POINTER(LoadOptions)]),
    "sddpm_mesh_load": (_S, [C.c_char_p, C.POINTER(LoadOptions), C.POINTER(_P)]),
    "sddpm_mesh_new_from_arrays": (_S, [_DP, _SZ, _U32P, _SZ, C.POINTER(LoadOptions), C.POINTER(_P)]),
    "sddpm_mesh_free": (None, [_P]),
    "sddpm_mesh_counts": (_S, [_P, C.POINTER(_SZ), C.POINTER(_SZ)]),
    "sddpm_mesh_check": (_S, [_P, C.POINTER(MeshReport)]),
    "sddpm_mesh_validate": (_S, [_P]),
    "sddpm_mesh_genus": (_S, [_P, C.POINTER(C.c_int64)]),
    "sddpm_mesh_copy_vertices": (_S, [_P, _DP, _SZ]),
    "sddpm_mesh_copy_triangles": (_S, [_P, _U32P, _SZ]),
    "sddpm_constraints_default": (_S, [C.POINTER(Constraints)]),
    "sddpm_context_new_from_labels": (_S, [_I32P, _SZ, C.POINTER(_P)]),
    "sddpm_context_new_from_string": (_S, [C.c_char_p, C.POINTER(_P)]),
    "sddpm_context_new_from_one_hot": (_S, [_F32P, _SZ, C.POINTER(_P)]),
    "sddpm_context_new_from_constraints": (_S, [C.POINTER(Constraints), C.POINTER(_P)]),
    "sddpm_context_free": (None, [_P]),
    "sddpm_context_count": (_S, [_P, C.POINTER(_SZ)]),
    "sddpm_context_get_labels": (_S, [_P, _SZ, _I32P, _SZ]),
    "sddpm_context_get_one_hot": (_S, [_P, _SZ, _F32P, _SZ]),
    "sddpm_context_genus": (_S, [_P, _SZ, C.POINTER(C.c_int64)]),
    "sddpm_context_validity": (_S, [_P, _SZ, C.c_char_p, _SZ, C.POINTER(C.c_bool)]),
    "sddpm_context_write_obj": (_S, [_P, _SZ, C.c_char_p]),
    "sddpm_model_new_default": (_S, [C.POINTER(_P)]),
    "sddpm_model_new_from_file": (_S, [C.c_char_p, C.POINTER(_P)]),
    "sddpm_model_new_from_bytes": (_S, [C.c_char_p, _SZ, C.POINTER(_P)]),
    "sddpm_model_free": (None, [_P]),
    "sddpm_model_get_info": (_S, [_P, C.POINTER(ModelInfo)]),
    "sddpm_generate_polycube": (_S, [_P, _P, _P, C.POINTER(Constraints), _DP, _P, PROGRESS, C.c_void_p, C.POINTER(_P)]),
    "sddpm_polycube_free": (None, [_P]),
    "sddpm_polycube_status": (_S, [_P]),
    "sddpm_polycube_labels": (_S, [_P, _I32P, _SZ]),
    "sddpm_polycube_candidate_count": (_S, [_P, C.POINTER(_SZ)]),
    "sddpm_polycube_candidate": (_S, [_P, _SZ, C.POINTER(CandidateReport)]),
    "sddpm_polycube_report_json": (_S, [_P, C.c_char_p, _SZ, C.POINTER(_SZ)]),
    "sddpm_polycube_copy_points": (_S, [_P, _DP, _DP, _SZ]),
    "sddpm_hex_mesh_build": (_S, [_P, _P, PROGRESS, C.c_void_p, C.POINTER(_P)]),
    "sddpm_hex_mesh_new_from_arrays": (_S, [_DP, _SZ, _U32P, _SZ, C.POINTER(_P)]),
    "sddpm_hex_mesh_free": (None, [_P]),
    "sddpm_hex_mesh_counts": (_S, [_P, C.POINTER(_SZ), C.POINTER(_SZ)]),
    "sddpm_hex_mesh_copy_nodes": (_S, [_P, _DP, _SZ]),
    "sddpm_hex_mesh_copy_elements": (_S, [_P, _U32P, _SZ]),
    "sddpm_hex_mesh_copy_scaled_jacobian": (_S, [_P, _DP, _SZ]),
    "sddpm_hex_mesh_histogram": (_S, [_P, C.POINTER(_SZ), _SZ]),
    "sddpm_hex_mesh_quality": (_S, [_P, C.POINTER(HexQuality)]),
    "sddpm_hex_mesh_report_json": (_S, [_P, C.c_char_p, _SZ, C.POINTER(_SZ)]),
    "sddpm_hex_mesh_write": (_S, [_P, C.c_char_p, C.c_int32]),
    "sddpm_spline_build": (_S, [_P, _P, _P, PROGRESS, C.c_void_p, C.POINTER(_P)]),
    "sddpm_spline_free": (None, [_P]),
    "sddpm_spline_counts": (_S, [_P, C.POINTER(_SZ), C.POINTER(_SZ)]),
    "sddpm_spline_element_extraction": (_S, [_P, _SZ, _U32P, _DP, _SZ, C.POINTER(_SZ)]),
    "sddpm_spline_evaluate": (_S, [_P, _SZ, C.c_double, C.c_double, C.c_double, _DP, _DP]),
    "sddpm_spline_write": (_S, [_P, C.c_char_p]),
    "sddpm_spline_report_json": (_S, [_P, C.c_char_p, _SZ, C.POINTER(_SZ)]),
    "sddpm_run": (_S, [C.POINTER(C.c_char_p), _SZ, PROGRESS, C.c_void_p]),
    "sddpm_run_arguments_json": (_S, [C.c_char_p, _SZ, C.POINTER(_SZ)]),
}

_lib: Optional[C.CDLL] = None
_lib_path: Optional[str] = None


def _candidates() -> Iterable[str]:
    """Where the library is looked for, in order: the one bundled in this package (an
    installed wheel: libsddpm*.so beside this file), $SDDPM_LIBRARY, target/release of
    the source tree this package sits in (or $CARGO_TARGET_DIR/release), the system's loader."""
    here = pathlib.Path(__file__).resolve().parent
    yield from sorted(str(p) for p in here.glob("libsddpm*.so"))
    env = os.environ.get("SDDPM_LIBRARY")
    if env:
        yield env
    target = os.environ.get("CARGO_TARGET_DIR")
    if target:
        yield str(pathlib.Path(target) / "release" / "libsddpm.so")
    for up in here.parents:
        p = up / "target" / "release" / "libsddpm.so"
        if p.exists():
            yield str(p)
            break
    yield "libsddpm.so"


def load_library() -> C.CDLL:
    """The loaded C library (loaded once, with every signature declared)."""
    global _lib, _lib_path
    if _lib is not None:
        return _lib
    errors = []
    for path in _candidates():
        if os.sep in path and not os.path.exists(path):
            errors.append(f"{path}: no such file")
            continue
        try:
            lib = C.CDLL(path)
            break
        except OSError as e:
            errors.append(f"{path}: {e}")
    else:
        raise OSError("libsddpm not found (install the package with pip, or set SDDPM_LIBRARY to libsddpm.so): " + "; ".join(errors))
    for name, (res, args) in _SIGNATURES.items():
        f = getattr(lib, name)
        f.restype = res
        f.argtypes = args
    _lib, _lib_path = lib, path
    return lib


def library_path() -> str:
    """The path of the loaded library (as it was found: see :func:`load_library`)."""
    load_library()
    return _lib_path


def _last_message() -> str:
    lib = load_library()
    need = _SZ(0)
    lib.sddpm_last_error_message(None, 0, C.byref(need))
    if need.value == 0:
        return ""
    buf = C.create_string_buffer(need.value)
    lib.sddpm_last_error_message(buf, need.value, C.byref(need))
    return buf.value.decode("utf-8", "replace")


def _error(status: int, message: str) -> Exception:
    """The exception for a failed call: a bad argument or context is a
    :class:`SddpmValueError` (a ValueError), every other failure an :class:`SddpmError`."""
    cls = SddpmValueError if status in _VALUE_STATUSES else SddpmError
    return cls(status, message)


def _check(status: int) -> None:
    if status != 0:
        raise _error(status, _last_message())


def _value_error(message: str) -> SddpmValueError:
    return SddpmValueError(1, message)


def _existing_file(path, what: str) -> bytes:
    """``path`` (str or os.PathLike; TypeError otherwise) encoded for C; FileNotFoundError
    when no file is there."""
    try:
        p = os.fspath(path)
    except TypeError:
        raise TypeError(f"{what} must be a str or os.PathLike, not {type(path).__name__}") from None
    if not os.path.exists(p):
        raise FileNotFoundError(errno.ENOENT, f"{what}: no such file", str(p))
    return os.fsencode(p)


def _path(path, what: str) -> bytes:
    try:
        return os.fsencode(os.fspath(path))
    except TypeError:
        raise TypeError(f"{what} must be a str or os.PathLike, not {type(path).__name__}") from None


def _require(obj, cls, what: str):
    """``obj`` when it is a ``cls`` (TypeError otherwise)."""
    if not isinstance(obj, cls):
        raise TypeError(f"{what} must be a sddpm.{cls.__name__}, not {type(obj).__name__}")
    return obj


def abi_version() -> int:
    return load_library().sddpm_abi_version()


def version() -> str:
    return load_library().sddpm_version_string().decode()


class _Handle:
    _free = ""

    def __init__(self, handle: C.c_void_p):
        self._h = handle

    def close(self) -> None:
        h, self._h = getattr(self, "_h", None), None
        if h:
            getattr(load_library(), self._free)(h)

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def handle(self) -> C.c_void_p:
        if not getattr(self, "_h", None):
            raise ValueError(f"{type(self).__name__} is closed")
        return self._h

    def _summary(self) -> str:
        return ""

    def __repr__(self) -> str:
        if not getattr(self, "_h", None):
            return f"<sddpm.{type(self).__name__} (closed)>"
        try:
            s = self._summary()
        except Exception as e:  # noqa: BLE001 - a repr never raises
            s = f"? ({e})"
        return f"<sddpm.{type(self).__name__} {s}>"


def _progress(fn: Optional[Callable[[float, str], bool]]):
    """A C callback for fn (or NULL), and a box that keeps a raised exception."""
    box = {"error": None}
    if fn is None:
        return PROGRESS(), box

    def call(fraction, stage, _user):
        try:
            return 0 if fn(fraction, stage.decode() if stage else "") is not False else 1
        except BaseException as e:  # noqa: BLE001 - reraised after the C call
            box["error"] = e
            return 1

    return PROGRESS(call), box


def _json(fn, *args):
    """The JSON a ``*_json(..., buf, len, needed)`` call writes, parsed."""
    need = _SZ()
    fn(*args, None, 0, C.byref(need))
    buf = C.create_string_buffer(need.value)
    _check(fn(*args, buf, need.value, C.byref(need)))
    return json.loads(buf.value.decode())
