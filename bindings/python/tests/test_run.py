"""pytest for ``sddpm.run`` (the command line's main job), the reprs, ``to_meshio``
and how the package finds its library (run by ctest: `python_bindings`)."""
import json
import os
import pathlib
import re
import subprocess
import sys
import types

import numpy as np
import pytest

import sddpm

ROOT = pathlib.Path(__file__).resolve().parents[3]
DATA = ROOT / "tests" / "data" / "meshes"
HOLE = DATA / "cgal_hole.off"
THC = "THC+Z,0,0,0,0,0,0,0,0,0,0,0"
# a quick run: user-guided, few sampler steps, a fixed octree level
QUICK = dict(labels=THC, steps=10, level=1)


def cli_binary():
    """The `sddpm` command beside the loaded library (the same cargo build), if there."""
    p = pathlib.Path(sddpm.library_path()).parent / "sddpm"
    return p if p.is_file() and os.access(p, os.X_OK) else None


def test_run_writes_what_the_command_writes(tmp_path):
    seen = []
    report = sddpm.run(HOLE, tmp_path / "py", progress=lambda f, s: seen.append(f) or True, **QUICK)
    assert seen and max(seen) <= 1.0
    out = tmp_path / "py"
    for f in ["polycube.obj", "hex.vtu", "hex.vtk", "hex.mesh", "hex.k", "spline.bext", "model.k", "report.json", "report.html"]:
        assert (out / f).is_file(), f
    assert report == json.loads((out / "report.json").read_text())
    assert report["hex"]["inverted"] == 0 and report["polycube"]["labels"][0] == 2
    # the report's command is the command line that does the same
    assert report["command"].startswith("sddpm run --output=") and "--labels=" + THC in report["command"]
    exe = cli_binary()
    if exe is None:
        pytest.skip("no sddpm command beside the library")
    cmd = [str(exe), "run", str(HOLE), "-o", str(tmp_path / "cli"), "--labels", THC, "--steps", "10", "--level", "1", "-q"]
    subprocess.run(cmd, check=True)
    cli = json.loads((tmp_path / "cli" / "report.json").read_text())
    assert [f["name"] for f in cli["files"]] == [f["name"] for f in report["files"]]
    for k in ["elements", "min_scaled_jacobian", "mean_scaled_jacobian", "inverted"]:
        assert cli["hex"][k] == report["hex"][k], k
    assert cli["spline"]["basis_functions"] == report["spline"]["basis_functions"]


def test_run_options_are_the_commands(tmp_path):
    names = {a["name"] for a in sddpm.run_arguments()}
    assert {"mesh", "output", "level", "no-spline", "labels", "goal-hausdorff", "strict", "force", "weld-tolerance"} <= names
    kinds = {a["name"]: (a["kind"], a["type"]) for a in sddpm.run_arguments()}
    assert kinds["level"] == ("value", "int") and kinds["no-spline"] == ("flag", "bool") and kinds["labels"] == ("list", "string")
    exe = cli_binary()
    if exe is None:
        pytest.skip("no sddpm command beside the library")
    help_text = subprocess.run([str(exe), "run", "--help"], check=True, capture_output=True, text=True).stdout
    longs = set(re.findall(r"^\s+(?:-\w, )?--([a-z0-9-]+)", help_text, re.M)) - {"help"}
    assert longs == names - {"mesh"}


