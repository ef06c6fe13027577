//! A clamped Hex20 box as an Abaqus/CalculiX deck: `nx × ny × nz` C3D20 elements on an
//! `lx × ly × lz` mm box of steel (E = 210 000 MPa, ν = 0.3), the face x = 0 clamped (all three
//! displacements), a total shear load `load` N in −z on the face x = lx, spread as the
//! consistent nodal loads of a uniform traction (per 8-node face: corners −A·t/12, midsides
//! A·t/3), one linear static step. Units mm, N, MPa.

use std::io::{self, Write};

/// The box's cells, size (mm) and tip load (N).
#[derive(Debug, Clone, Copy)]
pub struct BoxDeck {
    /// Elements along x, y, z.
    pub cells: [usize; 3],
    /// Edge lengths, mm.
    pub size: [f64; 3],
    /// Total load in −z on the face x = lx, N.
    pub load: f64,
}

/// C3D20 node offsets on the doubled lattice (corners 1–8, bottom midsides 9–12, top 13–16,
/// vertical 17–20), CalculiX's numbering.
const HEX20: [[usize; 3]; 20] = [
    [0, 0, 0],
    [2, 0, 0],
    [2, 2, 0],
    [0, 2, 0],
    [0, 0, 2],
    [2, 0, 2],
    [2, 2, 2],
    [0, 2, 2],
    [1, 0, 0],
    [2, 1, 0],
    [1, 2, 0],
    [0, 1, 0],
    [1, 0, 2],
    [2, 1, 2],
    [1, 2, 2],
    [0, 1, 2],
    [0, 0, 1],
    [2, 0, 1],
    [2, 2, 1],
    [0, 2, 1],
];

impl BoxDeck {
    /// Lattice points per direction (2 n + 1).
    fn lattice(&self) -> [usize; 3] {
        self.cells.map(|n| 2 * n + 1)
    }

    /// 1-based node ids on the doubled lattice (0: not a node — a face or cell centre), and
    /// the node count.
    fn node_ids(&self) -> (Vec<u32>, usize) {
        let [a, b, c] = self.lattice();
        let mut ids = vec![0u32; a * b * c];
        let mut next = 0usize;
        for k in 0..c {
            for j in 0..b {
                for i in 0..a {
                    if (i % 2) + (j % 2) + (k % 2) <= 1 {
                        next += 1;
                        ids[(k * b + j) * a + i] = next as u32;
                    }
                }
            }
        }
        (ids, next)
    }

    /// The 20 node ids of each element (1-based), elements in x, then y, then z order.
    fn elements(&self, ids: &[u32]) -> Vec<[u32; 20]> {
        let [a, b, _] = self.lattice();
        let [nx, ny, nz] = self.cells;
        let mut out = Vec::with_capacity(nx * ny * nz);
        for ez in 0..nz {
            for ey in 0..ny {
                for ex in 0..nx {
                    let mut e = [0u32; 20];
                    for (slot, o) in e.iter_mut().zip(HEX20) {
                        let (i, j, k) = (2 * ex + o[0], 2 * ey + o[1], 2 * ez + o[2]);
                        *slot = ids[(k * b + j) * a + i];
                    }
                    out.push(e);
                }
            }
        }
        out
    }

    /// DOF count and each element's 60 DOFs (node id − 1, times 3, plus the direction): the
    /// assembled stiffness's pattern, for estimates without writing the deck.
    pub fn dof_lists(&self) -> (usize, Vec<Vec<usize>>) {
        let (ids, nodes) = self.node_ids();
        let lists = self
            .elements(&ids)
            .iter()
            .map(|e| {
                e.iter()
                    .flat_map(|&n| (0..3).map(move |d| 3 * (n as usize - 1) + d))
                    .collect()
            })
            .collect();
        (3 * nodes, lists)
    }

    /// Writes the deck.
    pub fn write(&self, out: &mut impl Write) -> io::Result<()> {
        let [a, b, c] = self.lattice();
        let [nx, ny, nz] = self.cells;
        let h = [0, 1, 2].map(|d| self.size[d] / (2 * self.cells[d]) as f64);
        let (ids, nodes) = self.node_ids();
        writeln!(
            out,
            "** Clamped Hex20 box {nx} x {ny} x {nz} C3D20, {} x {} x {} mm, steel, {} N in -z on x = {} mm",
            self.size[0], self.size[1], self.size[2], self.load, self.size[0]
        )?;
        writeln!(
            out,
            "** {nodes} nodes, {} DOF (mm, N, MPa); written by benches/box_deck.rs",
            3 * nodes
        )?;
        writeln!(out, "*NODE, NSET=NALL")?;
        for k in 0..c {
            for j in 0..b {
                for i in 0..a {
                    let id = ids[(k * b + j) * a + i];
                    if id > 0 {
                        let x = [i as f64 * h[0], j as f64 * h[1], k as f64 * h[2]];
                        writeln!(out, "{id}, {}, {}, {}", x[0], x[1], x[2])?;
                    }
                }
            }
        }
        writeln!(out, "*ELEMENT, TYPE=C3D20, ELSET=EALL")?;
        for (n, e) in self.elements(&ids).iter().enumerate() {
            write!(out, "{}", n + 1)?;
            for (s, id) in e.iter().enumerate() {
                // At most 16 entries a line: the 15th node ends the first.
                write!(out, "{}{id}", if s == 15 { ",\n" } else { ", " })?;
            }
            writeln!(out)?;
        }
        // The clamped face (i = 0) and the loaded one (i = 2 nx).
        let face = |i: usize| {
            let mut v = Vec::new();
            for k in 0..c {
                for j in 0..b {
                    let id = ids[(k * b + j) * a + i];
                    if id > 0 {
                        v.push((id, j, k));
                    }
                }
            }
            v
        };
        writeln!(out, "*NSET, NSET=X0")?;
        for chunk in face(0).chunks(16) {
            let line: Vec<String> = chunk.iter().map(|n| n.0.to_string()).collect();
            writeln!(out, "{}", line.join(", "))?;
        }
        writeln!(out, "*MATERIAL, NAME=STEEL")?;
        writeln!(out, "*ELASTIC")?;
        writeln!(out, "210000., 0.3")?;
        writeln!(out, "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL")?;
        writeln!(out, "*STEP")?;
        writeln!(out, "*STATIC")?;
        writeln!(out, "*BOUNDARY")?;
        writeln!(out, "X0, 1, 3, 0.0")?;
        writeln!(out, "*CLOAD")?;
        // Traction t on each face cell of area A: corners −A t / 12, midsides A t / 3.
        let t = -self.load / (self.size[1] * self.size[2]);
        let area = 4.0 * h[1] * h[2];
        let mut force = vec![0.0; b * c];
        for ck in 0..nz {
            for cj in 0..ny {
                for (dj, dk) in [(0, 0), (2, 0), (2, 2), (0, 2)] {
                    force[(2 * ck + dk) * b + 2 * cj + dj] -= area * t / 12.0;
                }
                for (dj, dk) in [(1, 0), (2, 1), (1, 2), (0, 1)] {
                    force[(2 * ck + dk) * b + 2 * cj + dj] += area * t / 3.0;
                }
            }
        }
        for (id, j, k) in face(a - 1) {
            writeln!(out, "{id}, 3, {:e}", force[k * b + j])?;
        }
        writeln!(out, "*END STEP")?;
        Ok(())
    }
}
