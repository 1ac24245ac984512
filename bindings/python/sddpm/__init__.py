"""libsddpm for Python: a thin ctypes layer over the library's C ABI.

Objects (Options, Mesh, Contexts, Model, Polycube, HexMesh, Spline) own their C handle and
free it when collected (or explicitly with ``close()`` / a ``with`` block). Arrays go in and
come out as numpy arrays. Every failing call raises :class:`SddpmError` carrying
the status number, its name and the library's message.

Options are the library's named options ("hex.quality.pillow"; every one with its
type, default and documentation: ``Options().describe()``), given to the build calls
as keyword arguments with underscores for the dots (``hex_quality_pillow=False``), as
a dict (``options={"hex.quality.pillow": False}``) or as an :class:`Options`.

The shared library is found, in order, at ``$SDDPM_LIBRARY``, next to this
package (an installed wheel), in ``target/release`` of the source tree this file
sits in, then by the system's loader (``libsddpm.so``).
"""

from __future__ import annotations

import ctypes as C
import os
import pathlib
from typing import Callable, Iterable, Optional, Sequence

import numpy as np

__all__ = [
    "work",
    "SddpmError",
    "Options",
    "Mesh",
    "Contexts",
    "Model",
    "Polycube",
    "HexMesh",
    "Spline",
    "HEX_FORMATS",
    "load_library",
    "abi_version",
    "version",
    "STATUS",
]

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


class SddpmError(Exception):
    """A failed library call: ``status`` (int), ``name`` (e.g. "INVALID_MESH"), ``message``."""

    def __init__(self, status: int, message: str):
        self.status = status
        self.name = STATUS.get(status, "UNKNOWN")
        self.message = message
        super().__init__(f"{self.name}: {message}")


# ---------------------------------------------------------------- C declarations

class LoadOptions(C.Structure):
    _fields_ = [("weld_tolerance", C.c_double), ("remove_unreferenced", C.c_bool), ("repair_orientation", C.c_bool)]


class MeshReport(C.Structure):
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


class ModelInfo(C.Structure):
    _fields_ = [("parameters", C.c_size_t), ("base_width", C.c_size_t), ("diffusion_steps", C.c_size_t),
                ("trained_epochs", C.c_size_t), ("training_seed", C.c_uint64), ("final_loss", C.c_double)]


class Constraints(C.Structure):
    _fields_ = [("cube", C.c_int32), ("thc", C.c_int32), ("bhc", C.c_int32), ("per_label", C.c_int32 * 11),
                ("allowed_mask", C.c_uint16), ("required_mask", C.c_uint16), ("genus", C.c_int64)]


class CandidateReport(C.Structure):
    _fields_ = [("labels", C.c_int32 * 12), ("stage", C.c_int32), ("in_empty_fraction", C.c_double), ("fit", C.c_double),
                ("mean_target_pcd", C.c_double), ("score", C.c_double), ("chosen", C.c_bool)]


class HexQuality(C.Structure):
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
}

_lib: Optional[C.CDLL] = None


def _candidates() -> Iterable[str]:
    env = os.environ.get("SDDPM_LIBRARY")
    if env:
        yield env
    here = pathlib.Path(__file__).resolve().parent
    yield str(here / "libsddpm.so")
    for up in [here.parent.parent.parent, *here.parents]:
        p = up / "target" / "release" / "libsddpm.so"
        if p.exists():
            yield str(p)
            break
    yield "libsddpm.so"


def load_library() -> C.CDLL:
    """The loaded C library (loaded once, with every signature declared)."""
    global _lib
    if _lib is not None:
        return _lib
    errors = []
    for path in _candidates():
        try:
            lib = C.CDLL(path)
            break
        except OSError as e:
            errors.append(f"{path}: {e}")
    else:
        raise OSError("libsddpm not found (set SDDPM_LIBRARY): " + "; ".join(errors))
    for name, (res, args) in _SIGNATURES.items():
        f = getattr(lib, name)
        f.restype = res
        f.argtypes = args
    _lib = lib
    return lib


def _last_message() -> str:
    lib = load_library()
    need = _SZ(0)
    lib.sddpm_last_error_message(None, 0, C.byref(need))
    if need.value == 0:
        return ""
    buf = C.create_string_buffer(need.value)
    lib.sddpm_last_error_message(buf, need.value, C.byref(need))
    return buf.value.decode("utf-8", "replace")


