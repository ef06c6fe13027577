//! The polynomial predictor of an increment without prescribed-value changes (Abaqus's
//! `EXTRAPOLATION=LINEAR | PARABOLIC`, CalculiX's start from the previous increment): the
//! start of the increment to step time t is the Lagrange polynomial through the last converged
//! states (t_i, u_i), u(t) ≈ Σ_i u_i Π_{j≠i} (t − t_j)/(t_i − t_j) — linear through two states,
//! quadratic through three. The error of the quadratic start is O(Δt³·u‴) against the linear
//! one's O(Δt²·u″), which is what a Newton start needs on a curved path (the elastica's tip
//! turning through 80°).

use std::collections::VecDeque;

/// The last converged states of a path and the order of the polynomial through them.
#[derive(Debug, Clone)]
pub struct Extrapolation {
    order: usize,
    points: VecDeque<(f64, Vec<f64>)>,
}

impl Extrapolation {
    /// A predictor of polynomial `order` (0 = none, 1 = linear, 2 = quadratic; higher orders
    /// are clamped to 2: the elastica deck gains nothing beyond, docs/PERFORMANCE.md).
    pub fn new(order: usize) -> Self {
        Self {
            order: order.min(2),
            points: VecDeque::new(),
        }
    }

    /// Records the converged state `u` at step time `t` (t increasing).
    pub fn push(&mut self, t: f64, u: &[f64]) {
        if self.order == 0 {
            return;
        }
        if self.points.len() > self.order {
            self.points.pop_front();
        }
        self.points.push_back((t, u.to_vec()));
    }

    /// Forgets every state (a new step, or loads that jumped).
    pub fn clear(&mut self) {
        self.points.clear();
    }

    /// The predicted state at step time `t`, or `None` with fewer than two states (the plain
    /// start, the last converged state, is the caller's).
    pub fn predict(&self, t: f64) -> Option<Vec<f64>> {
        if self.points.len() < 2 {
            return None;
        }
        let ts: Vec<f64> = self.points.iter().map(|p| p.0).collect();
        let n = self.points[0].1.len();
        let mut out = vec![0.0; n];
        for (i, (ti, ui)) in self.points.iter().enumerate() {
            let w: f64 = ts
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &tj)| (t - tj) / (ti - tj))
                .product();
            for (o, x) in out.iter_mut().zip(ui) {
                *o += w * x;
            }
        }
        out.iter().all(|x| x.is_finite()).then_some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::Extrapolation;

    /// u(t) = (1 + 2t − 3t², t³): the quadratic predictor through t = 0, 0.1, 0.25 is exact for
    /// the first component and short by (t − 0)(t − 0.1)(t − 0.25)·u‴/6 = 0.4·0.3·0.15 = 0.018
    /// for the cubic one at t = 0.4; the linear one through the last two is over by
    /// −(t − 0.1)(t − 0.25)·u″/2 = 0.045·3 = 0.135 in the first.
    #[test]
    fn quadratic_is_exact_on_a_parabola() {
        let u = |t: f64| vec![1.0 + 2.0 * t - 3.0 * t * t, t * t * t];
        let mut q = Extrapolation::new(2);
        let mut l = Extrapolation::new(1);
        assert!(q.predict(0.1).is_none());
        for t in [0.0, 0.1, 0.25] {
            q.push(t, &u(t));
            l.push(t, &u(t));
        }
        let p = q.predict(0.4).unwrap();
        assert!((p[0] - u(0.4)[0]).abs() < 1e-14, "{p:?}");
        assert!((p[1] - u(0.4)[1] + 0.018).abs() < 1e-14, "{p:?}");
        let p = l.predict(0.4).unwrap();
        assert!((p[0] - u(0.4)[0] - 0.135).abs() < 1e-14, "{p:?}");
        assert!(Extrapolation::new(0).predict(0.4).is_none());
    }
}
