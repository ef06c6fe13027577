//! The release test's quantity: a contact pressure recovered from the nodal contact forces
//! with a face basis whose integrals are positive (docs/THEORY.md, "Contact pressure on
//! quadratic faces").
//!
//! A pressure p on a face gives the consistent nodal forces f_i = ∫ N_i p dA. On an 8-node
//! serendipity facet of area A under a uniform p, ∫N_corner = −A/12 and ∫N_mid = A/3: the
//! corner forces of a compressed face are tensile, and a release test on the raw forces opens
//! every corner pair of a Hex20 face that is pressed uniformly. The test is therefore made on
//! f̂ = T f, the forces of the transformed basis N̂ = T N (per facet)
//!
//! N̂_c = N_c + α (N_m + N_m′)  (c a corner, m, m′ the mid-edge nodes of its two edges),
//! N̂_m = (1 − 2α) N_m,
//!
//! which spans the same space and sums to 1 as N does (each N_m is added to its two corners:
//! 2α + 1 − 2α = 1). Assembled over the facets around a node, with f_m the assembled force of
//! mid-edge node m (every facet that holds m holds both its corners):
//!
//! f̂_c = f_c + α Σ_{m next to c} f_m,   f̂_m = (1 − 2α) f_m.
//!
//! ∫N̂_c = A(−1/12 + 2α/3) > 0 needs α > 1/8, ∫N̂_m = (1 − 2α) A/3 > 0 needs α < 1/2; with
//! α = 1/5 they are A/20 and A/5 (sum 4·A/20 + 4·A/5 = A). The recovered pressure
//! p̂_i = f̂_i / ∫N̂_i is exact for a uniform p at every node (f̂_i = p ∫N̂_i), and its sign is
//! that of f̂_i: the release test compares f̂_i with the force tolerance. On linear (Hex8)
//! faces there is no mid-edge node, T = I, f̂ = f and p̂_i = f_i / (A/4 per facet).

use crate::facet::{Basis, Facet, cross_norm, sub};

/// The weight α of the mid-edge functions added to their corners (module docs: 1/8 < α < 1/2).
pub const ALPHA: f64 = 0.2;

/// The transformed basis of each pair's lower node: whether it is a mid-edge node, the
/// mid-edge pairs next to it (corners), and ∫N̂ dA over its reference facets. `index` maps a
/// node to its pair (usize::MAX: not a pair's lower node).
pub(crate) fn bases(
    facets: &[Facet],
    index: &[usize],
    coords: &[[f64; 3]],
    pairs: usize,
) -> Vec<Basis> {
    let mut out = vec![Basis::default(); pairs];
    let pair = |v: usize| index.get(v).copied().filter(|&i| i < pairs);
    for f in facets {
        let x = f.corners.map(|v| coords[v]);
        // Area of the planar quad: half the cross product of its diagonals.
        let area = 0.5 * cross_norm(sub(x[2], x[0]), sub(x[3], x[1]));
        let quadratic = !f.mids.is_empty();
        let corner_weight = if quadratic {
            area * (-1.0 / 12.0 + 2.0 * ALPHA / 3.0)
        } else {
            area / 4.0
        };
        for &c in &f.corners {
            if let Some(i) = pair(c) {
                out[i].weight += corner_weight;
            }
        }
        for &(m, ends) in &f.mids {
            let Some(j) = pair(m) else { continue };
            out[j].mid = true;
            out[j].weight += (1.0 - 2.0 * ALPHA) * area / 3.0;
            for c in ends.iter().filter_map(|&c| pair(c)) {
                if !out[c].next.contains(&j) {
                    out[c].next.push(j);
                }
                if !out[j].ends.contains(&c) {
                    out[j].ends.push(c);
                }
            }
        }
    }
    out
}

/// f̂ = T f (module docs) from the nodal contact forces `forces` (one per pair, N).
pub(crate) fn transformed(basis: &[Basis], forces: &[f64]) -> Vec<f64> {
    basis
        .iter()
        .zip(forces)
        .map(|(b, &f)| {
            if b.mid {
                (1.0 - 2.0 * ALPHA) * f
            } else {
                f + ALPHA * b.next.iter().map(|&m| forces[m]).sum::<f64>()
            }
        })
        .collect()
}

