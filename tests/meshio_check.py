"""Reads VTU/PVD files with meshio, as a user's Python tools would.

- DIR: written by `cargo run --release --example write_vtu -- DIR`: counts, cell type, values.
- RUN_DIR (optional): a `nonlin3d run --out RUN_DIR` folder: every file model.pvd and front.pvd
  list, every field with its shape, and the front's G against results.json's.
- SOLVE_DIR (optional): a `nonlin3d solve tests/decks/uniaxial_box.inp --out SOLVE_DIR` folder:
  every file model.pvd lists, every field with its shape, S_xx = E E_xx to 1e-6.

Usage: python3 tests/meshio_check.py DIR [RUN_DIR SOLVE_DIR]
"""
import json
import os
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np

d = sys.argv[1]
for step, scale in [(0, 1.0), (1, 2.0)]:
    m = meshio.read(f"{d}/box_{step}.vtu")
    # 4 × 3 × 2 Hex20: 5·4·3 corners + 4·4·3 + 5·3·3 + 5·4·2 mid-edge nodes.
    assert m.points.shape == (60 + 48 + 45 + 40, 3), m.points.shape
    assert len(m.cells) == 1 and m.cells[0].type == "hexahedron20", m.cells
    assert m.cells[0].data.shape == (24, 20)
    x = m.points
    u = m.point_data["displacement"]
    expect = np.column_stack([scale * 1e-3 * x[:, 0], scale * 2e-3 * x[:, 1], -scale * 0.1 * x[:, 0] ** 2])
    assert np.allclose(u, expect, rtol=0, atol=1e-15), np.abs(u - expect).max()
    sxx = np.ravel(m.cell_data["sxx"][0])
    assert np.allclose(sxx, scale * np.arange(24) * 1e6)
    assert (np.ravel(m.cell_data["material"][0]) == 0).all()
    # Mid-edge node 8 of every cell sits halfway between corners 0 and 1 (VTK = Abaqus order).
    c = m.cells[0].data
    assert np.allclose(x[c[:, 8]], 0.5 * (x[c[:, 0]] + x[c[:, 1]]), atol=1e-15)
    # Grading 0.5 along x: last element half the first.
    xs = np.unique(np.round(x[:, 0], 12))
    corners = xs[::2]
    assert abs((corners[-1] - corners[-2]) / (corners[1] - corners[0]) - 0.5) < 1e-9, corners
pvd = ET.parse(f"{d}/box.pvd").getroot()
files = [ds.get("file") for ds in pvd.iter("DataSet")]
assert files == ["box_0.vtu", "box_1.vtu"], files
checked = 2


def pvd(path):
    """The files a PVD lists, in order."""
    root = ET.parse(path).getroot()
    return [os.path.join(os.path.dirname(path), ds.get("file")) for ds in root.iter("DataSet")]


def fields(m, point, cell):
    """Every listed field is there with (count, components) and finite."""
    n = len(m.points)
    for name, c in point.items():
        v = m.point_data[name]
        assert v.reshape(n, -1).shape == (n, c), (name, v.shape)
        assert np.isfinite(v).all(), name
    ncell = sum(len(b.data) for b in m.cells)
    for name, c in cell.items():
        v = np.concatenate([np.asarray(a).reshape(len(a), -1) for a in m.cell_data[name]])
        assert v.shape == (ncell, c), (name, v.shape)
        assert np.isfinite(v).all(), name


if len(sys.argv) > 3:
    run, solve = sys.argv[2], sys.argv[3]
    results = json.load(open(f"{run}/results.json"))
    models = pvd(f"{run}/model.pvd")
    fronts = pvd(f"{run}/front.pvd")
    assert len(models) == len(fronts) == len(results["levels"]) > 0
    for path, level in zip(models, results["levels"]):
        m = meshio.read(path)
        fields(
            m,
            {"node": 1, "displacement_mm": 3, "strain_green_lagrange": 6, "stress_pk2_MPa": 6,
             "stress_cauchy_MPa": 6, "reaction_N": 3, "crack_opening_mm": 3},
            {"material": 1, "ply_angle_deg": 1, "strain_green_lagrange": 6,
             "stress_pk2_MPa": 6, "stress_cauchy_MPa": 6},
        )
        checked += 1
    for path, level in zip(fronts, results["levels"]):
        m = meshio.read(path)
        rows = level["front"]
        fields(m, {k: 1 for k in ["s_mm", "G_I_J_m2", "G_II_J_m2", "G_III_J_m2", "G_T_J_m2",
                                  "mode_mix", "open"]}, {})
        assert m.cells[0].type == "line" and m.cells[0].data.shape == (len(rows) - 1, 2)
        for name, key in [("G_I_J_m2", "g_i"), ("G_II_J_m2", "g_ii"), ("G_III_J_m2", "g_iii"),
                          ("G_T_J_m2", "g_t")]:
            got = np.ravel(m.point_data[name])
            want = np.array([r[key] for r in rows])
            assert np.allclose(got, want, rtol=1e-15, atol=0), (name, got, want)
        opened = np.ravel(m.point_data["open"]) == 1.0
        assert (opened == np.array([r["faces"] == "open" for r in rows])).all()
        checked += 1
    e_mod = 70000.0
    for path in pvd(f"{solve}/model.pvd"):
        m = meshio.read(path)
        fields(
            m,
            {"node": 1, "displacement": 3, "strain_green_lagrange": 6, "stress_pk2": 6,
             "stress_cauchy": 6, "reaction": 3},
            {"material": 1, "ply_angle_deg": 1, "strain_green_lagrange": 6, "stress_pk2": 6,
             "stress_cauchy": 6},
        )
        s, e = m.point_data["stress_pk2"], m.point_data["strain_green_lagrange"]
        assert np.allclose(s[:, 0], e_mod * e[:, 0], rtol=1e-6, atol=0)
        checked += 1
print(f"meshio check: {checked} passed, 0 failed")
