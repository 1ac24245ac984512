"""pytest for the Python package (run by ctest: `python_bindings`)."""
import pathlib
import threading

import numpy as np
import pytest

import sddpm

DATA = pathlib.Path(__file__).resolve().parents[3] / "tests" / "data" / "meshes"


def test_versions():
    assert sddpm.abi_version() == 1
    assert sddpm.version().count(".") == 2


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
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.Mesh.load("/nonexistent/part.obj")
    assert e.value.name == "IO" and e.value.status == 2 and "/nonexistent/part.obj" in e.value.message
    bad = sddpm.Mesh.load(DATA / "bad" / "cgal_mech-holes-shark.off")
    with pytest.raises(sddpm.SddpmError) as e:
        bad.validate()
    assert e.value.name == "INVALID_MESH" and "boundary edges" in e.value.message
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.Mesh.from_arrays(np.zeros((3, 3)), np.array([[0, 1, 7]]))
    assert e.value.name == "INVALID_ARGUMENT" and "vertex 7" in e.value.message
    with pytest.raises(sddpm.SddpmError) as e:
        sddpm.Contexts.parse("cube,0,0")
    assert e.value.name == "INVALID_CONTEXT"


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