def _check(status: int) -> None:
    if status != 0:
        raise SddpmError(status, _last_message())


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
        if not self._h:
            raise ValueError(f"{type(self).__name__} is closed")
        return self._h


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


# ---------------------------------------------------------------- Options

_UNDERSCORE_NAMES: Optional[dict] = None


def _option_name(key: str) -> str:
    """The library's name for a keyword: "hex_quality_pillow" -> "hex.quality.pillow"
    (a name with dots, or one the library does not know, is passed on as it is)."""
    global _UNDERSCORE_NAMES
    if "." in key:
        return key
    if _UNDERSCORE_NAMES is None:
        _UNDERSCORE_NAMES = {n.replace(".", "_"): n for n in Options().describe()}
    return _UNDERSCORE_NAMES.get(key, key)


class Options(_Handle):
    """The library's options by name, each checked when set: an unknown name, a value
    of another type or out of range raises SddpmError (INVALID_ARGUMENT, naming the
    option) and leaves the options as they were.

    ``Options({"hex.quality.pillow": False}, hex_map_level=2)``: a dict of names (dots or
    underscores) and keyword arguments (underscores for the dots). A value of None
    unsets an option that may be unset (e.g. ``hex_map_level=None``: the automatic level).
    """

    _free = "sddpm_options_free"

    def __init__(self, options: Optional[dict] = None, **kwargs):
        h = _P()
        _check(load_library().sddpm_options_new(C.byref(h)))
        super().__init__(h)
        self.update(options, **kwargs)

    def set(self, name: str, value) -> "Options":
        lib = load_library()
        n = _option_name(name).encode()
        if value is None:
            _check(lib.sddpm_options_unset(self.handle, n))
        elif isinstance(value, (bool, np.bool_)):
            _check(lib.sddpm_options_set_bool(self.handle, n, bool(value)))
        elif isinstance(value, (int, float, np.integer, np.floating)):
            _check(lib.sddpm_options_set_number(self.handle, n, float(value)))
        elif isinstance(value, str):
            _check(lib.sddpm_options_set_string(self.handle, n, value.encode()))
        else:
            raise SddpmError(1, f"option {name}: {type(value).__name__} is not a number, bool, string or None")
        return self

    def update(self, options=None, **kwargs) -> "Options":
        """Set every option of ``options`` (a dict or another Options), then the keywords."""
        if isinstance(options, Options):
            options = {k: d["value"] for k, d in options.describe().items() if d["value"] != d["default"]}
        for k, v in {**(options or {}), **kwargs}.items():
            self.set(k, v)
        return self

    def get(self, name: str):
        """The option's value (None when unset)."""
        name = _option_name(name)
        d = self.describe()
        if name not in d:
            # the library's refusal, naming it
            _check(load_library().sddpm_options_get_number(self.handle, name.encode(), C.byref(C.c_double())))
        return d[name]["value"]

    def describe(self) -> dict:
        """Every option: name -> {"default", "doc", "nullable", "type", "value"}."""
        return _json(load_library().sddpm_options_describe_json, self.handle)

    def __getitem__(self, name: str):
        return self.get(name)

    def __setitem__(self, name: str, value) -> None:
        self.set(name, value)


def _options(options, kwargs: dict, **named) -> Options:
    """The options of a build call: ``options`` (dict or Options), the keywords, then
    the call's own named arguments (those not None)."""
    o = options if isinstance(options, Options) and not kwargs and all(v is None for v in named.values()) else Options(options, **kwargs)
    for k, v in named.items():
        if v is not None:
            o.set(k, v)
    return o


# ---------------------------------------------------------------- Mesh

