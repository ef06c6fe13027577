//! `[substructure]`: which cells of the model are condensed once into a superelement and which
//! are solved by Newton on top of it (thesis §2.6, §3.2 and Fig. 3.2.2, §4.5).

use serde::{Deserialize, Serialize};

/// The partition of a delamination model into a nonlinear and a linear substructure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PartitionName {
    /// The whole model nonlinear, no superelement (the default this round).
    #[default]
    None,
    /// The thesis's (Fig. 3.2.2): the sublaminate cells lying ℓ = `offset_mm` inside the front
    /// nonlinear; the base, the far field and the sublaminate's strip next to the front (so
    /// the front itself) linear and condensed.
    Thesis,
    /// The whole sublaminate nonlinear, the base laminate linear and condensed (the front on
    /// the interface).
    Sublaminate,
}

impl PartitionName {
    /// The name as written in a scene.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Thesis => "thesis",
            Self::Sublaminate => "sublaminate",
        }
    }
}

/// Substructuring options.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SubstructureOptions {
    /// Which partition.
    #[serde(default)]
    pub partition: PartitionName,
    /// ℓ, mm: how far inside the front the nonlinear region begins (`partition = "thesis"`
    /// only; default the sublaminate thickness h, as in the thesis, §3.2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset_mm: Option<f64>,
    /// Write the superelement's condensed stiffness K_red as `superelement.mtx` in the output
    /// folder, in the text CalculiX's `*SUBSTRUCTURE MATRIX OUTPUT` writes (N/m; node ids the
    /// mesh's + 1, as in `nonlin3d export`'s decks; docs/DECKS.md). Needs a partition.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub write_matrix: bool,
}
