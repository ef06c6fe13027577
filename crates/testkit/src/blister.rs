//! The straight-sided (one-dimensional) buckle-driven blister of a thin film, Hutchinson & Suo
//! (1992), "Mixed mode cracking in layered materials", Adv. Appl. Mech. 29 (buckling-driven
//! delamination): the closed form a through-width delamination is checked against.
//!
//! A film of thickness h, compressed to the strain ε (compression positive), is delaminated
//! over a length ℓ = 2a and buckles as a clamped–clamped column at ε_b (= π²h²/(3ℓ²) for a rigid
//! clamp). Past ε_b the buckle's amplitude is δ = h·√((4/3)(ε/ε_b − 1)), and the film at each
//! crack tip carries, relative to the bonded film ahead, the edge force ΔN = Ē·h·(ε − ε_b) and
//! the edge moment M = Ē·h·ε_b·δ/2 = Ē·h²·ε_b·√((ε/ε_b − 1)/3) (beam theory: M = (Ēh³/12)·w''
//! at the clamp of w = (δ/2)(1 + cos 2πx/ℓ); Ē the modulus of the film's bending and
//! stretching, the plane-strain modulus for a strip held in plane strain). Then, with ξ = δ/h
//! (H&S, the one-dimensional blister of the section on buckling-driven delamination):
//!
//! - G = (Ē·h/2)·(ε − ε_b)·(ε + 3ε_b) (from G = (P²/h + 12M²/h³)/(2Ē) of the edge-loaded film);
//! - tan ψ = (4 cos ω + √3 ξ sin ω)/(−4 sin ω + √3 ξ cos ω), ψ = atan(K_II/K_I), taken on the
//!   branch that starts at ψ = ω − 90° = −37.9° at ε = ε_b (pure moment) and passes −90° (pure
//!   mode II) at ξ = 4 tan ω/√3 (ε/ε_b = 1 + 4 tan²ω = 7.59): beyond, K_I < 0 and the faces
//!   touch at the tip;
//! - G_I = G·cos²ψ, G_II = G·sin²ψ (no oscillatory index: film and substrate of one material).
//!
//! ω is Suo & Hutchinson's (1990) angle of the edge-loaded film on a substrate: ω = 52.07° for a
//! film on a half-space of the same isotropic material ([`OMEGA_THIN_FILM_DEG`]); it depends on
//! η = h/H for a substrate of finite thickness H and moves with elastic mismatch and
//! orthotropy, which the caller states as departures. All quantities in consistent units (SI:
//! Pa, m, J/m²).

/// ω of a thin film on a half-space of the same isotropic material (Suo & Hutchinson 1990,
/// η = h/H → 0, Dundurs α = β = 0), degrees.
pub const OMEGA_THIN_FILM_DEG: f64 = 52.07;

/// The blister's energy release rate and its mode split at one compressive strain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blister {
    /// ξ = δ/h, the buckle's amplitude over the film's thickness.
    pub xi: f64,
    /// The mode-mix angle ψ = atan2(K_II, K_I), radians (negative: the buckle shears the film's
    /// edge towards the blister's centre).
    pub psi: f64,
    /// G = G_I + G_II, J/m².
    pub g: f64,
    /// G·cos²ψ, J/m².
    pub g_i: f64,
    /// G·sin²ψ, J/m².
    pub g_ii: f64,
}

impl Blister {
    /// G_II/G = sin²ψ.
    pub fn mode_ii_share(&self) -> f64 {
        self.psi.sin().powi(2)
    }
}

