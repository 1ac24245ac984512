"""pytest for the Python package (run by ctest: `python_bindings`)."""
import pathlib
import threading

import numpy as np
import pytest

import sddpm

DATA = pathlib.Path(__file__).resolve().parents[3] / "tests" / "data" / "meshes"


def test_versions():
    assert sddpm.abi_version() == 5
    assert sddpm.version().count(".") == 2


def test_options_by_name():
    o = sddpm.Options()
    d = o.describe()
    # every option with its value, default, type and documentation; the keyword
    # spelling (underscores for the dots) names each one once
    assert len(d) > 90
    assert all(set(v) == {"default", "doc", "nullable", "type", "value"} and v["doc"] for v in d.values())
    assert len({n.replace(".", "_") for n in d}) == len(d)
    assert d["hex.goals.hausdorff"] == {**d["hex.goals.hausdorff"], "default": 0.01, "type": "number", "value": 0.01}
    assert d["hex.map.level"]["nullable"] and d["hex.map.level"]["value"] is None
    for name, v in d.items():
        assert o.get(name) == v["value"], name
    # a number, a bool, a string, by name, keyword and dict; read back
    o = sddpm.Options({"hex.quality.pillow": False}, hex_map_level=2, polycube_orientations="SignFlips")
    o.set("hex.goals.hausdorff", 0.02)
    o["hex_candidates"] = 2
    assert (o.get("hex.quality.pillow"), o.get("hex_map_level"), o["polycube.orientations"]) == (False, 2, "SignFlips")
    assert (o.get("hex.goals.hausdorff"), o.get("hex_candidates")) == (0.02, 2)
    o.set("hex_map_level", None)  # back to the automatic level
    assert o.get("hex.map.level") is None
    # refusals name the option and leave the value as it was: an unknown name or a
    # value out of range is a ValueError, a value of another type a TypeError, an
    # unknown keyword a TypeError (as for any Python call)
    with pytest.raises(sddpm.SddpmValueError) as e:
        o.set("hex.quality.pilow", True)
    assert e.value.name == "INVALID_ARGUMENT" and 'unknown option "hex.quality.pilow"' in e.value.message
    assert isinstance(e.value, ValueError) and not isinstance(e.value, RuntimeError)
    with pytest.raises(TypeError, match="hex_quality_pilow.*did you mean 'hex_quality_pillow'"):
        sddpm.Options(hex_quality_pilow=True)
    with pytest.raises(ValueError) as e:
        o.set("hex.goals.hausdorff", -1)
    assert e.value.name == "INVALID_ARGUMENT" and "option hex.goals.hausdorff must be" in e.value.message
    with pytest.raises(ValueError) as e:
        o.set("hex.fallback.resolution", 2.5)
    assert "option hex.fallback.resolution must be a whole number" in e.value.message
    with pytest.raises(TypeError, match="option hex.quality.pillow takes a bool, not int"):
        o.set("hex.quality.pillow", 1)
    with pytest.raises(TypeError, match="option hex.goals.hausdorff takes a number"):
        o.set("hex.goals.hausdorff", "0.5")
    with pytest.raises(TypeError):
        sddpm.Options(["hex.quality.pillow"])
    with pytest.raises(ValueError) as e:
        o.set("polycube.orientations", "sideways")
    assert "option polycube.orientations" in e.value.message
    assert o.get("hex.goals.hausdorff") == 0.02
    # another Options as the start of a build call's options
    assert sddpm.Options(o).get("hex.quality.pillow") is False


def test_mesh_load_check_and_arrays():
    m = sddpm.Mesh.load(DATA / "cgal_hole.off")
    assert m.genus == 1
    r = m.check()
    assert r["closed"] and r["manifold"] and r["can_proceed"]
    v, t = m.vertices, m.triangles
    assert v.shape == (m.counts()[0], 3) and v.dtype == np.float64
    assert t.shape == (m.counts()[1], 3) and t.dtype == np.uint32
    again = sddpm.Mesh.from_arrays(v, t)
    assert again.genus == 1
    assert abs(again.check()["volume"] - r["volume"]) < 1e-12 * abs(r["volume"])
    m.close()
    with pytest.raises(ValueError):
        m.genus  # noqa: B018 - closed handle


