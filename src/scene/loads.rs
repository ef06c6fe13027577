//! `[loads]` and `[criterion]` of a scene: the strain sweep or plate loads, the §3.2
//! perturbation, an imperfection, and the mixed-mode growth criterion (docs/SCENES.md).

use nonlin3d_vcct::MixedMode;
use serde::{Deserialize, Serialize};

/// Loads: a strain sweep (embedded, edge, through-width) or transverse loads (plate).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    /// Applied axial strains ε_x (compression negative), in the order applied: u = W·ε on x = W.
    #[serde(default)]
    pub strains: Vec<f64>,
    /// Transverse perturbation force (N, on the quarter model) at the sublaminate centre,
    /// converged with the first strain and then removed at once (§3.2). Unset: a force that
    /// would deflect the clamped sublaminate by h/4 in the linear range (eq. 4.1.1). 0: none.
    #[serde(default)]
    pub perturbation_n: Option<f64>,
    /// Initial imperfection amplitude (mm) of the sublaminate, eq. 5.3.1 shape; instead of or
    /// besides the perturbation.
    #[serde(default)]
    pub imperfection_mm: f64,
    /// Plate: central transverse loads P (N, on the whole plate), in order.
    #[serde(default)]
    pub transverse_n: Vec<f64>,
}

/// A mixed-mode growth criterion (toughnesses in J/m²).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum CriterionSpec {
    /// (G_I/G_Ic)^α + ((G_II)/G_IIc)^β + (G_III/G_IIIc)^β = 1.
    PowerLaw {
        /// G_Ic.
        g_ic: f64,
        /// G_IIc.
        g_iic: f64,
        /// G_IIIc (defaults to G_IIc).
        #[serde(default)]
        g_iiic: Option<f64>,
        /// α.
        #[serde(default = "one")]
        alpha: f64,
        /// β.
        #[serde(default = "one")]
        beta: f64,
    },
    /// Benzeggagh–Kenane.
    BenzeggaghKenane {
        /// G_Ic.
        g_ic: f64,
        /// G_IIc.
        g_iic: f64,
        /// η.
        eta: f64,
    },
}

fn one() -> f64 {
    1.0
}

impl CriterionSpec {
    /// The criterion.
    pub fn criterion(&self) -> MixedMode {
        match *self {
            Self::PowerLaw {
                g_ic,
                g_iic,
                g_iiic,
                alpha,
                beta,
            } => MixedMode::PowerLaw {
                g_ic,
                g_iic,
                g_iiic: g_iiic.unwrap_or(g_iic),
                alpha,
                beta,
            },
            Self::BenzeggaghKenane { g_ic, g_iic, eta } => {
                MixedMode::BenzeggaghKenane { g_ic, g_iic, eta }
            }
        }
    }
}
