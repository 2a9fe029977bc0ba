"""incise from Python: load and check meshes, run scenes, run the certification catalogue.

A thin layer over the C++ library (docs/python.md). Every computation is the library's; arrays
are NumPy copies. Bad files and bad parameters raise ``incise.ParseError`` (a ``ValueError``
naming file and line) or ``ValueError``; numerical failures are not exceptions but the ``status``
and ``converged`` fields of the returned summary, as in ``incise run``.
"""

import json
import os

from ._incise import ParseError, check_mesh, environment
from ._incise import _certify, _run_scene

__all__ = ["ParseError", "SceneRun", "check_mesh", "run_scene", "certify", "environment"]


class SceneRun:
    """What one scene run produced.

    summary       dict: the summary ``incise run --summary-json`` writes (status, iterations,
                  residual, energy, probes, environment, ... ; docs/scenes.md)
    mesh          dict: dimension, points (n x 3), cells (m x 4 or m x 3), cell_tags
    displacement  NumPy array (n x dim) of the final displacement (m) on ``mesh``; None for runs
                  whose final mesh differs from the built one (cutting, needle refinement)
    trace         dict of NumPy arrays, one entry per iteration: iteration, residual_norm (N),
                  energy (J), seconds
    """

    def __init__(self, raw):
        self.summary = json.loads(raw["summary_json"])
        self.mesh = raw["mesh"]
        self.displacement = raw["displacement"]
        self.trace = raw["trace"]

    @property
    def converged(self):
        return bool(self.summary["converged"])

    def __repr__(self):
        s = self.summary
        return "SceneRun(%r, result=%r, iterations=%r)" % (s["name"], s["result"], s["iterations"])


def run_scene(scene, base_dir=None, write_outputs=False):
    """Runs a scene: ``scene`` is a path to a scene file, or a dict in the scene format
    (docs/scenes.md; relative mesh paths resolved against ``base_dir``, default the current
    folder). ``write_outputs`` writes the files the scene's ``outputs`` name (CSV, final VTU);
    the VTU frame series of ``vtu_every`` is written by ``incise run`` only. Returns a SceneRun.
    """
    if isinstance(scene, dict):
        text = json.dumps(scene)
        raw = _run_scene("<python dict>", text, base_dir or "", write_outputs)
    else:
        raw = _run_scene(os.fspath(scene), "", "", write_outputs)
    return SceneRun(raw)


def certify(data_dir=None, quick=True, filter=""):
    """Runs the certification catalogue (``incise certify``; docs/certify.md) and returns
    ``(summary, html)``: the summary.json contents as a dict and the report page as text.
    ``data_dir`` is the reference_data folder (default: ``$INCISE_DATA_DIR``); ``filter`` an
    ECMAScript regular expression over check ids."""
    if data_dir is None:
        data_dir = os.environ.get("INCISE_DATA_DIR")
        if not data_dir:
            raise ValueError("certify: give data_dir (the reference_data folder, installed as "
                             "<prefix>/share/incise) or set INCISE_DATA_DIR")
    raw = _certify(os.fspath(data_dir), quick, filter)
    return json.loads(raw["summary_json"]), raw["html"]