def test_errors_carry_status_and_message():
    with pytest.raises(FileNotFoundError) as e:
        sddpm.Mesh.load("/nonexistent/part.obj")
    assert e.value.filename == "/nonexistent/part.obj"
    with pytest.raises(TypeError):
        sddpm.Mesh.load(42)
    bad = sddpm.Mesh.load(DATA / "bad" / "cgal_mech-holes-shark.off")
    with pytest.raises(sddpm.SddpmError) as e:
        bad.validate()
    assert e.value.name == "INVALID_MESH" and e.value.status == 4 and "boundary edges" in e.value.message
    assert isinstance(e.value, RuntimeError)
    with pytest.raises(sddpm.SddpmValueError) as e:
        sddpm.Mesh.from_arrays(np.zeros((3, 3)), np.array([[0, 1, 7]]))
    assert e.value.name == "INVALID_ARGUMENT" and "vertex 7" in e.value.message
    with pytest.raises(ValueError, match="vertices must be"):
        sddpm.Mesh.from_arrays(np.zeros((3, 2)), np.array([[0, 1, 2]]))
    with pytest.raises(ValueError) as e:
        sddpm.Contexts.parse("cube,0,0")
    assert e.value.name == "INVALID_CONTEXT"
    with pytest.raises(TypeError):
        sddpm.Contexts.parse(["cube"])
    with pytest.raises(FileNotFoundError):
        sddpm.Model.from_file("/nonexistent/weights.sddpmw")
    with pytest.raises(TypeError, match="model must be a sddpm.Model"):
        sddpm.Polycube.generate("model", bad)


def test_contexts():
    c = sddpm.Contexts.parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0;cube,cube,0,0,0,0,0,0,0,0,0,0")
    assert len(c) == 2
    assert c.genus(0) == 1 and c.genus(1) == 0
    assert list(c.labels(1)[:2]) == [1, 1]
    hot = c.one_hot(0)
    assert hot.shape == (132,) and hot.sum() == 12
    assert list(sddpm.Contexts.from_one_hot(hot).labels()) == list(c.labels(0))
    assert sddpm.Contexts.parse("cube,0,0,0,cube,0,0,0,0,0,0,0").invalid_reason() != ""
    all3 = sddpm.Contexts.from_constraints(cube=3, thc=0, bhc=0, allowed_cells=range(6))
    assert len(all3) > 0 and all(all3.genus(i) == 0 for i in range(len(all3)))


def test_polycube_progress_cancel_and_threads():
    model = sddpm.Model.embedded()
    assert model.info()["parameters"] > 0
    mesh = sddpm.Mesh.load(DATA / "cgal_hole.off")
    ctx = sddpm.Contexts.parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0")
    seen = []
    pc = sddpm.Polycube.generate(model, mesh, ctx, steps=10, progress=lambda f, s: seen.append((f, s)) or True)
    assert seen and all(0.0 <= f <= 1.0 for f, _ in seen)
    cands = pc.candidates()
    assert len(cands) == 1 and cands[0]["labels"][0] == 2
    assert "candidates" in pc.report()["result"]
    if pc.accepted:
        out, inp = pc.points()
        assert out.shape == (6144, 3)
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.Polycube.generate(model, mesh, sddpm.Contexts.parse("cube,0,0,0,0,0,0,0,0,0,0,0"), steps=10)
    assert e.value.name == "GENUS_MISMATCH" and "genus 1" in e.value.message
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.Polycube.generate(model, mesh, ctx, steps=10, progress=lambda f, s: False)
    assert e.value.name == "CANCELLED"

    class Stop(Exception):
        pass

    def boom(f, s):
        raise Stop()

    with pytest.raises(Stop):
        sddpm.Polycube.generate(model, mesh, ctx, steps=10, progress=boom)
    # one model, two threads: the same results as one after the other
    ref = [c["mean_target_pcd"] for c in sddpm.Polycube.generate(model, mesh, ctx, steps=10, seed=5).candidates()]
    res = [None, None]

    def work(i):
        res[i] = [c["mean_target_pcd"] for c in sddpm.Polycube.generate(model, mesh, ctx, steps=10, seed=5).candidates()]

    ts = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    [t.start() for t in ts]
    [t.join() for t in ts]
    assert res[0] == ref and res[1] == ref


