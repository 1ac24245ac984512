"""The library's objects: options, meshes, contexts, the model, polycube results,
hex meshes and splines (each owns its C handle)."""

from __future__ import annotations

import ctypes as C
import difflib
import os
import pathlib
from typing import Callable, Optional, Sequence

import numpy as np

from ._capi import (_DP, _F32P, _I32P, _P, _SZ, _U32P, HEX_FORMATS, CandidateReport, Constraints, HexQuality, LoadOptions,
                    MeshReport, ModelInfo, _check, _existing_file, _Handle, _json, _path, _progress, _require, _value_error,
                    load_library)

# ---------------------------------------------------------------- Options

_UNDERSCORE_NAMES: Optional[dict] = None


_TYPES: Optional[dict] = None


def _option_types() -> dict:
    """Every option's name -> its type ("number", "integer", "bool", "string")."""
    global _TYPES
    if _TYPES is None:
        _TYPES = {n: d["type"] for n, d in Options().describe().items()}
    return _TYPES


def _option_name(key: str) -> str:
    """The library's name for a keyword: "hex_quality_pillow" -> "hex.quality.pillow"
    (a name with dots, or one the library does not know, is passed on as it is)."""
    global _UNDERSCORE_NAMES
    if not isinstance(key, str):
        raise TypeError(f"an option name is a str, not {type(key).__name__}")
    if "." in key:
        return key
    if _UNDERSCORE_NAMES is None:
        _UNDERSCORE_NAMES = {n.replace(".", "_"): n for n in _option_types()}
    return _UNDERSCORE_NAMES.get(key, key)


_PY_TYPES = {"number": "a number (int or float)", "integer": "a whole number", "bool": "a bool", "string": "a str"}


def _type_matches(kind: str, value) -> bool:
    if kind == "bool":
        return isinstance(value, (bool, np.bool_))
    if kind in ("number", "integer"):
        # a float for an integer option is the library's to refuse (ValueError) unless whole
        return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
    return isinstance(value, str)


