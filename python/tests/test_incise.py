"""pytest suite of the incise Python module (python/incise_py.cpp, docs/python.md).

Run by ctest (test python_pytest, label python) with PYTHONPATH=<build>/python and
INCISE_SOURCE_DIR=<source>. Expected values are recomputed here from the returned arrays (NumPy),
never copied from a run.
"""

import copy
import json
import os

import numpy as np
import pytest

import incise

SOURCE = os.environ.get("INCISE_SOURCE_DIR",
                        os.path.join(os.path.dirname(__file__), "..", ".."))
DATA = os.path.join(SOURCE, "reference_data")
LIVER = os.path.join(DATA, "meshes", "liver_coarse.mesh")
CANTILEVER = os.path.join(DATA, "scenes", "cantilever.json")


def tet_volumes(points, cells):
    a, b, c, d = (points[cells[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def test_check_mesh_returns_the_liver_with_its_report_invariants_and_quality():
    m = incise.check_mesh(LIVER)
    assert m["dimension"] == 3
    pts, cells = m["points"], m["cells"]
    assert pts.shape == (m["load_report"]["num_points"], 3)
    assert cells.shape == (m["load_report"]["num_cells"], 4)
    assert m["valid"] and m["violations"] == []
    vol = tet_volumes(pts, cells)
    # quality["size"] is the signed volume computed by the library: equal to NumPy's to
    # round-off (relative 1e-12 of the largest cell; both are one triple product).
    np.testing.assert_allclose(m["quality"]["size"], vol, rtol=0, atol=1e-12 * vol.max())
    assert (vol > 0).all()
    assert len(m["quality"]["shape"]) == cells.shape[0]
    assert m["load_report"]["format"].startswith("medit")


def test_bad_mesh_file_raises_parse_error_naming_file_and_line(tmp_path):
    bad = tmp_path / "bad.mesh"
    bad.write_text("MeshVersionFormatted 1\nDimension 3\nVertices\n2\n0 0 0 0\nnot a number\n")
    with pytest.raises(incise.ParseError) as e:
        incise.check_mesh(str(bad))
    assert isinstance(e.value, ValueError)
    assert "bad.mesh:6" in str(e.value)


def test_cantilever_scene_converges_and_its_probe_is_the_mean_of_the_loaded_nodes():
    run = incise.run_scene(CANTILEVER)
    s = run.summary
    assert run.converged and s["status"] == "ok"
    pts = run.mesh["points"]
    u = run.displacement
    assert u.shape == (pts.shape[0], 3)
    # The probe "tip" averages the nodes of the plane x = 1.2 (the scene's region).
    tip = u[np.abs(pts[:, 0] - 1.2) < 1e-9].mean(axis=0)
    np.testing.assert_allclose(s["probes"][0]["displacement"], tip, rtol=1e-12, atol=0)
    # One trace row per iteration, residual ending below tolerance * |f_ext|.
    assert len(run.trace["iteration"]) == s["iterations"]
    assert run.trace["residual_norm"][-1] <= s["tolerance"] * s["external_force_norm"]
    assert set(s["environment"]) == set(incise.environment())


def test_scene_as_a_dict_runs_like_the_file():
    with open(CANTILEVER) as f:
        scene = json.load(f)
    scene.pop("outputs")
    from_dict = incise.run_scene(scene)
    from_file = incise.run_scene(CANTILEVER)
    # Same spec, same deterministic solver: the same iterates.
    assert from_dict.summary["iterations"] == from_file.summary["iterations"]
    np.testing.assert_array_equal(from_dict.displacement, from_file.displacement)


def test_bad_scene_dict_raises_parse_error_with_the_key():
    with open(CANTILEVER) as f:
        scene = json.load(f)
    bad = copy.deepcopy(scene)
    bad["material"]["E"] = -1.0
    with pytest.raises(incise.ParseError) as e:
        incise.run_scene(bad)
    assert "/material/E" in str(e.value)


def test_numerical_failure_is_a_status_not_an_exception():
    with open(CANTILEVER) as f:
        scene = json.load(f)
    scene.pop("outputs")
    scene["solver"]["max_iterations"] = 5
    run = incise.run_scene(scene)
    assert not run.converged
    assert run.summary["status"] == "failed"
    assert run.summary["iterations"] == 5


def test_certify_runs_a_filtered_catalogue_and_reports_the_environment():
    summary, html = incise.certify(DATA, quick=True, filter="^box_volume$")
    assert summary["passed"] == 1 and summary["failed"] == 0
    assert [c["id"] for c in summary["checks"]] == ["box_volume"]
    assert summary["environment"]["build_type"] != ""
    assert "<table id=\"environment\">" in html


def test_certify_without_data_dir_says_what_to_give(monkeypatch):
    monkeypatch.delenv("INCISE_DATA_DIR", raising=False)
    with pytest.raises(ValueError, match="INCISE_DATA_DIR"):
        incise.certify()
