#!/usr/bin/env python3
"""Reads every VTU and PVD that `incise run` writes back with VTK's own reader (issue 20).

ctest `io_vtk_readback` (label `vtk`): runs shipped scenes with VTU output in both encodings
(binary zlib default and ASCII), then reads each written .vtu with vtkXMLUnstructuredGridReader
and each .pvd with vtkXMLCollectionReader's format (parsed here, every listed file read with
VTK), and checks array names, component counts, sizes and values against the run's summary
JSON (the tip probe = the mean of the file's x = l displacements; point and cell counts),
reactions sum to minus the load, S = σ for the linear model, frame names have 6 digits, the
.pvd times are iterations, cut steps, or simulated seconds of dynamic relaxation; cell tags
survive `incise cut`; `incise cut` and `incise mesh check --vtu` honour `--vtu-format`; a 2D
needle run's frames and final state carry the plane-stress fields, equal to an independent
recomputation from the file's points and displacements (linear plane-stress Hooke law). Exits 77 (ctest SKIP_RETURN_CODE) only when Python's `vtk` module (Debian
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

    # A 2D needle insertion (§6.3 plane stress, ch. 6): every frame and the final state carry the
    # plane-stress fields (no reactions, as in 3D) and the needle state; the last frame is the
    # final state bit for bit. Independent check: each triangle's fields recomputed here from the
    # file's points and displacements (P1 gradient, linear plane-stress Hooke law with the
    # scene's E and nu) — strain xx, yy, xy and the thickness strain zz = -nu/(1-nu)(xx + yy),
    # stress with zz = 0, von Mises sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2), W = s:e/2.
    d, s = run("property_tests/scene/data/needle/needle_small.json", "needle2d_" + fmt,
               {"vtu": "out/n", "vtu_every": 2, "vtu_format": fmt})
    with open(os.path.join(source, "property_tests/scene/data/needle/needle_small.json")) as f:
        mat = json.load(f)["material"]
    frames = read_pvd(os.path.join(d, "out/n.pvd"))
    check(len(frames) >= 2, f"needle2d: {len(frames)} frames")
    final = read_vtu(os.path.join(d, "out/n.vtu"))
    for what, g in [("needle2d frame", g) for _, g in frames] + [("needle2d n.vtu", final)]:
        pd, cd = arrays(g.GetPointData()), arrays(g.GetCellData())
        check(g.GetCellType(0) == 5, f"{what}: not VTK_TRIANGLE")
        for n, k in TET_CELL.items():
            check(n in cd and cd[n].GetNumberOfComponents() == k and
                  cd[n].GetNumberOfTuples() == g.GetNumberOfCells(), f"{what}: cell array {n}")
        for n in ("displacement", "fixed", "loaded", "needle_state"):
            check(n in pd and pd[n].GetNumberOfTuples() == g.GetNumberOfPoints(),
                  f"{what}: point array {n}")
        check("reaction_force" not in pd, f"{what}: unexpected reaction_force")
        check(vtk_to_numpy(pd["fixed"]).sum() >= 2, f"{what}: no fixed nodes")
    lpd, lcd = arrays(frames[-1][1].GetPointData()), arrays(frames[-1][1].GetCellData())
    fpd, fcd = arrays(final.GetPointData()), arrays(final.GetCellData())
    for n in TET_CELL:
        check((vtk_to_numpy(lcd[n]) == vtk_to_numpy(fcd[n])).all(), f"needle2d: last frame {n} != final")
    young, nu = mat["E"], mat["nu"]
    pts = vtk_to_numpy(final.GetPoints().GetData())
    u = vtk_to_numpy(fpd["displacement"])
    check(abs(u[:, 2]).max() == 0.0 and abs(pts[:, 2]).max() == 0.0, "needle2d: z not 0")
    check(abs(u).max() > 0.0, "needle2d: nothing moved")
    strain, stress = vtk_to_numpy(fcd["strain"]), vtk_to_numpy(fcd["cauchy_stress"])
    vm, w = vtk_to_numpy(fcd["von_mises_stress"]), vtk_to_numpy(fcd["strain_energy_density"])
    check((vtk_to_numpy(fcd["second_piola_stress"]) == stress).all(), "needle2d: linear S != sigma")
    scale = abs(stress).max()
    check(scale > 0.0, "needle2d: zero stress")
    worst = 0.0
    for c in range(final.GetNumberOfCells()):
        ids = final.GetCell(c).GetPointIds()
        v = [ids.GetId(k) for k in range(3)]
        x = [pts[i, :2] for i in v]
        du = [u[i, :2] for i in v]
        z = [[x[0][0] - x[2][0], x[1][0] - x[2][0]], [x[0][1] - x[2][1], x[1][1] - x[2][1]]]
        det = z[0][0] * z[1][1] - z[0][1] * z[1][0]
        zi = [[z[1][1] / det, -z[0][1] / det], [-z[1][0] / det, z[0][0] / det]]
        U = [[du[0][0] - du[2][0], du[1][0] - du[2][0]], [du[0][1] - du[2][1], du[1][1] - du[2][1]]]
        G = [[sum(U[i][k] * zi[k][j] for k in range(2)) for j in range(2)] for i in range(2)]
        exx, eyy, exy = G[0][0], G[1][1], 0.5 * (G[0][1] + G[1][0])
        ezz = -nu / (1 - nu) * (exx + eyy)
        k = young / (1 - nu * nu)
        sxx, syy, sxy = k * (exx + nu * eyy), k * (eyy + nu * exx), young / (1 + nu) * exy
        svm = (sxx * sxx - sxx * syy + syy * syy + 3 * sxy * sxy) ** 0.5
        we = 0.5 * (sxx * exx + syy * eyy + 2 * sxy * exy)
        emax = max(abs(exx), abs(eyy), abs(exy), 1e-300)
        diffs = [abs(strain[c][i] - e) / emax for i, e in enumerate([exx, eyy, ezz, exy, 0, 0])]
        diffs += [abs(stress[c][i] - t) / scale for i, t in enumerate([sxx, syy, 0, sxy, 0, 0])]
        diffs += [abs(vm[c] - svm) / scale, abs(w[c] - we) / (scale * emax)]
        worst = max(worst, max(diffs))
    # Both sides are O(1)-conditioned double formulas on the same (exactly stored) numbers; the
    # library's zz stress is the out-of-plane solve's residual (rounding level): 1e-9 leaves a
    # margin of ~10^5 over the rounding seen (~1e-15) and fails any wrong formula or component.
    check(worst <= 1e-9, f"needle2d: fields differ from plane-stress Hooke by {worst:.3g} (relative)")

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