class Mesh(_Handle):
    """A checked triangle surface."""

    _free = "sddpm_mesh_free"

    @staticmethod
    def load(path: str | os.PathLike, weld_tolerance: Optional[float] = None, repair_orientation: bool = False) -> "Mesh":
        lib = load_library()
        o = LoadOptions()
        _check(lib.sddpm_load_options_default(C.byref(o)))
        if weld_tolerance is not None:
            o.weld_tolerance = weld_tolerance
        o.repair_orientation = repair_orientation
        h = _P()
        _check(lib.sddpm_mesh_load(os.fsencode(path), C.byref(o), C.byref(h)))
        return Mesh(h)

    @staticmethod
    def from_arrays(vertices, triangles) -> "Mesh":
        """vertices: (n, 3) floats; triangles: (m, 3) non-negative ints."""
        v = np.ascontiguousarray(vertices, dtype=np.float64)
        t = np.asarray(triangles)
        if v.ndim != 2 or v.shape[1] != 3 or t.ndim != 2 or t.shape[1] != 3:
            raise SddpmError(1, f"vertices must be (n, 3) and triangles (m, 3), got {v.shape} and {t.shape}")
        if t.size and (t.min() < 0 or t.max() > 0xFFFFFFFF):
            raise SddpmError(1, "triangle indices must be in 0 .. 2^32 - 1")
        t = np.ascontiguousarray(t, dtype=np.uint32)
        h = _P()
        _check(load_library().sddpm_mesh_new_from_arrays(v.ctypes.data_as(_DP), v.shape[0], t.ctypes.data_as(_U32P), t.shape[0], None, C.byref(h)))
        return Mesh(h)

    def counts(self) -> tuple[int, int]:
        nv, nt = _SZ(), _SZ()
        _check(load_library().sddpm_mesh_counts(self.handle, C.byref(nv), C.byref(nt)))
        return nv.value, nt.value

    def check(self) -> dict:
        r = MeshReport()
        _check(load_library().sddpm_mesh_check(self.handle, C.byref(r)))
        return r.as_dict()

    def validate(self) -> None:
        """Raise SddpmError (INVALID_MESH, naming the problem) unless the mesh can be meshed."""
        _check(load_library().sddpm_mesh_validate(self.handle))

    @property
    def genus(self) -> int:
        g = C.c_int64()
        _check(load_library().sddpm_mesh_genus(self.handle, C.byref(g)))
        return g.value

    @property
    def vertices(self) -> np.ndarray:
        nv, _ = self.counts()
        a = np.empty((nv, 3), dtype=np.float64)
        _check(load_library().sddpm_mesh_copy_vertices(self.handle, a.ctypes.data_as(_DP), a.size))
        return a

    @property
    def triangles(self) -> np.ndarray:
        _, nt = self.counts()
        a = np.empty((nt, 3), dtype=np.uint32)
        _check(load_library().sddpm_mesh_copy_triangles(self.handle, a.ctypes.data_as(_U32P), a.size))
        return a


# ---------------------------------------------------------------- Contexts

class Contexts(_Handle):
    """A stack of contexts (12 labels each, cell-index order)."""

    _free = "sddpm_context_free"

    @staticmethod
    def parse(text: str) -> "Contexts":
        h = _P()
        _check(load_library().sddpm_context_new_from_string(text.encode(), C.byref(h)))
        return Contexts(h)

    @staticmethod
    def from_labels(labels) -> "Contexts":
        a = np.ascontiguousarray(labels, dtype=np.int32).reshape(-1)
        h = _P()
        _check(load_library().sddpm_context_new_from_labels(a.ctypes.data_as(_I32P), a.size, C.byref(h)))
        return Contexts(h)

    @staticmethod
    def from_one_hot(vectors) -> "Contexts":
        a = np.ascontiguousarray(vectors, dtype=np.float32).reshape(-1)
        h = _P()
        _check(load_library().sddpm_context_new_from_one_hot(a.ctypes.data_as(_F32P), a.size, C.byref(h)))
        return Contexts(h)

    @staticmethod
    def from_constraints(cube: int = -1, thc: int = -1, bhc: int = -1, allowed_cells: Optional[Sequence[int]] = None,
                         required_cells: Sequence[int] = (), genus: int = -1) -> "Contexts":
        k = Constraints()
        lib = load_library()
        _check(lib.sddpm_constraints_default(C.byref(k)))
        k.cube, k.thc, k.bhc, k.genus = cube, thc, bhc, genus
        if allowed_cells is not None:
            k.allowed_mask = sum(1 << c for c in allowed_cells)
        k.required_mask = sum(1 << c for c in required_cells)
        h = _P()
        _check(lib.sddpm_context_new_from_constraints(C.byref(k), C.byref(h)))
        return Contexts(h)

    def __len__(self) -> int:
        n = _SZ()
        _check(load_library().sddpm_context_count(self.handle, C.byref(n)))
        return n.value

    def labels(self, i: int = 0) -> np.ndarray:
        a = np.empty(12, dtype=np.int32)
        _check(load_library().sddpm_context_get_labels(self.handle, i, a.ctypes.data_as(_I32P), 12))
        return a

    def one_hot(self, i: int = 0) -> np.ndarray:
        a = np.empty(132, dtype=np.float32)
        _check(load_library().sddpm_context_get_one_hot(self.handle, i, a.ctypes.data_as(_F32P), 132))
        return a

    def genus(self, i: int = 0) -> int:
        g = C.c_int64()
        _check(load_library().sddpm_context_genus(self.handle, i, C.byref(g)))
        return g.value

    def invalid_reason(self, i: int = 0) -> str:
        """'' when the assembly is a valid solid, else why not."""
        buf = C.create_string_buffer(512)
        ok = C.c_bool()
        _check(load_library().sddpm_context_validity(self.handle, i, buf, 512, C.byref(ok)))
        return "" if ok.value else buf.value.decode()

    def write_obj(self, path: str | os.PathLike, i: int = 0) -> None:
        _check(load_library().sddpm_context_write_obj(self.handle, i, os.fsencode(path)))


