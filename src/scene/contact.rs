//! `[contact]`: whether and how crack-face contact acts (thesis §2.7); the stage that applies it
//! is `crate::contact`.

use crate::Error;
use serde::{Deserialize, Serialize};

/// When crack-face contact acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CrackFacesName {
    /// Only from the first level whose faces overlap beyond the tolerance.
    #[default]
    Auto,
    /// At every level.
    On,
    /// Never: overlapping faces are reported as `overlapped`.
    Off,
}

impl CrackFacesName {
    /// The name as written in a scene.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::On => "on",
            Self::Off => "off",
        }
    }
}

/// How a closed pair is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactModeName {
    /// Two-body contact: upper and lower node tied along the deformed normal (Fig. 2.7.1b).
    #[default]
    TwoBody,
    /// The thesis's approximation (Fig. 2.7.1c): the upper node held at the lower node's height
    /// by an external force the base does not react.
    Thesis,
}

/// The scene's `[contact]` section.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactOptions {
    /// `auto` (default), `on` or `off`.
    #[serde(default)]
    pub crack_faces: CrackFacesName,
    /// Overlap allowed before a pair closes, mm. Default [`DEFAULT_TOLERANCE_MM`].
    #[serde(default)]
    pub tolerance_mm: Option<f64>,
    /// `two_body` (default) or `thesis`.
    #[serde(default)]
    pub mode: ContactModeName,
    /// Changes of the set read at Newton iterates near equilibrium per level before the
    /// loop's re-solves are converged each time (`nonlin3d_contact::ContactSettings::
    /// inexact_passes`); 0: the exact loop of thesis Fig. 2.7.2. Default 10.
    #[serde(default)]
    pub inexact_passes: Option<usize>,
}

/// The default overlap tolerance, mm: 1e-6 mm = 1 nm, far above the round-off of nodal
/// coordinates of centimetre models (~1e-15 mm) and far below the overlaps that change G
/// (the 30 mm circle overlaps by ~1e-2 mm at ε = −0.005).
pub const DEFAULT_TOLERANCE_MM: f64 = 1e-6;

impl ContactOptions {
    /// The overlap tolerance, mm.
    pub fn tolerance(&self) -> f64 {
        self.tolerance_mm.unwrap_or(DEFAULT_TOLERANCE_MM)
    }

    /// Whether contact can act at all (`auto` or `on`).
    pub fn enabled(&self) -> bool {
        self.crack_faces != CrackFacesName::Off
    }
}

/// Checks the section (field names as written in the scene).
pub(crate) fn check(o: &ContactOptions) -> Result<(), Error> {
    if let Some(t) = o.tolerance_mm
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(Error::Scene(format!(
            "contact.tolerance_mm = {t}: must be a finite overlap ≥ 0 mm"
        )));
    }
    Ok(())
}