class Options(_Handle):
    """The library's options by name, each checked when set: an unknown name or a value
    out of range raises SddpmValueError (a ValueError; INVALID_ARGUMENT, naming the
    option), a value of another type TypeError, and the options stay as they were.

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
        """Set one option. TypeError for a value of another type than the option's,
        SddpmValueError (a ValueError) for an unknown name or a value out of range."""
        lib = load_library()
        full = _option_name(name)
        kind = _option_types().get(full)
        if value is not None and kind is not None and not _type_matches(kind, value):
            raise TypeError(f"option {full} takes {_PY_TYPES.get(kind, kind)}, not {type(value).__name__}")
        n = full.encode()
        if value is None:
            _check(lib.sddpm_options_unset(self.handle, n))
        elif isinstance(value, (bool, np.bool_)):
            _check(lib.sddpm_options_set_bool(self.handle, n, bool(value)))
        elif isinstance(value, (int, float, np.integer, np.floating)):
            _check(lib.sddpm_options_set_number(self.handle, n, float(value)))
        elif isinstance(value, str):
            _check(lib.sddpm_options_set_string(self.handle, n, value.encode()))
        else:
            raise TypeError(f"option {name}: {type(value).__name__} is not a number, bool, str or None")
        return self

    def update(self, options=None, **kwargs) -> "Options":
        """Set every option of ``options`` (a dict or another Options), then the keywords
        (an unknown keyword is a TypeError, as for any Python call)."""
        if isinstance(options, Options):
            options = {k: d["value"] for k, d in options.describe().items() if d["value"] != d["default"]}
        elif options is not None and not isinstance(options, dict):
            raise TypeError(f"options must be a dict or a sddpm.Options, not {type(options).__name__}")
        for k in kwargs:
            if _option_name(k) not in _option_types():
                close = difflib.get_close_matches(k, [n.replace(".", "_") for n in _option_types()], n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise TypeError(f"unknown option keyword {k!r}{hint}; Options().describe() lists them all")
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

    def changed(self) -> dict:
        """The options whose value is not the default: name -> value."""
        return {k: d["value"] for k, d in self.describe().items() if d["value"] != d["default"]}

    def _summary(self) -> str:
        c = self.changed()
        return ", ".join(f"{k}={v!r}" for k, v in c.items()) if c else "(defaults)"


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
        """Read an OBJ, STL or OFF file (FileNotFoundError when it is not there)."""
        p = _existing_file(path, "mesh file")
        lib = load_library()
        o = LoadOptions()
        _check(lib.sddpm_load_options_default(C.byref(o)))
        if weld_tolerance is not None:
            o.weld_tolerance = weld_tolerance
        o.repair_orientation = repair_orientation
        h = _P()
        _check(lib.sddpm_mesh_load(p, C.byref(o), C.byref(h)))
        return Mesh(h)

    @staticmethod
    def from_arrays(vertices, triangles) -> "Mesh":
        """vertices: (n, 3) floats; triangles: (m, 3) non-negative ints."""
        v = np.ascontiguousarray(vertices, dtype=np.float64)
        t = np.asarray(triangles)
        if v.ndim != 2 or v.shape[1] != 3 or t.ndim != 2 or t.shape[1] != 3:
            raise _value_error(f"vertices must be (n, 3) and triangles (m, 3), got {v.shape} and {t.shape}")
        if t.size and (t.min() < 0 or t.max() > 0xFFFFFFFF):
            raise _value_error("triangle indices must be in 0 .. 2^32 - 1")
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

    def _summary(self) -> str:
        nv, nt = self.counts()
        return f"{nv} vertices, {nt} triangles"


# ---------------------------------------------------------------- Contexts

class Contexts(_Handle):
    """A stack of contexts (12 labels each, cell-index order)."""

    _free = "sddpm_context_free"

    @staticmethod
    def parse(text: str) -> "Contexts":
        """Contexts from text: 12 labels a context, separated by ";" (SddpmValueError when refused)."""
        if not isinstance(text, str):
            raise TypeError(f"contexts text must be a str, not {type(text).__name__}")
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
        _check(load_library().sddpm_context_write_obj(self.handle, i, _path(path, "path")))

    def _summary(self) -> str:
        n = len(self)
        return f"{n} context{'s' if n != 1 else ''}, first labels {self.labels(0).tolist() if n else []}"


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
        p = _existing_file(path, "weights file")
        h = _P()
        _check(load_library().sddpm_model_new_from_file(p, C.byref(h)))
        return Model(h)

    @staticmethod
    def from_bytes(data: bytes) -> "Model":
        if not isinstance(data, (bytes, bytearray)):
            raise TypeError(f"data must be bytes, not {type(data).__name__}")
        data = bytes(data)
        h = _P()
        _check(load_library().sddpm_model_new_from_bytes(data, len(data), C.byref(h)))
        return Model(h)

    def info(self) -> dict:
        i = ModelInfo()
        _check(load_library().sddpm_model_get_info(self.handle, C.byref(i)))
        return {name: getattr(i, name) for name, _ in i._fields_}

    def _summary(self) -> str:
        i = self.info()
        return f"{i['parameters']} parameters, {i['trained_epochs']} epochs"


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
        _require(model, Model, "model")
        _require(mesh, Mesh, "mesh")
        if contexts is not None:
            _require(contexts, Contexts, "contexts")
        lib = load_library()
        o = _options(options, kwargs, **{"polycube.seed": seed, "polycube.sampler.seed": seed, "polycube.sampler.steps": steps})
        r = None
        if ratios is not None:
            if len(ratios) != 7:
                raise _value_error(f"ratios need 7 numbers (X1,X2,X3,Y1,Y2,Z1,Z2), got {len(ratios)}")
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
        return _json(load_library().sddpm_polycube_report_json, self.handle)

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """(output points, input samples they came from), each (6144, 3), user coordinates."""
        out = np.empty((6144, 3))
        inp = np.empty((6144, 3))
        _check(load_library().sddpm_polycube_copy_points(self.handle, out.ctypes.data_as(_DP), inp.ctypes.data_as(_DP), out.size))
        return out, inp

    def _summary(self) -> str:
        n = _SZ()
        _check(load_library().sddpm_polycube_candidate_count(self.handle, C.byref(n)))
        return f"{'accepted' if self.accepted else 'not accepted'}, labels {self.labels.tolist()}, {n.value} candidates"


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
        _require(polycube, Polycube, "polycube")
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
            raise _value_error(f"nodes must be (n, 3) and elements (m, 8), got {x.shape} and {e.shape}")
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
        p = _path(path, "path")
        fmt = fmt or pathlib.Path(os.fsdecode(p)).suffix.lstrip(".").lower()
        if fmt not in HEX_FORMATS:
            raise _value_error(f"unknown hex format {fmt!r} (vtu, vtk, mesh, k)")
        _check(load_library().sddpm_hex_mesh_write(self.handle, p, HEX_FORMATS[fmt]))

    def to_meshio(self):
        """The mesh as a ``meshio.Mesh`` (one "hexahedron" block, VTK node order, with the
        cell data "scaled_jacobian"); needs the meshio package."""
        try:
            import meshio
        except ImportError as e:
            raise ImportError("HexMesh.to_meshio needs the meshio package: pip install meshio (or pip install 'sddpm[meshio]')") from e
        return meshio.Mesh(self.nodes, [("hexahedron", self.elements.astype(np.int64))], cell_data={"scaled_jacobian": [self.scaled_jacobian]})

    def _summary(self) -> str:
        q = self.quality()
        return f"{q['nodes']} nodes, {q['elements']} elements, min scaled Jacobian {q['min_scaled_jacobian']:.3f}"


class Spline(_Handle):
    """The TH-spline3D volume and its Bezier extraction."""

    _free = "sddpm_spline_free"

    @staticmethod
    def build(hex_mesh: HexMesh, surface: Optional[Mesh] = None, progress: Optional[Callable[[float, str], bool]] = None,
              options=None, **kwargs) -> "Spline":
        """Fitted to ``surface``, or to the surface the hex mesh was built for; "spline.*"
        options by keyword (``spline_fit_enabled=False``) or ``options``."""
        _require(hex_mesh, HexMesh, "hex_mesh")
        if surface is not None:
            _require(surface, Mesh, "surface")
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
        """spline.bext, model.k, spline.vtu, spline_control.vtk into folder."""
        _check(load_library().sddpm_spline_write(self.handle, _path(folder, "folder")))

    def report(self) -> dict:
        return _json(load_library().sddpm_spline_report_json, self.handle)

    def _summary(self) -> str:
        e, b = self.counts()
        return f"{e} elements, {b} basis functions"
