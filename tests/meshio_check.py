"""Reads the VTU files written by `cargo run --release --example write_vtu -- DIR` with meshio,
as a user's Python tools would, and checks counts, cell type and field values.

Usage: python3 tests/meshio_check.py DIR
"""
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
print("meshio check: 2 passed, 0 failed")
