//! Gauss rules and the thesis's selective-reduced Hex8 rule (§2.3).

use crate::ElementKind;

/// Integration rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IntegrationRule {
    /// 2×2×2 Gauss: exact for polynomials of degree 3 in each coordinate. The thesis's rule for
    /// the Hex20 (reduced for it) and the full rule for the Hex8.
    Gauss2,
    /// 3×3×3 Gauss: exact to degree 5 in each coordinate; full integration of the Hex20.
    Gauss3,
    /// Hex8 only: ε1–ε4 at the 2×2×2 points, ε5 (γyz) and ε6 (γxz) at the centroid with the
    /// whole weight 8 (§2.3, refs. 3, 30, 31). One spurious zero-energy mode per reduced shear
    /// strain (§2.5).
    SelectiveReduced,
}

/// One sampling station of a rule: where, with what weight, and which strain components
/// (zero-based, half-open range) are integrated there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Station {
    /// Reference coordinates (ξ, η, ζ).
    pub xi: [f64; 3],
    /// Quadrature weight W.
    pub weight: f64,
    /// First strain component integrated here (0 = xx).
    pub first: usize,
    /// One past the last strain component integrated here (6 = all).
    pub last: usize,
}

impl Station {
    /// Number of strain components integrated at this station.
    pub fn components(&self) -> usize {
        self.last - self.first
    }
}

/// 1-D Gauss–Legendre points and weights on [−1, 1].
pub fn gauss_1d(points: usize) -> Option<(&'static [f64], &'static [f64])> {
    const A2: f64 = 0.577_350_269_189_625_8; // 1/√3
    const A3: f64 = 0.774_596_669_241_483_4; // √(3/5)
    match points {
        1 => Some((&[0.0], &[2.0])),
        2 => Some((&[-A2, A2], &[1.0, 1.0])),
        3 => Some((&[-A3, 0.0, A3], &[5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])),
        _ => None,
    }
}

impl IntegrationRule {
    /// Whether the rule is defined for `kind` (the selective-reduced rule is Hex8-only).
    pub fn supports(self, kind: ElementKind) -> bool {
        !matches!((self, kind), (Self::SelectiveReduced, ElementKind::Hex20))
    }

    /// The stations of the rule, ξ varying fastest, then η, then ζ; the selective-reduced rule
    /// lists its eight 2×2×2 stations (components 0–3) and then the centroid (components 4–5).
    pub fn stations(self) -> Vec<Station> {
        let tensor = |n: usize, first: usize, last: usize| {
            let mut out = Vec::with_capacity(n * n * n);
            if let Some((p, w)) = gauss_1d(n) {
                for k in 0..n {
                    for j in 0..n {
                        for i in 0..n {
                            out.push(Station {
                                xi: [p[i], p[j], p[k]],
                                weight: w[i] * w[j] * w[k],
                                first,
                                last,
                            });
                        }
                    }
                }
            }
            out
        };
        match self {
            Self::Gauss2 => tensor(2, 0, 6),
            Self::Gauss3 => tensor(3, 0, 6),
            Self::SelectiveReduced => {
                let mut s = tensor(2, 0, 4);
                s.extend(tensor(1, 4, 6));
                s
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫_{-1}^{1} x^p dx.
    fn exact(p: u32) -> f64 {
        if p % 2 == 1 {
            0.0
        } else {
            2.0 / (p as f64 + 1.0)
        }
    }

    #[test]
    fn gauss_rules_are_exact_to_their_degree() {
        for (rule, deg) in [(IntegrationRule::Gauss2, 3), (IntegrationRule::Gauss3, 5)] {
            let st = rule.stations();
            for a in 0..=deg {
                for b in 0..=deg {
                    for c in 0..=deg {
                        let q: f64 = st
                            .iter()
                            .map(|s| {
                                s.weight
                                    * s.xi[0].powi(a as i32)
                                    * s.xi[1].powi(b as i32)
                                    * s.xi[2].powi(c as i32)
                            })
                            .sum();
                        let e = exact(a) * exact(b) * exact(c);
                        assert!(
                            (q - e).abs() < 1e-14,
                            "{rule:?} x^{a} y^{b} z^{c}: {q} vs {e}"
                        );
                    }
                }
            }
            // and not exact one degree higher (x^(deg+1) is even → nonzero integral)
            let q: f64 = st
                .iter()
                .map(|s| s.weight * s.xi[0].powi(deg as i32 + 1))
                .sum();
            assert!((q - exact(deg + 1) * 4.0).abs() > 1e-3);
        }
    }

    #[test]
    fn selective_reduced_weights_cover_the_volume_for_each_component() {
        let st = IntegrationRule::SelectiveReduced.stations();
        for comp in 0..6 {
            let w: f64 = st
                .iter()
                .filter(|s| s.first <= comp && comp < s.last)
                .map(|s| s.weight)
                .sum();
            assert!((w - 8.0).abs() < 1e-14, "component {comp} weight {w}");
        }
        assert!(!IntegrationRule::SelectiveReduced.supports(ElementKind::Hex20));
    }
}
