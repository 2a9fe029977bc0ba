#!/usr/bin/env python3
"""Reads every VTU and PVD that `incise run` writes back with VTK's own reader (issue 20).

ctest `io_vtk_readback` (label `vtk`): runs shipped scenes with VTU output in both encodings
(binary zlib default and ASCII), then reads each written .vtu with vtkXMLUnstructuredGridReader
and each .pvd with vtkXMLCollectionReader's format (parsed here, every listed file read with
VTK), and checks array names, component counts, sizes and values against the run's summary
JSON (the tip probe = the mean of the file's x = l displacements; point and cell counts),
reactions sum to minus the load, S = σ for the linear model, frame names have 6 digits, the
.pvd times are iterations, cut steps, or simulated seconds of dynamic relaxation; cell tags
survive `incise cut`; `incise cut` and `incise mesh check --vtu` honour `--vtu-format`. Exits 77 (ctest SKIP_RETURN_CODE) only when Python's `vtk` module (Debian
python3-vtk9, installed by ci/install-deps.sh) is missing.

usage: vtk_readback.py INCISE SOURCE_DIR WORK_DIR
"""
import json
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

try:
    import vtk  # noqa: F401
    from vtkmodules.util.numpy_support import vtk_to_numpy
except ImportError:
    print("SKIP: Python module vtk not found (Debian python3-vtk9; ci/install-deps.sh installs it)")
    sys.exit(77)

incise, source, work = sys.argv[1], sys.argv[2], sys.argv[3]
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)