# ---------------------------------------------------------------- Model and Polycube

class Model(_Handle):
    """The diffusion model (immutable; may be shared by threads)."""

    _free = "sddpm_model_free"

    @staticmethod
    def embedded() -> "Model":
        h = _P()
        _check(load_library().sddpm_model_new_default(C.byref(h)))
        return Model(h)

    @staticmethod
    def from_file(path: str | os.PathLike) -> "Model":
        h = _P()
        _check(load_library().sddpm_model_new_from_file(os.fsencode(path), C.byref(h)))
        return Model(h)

    @staticmethod
    def from_bytes(data: bytes) -> "Model":
        h = _P()
        _check(load_library().sddpm_model_new_from_bytes(data, len(data), C.byref(h)))
        return Model(h)

    def info(self) -> dict:
        i = ModelInfo()
        _check(load_library().sddpm_model_get_info(self.handle, C.byref(i)))
        return {name: getattr(i, name) for name, _ in i._fields_}


STAGES = {0: "pending", 1: "pre-check", 2: "gocc", 3: "tcv", 4: "verified"}


class Polycube(_Handle):
    """The result of a polycube search: every candidate and its verification."""

    _free = "sddpm_polycube_free"

    @staticmethod
    def generate(model: Model, mesh: Mesh, contexts: Optional[Contexts] = None, ratios: Optional[Sequence[float]] = None,
                 seed: Optional[int] = None, steps: Optional[int] = None, progress: Optional[Callable[[float, str], bool]] = None,
                 options=None, **kwargs) -> "Polycube":
        """Contexts given: user-guided; ratios given (7 numbers X1,X2,X3,Y1,Y2,Z1,Z2): automated
        on the full grid; neither: automated over every box. ``progress(fraction, stage)``
        returning False cancels (SddpmError CANCELLED). ``seed`` sets the sampling and the
        sampler seeds, ``steps`` the sampler's steps; other "polycube.*" / "auto.*"
        options by keyword (``polycube_verify_tau_cd=0.02``) or ``options``."""
        lib = load_library()
        o = _options(options, kwargs, **{"polycube.seed": seed, "polycube.sampler.seed": seed, "polycube.sampler.steps": steps})
        r = None
        if ratios is not None:
            if len(ratios) != 7:
                raise SddpmError(1, f"ratios need 7 numbers (X1,X2,X3,Y1,Y2,Z1,Z2), got {len(ratios)}")
            r = (C.c_double * 7)(*ratios)
        cb, box = _progress(progress)
        h = _P()
        st = lib.sddpm_generate_polycube(model.handle, mesh.handle, contexts.handle if contexts else None, None,
                                         C.cast(r, _DP) if r is not None else None, o.handle, cb, None, C.byref(h))
        pc = Polycube(h) if h else None
        if box["error"] is not None:
            raise box["error"]
        _check(st)
        return pc

    @property
    def accepted(self) -> bool:
        return load_library().sddpm_polycube_status(self.handle) == 0

    def require_accepted(self) -> None:
        _check(load_library().sddpm_polycube_status(self.handle))

    @property
    def labels(self) -> np.ndarray:
        a = np.empty(12, dtype=np.int32)
        _check(load_library().sddpm_polycube_labels(self.handle, a.ctypes.data_as(_I32P), 12))
        return a

    def candidates(self) -> list[dict]:
        lib = load_library()
        n = _SZ()
        _check(lib.sddpm_polycube_candidate_count(self.handle, C.byref(n)))
        out = []
        for i in range(n.value):
            c = CandidateReport()
            _check(lib.sddpm_polycube_candidate(self.handle, i, C.byref(c)))
            out.append({"labels": list(c.labels), "stage": STAGES.get(c.stage, str(c.stage)), "in_empty_fraction": c.in_empty_fraction,
                        "fit": c.fit, "mean_target_pcd": c.mean_target_pcd, "score": c.score, "chosen": c.chosen})
        return out

    def report(self) -> dict:
        import json

        lib = load_library()
        need = _SZ()
        lib.sddpm_polycube_report_json(self.handle, None, 0, C.byref(need))
        buf = C.create_string_buffer(need.value)
        _check(lib.sddpm_polycube_report_json(self.handle, buf, need.value, C.byref(need)))
        return json.loads(buf.value.decode())

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """(output points, input samples they came from), each (6144, 3), user coordinates."""
        out = np.empty((6144, 3))
        inp = np.empty((6144, 3))
        _check(load_library().sddpm_polycube_copy_points(self.handle, out.ctypes.data_as(_DP), inp.ctypes.data_as(_DP), out.size))
        return out, inp


