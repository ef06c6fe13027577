//! Richardson extrapolation of a refinement family: f(h) = f∞ + C·h^p, fitted to the three
//! finest meshes with the observed order p (Richardson 1911; the non-uniform-ratio form of
//! Roache, "Verification and Validation in Computational Science and Engineering", 1998, §5.4),
//! and whether the family is in the asymptotic range.

use serde::Serialize;

/// Smallest observed order taken as convergence: below it the sequence barely converges and
/// the extrapolated limit lies far beyond the data.
pub const MIN_ORDER: f64 = 0.5;
/// Largest observed order believed: the VCCT's G converges at p ≈ 1–2.5 on the committed
/// families (docs/ACCURACY.md); far above that the differences fell by chance.
pub const MAX_ORDER: f64 = 5.0;
/// Orders of successive triples that differ by more than this fraction of their mean
/// disagree: the coarser meshes are not yet in the asymptotic range.
pub const ORDER_AGREEMENT: f64 = 0.25;

/// f∞ and p from three meshes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extrapolation {
    /// The extrapolated limit f∞.
    pub limit: f64,
    /// The observed order p.
    pub order: f64,
}

/// Why three values give no extrapolation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NoOrder {
    /// The differences change sign (the sequence goes up, then down).
    NonMonotone,
    /// The differences do not shrink (p ≤ 0): diverging or not yet converging.
    NotShrinking,
    /// The last two values are equal to round-off: nothing to extrapolate (the limit is the
    /// last value).
    Settled,
}

impl std::fmt::Display for NoOrder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::NonMonotone => "non-monotone (the differences change sign)",
            Self::NotShrinking => "the differences do not shrink",
            Self::Settled => "the finest values agree to round-off",
        })
    }
}

/// The ratio of successive differences that order `p` gives for sizes h1 > h2 > h3:
/// (h1^p − h2^p)/(h2^p − h3^p); r^p for a constant ratio r = h1/h2 = h2/h3.
fn difference_ratio(h: [f64; 3], p: f64) -> f64 {
    (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p))
}

/// f∞ and p from three (h, f) points, coarse to fine (h1 > h2 > h3 > 0): p solves
/// (f1 − f2)/(f2 − f3) = (h1^p − h2^p)/(h2^p − h3^p) (by bisection: the right side rises
/// with p), then C = (f2 − f3)/(h2^p − h3^p) and f∞ = f3 − C·h3^p. An order above 64 is
/// returned as 64 (the limit is then f3).
pub fn three_point(points: [(f64, f64); 3]) -> Result<Extrapolation, NoOrder> {
    let [(h1, f1), (h2, f2), (h3, f3)] = points;
    // Sizes relative to the coarsest: h^p stays in [0, 1].
    let h = [1.0, h2 / h1, h3 / h1];
    let (d1, d2) = (f1 - f2, f2 - f3);
    let scale = f1.abs().max(f2.abs()).max(f3.abs()).max(f64::MIN_POSITIVE);
    if d2.abs() <= 1e-12 * scale {
        return Err(NoOrder::Settled);
    }
    let q = d1 / d2;
    if q <= 0.0 {
        return Err(NoOrder::NonMonotone);
    }
    let (mut lo, mut hi) = (1e-9, 64.0);
    if q <= difference_ratio(h, lo) {
        return Err(NoOrder::NotShrinking);
    }
    if q < difference_ratio(h, hi) {
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if difference_ratio(h, mid) < q {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }
    let p = 0.5 * (lo + hi);
    let c = d2 / (h[1].powf(p) - h[2].powf(p));
    Ok(Extrapolation {
        limit: f3 - c * h[2].powf(p),
        order: p,
    })
}

/// The reference of one quantity from a family, and how far to trust it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FamilyFit {
    /// The reference value: Richardson's limit from the three finest meshes, or the finest
    /// value when there is no extrapolation.
    pub reference: f64,
    /// `richardson` or `finest`.
    pub method: &'static str,
    /// The observed order of the finest triple.
    pub order: Option<f64>,
    /// The observed order of every triple, coarse to fine (None where it has none).
    pub orders: Vec<Option<f64>>,
    /// Whether the family looks asymptotic: monotone, orders within [`MIN_ORDER`] …
    /// [`MAX_ORDER`] and, with four or more meshes, the two finest triples' orders agreeing
    /// within [`ORDER_AGREEMENT`].
    pub asymptotic: bool,
    /// What is wrong when it is not.
    pub note: Option<String>,
}