def read_vtu(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    check(r.GetErrorCode() == 0, f"{path}: VTK reader error {r.GetErrorCode()}")
    return r.GetOutput()


def arrays(data):
    return {data.GetArrayName(i): data.GetArray(i) for i in range(data.GetNumberOfArrays())}


def run(scene_path, name, outputs, solver=None, material=None):
    """Runs the shipped scene `scene_path` with `outputs` (keeping its probes; and `solver`,
    when given) replacing its own, in WORK/name; returns the folder and the summary JSON."""
    d = os.path.join(work, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    with open(os.path.join(source, scene_path)) as f:
        scene = json.load(f)
    probes = scene.get("outputs", {}).get("probes")
    scene["outputs"] = dict(outputs, **({"probes": probes} if probes else {}))
    if solver:
        scene["solver"] = solver
    if material:
        scene["material"].update(material)
    path = os.path.join(d, "scene.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    subprocess.run([incise, "run", path, "--summary-json", "summary.json"], cwd=d, check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(d, "summary.json")) as f:
        return d, json.load(f)


def read_pvd(path):
    """(timestep, dataset) of every DataSet of a .pvd, each read with VTK."""
    root = ET.parse(path).getroot()
    check(root.get("type") == "Collection", f"{path}: not a VTK collection")
    out = []
    for ds in root.iter("DataSet"):
        out.append((float(ds.get("timestep")),
                    read_vtu(os.path.join(os.path.dirname(path), ds.get("file")))))
    return out


TET_POINT = {"displacement": 3, "reaction_force": 3, "fixed": 1, "loaded": 1}
TET_CELL = {"strain": 6, "second_piola_stress": 6, "cauchy_stress": 6, "von_mises_stress": 1,
            "strain_energy_density": 1, "inverted": 1}


def check_tet_fields(path, grid, load):
    pd, cd = arrays(grid.GetPointData()), arrays(grid.GetCellData())
    for names, data, count in ((TET_POINT, pd, grid.GetNumberOfPoints()),
                               (TET_CELL, cd, grid.GetNumberOfCells())):
        for n, k in names.items():
            check(n in data, f"{path}: array {n} missing")
            if n in data:
                check(data[n].GetNumberOfComponents() == k, f"{path}: {n} components")
                check(data[n].GetNumberOfTuples() == count, f"{path}: {n} size")
    check(pd["fixed"].GetDataTypeAsString() == "unsigned char", f"{path}: fixed is not UInt8")
    if load is not None:
        r = vtk_to_numpy(pd["reaction_force"]).sum(axis=0)
        # the run converged to ||r|| <= 1e-8 ||f_ext||: the imbalance is far below 1e-6 N
        for c in range(3):
            check(abs(r[c] + load[c]) <= 1e-6, f"{path}: reactions {r} do not balance {load}")
    return pd, cd


for fmt in ("binary", "ascii"):
    # The cantilever: static CG, frames every 200 iterations, final state with all fields.
    d, s = run("reference_data/scenes/cantilever.json", "cantilever_" + fmt,
               {"vtu": "out/c", "vtu_every": 200, "vtu_format": fmt})
    check(s["converged"], "cantilever did not converge")
    final = read_vtu(os.path.join(d, "out/c.vtu"))
    check(final.GetNumberOfPoints() == s["mesh"]["nodes"], "cantilever: point count")
    check(final.GetNumberOfCells() == s["mesh"]["tetrahedra"], "cantilever: cell count")
    check(final.GetCellType(0) == 10, "cantilever: not VTK_TETRA")
    pd, cd = check_tet_fields("c.vtu", final, [0.0, -3.0, 0.0])
    u = vtk_to_numpy(pd["displacement"])
    # The tip probe averages the x = 1.2 face: its y equals the mean y of those nodes in the file.
    pts = vtk_to_numpy(final.GetPoints().GetData())
    tip = u[abs(pts[:, 0] - 1.2) < 1e-9, 1].mean()
    probe = s["probes"][0]["displacement"][1]
    check(abs(tip - probe) <= 1e-15 * abs(probe) * 10, f"cantilever: tip {tip} vs summary {probe}")
    # Linear model: second Piola–Kirchhoff = Cauchy, bit for bit.
    check((vtk_to_numpy(cd["second_piola_stress"]) == vtk_to_numpy(cd["cauchy_stress"])).all(),
          "cantilever: linear model S != sigma")
    frames = read_pvd(os.path.join(d, "out/c.pvd"))
    check(len(frames) == s["iterations"] // 200, f"cantilever: {len(frames)} frames")
    times = [t for t, _ in frames]
    check(times == sorted(times) and times[0] == 200, f"cantilever: pvd times {times[:3]}")
    for name in os.listdir(os.path.join(d, "out")):
        if name.startswith("c_"):
            check(len(name) == len("c_000200.vtu"), f"cantilever: frame name {name} not 6 digits")
    for _, g in frames:
        check_tet_fields("cantilever frame", g, None)

    # The augmented cut run: frames of the cut mesh, the final state with its fields.
    d, s = run("reference_data/scenes/cube_cut_augmented.json", "cut_" + fmt,
               {"vtu": "out/cut", "vtu_every": 1, "vtu_format": fmt})
    frames = read_pvd(os.path.join(d, "out/cut.pvd"))
    check(len(frames) == len(s["cut_steps"]), "cut: one frame per solve")
    check([t for t, _ in frames] == [float(c["step"]) for c in s["cut_steps"]], "cut: pvd steps")
    final = read_vtu(os.path.join(d, "out/cut.vtu"))
    check(final.GetNumberOfPoints() == s["mesh"]["nodes"], "cut: final point count")
    fpd, fcd = check_tet_fields("cut.vtu", final, None)
    # Every frame carries the fields of its cut mesh (scene::cut_session_problem); the last
    # frame is the final state: the same problem definition and u, so the same values, bit for
    # bit (tags included: the cut keeps them).
    for _, g in frames:
        check_tet_fields("cut frame", g, None)
    lpd, lcd = arrays(frames[-1][1].GetPointData()), arrays(frames[-1][1].GetCellData())
    for n in ("displacement", "reaction_force"):
        check((vtk_to_numpy(lpd[n]) == vtk_to_numpy(fpd[n])).all(), f"cut: last frame {n} != final")
    for n in ("von_mises_stress", "strain"):
        check((vtk_to_numpy(lcd[n]) == vtk_to_numpy(fcd[n])).all(), f"cut: last frame {n} != final")

    # A 3D needle insertion (§6.9): every frame of the refined mesh has the elastic fields (no
    # reactions: evaluating them would add to the run's reported flops), the needle state and
    # the needle faces.
    d, s = run("property_tests/scene/data/needle/needle3d_small.json", "needle3d_" + fmt,
               {"vtu": "out/n", "vtu_every": 4, "vtu_format": fmt})
    frames = read_pvd(os.path.join(d, "out/n.pvd"))
    check(len(frames) >= 2, f"needle3d: {len(frames)} frames")
    for _, g in frames:
        pd, cd = arrays(g.GetPointData()), arrays(g.GetCellData())
        for n, k in dict(TET_CELL, needle_faces=1).items():
            check(n in cd and cd[n].GetNumberOfTuples() == g.GetNumberOfCells(),
                  f"needle3d frame: cell array {n}")
        for n in ("displacement", "fixed", "loaded", "needle_state"):
            check(n in pd and pd[n].GetNumberOfTuples() == g.GetNumberOfPoints(),
                  f"needle3d frame: point array {n}")
        check("reaction_force" not in pd, "needle3d frame: unexpected reaction_force")
    last = arrays(frames[-1][1].GetCellData())
    if "needle_faces" in last:
        check(vtk_to_numpy(last["needle_faces"]).max() >= 1, "needle3d: no needle faces")

# A dynamic-ss22 run of the cantilever: pvd times are simulated time (s), strictly increasing;
# frame k is ū of (2.56) at (k + ½)·Δt when no restart changed Δt.
d, s = run("reference_data/scenes/cantilever.json", "ss22", {"vtu": "out/d", "vtu_every": 100},
           {"method": "dynamic-ss22", "tolerance": 1e-6, "max_iterations": 5000}, {"rho": 1000.0})
frames = read_pvd(os.path.join(d, "out/d.pvd"))
times = [t for t, _ in frames]
check(len(frames) >= 2, "ss22: fewer than 2 frames")
check(all(b > a for a, b in zip(times, times[1:])), f"ss22: times not increasing {times[:4]}")
check(abs(times[0] - 100.5 * s["final_time_step"]) <= 1e-9 * times[0] or s["restarts"] > 0,
      f"ss22: first frame time {times[0]} != 100.5 dt")
for _, g in frames:
    check_tet_fields("ss22 frame", g, None)

# `incise cut` on the liver keeps its cell tags, in both encodings (--vtu-format).
for fmt in ("binary", "ascii"):
    out = os.path.join(work, f"liver_cut_{fmt}.vtu")
    subprocess.run([incise, "cut", os.path.join(source, "reference_data/meshes/liver_coarse.mesh"),
                    os.path.join(source, "property_tests/cut/liver_sweep.txt"), "--out", out,
                    "--vtu-format", fmt], check=True, stdout=subprocess.DEVNULL)
    with open(out, "rb") as f:
        check((b'format="ascii"' in f.read()) == (fmt == "ascii"), f"incise cut: not {fmt}")
    g = read_vtu(out)
    cd = arrays(g.GetCellData())
    check("tag" in cd, f"incise cut ({fmt}): cell tags dropped")
    if "tag" in cd:
        tags = set(vtk_to_numpy(cd["tag"]).tolist())
        check(len(tags) >= 2, f"incise cut ({fmt}): tags {tags}")

# `incise mesh check --vtu` in both encodings: the same quality arrays and values.
checked = {}
for fmt in ("binary", "ascii"):
    out = os.path.join(work, f"liver_check_{fmt}.vtu")
    subprocess.run([incise, "mesh", "check", os.path.join(source, "reference_data/meshes/liver_coarse.mesh"),
                    "--vtu", out, "--vtu-format", fmt], check=True, stdout=subprocess.DEVNULL)
    g = read_vtu(out)
    check(g.GetNumberOfCells() > 0, f"mesh check ({fmt}): no cells")
    checked[fmt] = {k: vtk_to_numpy(v) for k, v in arrays(g.GetCellData()).items()}
check(len(checked["binary"]) >= 2 and checked["binary"].keys() == checked["ascii"].keys(),
      f"mesh check: arrays {sorted(checked['binary'])} vs {sorted(checked['ascii'])}")
for k in checked["binary"]:
    # ascii doubles are written in the shortest exact form: the values are identical.
    if k in checked["ascii"]:
        check((checked["binary"][k] == checked["ascii"][k]).all(), f"mesh check: {k} differs")

if failures:
    print(f"{len(failures)} failures")
    sys.exit(1)
print("vtk readback: all files read by VTK with the expected arrays")