def _json(fn, handle) -> dict:
    import json

    need = _SZ()
    fn(handle, None, 0, C.byref(need))
    buf = C.create_string_buffer(need.value)
    _check(fn(handle, buf, need.value, C.byref(need)))
    return json.loads(buf.value.decode())


# ---------------------------------------------------------------- HexMesh and Spline

class HexMesh(_Handle):
    """An all-hex mesh (VTK_HEXAHEDRON order) with its quality."""

    _free = "sddpm_hex_mesh_free"

    @staticmethod
    def build(polycube: Polycube, level: Optional[int] = None, accept_unverified: Optional[bool] = None, hex_candidates: Optional[int] = None,
              progress: Optional[Callable[[float, str], bool]] = None, options=None, **kwargs) -> "HexMesh":
        """From a polycube result, as the main job meshes it (its best candidates, the grid-based
        fallback when none meets the quality goals). ``level`` fixes the octree level (None or -1:
        automatic); other options by keyword (``hex_quality_pillow=False``) or ``options``."""
        lib = load_library()
        named = {"hex.map.level": level if level is not None and level >= 0 else None, "accept_unverified": accept_unverified, "hex_candidates": hex_candidates}
        o = _options(options, kwargs, **named)
        cb, box = _progress(progress)
        h = _P()
        st = lib.sddpm_hex_mesh_build(polycube.handle, o.handle, cb, None, C.byref(h))
        hm = HexMesh(h) if h else None
        if box["error"] is not None:
            raise box["error"]
        _check(st)
        return hm

    @staticmethod
    def from_arrays(nodes, elements) -> "HexMesh":
        x = np.ascontiguousarray(nodes, dtype=np.float64)
        e = np.ascontiguousarray(elements, dtype=np.uint32)
        if x.ndim != 2 or x.shape[1] != 3 or e.ndim != 2 or e.shape[1] != 8:
            raise SddpmError(1, f"nodes must be (n, 3) and elements (m, 8), got {x.shape} and {e.shape}")
        h = _P()
        _check(load_library().sddpm_hex_mesh_new_from_arrays(x.ctypes.data_as(_DP), x.shape[0], e.ctypes.data_as(_U32P), e.shape[0], C.byref(h)))
        return HexMesh(h)

    def counts(self) -> tuple[int, int]:
        n, e = _SZ(), _SZ()
        _check(load_library().sddpm_hex_mesh_counts(self.handle, C.byref(n), C.byref(e)))
        return n.value, e.value

    @property
    def nodes(self) -> np.ndarray:
        a = np.empty((self.counts()[0], 3))
        _check(load_library().sddpm_hex_mesh_copy_nodes(self.handle, a.ctypes.data_as(_DP), a.size))
        return a

    @property
    def elements(self) -> np.ndarray:
        a = np.empty((self.counts()[1], 8), dtype=np.uint32)
        _check(load_library().sddpm_hex_mesh_copy_elements(self.handle, a.ctypes.data_as(_U32P), a.size))
        return a

    @property
    def scaled_jacobian(self) -> np.ndarray:
        a = np.empty(self.counts()[1])
        _check(load_library().sddpm_hex_mesh_copy_scaled_jacobian(self.handle, a.ctypes.data_as(_DP), a.size))
        return a

    def histogram(self, bins: int = 20) -> np.ndarray:
        a = (_SZ * bins)()
        _check(load_library().sddpm_hex_mesh_histogram(self.handle, a, bins))
        return np.array(list(a), dtype=np.int64)

    def quality(self) -> dict:
        q = HexQuality()
        _check(load_library().sddpm_hex_mesh_quality(self.handle, C.byref(q)))
        return {name: getattr(q, name) for name, _ in q._fields_}

    def report(self) -> dict:
        return _json(load_library().sddpm_hex_mesh_report_json, self.handle)

    def write(self, path: str | os.PathLike, fmt: Optional[str] = None) -> None:
        """fmt: "vtu", "vtk", "mesh" or "k" (default: from the file extension)."""
        fmt = fmt or pathlib.Path(path).suffix.lstrip(".").lower()
        if fmt not in HEX_FORMATS:
            raise SddpmError(1, f"unknown hex format {fmt!r} (vtu, vtk, mesh, k)")
        _check(load_library().sddpm_hex_mesh_write(self.handle, os.fsencode(path), HEX_FORMATS[fmt]))