def test_whole_pipeline(tmp_path):
    model = sddpm.Model.embedded()
    mesh = sddpm.Mesh.load(DATA / "cgal_hole.off")
    pc = sddpm.Polycube.generate(model, mesh, sddpm.Contexts.parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0"), steps=10)
    with pytest.raises(sddpm.SddpmValueError) as e:
        sddpm.HexMesh.build(pc, level=1, hex_fallback_resolution=1)
    assert e.value.name == "INVALID_ARGUMENT" and "hex.fallback.resolution" in e.value.message
    hexm = sddpm.HexMesh.build(pc, level=1, options={"hex.quality.pillow": True})
    q = hexm.quality()
    assert q["inverted"] == 0 and q["min_scaled_jacobian"] > 0.2 and q["hausdorff_relative"] < 0.01
    sj = hexm.scaled_jacobian
    assert sj.shape == (q["elements"],) and abs(sj.min() - q["min_scaled_jacobian"]) < 1e-15
    assert hexm.histogram().sum() == q["elements"]
    assert hexm.elements.max() < hexm.nodes.shape[0]
    hexm.write(tmp_path / "hex.vtu")
    hexm.write(tmp_path / "hex.k")
    sp = sddpm.Spline.build(hexm, spline_sparse_bext=False)
    ne, nb = sp.counts()
    assert ne == q["elements"] and nb > 0
    ids, op = sp.extraction(0)
    assert op.shape == (len(ids), 64)
    np.testing.assert_allclose(op.sum(axis=0), 1.0, atol=1e-12)  # partition of unity
    x, j = sp.evaluate(0, 0.5, 0.5, 0.5)
    assert np.linalg.det(j) > 0
    sp.write(tmp_path)
    for f in ["hex.vtu", "hex.k", "spline.bext", "model.k"]:
        assert (tmp_path / f).is_file(), f
    with pytest.raises(sddpm.SddpmValueError) as e:
        sp.evaluate(0, 2.0, 0.5, 0.5)
    assert e.value.name == "INVALID_ARGUMENT"
    cube = sddpm.HexMesh.from_arrays([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], [list(range(8))])
    assert cube.quality()["min_scaled_jacobian"] == pytest.approx(1.0)


def test_freecad_macro_core(tmp_path):
    """The FreeCAD macro's work, on a tessellation read from disk (FreeCAD not needed)."""
    import importlib.util

    path = pathlib.Path(__file__).resolve().parents[3] / "examples" / "freecad_sddpm_macro.py"
    spec = importlib.util.spec_from_file_location("freecad_sddpm_macro", path)
    macro = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(macro)
    m = sddpm.Mesh.load(DATA / "cgal_hole.off")
    s = macro.mesh_tessellation(m.vertices, m.triangles.astype(np.int64), str(tmp_path), contexts="THC+Z,0,0,0,0,0,0,0,0,0,0,0", level=1)
    assert s["genus"] == 1 and s["hex"]["inverted"] == 0
    for f in ["hex.vtu", "hex.k", "spline.bext", "model.k", "report.json"]:
        assert (tmp_path / f).is_file(), f


def test_dask_local_cluster(tmp_path):
    """The work unit under Dask's local cluster: two worker processes, a bad file among good ones."""
    distributed = pytest.importorskip("distributed")
    import shutil

    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(DATA / "cgal_hole.off", src / "hole.off")
    shutil.copy(DATA / "cinolib_torus.obj", src / "torus.obj")
    shutil.copy(DATA / "bad" / "cgal_cow.off", src / "cow.off")
    files = sorted(src.iterdir())
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        futures = client.map(sddpm.work.mesh_file, [str(f) for f in files], [str(tmp_path / "out" / f.stem) for f in files],
                             contexts="THC+Z,0,0,0,0,0,0,0,0,0,0,0", level=1, steps=10, spline=False)
        res = {pathlib.Path(s["file"]).stem: s for s in client.gather(futures)}
    assert res["cow"]["status"] == "INVALID_MESH" and "non-manifold" in res["cow"]["error"]
    for name in ("hole", "torus"):
        assert res[name]["status"] == "OK", res[name]
        assert res[name]["inverted"] == 0
        assert (tmp_path / "out" / name / "hex.vtu").is_file()
    # the same work unit in this process gives the same mesh
    local = sddpm.work.mesh_file(str(src / "hole.off"), str(tmp_path / "local"), contexts="THC+Z,0,0,0,0,0,0,0,0,0,0,0", level=1, steps=10, spline=False)
    assert local["min_scaled_jacobian"] == res["hole"]["min_scaled_jacobian"]
