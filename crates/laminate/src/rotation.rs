//! Exact rotation of a Voigt stiffness (thesis strain order, engineering shears).

/// Tensor index pairs of the six Voigt components in the thesis order (eq. 2.1.4):
/// xx, yy, zz, xy, yz, xz.
pub const VOIGT_PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];

/// The rotation matrix about z by `theta` radians; its columns are the rotated x, y, z axes.
pub fn rotation_about_z(theta: f64) -> [[f64; 3]; 3] {
    let (s, c) = theta.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// Voigt index of the tensor pair (i, j) in the thesis order xx, yy, zz, xy, yz, xz.
fn voigt(i: usize, j: usize) -> usize {
    match (i.min(j), i.max(j)) {
        (0, 0) => 0,
        (1, 1) => 1,
        (2, 2) => 2,
        (0, 1) => 3,
        (1, 2) => 4,
        _ => 5,
    }
}

/// C′_ijkl = R_ia R_jb R_kc R_ld C_abcd for a stiffness in Voigt form with engineering shear
/// strains (for which C_IJ = C_ijkl with no factors). `r` maps material to global axes.
pub fn rotate_voigt(c: &[[f64; 6]; 6], r: &[[f64; 3]; 3]) -> [[f64; 6]; 6] {
    // Contract one index at a time: four passes of 81·3 multiply-adds.
    let mut t = [[[[0.0; 3]; 3]; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            for cc in 0..3 {
                for d in 0..3 {
                    t[a][b][cc][d] = c[voigt(a, b)][voigt(cc, d)];
                }
            }
        }
    }
    for pass in 0..4 {
        let mut next = [[[[0.0; 3]; 3]; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        let idx = [i, j, k, l];
                        let mut s = 0.0;
                        for a in 0..3 {
                            let mut src = idx;
                            src[pass] = a;
                            s += r[idx[pass]][a] * t[src[0]][src[1]][src[2]][src[3]];
                        }
                        next[i][j][k][l] = s;
                    }
                }
            }
        }
        t = next;
    }
    let mut out = [[0.0; 6]; 6];
    for (p, &(i, j)) in VOIGT_PAIRS.iter().enumerate() {
        for (q, &(k, l)) in VOIGT_PAIRS.iter().enumerate() {
            out[p][q] = t[i][j][k][l];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Orthotropic;

    #[test]
    fn rotation_by_90_degrees_swaps_axes() {
        let m = crate::materials::generic_graphite_epoxy();
        let c = m.stiffness().unwrap();
        let r = rotate_voigt(c.c(), &rotation_about_z(core::f64::consts::FRAC_PI_2));
        let tol = 1e-6; // Pa, round-off of cos(π/2) ≈ 6e-17 times 1e11
        assert!((r[1][1] - c.c()[0][0]).abs() < tol);
        assert!((r[0][0] - c.c()[1][1]).abs() < tol);
        assert!((r[4][4] - c.c()[5][5]).abs() < tol);
        assert!((r[1][2] - c.c()[0][2]).abs() < tol);
    }

    #[test]
    fn isotropic_material_is_invariant() {
        let c = Orthotropic::isotropic(70e9, 0.33).stiffness().unwrap();
        let r = rotate_voigt(c.c(), &rotation_about_z(0.7));
        for i in 0..6 {
            for j in 0..6 {
                assert!((r[i][j] - c.c()[i][j]).abs() < 1e-12 * 70e9 * 2.0);
            }
        }
    }

    #[test]
    fn rotation_round_trip_is_identity() {
        let c = crate::materials::im7_8551_7().stiffness().unwrap();
        let there = rotate_voigt(c.c(), &rotation_about_z(0.4));
        let back = rotate_voigt(&there, &rotation_about_z(-0.4));
        for i in 0..6 {
            for j in 0..6 {
                assert!((back[i][j] - c.c()[i][j]).abs() < 1e-12 * 2e11);
            }
        }
    }
}