class Spline(_Handle):
    """The TH-spline3D volume and its Bezier extraction."""

    _free = "sddpm_spline_free"

    @staticmethod
    def build(hex_mesh: HexMesh, surface: Optional[Mesh] = None, progress: Optional[Callable[[float, str], bool]] = None,
              options=None, **kwargs) -> "Spline":
        """Fitted to ``surface``, or to the surface the hex mesh was built for; "spline.*"
        options by keyword (``spline_fit_enabled=False``) or ``options``."""
        lib = load_library()
        o = _options(options, kwargs)
        cb, box = _progress(progress)
        h = _P()
        st = lib.sddpm_spline_build(hex_mesh.handle, surface.handle if surface else None, o.handle, cb, None, C.byref(h))
        sp = Spline(h) if h else None
        if box["error"] is not None:
            raise box["error"]
        _check(st)
        return sp

    def counts(self) -> tuple[int, int]:
        e, b = _SZ(), _SZ()
        _check(load_library().sddpm_spline_counts(self.handle, C.byref(e), C.byref(b)))
        return e.value, b.value

    def extraction(self, element: int) -> tuple[np.ndarray, np.ndarray]:
        """(basis ids, operator (n, 64)) of one element; column i + 4j + 16k, u fastest."""
        lib = load_library()
        n = _SZ()
        st = lib.sddpm_spline_element_extraction(self.handle, element, None, None, 0, C.byref(n))
        if st not in (0, 12):
            _check(st)
        ids = np.empty(n.value, dtype=np.uint32)
        op = np.empty((n.value, 64))
        _check(lib.sddpm_spline_element_extraction(self.handle, element, ids.ctypes.data_as(_U32P), op.ctypes.data_as(_DP), n.value, C.byref(n)))
        return ids, op

    def evaluate(self, element: int, u: float, v: float, w: float) -> tuple[np.ndarray, np.ndarray]:
        """The map at (u, v, w) and its Jacobian (3, 3)."""
        x = np.empty(3)
        j = np.empty((3, 3))
        _check(load_library().sddpm_spline_evaluate(self.handle, element, u, v, w, x.ctypes.data_as(_DP), j.ctypes.data_as(_DP)))
        return x, j

    def write(self, folder: str | os.PathLike) -> None:
        """spline.bext, model.k, spline.vtk, spline_control.vtk into folder."""
        _check(load_library().sddpm_spline_write(self.handle, os.fsencode(folder)))

    def report(self) -> dict:
        return _json(load_library().sddpm_spline_report_json, self.handle)


from . import work  # noqa: E402  (the scale-out work unit; imports this module lazily)

#: The issue's name for the context object (a stack of one or more contexts).
Context = Contexts
__all__.append("Context")
