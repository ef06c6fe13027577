"""Mattiasson elastica deck: slender cantilever of C3D20, NLGEOM, dead tip load to PL^2/EI = 10."""
import sys
n = int(sys.argv[1]) if len(sys.argv) > 1 else 40
L, b, h = 0.1, 0.002, 0.002
E = 210e9
I = b * h**3 / 12
P = 10 * E * I / L**2
xs = [L * i / (2 * n) for i in range(2 * n + 1)]  # half-steps
ys = [0.0, b / 2, b]
zs = [0.0, h / 2, h]
ids = {}
lines = []
nid = 0
for i, x in enumerate(xs):
    for j, y in enumerate(ys):
        for k, z in enumerate(zs):
            odd = (i % 2) + (j % 2) + (k % 2)
            if odd > 1:
                continue
            nid += 1
            ids[(i, j, k)] = nid
            lines.append(f"{nid}, {x:.12g}, {y:.12g}, {z:.12g}")
out = []
out.append("*HEADING")
out.append(f"Mattiasson elastica: cantilever {L*1e3:g} x {b*1e3:g} x {h*1e3:g} mm, {n} x 1 x 1 C3D20, E = {E/1e9:g} GPa, nu = 0,")
out.append(f"dead tip load P = 10 EI/L^2 = {P:.6g} N in *STATIC 0.1, 1 (PL^2/EI = 1 ... 10)")
out.append("** Written by tests/decks/mattiasson.py (nonlin3d); Mattiasson 1981, the elastica under a tip load.")
out.append("*NODE, NSET=NALL")
out += lines
out.append("*ELEMENT, TYPE=C3D20, ELSET=ALL")
for e in range(n):
    i0 = 2 * e
    c = lambda di, j, k: ids[(i0 + di, j, k)]
    # corners: bottom face z=0 (1,2,3,4), top z=h (5..8); x along 1->2, y along 2->3
    conn = [c(0,0,0), c(2,0,0), c(2,2,0), c(0,2,0), c(0,0,2), c(2,0,2), c(2,2,2), c(0,2,2),
            c(1,0,0), c(2,1,0), c(1,2,0), c(0,1,0), c(1,0,2), c(2,1,2), c(1,2,2), c(0,1,2),
            c(0,0,1), c(2,0,1), c(2,2,1), c(0,2,1)]
    out.append(f"{e+1}, " + ", ".join(map(str, conn[:15])) + ",")
    out.append(", ".join(map(str, conn[15:])))
root = sorted(v for (i, j, k), v in ids.items() if i == 0)
tip = sorted(v for (i, j, k), v in ids.items() if i == 2 * n)
def nset(name, nodes):
    out.append(f"*NSET, NSET={name}")
    for s in range(0, len(nodes), 16):
        out.append(", ".join(map(str, nodes[s:s+16])))
nset("ROOT", root)
nset("TIP", tip)
out.append("*MATERIAL, NAME=STEEL")
out.append("*ELASTIC")
out.append(f"{E:.6g}, 0.0")
out.append("*SOLID SECTION, ELSET=ALL, MATERIAL=STEEL")
out.append("*STEP, NLGEOM, INC=100")
out.append("*STATIC")
out.append("0.1, 1.0")
out.append("*BOUNDARY")
out.append("ROOT, 1, 3")
out.append("*CLOAD")
out.append("** Consistent nodal forces of a uniform shear traction on the 8-node tip face:")
out.append("** corners -1/12, mid-sides 1/3 of P (downward: -z).")
for (i, j, k), v in sorted(ids.items(), key=lambda kv: kv[1]):
    if i != 2 * n:
        continue
    corner = (j % 2 == 0) and (k % 2 == 0)
    f = -P / 12 if corner else P / 3
    out.append(f"{v}, 3, {-f:.10g}")
out.append("*NODE PRINT, NSET=TIP")
out.append("U")
out.append("*END STEP")
print("\n".join(out))