/// The straight-sided blister of Hutchinson & Suo (1992) at the compressive strain `strain`
/// (positive), with the film's modulus `modulus` (Ē), thickness `h`, buckling strain
/// `strain_b` (positive) and the angle `omega_deg` (ω, [`OMEGA_THIN_FILM_DEG`] for a thin film
/// on a thick substrate of its own material): G = (Ē·h/2)(ε − ε_b)(ε + 3ε_b),
/// tan ψ = (4 cos ω + √3 ξ sin ω)/(−4 sin ω + √3 ξ cos ω), ξ = √((4/3)(ε/ε_b − 1)). Below the
/// buckling strain the film is flat: G = 0 and ψ the limit at ε_b.
///
/// At ε = 2ε_b: ξ = 2/√3, so √3 ξ = 2 and tan ψ = (4 cos ω + 2 sin ω)/(2 cos ω − 4 sin ω):
///
/// ```
/// use nonlin3d_testkit::blister::{straight_blister, OMEGA_THIN_FILM_DEG};
///
/// let b = straight_blister(60e9, 0.4e-3, 1.2e-3, 0.6e-3, OMEGA_THIN_FILM_DEG);
/// assert!((b.g - 0.5 * 60e9 * 0.4e-3 * 0.6e-3 * 3.0e-3).abs() < 1e-9); // 21.6 J/m²
/// let w = OMEGA_THIN_FILM_DEG.to_radians();
/// let t = (4.0 * w.cos() + 2.0 * w.sin()) / (2.0 * w.cos() - 4.0 * w.sin());
/// assert!((b.psi.tan() - t).abs() < 1e-12);
/// assert!((b.g_i + b.g_ii - b.g).abs() < 1e-12);
/// ```
pub fn straight_blister(
    modulus: f64,
    h: f64,
    strain: f64,
    strain_b: f64,
    omega_deg: f64,
) -> Blister {
    let w = omega_deg.to_radians();
    let over = (strain / strain_b - 1.0).max(0.0);
    let xi = (4.0 / 3.0 * over).sqrt();
    let s3xi = 3f64.sqrt() * xi;
    // K_II and K_I up to the common positive factor M·√3/(2h) (module comment).
    let k_ii = -(4.0 * w.cos() + s3xi * w.sin());
    let k_i = 4.0 * w.sin() - s3xi * w.cos();
    let psi = k_ii.atan2(k_i);
    let g = if over > 0.0 {
        0.5 * modulus * h * (strain - strain_b) * (strain + 3.0 * strain_b)
    } else {
        0.0
    };
    Blister {
        xi,
        psi,
        g,
        g_i: g * psi.cos().powi(2),
        g_ii: g * psi.sin().powi(2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: f64 = OMEGA_THIN_FILM_DEG;

    /// At the onset the edge carries the moment alone: ψ = ω − 90° (Suo & Hutchinson's pure
    /// moment), and G = 0.
    #[test]
    fn onset_is_pure_moment() {
        let b = straight_blister(1.0, 1.0, 1e-3, 1e-3, W);
        assert!((b.psi.to_degrees() - (W - 90.0)).abs() < 1e-12);
        assert_eq!(b.g, 0.0);
        let flat = straight_blister(1.0, 1.0, 0.5e-3, 1e-3, W);
        assert_eq!((flat.g, flat.psi), (0.0, b.psi));
    }

    /// ψ passes −90° (K_I = 0) where √3 ξ cos ω = 4 sin ω, i.e. ε/ε_b = 1 + 4 tan²ω: 7.59 for
    /// ω = 52.07°; G_I vanishes there and G is all mode II.
    #[test]
    fn pure_mode_ii_where_k_i_vanishes() {
        let ratio = 1.0 + 4.0 * W.to_radians().tan().powi(2);
        assert!((ratio - 7.586).abs() < 1e-3, "{ratio}");
        let b = straight_blister(1.0, 1.0, ratio * 1e-3, 1e-3, W);
        assert!((b.psi.to_degrees() + 90.0).abs() < 1e-9);
        assert!(b.g_i < 1e-12 * b.g && (b.mode_ii_share() - 1.0).abs() < 1e-12);
        // Either side: ψ above −90° before, below after (the faces then touch at the tip).
        let before = straight_blister(1.0, 1.0, 0.9 * ratio * 1e-3, 1e-3, W);
        let after = straight_blister(1.0, 1.0, 1.1 * ratio * 1e-3, 1e-3, W);
        assert!(before.psi.to_degrees() > -90.0 && after.psi.to_degrees() < -90.0);
    }

    /// G against the film's energy: with P = Ē h (ε − ε_b) and M = Ē h² ε_b √((ε/ε_b − 1)/3),
    /// (P²/h + 12 M²/h³)/(2Ē) is the closed form's G.
    #[test]
    fn g_is_the_edge_loaded_films() {
        let (e, h, eb): (f64, f64, f64) = (57.98e9, 0.4e-3, 5.85e-4);
        for eps in [1.0e-3, 2.0e-3, 4.0e-3] {
            let p = e * h * (eps - eb);
            let m = e * h * h * eb * ((eps / eb - 1.0) / 3.0).sqrt();
            let g = (p * p / h + 12.0 * m * m / h.powi(3)) / (2.0 * e);
            let b = straight_blister(e, h, eps, eb, W);
            assert!((b.g / g - 1.0).abs() < 1e-12, "{} vs {g}", b.g);
        }
    }
}
