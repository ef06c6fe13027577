"""Writes ring_cylindrical.inp (python3 ring_cylindrical.py yes > ring_cylindrical.inp); with
"no" the same deck without the *ORIENTATION (for the comparison in docs/VALIDATION.md)."""
import math, sys
orient = sys.argv[1] == "yes"
nr, nt, nz = 2, 6, 1
r0, r1, t1, h = 0.010, 0.012, 60.0, 0.002
ids = {}
nodes = []
def nid(i, j, k):
    key = (i, j, k)
    if key not in ids:
        r = r0 + (r1 - r0) * i / (2 * nr)
        t = math.radians(t1 * j / (2 * nt))
        z = h * k / (2 * nz)
        ids[key] = len(nodes) + 1
        nodes.append((r * math.cos(t), r * math.sin(t), z))
    return ids[key]
# C3D20 reference order in (xi, eta, zeta) with xi = radial, eta = theta, zeta = z
corners = [(0,0,0),(2,0,0),(2,2,0),(0,2,0),(0,0,2),(2,0,2),(2,2,2),(0,2,2)]
mids = [(1,0,0),(2,1,0),(1,2,0),(0,1,0),(1,0,2),(2,1,2),(1,2,2),(0,1,2),(0,0,1),(2,0,1),(2,2,1),(0,2,1)]
elems = []
for k in range(nz):
    for j in range(nt):
        for i in range(nr):
            elems.append([nid(2*i+a, 2*j+b, 2*k+c) for (a,b,c) in corners + mids])
out = []
w = out.append
w("*HEADING")
w("Ring segment r 10-12 mm, theta 0-60 deg, 2 mm high, 2 x 6 x 1 C3D20 (m): hoop-stiff ply axes in a")
w("cylindrical *ORIENTATION about z (local 1 radial, 2 tangential, 3 axial); clamped at theta = 0,")
w("NLGEOM end load; stresses in the local axes of each integration point and in global axes")
w("*NODE, NSET=NALL")
for n, p in enumerate(nodes, 1):
    w(f"{n}, {p[0]:.15g}, {p[1]:.15g}, {p[2]:.15g}")
w("*ELEMENT, TYPE=C3D20, ELSET=ALL")
for e, ns in enumerate(elems, 1):
    w(f"{e}, " + ", ".join(map(str, ns[:15])) + ",")
    w(", ".join(map(str, ns[15:])))
fixed = sorted(v for (i, j, k), v in ids.items() if j == 0)
tip = sorted(v for (i, j, k), v in ids.items() if j == 2 * nt)
def nset(name, l):
    w(f"*NSET, NSET={name}")
    for a in range(0, len(l), 10):
        w(", ".join(map(str, l[a:a+10])))
nset("FIXED", fixed)
nset("TIP", tip)
w("*ELSET, ELSET=ONE\n1")
w("*ELSET, ELSET=LAST\n12")
w("*MATERIAL, NAME=HOOP")
w("*ELASTIC, TYPE=ENGINEERING CONSTANTS")
w("10.2e9, 134e9, 10.2e9, 0.0228, 0.49, 0.3, 5.52e9, 3.43e9")
w("5.52e9")
if orient:
    w("*ORIENTATION, NAME=CYL, SYSTEM=CYLINDRICAL")
    w("0., 0., 0., 0., 0., 1.")
    w("*SOLID SECTION, ELSET=ALL, MATERIAL=HOOP, ORIENTATION=CYL")
else:
    w("*SOLID SECTION, ELSET=ALL, MATERIAL=HOOP")
w("*CONTROLS, PARAMETERS=FIELD\n1e-7")
w("*STEP, NLGEOM\n*STATIC\n0.5, 1.")
w("*BOUNDARY\nFIXED, 1, 3")
w("*CLOAD\nTIP, 1, -8.\nTIP, 3, 2.")
w("*NODE PRINT, NSET=TIP\nU")
w("*NODE PRINT, NSET=FIXED, TOTALS=ONLY\nRF")
w("*EL PRINT, ELSET=ONE\nS")
w("*EL PRINT, ELSET=LAST, GLOBAL=YES\nS")
w("*END STEP")
print("\n".join(out))