def test_run_options_and_flags(tmp_path):
    # a flag, a list, a number, an int, a path-valued option, and force on a used folder
    r = sddpm.run(HOLE, tmp_path / "a", labels=[THC], steps=10, level=1, no_spline=True, goal_hausdorff=0.02, weld_tolerance=1e-9)
    assert r["spline"] is None and not (tmp_path / "a" / "spline.bext").exists()
    assert "--no-spline" in r["command"] and "--goal-hausdorff=0.02" in r["command"]
    with pytest.raises(sddpm.SddpmValueError, match="not empty"):
        sddpm.run(HOLE, tmp_path / "a", no_spline=True, **QUICK)
    (tmp_path / "a" / "mine.txt").write_text("kept")
    sddpm.run(HOLE, tmp_path / "a", no_spline=True, force=True, no_visible_retry=False, **QUICK)
    assert (tmp_path / "a" / "mine.txt").read_text() == "kept"
    c = tmp_path / "constraints.json"
    c.write_text(json.dumps({"thc": 1, "cube": 0, "bhc": 0}))
    r = sddpm.run(HOLE, tmp_path / "b", constraints=c, steps=10, level=1, no_spline=True)
    assert r["hex"]["inverted"] == 0


def test_run_errors(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(FileNotFoundError):
        sddpm.run(tmp_path / "missing.obj", out)
    with pytest.raises(FileNotFoundError):
        sddpm.run(HOLE, out, constraints=tmp_path / "missing.json")
    with pytest.raises(TypeError, match="unexpected keyword argument 'levl'.*'level'"):
        sddpm.run(HOLE, out, levl=2)
    with pytest.raises(TypeError, match="option level takes an int"):
        sddpm.run(HOLE, out, level="2")
    with pytest.raises(TypeError, match="option level takes an int"):
        sddpm.run(HOLE, out, level=True)
    with pytest.raises(TypeError, match="flag"):
        sddpm.run(HOLE, out, no_spline=1)
    with pytest.raises(TypeError):
        sddpm.run(HOLE, out, labels=3)
    with pytest.raises(TypeError):
        sddpm.run(42, out)
    with pytest.raises(sddpm.SddpmValueError, match="--level") as e:
        sddpm.run(HOLE, out, level=-1)
    assert e.value.name == "INVALID_ARGUMENT" and "Usage" not in e.value.message
    with pytest.raises(ValueError, match="--goal-hausdorff"):
        sddpm.run(HOLE, out, goal_hausdorff=-1.0)
    with pytest.raises(ValueError, match="--sampler"):
        sddpm.run(HOLE, out, sampler="sideways")
    with pytest.raises(ValueError):
        sddpm.run(HOLE, out, labels="cube,0,0")
    assert not out.exists()  # every refusal above comes before the folder is made
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.run(DATA / "bad" / "cgal_cow.off", out)
    assert e.value.name == "INVALID_MESH" and isinstance(e.value, RuntimeError)
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.run(HOLE, tmp_path / "g", labels="cube,0,0,0,0,0,0,0,0,0,0,0", steps=10)
    assert e.value.name == "GENUS_MISMATCH"
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.run(HOLE, tmp_path / "c", progress=lambda f, s: False, **QUICK)
    assert e.value.name == "CANCELLED"


def test_reprs(tmp_path):
    model = sddpm.Model.embedded()
    mesh = sddpm.Mesh.load(HOLE)
    ctx = sddpm.Contexts.parse(THC)
    pc = sddpm.Polycube.generate(model, mesh, ctx, steps=10)
    hexm = sddpm.HexMesh.build(pc, level=1)
    sp = sddpm.Spline.build(hexm)
    nv, nt = mesh.counts()
    assert repr(mesh) == f"<sddpm.Mesh {nv} vertices, {nt} triangles>"
    assert repr(ctx).startswith("<sddpm.Contexts 1 context, first labels [2, 0")
    assert "parameters" in repr(model)
    assert re.match(r"<sddpm.Polycube (accepted|not accepted), labels \[2, .*\], 1 candidates>", repr(pc))
    assert f"{hexm.counts()[1]} elements" in repr(hexm) and "min scaled Jacobian" in repr(hexm)
    assert f"{sp.counts()[1]} basis functions" in repr(sp)
    assert repr(sddpm.Options()) == "<sddpm.Options (defaults)>"
    assert repr(sddpm.Options(hex_map_level=2)) == "<sddpm.Options hex.map.level=2>"
    e = sddpm.SddpmError(4, "open surface")
    assert repr(e) == "SddpmError(status=4, name='INVALID_MESH', message='open surface')" and str(e) == "INVALID_MESH: open surface"
    assert repr(sddpm.SddpmValueError(1, "x")).startswith("SddpmValueError(status=1")
    mesh.close()
    assert repr(mesh) == "<sddpm.Mesh (closed)>"
    # every public class has its own repr (not object's)
    for name in sddpm.__all__:
        obj = getattr(sddpm, name)
        if isinstance(obj, type):
            assert obj.__repr__ is not object.__repr__, name


def test_to_meshio(monkeypatch):
    cube = sddpm.HexMesh.from_arrays([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], [list(range(8))])
    monkeypatch.setitem(sys.modules, "meshio", None)  # as if it were not installed
    with pytest.raises(ImportError, match="pip install meshio"):
        cube.to_meshio()

    class FakeMesh:
        def __init__(self, points, cells, cell_data=None):
            self.points, self.cells, self.cell_data = points, cells, cell_data

    monkeypatch.setitem(sys.modules, "meshio", types.SimpleNamespace(Mesh=FakeMesh))
    m = cube.to_meshio()
    assert m.points.shape == (8, 3) and m.cells[0][0] == "hexahedron" and m.cells[0][1].tolist() == [list(range(8))]
    assert m.cell_data["scaled_jacobian"][0].tolist() == pytest.approx([1.0])


def test_to_meshio_real(tmp_path):
    meshio = pytest.importorskip("meshio")
    mesh = sddpm.Mesh.load(HOLE)
    pc = sddpm.Polycube.generate(sddpm.Model.embedded(), mesh, sddpm.Contexts.parse(THC), steps=10)
    hexm = sddpm.HexMesh.build(pc, level=1)
    m = hexm.to_meshio()
    meshio.write(tmp_path / "hex.vtu", m)
    back = meshio.read(tmp_path / "hex.vtu")
    assert back.cells_dict["hexahedron"].shape == (hexm.counts()[1], 8)
    np.testing.assert_allclose(back.points, hexm.nodes)


def test_library_is_found():
    p = sddpm.library_path()
    assert os.path.isfile(p) or p == "libsddpm.so"
    bundled = sorted(pathlib.Path(sddpm.__file__).parent.glob("libsddpm*.so"))
    if bundled:
        assert p == str(bundled[0])  # an installed package uses its own library first
    elif os.environ.get("SDDPM_LIBRARY"):
        assert p == os.environ["SDDPM_LIBRARY"]


def test_work_unit_returns_every_refusal(tmp_path):
    """sddpm.work.mesh_file reports errors in its summary, whatever their Python type."""
    s = sddpm.work.mesh_file(str(tmp_path / "missing.obj"), str(tmp_path / "a"))
    assert s["status"] == "IO" and "missing.obj" in s["error"]
    s = sddpm.work.mesh_file(str(HOLE), str(tmp_path / "b"), contexts="cube,0,0")
    assert s["status"] == "INVALID_CONTEXT"


def test_c_run_contract():
    """sddpm_run's C contract: NULL arguments are refused naming them, as the parser's errors."""
    import ctypes as C

    lib = sddpm.load_library()
    cb = C.CFUNCTYPE(C.c_int, C.c_double, C.c_char_p, C.c_void_p)()
    assert lib.sddpm_run(None, 1, cb, None) == 1
    assert "`args` is NULL" in sddpm._capi._last_message()
    argv = (C.c_char_p * 2)(b"--output=/nonexistent-dir/out", None)
    assert lib.sddpm_run(argv, 2, cb, None) == 1
    assert "`args[1]` is NULL" in sddpm._capi._last_message()
    assert lib.sddpm_run(None, 0, cb, None) == 1  # no mesh, no output: the parser's refusal
    assert "required" in sddpm._capi._last_message()
    need = C.c_size_t()
    assert lib.sddpm_run_arguments_json(None, 0, C.byref(need)) == 12 and need.value > 100