/// Fits a family given as (h, f) from coarse to fine (h strictly decreasing).
pub fn fit(points: &[(f64, f64)]) -> Option<FamilyFit> {
    let finest = points.last()?.1;
    if points.len() < 3 {
        return Some(FamilyFit {
            reference: finest,
            method: "finest",
            order: None,
            orders: Vec::new(),
            asymptotic: false,
            note: Some(format!(
                "{} meshes in the family: three are needed to extrapolate",
                points.len()
            )),
        });
    }
    let fits: Vec<Result<Extrapolation, NoOrder>> = points
        .windows(3)
        .map(|w| three_point([w[0], w[1], w[2]]))
        .collect();
    let orders: Vec<Option<f64>> = fits.iter().map(|f| f.ok().map(|e| e.order)).collect();
    let diffs: Vec<f64> = points.windows(2).map(|w| w[1].1 - w[0].1).collect();
    let monotone = diffs.iter().all(|&d| d >= 0.0) || diffs.iter().all(|&d| d <= 0.0);
    let mut notes = Vec::new();
    if !monotone {
        notes.push("non-monotone: the values go up and down with refinement".to_string());
    }
    let last = fits[fits.len() - 1];
    let (reference, method, order) = match last {
        Ok(e) => (e.limit, "richardson", Some(e.order)),
        Err(NoOrder::Settled) => (finest, "finest", None),
        Err(why) => {
            notes.push(format!("finest three meshes: {why}"));
            (finest, "finest", None)
        }
    };
    if let Some(p) = order
        && !(MIN_ORDER..=MAX_ORDER).contains(&p)
    {
        notes.push(format!(
            "observed order {p:.2} outside {MIN_ORDER} … {MAX_ORDER}"
        ));
    }
    if let [.., Some(a), Some(b)] = orders[..]
        && (a - b).abs() > ORDER_AGREEMENT * 0.5 * (a + b)
    {
        notes.push(format!(
            "orders disagree: {a:.2} then {b:.2} over the two finest triples"
        ));
    }
    if orders.len() >= 2 && orders[orders.len() - 2].is_none() && order.is_some() {
        notes.push("the coarser triple has no order".to_string());
    }
    Some(FamilyFit {
        reference,
        method,
        order,
        orders,
        asymptotic: notes.is_empty() && (order.is_some() || last == Err(NoOrder::Settled)),
        note: (!notes.is_empty()).then(|| notes.join("; ")),
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// f(h) = f∞ + C·h^p sampled at `h`.
    fn sample(limit: f64, c: f64, p: f64, h: &[f64]) -> Vec<(f64, f64)> {
        h.iter().map(|&h| (h, limit + c * h.powf(p))).collect()
    }

    #[test]
    fn a_power_law_gives_back_its_limit_and_order() {
        // Constant ratio 2: p = log2(d1/d2) exactly; the bisection runs to machine precision,
        // so 1e-9 is round-off of h^p differences, not a discretisation tolerance.
        let s = sample(2.0, 3.0, 1.5, &[1.0, 0.5, 0.25]);
        let e = three_point([s[0], s[1], s[2]]).unwrap();
        assert_relative_eq!(e.limit, 2.0, max_relative = 1e-9);
        assert_relative_eq!(e.order, 1.5, max_relative = 1e-9);
        // Non-uniform ratios (1 → 0.6 → 0.25), converging from below, large h.
        let s = sample(218.5, -40.0, 1.35, &[1.2, 0.6, 0.25]);
        let e = three_point([s[0], s[1], s[2]]).unwrap();
        assert_relative_eq!(e.limit, 218.5, max_relative = 1e-9);
        assert_relative_eq!(e.order, 1.35, max_relative = 1e-9);
    }

    #[test]
    fn a_family_on_a_power_law_is_asymptotic() {
        let s = sample(-1.7e-3, 2e-4, 2.0, &[0.4, 0.2, 0.1, 0.05]);
        let f = fit(&s).unwrap();
        assert!(f.asymptotic, "{f:?}");
        assert_eq!(f.method, "richardson");
        assert_relative_eq!(f.reference, -1.7e-3, max_relative = 1e-9);
        for p in &f.orders {
            assert_relative_eq!(p.unwrap(), 2.0, max_relative = 1e-9);
        }
    }

    #[test]
    fn orders_that_disagree_are_named() {
        // f = 1 + h + 10 h⁴: the quartic term dominates the coarse meshes, so the coarse
        // triple's order (3.56) is far above the fine one's (2.35; 1 in the limit).
        let h: [f64; 4] = [1.0, 0.5, 0.25, 0.125];
        let s: Vec<(f64, f64)> = h.iter().map(|&h| (h, 1.0 + h + 10.0 * h.powi(4))).collect();
        let f = fit(&s).unwrap();
        assert!(!f.asymptotic);
        assert!(
            f.note.as_deref().unwrap().contains("orders disagree"),
            "{f:?}"
        );
    }

    #[test]
    fn a_non_monotone_sequence_is_not_extrapolated() {
        let s = [(1.0, 10.0), (0.5, 12.0), (0.25, 11.0)];
        assert_eq!(three_point(s), Err(NoOrder::NonMonotone));
        let f = fit(&s).unwrap();
        assert!(!f.asymptotic);
        assert_eq!(f.method, "finest");
        assert_eq!(f.reference, 11.0);
        assert!(f.note.as_deref().unwrap().contains("non-monotone"), "{f:?}");
    }

    #[test]
    fn growing_differences_and_short_families_are_refused() {
        let s = [(1.0, 10.0), (0.5, 11.0), (0.25, 13.0)];
        assert_eq!(three_point(s), Err(NoOrder::NotShrinking));
        let f = fit(&s[..2]).unwrap();
        assert!(!f.asymptotic && f.method == "finest" && f.reference == 11.0);
        assert!(fit(&[]).is_none());
        let settled = [(1.0, 5.0), (0.5, 5.0), (0.25, 5.0)];
        assert_eq!(three_point(settled), Err(NoOrder::Settled));
        assert!(fit(&settled).unwrap().asymptotic);
    }
}
