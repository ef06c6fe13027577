"""Reads VTU/PVD files with ParaView's own readers (pvpython), as users open them.

The same three folders as tests/meshio_check.py:
- DIR: written by `cargo run --release --example write_vtu -- DIR`: the PVD's two time steps,
  counts, VTK's quadratic hexahedron (type 25), the displacement and sxx values, and the mesh
  ParaView's WarpByVector makes of it.
- RUN_DIR: a `nonlin3d run --out RUN_DIR` folder: one time step per level in model.pvd and
  front.pvd, every field with its shape and finite, the front's G against results.json's.
- SOLVE_DIR: a `nonlin3d solve tests/decks/uniaxial_box.inp --out SOLVE_DIR` folder: every
  field, S_xx = E E_xx to 1e-6.

Usage: pvpython tests/paraview_check.py DIR RUN_DIR SOLVE_DIR
"""
import json
import sys

import numpy as np
from paraview import servermanager as sm
from paraview.simple import PVDReader, WarpByVector
from vtk.numpy_interface import dataset_adapter as dsa

box, run, solve = sys.argv[1], sys.argv[2], sys.argv[3]
checked = 0


def states(path):
    """The PVD's time values and, per time, the wrapped unstructured grid ParaView reads."""
    reader = PVDReader(FileName=path)
    times = list(reader.TimestepValues)
    out = []
    for t in times:
        reader.UpdatePipeline(t)
        out.append(dsa.WrapDataObject(sm.Fetch(reader)))
    return reader, times, out


def fields(d, point, cell):
    """Every listed field is there with (count, components) and finite."""
    for data, listed, n in [(d.PointData, point, d.GetNumberOfPoints()),
                            (d.CellData, cell, d.GetNumberOfCells())]:
        for name, c in listed.items():
            assert name in data.keys(), (name, data.keys())
            v = np.asarray(data[name]).reshape(n, -1)
            assert v.shape == (n, c), (name, v.shape)
            assert np.isfinite(v).all(), name


# The example's box: 4 × 3 × 2 Hex20 (see meshio_check.py), u = s·(1e-3 x, 2e-3 y, −0.1 x²).
reader, times, grids = states(f"{box}/box.pvd")
assert len(times) == 2, times
for (scale, d) in zip([1.0, 2.0], grids):
    assert d.GetNumberOfPoints() == 60 + 48 + 45 + 40 and d.GetNumberOfCells() == 24
    assert set(np.asarray(d.CellTypes).tolist()) == {25}  # VTK_QUADRATIC_HEXAHEDRON
    x = np.asarray(d.Points)
    u = np.asarray(d.PointData["displacement"])
    expect = np.column_stack([scale * 1e-3 * x[:, 0], scale * 2e-3 * x[:, 1],
                              -scale * 0.1 * x[:, 0] ** 2])
    assert np.allclose(u, expect, rtol=0, atol=1e-15), np.abs(u - expect).max()
    assert np.allclose(np.ravel(d.CellData["sxx"]), scale * np.arange(24) * 1e6)
    checked += 1
warp = WarpByVector(Input=reader, Vectors=["POINTS", "displacement"])
warp.UpdatePipeline(times[-1])
bounds = warp.GetDataInformation().GetBounds()
x = np.asarray(grids[-1].Points)
moved = x + np.asarray(grids[-1].PointData["displacement"])
want = [v for i in range(3) for v in (moved[:, i].min(), moved[:, i].max())]
assert np.allclose(bounds, want, rtol=0, atol=1e-12), (bounds, want)
checked += 1

# A scene's run: one time step per level, the front's G as results.json has it.
results = json.load(open(f"{run}/results.json"))
levels = results["levels"]
_, times, grids = states(f"{run}/model.pvd")
assert len(grids) == len(levels) > 0, (len(grids), len(levels))
for d in grids:
    fields(
        d,
        {"node": 1, "displacement_mm": 3, "strain_green_lagrange": 6, "stress_pk2_MPa": 6,
         "stress_cauchy_MPa": 6, "reaction_N": 3, "crack_opening_mm": 3},
        {"material": 1, "ply_angle_deg": 1, "strain_green_lagrange": 6, "stress_pk2_MPa": 6,
         "stress_cauchy_MPa": 6},
    )
    checked += 1
_, _, fronts = states(f"{run}/front.pvd")
assert len(fronts) == len(levels)
for d, level in zip(fronts, levels):
    rows = level["front"]
    fields(d, {k: 1 for k in ["s_mm", "G_I_J_m2", "G_II_J_m2", "G_III_J_m2", "G_T_J_m2",
                              "mode_mix", "open"]}, {})
    assert d.GetNumberOfCells() == len(rows) - 1
    assert set(np.asarray(d.CellTypes).tolist()) == {3}  # VTK_LINE
    for name, key in [("G_I_J_m2", "g_i"), ("G_II_J_m2", "g_ii"), ("G_III_J_m2", "g_iii"),
                      ("G_T_J_m2", "g_t")]:
        got = np.ravel(d.PointData[name])
        want = np.array([r[key] for r in rows])
        assert np.allclose(got, want, rtol=1e-15, atol=0), (name, got, want)
    checked += 1

# The uniaxial box deck's solve: S_xx = E E_xx at the points (E = 70 000 in the deck's units).
_, _, grids = states(f"{solve}/model.pvd")
assert len(grids) > 0
for d in grids:
    fields(
        d,
        {"node": 1, "displacement": 3, "strain_green_lagrange": 6, "stress_pk2": 6,
         "stress_cauchy": 6, "reaction": 3},
        {"material": 1, "ply_angle_deg": 1, "strain_green_lagrange": 6, "stress_pk2": 6,
         "stress_cauchy": 6},
    )
    s = np.asarray(d.PointData["stress_pk2"])
    e = np.asarray(d.PointData["strain_green_lagrange"])
    assert np.allclose(s[:, 0], 70000.0 * e[:, 0], rtol=1e-6, atol=0)
    checked += 1
print(f"ParaView check: {checked} passed, 0 failed")
