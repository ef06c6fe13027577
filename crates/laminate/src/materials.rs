//! The materials of the thesis (Table 1, §2.9) and the usual metals.

use crate::Orthotropic;

/// Generic graphite/epoxy of Table 1 (thesis ref. 41): E11 = 134 GPa, E22 = E33 = 10.2 GPa,
/// ν12 = ν13 = 0.3, ν23 = 0.49, G12 = G13 = 5.52 GPa, G23 = 3.43 GPa.
pub fn generic_graphite_epoxy() -> Orthotropic {
    Orthotropic {
        e11: 13.4e10,
        e22: 1.02e10,
        e33: 1.02e10,
        nu12: 0.3,
        nu23: 0.49,
        nu13: 0.3,
        g12: 0.552e10,
        g23: 0.343e10,
        g13: 0.552e10,
    }
}

/// IM7/8551-7 of Table 1: E11 = 162 GPa, E22 = E33 = 8.14 GPa, all ν = 0.22,
/// all G = 6.48 GPa (the out-of-plane constants were assumed in the thesis).
pub fn im7_8551_7() -> Orthotropic {
    Orthotropic {
        e11: 16.2e10,
        e22: 0.814e10,
        e33: 0.814e10,
        nu12: 0.22,
        nu23: 0.22,
        nu13: 0.22,
        g12: 0.648e10,
        g23: 0.648e10,
        g13: 0.648e10,
    }
}

/// Steel as in §4.1 of the thesis: E = 207 GPa, ν = 0.3.
pub fn steel() -> Orthotropic {
    Orthotropic::isotropic(207e9, 0.3)
}

/// Aluminium: E = 72.4 GPa, ν = 0.33 (the thesis says only "the usual assumed properties";
/// these are the common handbook values for 2024-T3 and 7075-T6).
pub fn aluminium() -> Orthotropic {
    Orthotropic::isotropic(72.4e9, 0.33)
}

#[cfg(test)]
mod tests {
    #[test]
    fn table_one_materials_are_valid() {
        for m in [
            super::generic_graphite_epoxy(),
            super::im7_8551_7(),
            super::steel(),
            super::aluminium(),
        ] {
            assert!(m.stiffness().is_ok(), "{m:?}");
        }
    }
}