/// The gaps in the basis of f̂: g̃ = T⁻ᵀ g (module docs of `active`), so that f̂·g̃ = f·g.
/// Corners g̃_c = g_c; mid-edge nodes g̃_m = (g_m − α Σ_{c at its ends} g_c)/(1 − 2α).
pub(crate) fn weighted_gaps(basis: &[Basis], gaps: &[f64]) -> Vec<f64> {
    basis
        .iter()
        .zip(gaps)
        .map(|(b, &g)| {
            if b.mid {
                (g - ALPHA * b.ends.iter().map(|&c| gaps[c]).sum::<f64>()) / (1.0 - 2.0 * ALPHA)
            } else {
                g
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::CrackFaces;
    use approx::assert_relative_eq;
    use nonlin3d_element::ElementKind;
    use nonlin3d_mesh::{BoxParams, structured_box};

    /// A Hex20 box 3 × 2 cells on its top face z = 1 as the lower face (the upper face loose
    /// copies of its nodes: only the lower face matters here): the consistent forces of
    /// a uniform pressure p, f_i = p Σ ∫N_i dA (corners −A/12, mid-edges A/3 per facet), are
    /// tensile at the corners, and the recovered pressure is p at every node; the weights sum
    /// to the face's area.
    #[test]
    fn a_uniform_pressure_is_recovered_at_every_node_of_a_quadratic_face() {
        let mut mesh = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [3, 2, 1],
            [3.0, 2.0, 1.0],
        ))
        .unwrap();
        let lower = mesh.node_sets["z1"].clone();
        // The upper face: loose copies of the lower face's nodes.
        let upper: Vec<usize> = (mesh.nodes.len()..mesh.nodes.len() + lower.len()).collect();
        let copies: Vec<[f64; 3]> = lower.iter().map(|&v| mesh.nodes[v]).collect();
        mesh.nodes.extend(copies);
        let faces = CrackFaces::from_sets(&mesh, &upper, &lower).unwrap();
        let p = 7.0;
        // f_i = p ∫N_i: corners −1/12, mid-edges 1/3 of each unit facet around the node; a
        // node has 2 facets along an axis where it is inside the face, 1 on its rim.
        let count = |x: f64, n: f64| if x > 0.0 && x < n { 2.0 } else { 1.0 };
        let forces: Vec<f64> = lower
            .iter()
            .map(|&v| {
                let [x, y, _] = mesh.nodes[v];
                let half = |c: f64| c.fract() != 0.0;
                if half(x) {
                    p * count(y, 2.0) / 3.0
                } else if half(y) {
                    p * count(x, 3.0) / 3.0
                } else {
                    -p * count(x, 3.0) * count(y, 2.0) / 12.0
                }
            })
            .collect();
        assert_relative_eq!(forces.iter().sum::<f64>(), p * 6.0, max_relative = 1e-13);
        assert!(forces.iter().filter(|&&f| f < 0.0).count() == 12);
        for q in faces.pressures(&forces) {
            assert_relative_eq!(q, p, max_relative = 1e-13);
        }
        let area: f64 = faces.basis.iter().map(|b| b.weight).sum();
        assert_relative_eq!(area, 6.0, max_relative = 1e-13);
    }

    /// The 3 × 2 Hex20 face of the test above (as upper and lower face).
    fn face() -> CrackFaces {
        let mut mesh = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [3, 2, 1],
            [3.0, 2.0, 1.0],
        ))
        .unwrap();
        let lower = mesh.node_sets["z1"].clone();
        let upper: Vec<usize> = (mesh.nodes.len()..mesh.nodes.len() + lower.len()).collect();
        let copies: Vec<[f64; 3]> = lower.iter().map(|&v| mesh.nodes[v]).collect();
        mesh.nodes.extend(copies);
        CrackFaces::from_sets(&mesh, &upper, &lower).unwrap()
    }

    proptest::proptest! {
        /// g̃ = T⁻ᵀ g is the conjugate of f̂ = T f: f̂·g̃ = f·g for any forces and gaps (to the
        /// round-off of sums of a few dozen terms of size 1 × 1: 1e-12), and g = Tᵀ g̃ has non-negative
        /// weights, so g̃ ≥ 0 at every pair gives g ≥ 0 at every pair (no nodal overlap).
        #[test]
        fn weighted_gaps_are_conjugate_to_recovered_forces(
            f in proptest::collection::vec(-1.0..1.0f64, 64),
            g in proptest::collection::vec(-1.0..1.0f64, 64),
        ) {
            let faces = face();
            let (f, g) = (&f[..faces.len()], &g[..faces.len()]);
            let (fh, gt) = (faces.recovered(f), faces.weighted_gaps(g));
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            proptest::prop_assert!((dot(&fh, &gt) - dot(f, g)).abs() < 1e-12);
            // g from g̃ ≥ 0 (|g̃|): g = Tᵀ g̃ ≥ 0.
            let pos: Vec<f64> = gt.iter().map(|x| x.abs()).collect();
            let back = transpose_apply(&faces, &pos);
            proptest::prop_assert!(back.iter().all(|&x| x >= 0.0));
            let again = faces.weighted_gaps(&back);
            for (a, b) in again.iter().zip(&pos) {
                proptest::prop_assert!((a - b).abs() < 1e-12);
            }
        }
    }

    /// g = Tᵀ g̃: g_c = g̃_c, g_m = (1 − 2α) g̃_m + α Σ_ends g̃_c.
    fn transpose_apply(faces: &CrackFaces, gt: &[f64]) -> Vec<f64> {
        faces
            .basis
            .iter()
            .zip(gt)
            .map(|(b, &x)| {
                if b.mid {
                    (1.0 - 2.0 * super::ALPHA) * x
                        + super::ALPHA * b.ends.iter().map(|&c| gt[c]).sum::<f64>()
                } else {
                    x
                }
            })
            .collect()
    }
}
