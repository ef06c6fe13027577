//! The values and fragments the mutations draw from (`mutate.rs`). Their order is part of the
//! case → input map: changing a list changes which input a case index produces.

/// Values substituted for numbers: zeros of both signs, the extremes of f64, non-finite values,
/// integers at and past the 32- and 64-bit limits (the 9223372036854775807 and
/// 4294967297), negative counts, the largest accepted mesh count, and physically degenerate
/// ones (ν = 0.5, tiny negatives).
pub const SCENE_EXTREMES: &[&str] = &[
    "0",
    "-0",
    "0.0",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-308",
    "-1e-308",
    "5e-324",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "4294967297",
    "-1",
    "-3",
    "1e30",
    "1e-30",
    "10000",
    "9999",
    "1",
    "2",
    "0.5",
    "-1e-12",
];

/// Deck values: as for scenes, plus Fortran exponents, words Rust parses as non-finite, and
/// literals that overflow to infinity when parsed.
pub const DECK_EXTREMES: &[&str] = &[
    "0",
    "-0",
    "0.0",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-308",
    "-1e-308",
    "5e-324",
    "1e309",
    "-1d309",
    "1d300",
    "NaN",
    "inf",
    "-Infinity",
    "9223372036854775807",
    "18446744073709551615",
    "18446744073709551616",
    "4294967297",
    "-1",
    "1e30",
    "1e-30",
    "10000000",
    "1",
    "2",
    "0.5",
    "-1e-12",
];

/// Values for quoted scene fields: every enum value of the scene format, two unknown names and
/// an empty string.
pub const ENUM_VALUES: &[&str] = &[
    "embedded",
    "edge",
    "through-width",
    "plate",
    "ellipse",
    "rectangle",
    "hex20",
    "hex8",
    "gauss2",
    "gauss3",
    "selective-reduced",
    "full",
    "modified",
    "bfgs",
    "faer",
    "profile",
    "none",
    "quasi-isotropic",
    "nonlinear",
    "linear",
    "named",
    "isotropic",
    "orthotropic",
    "steel",
    "aluminium",
    "im7-8551-7",
    "generic-graphite-epoxy",
    "power-law",
    "benzeggagh-kenane",
    "unobtainium",
    "",
];

/// Materials that are invalid, degenerate or at the edge of validity.
pub const SCENE_MATERIALS: &[&str] = &[
    "[material]\nkind = \"isotropic\"\ne_gpa = 200.0\nnu = 0.5\n",
    "[material]\nkind = \"isotropic\"\ne_gpa = 200.0\nnu = -1.0\n",
    "[material]\nkind = \"isotropic\"\ne_gpa = 70.0\nnu = 0.4999999999\n",
    "[material]\nkind = \"isotropic\"\ne_gpa = 1e-300\nnu = 0.3\n",
    "[material]\nkind = \"isotropic\"\ne_gpa = 1e300\nnu = 0.3\n",
    "[material]\nkind = \"isotropic\"\ne_gpa = -70.0\nnu = 0.3\n",
    "[material]\nkind = \"isotropic\"\ne_gpa = 70.0\n",
    "[material]\nkind = \"orthotropic\"\ne11_gpa = 134.0\ne22_gpa = 10.2\ne33_gpa = 10.2\n\
     nu12 = 5.0\nnu13 = 0.3\nnu23 = 0.49\ng12_gpa = 5.52\ng13_gpa = 5.52\ng23_gpa = 3.43\n",
    "[material]\nkind = \"orthotropic\"\ne11_gpa = 134.0\ne22_gpa = 10.2\ne33_gpa = 10.2\n\
     nu12 = 0.3\nnu13 = 0.3\nnu23 = 0.49\ng12_gpa = 0.0\ng13_gpa = 5.52\ng23_gpa = 3.43\n",
    "[material]\nkind = \"orthotropic\"\ne11_gpa = 1e6\ne22_gpa = 1e-6\ne33_gpa = 1e-6\n\
     nu12 = 0.3\nnu13 = 0.3\nnu23 = 0.3\ng12_gpa = 1e-6\ng13_gpa = 1e-6\ng23_gpa = 1e-6\n\
     homogenize = \"quasi-isotropic\"\n",
    "[material]\nkind = \"orthotropic\"\ne11_gpa = 134.0\ne22_gpa = 10.2\ne33_gpa = 10.2\n\
     nu12 = 0.3\nnu13 = 0.3\nnu23 = 0.999\ng12_gpa = 5.52\ng13_gpa = 5.52\ng23_gpa = 3.43\n\
     homogenize = \"quasi-isotropic\"\n",
    "[material]\nkind = \"named\"\nname = \"unobtainium\"\n",
    "[material]\nkind = \"named\"\nname = \"steel\"\nhomogenize = \"quasi-isotropic\"\n",
    "[material]\nkind = \"isotropic\"\ne_gpa = 70.0\nnu = 0.3\nhomogenize = \"quasi-isotropic\"\n",
];

/// Scene options inserted into (or replacing the same key in) their section.
pub const SCENE_OPTIONS: &[(&str, &str)] = &[
    ("mesh", "inside = 1"),
    ("mesh", "outside = 1"),
    ("mesh", "sub_layers = 3"),
    ("mesh", "base_layers = 1"),
    ("mesh", "front_grading = 1e-6"),
    ("mesh", "front_grading = 1e6"),
    ("mesh", "element = \"hex8\""),
    ("mesh", "slices = 2"),
    ("mesh", "slices = 10000"),
    ("mesh", "inside = 10000"),
    ("mesh", "across = 2"),
    ("loads", "perturbation_n = 0.0"),
    ("loads", "perturbation_n = 1e12"),
    ("loads", "perturbation_n = -1.0"),
    ("loads", "imperfection_mm = 0.01"),
    ("loads", "imperfection_mm = -100.0"),
    ("loads", "imperfection_mm = 1e300"),
    ("loads", "strains = [-0.001, 0.001, -0.001]"),
    ("loads", "strains = [1e-300]"),
    ("loads", "strains = [-0.5]"),
    ("loads", "transverse_n = [1e9]"),
    ("analysis", "newton = \"bfgs\""),
    ("analysis", "newton = \"modified\""),
    ("analysis", "refactor_every = 1000000"),
    ("analysis", "solver = \"profile\""),
    ("analysis", "threads = 0"),
    ("analysis", "threads = 2"),
    ("analysis", "vcct_forces = \"linear\""),
    ("analysis", "max_increment = 1e-9"),
    ("analysis", "max_increment = 1e9"),
    ("analysis", "integration = \"gauss3\""),
    ("analysis", "integration = \"selective-reduced\""),
    ("analysis", "tolerance_n = 1e-300"),
    ("analysis", "tolerance_n = 1e300"),
    (
        "layup",
        "ply_mm = 0.1\nsublaminate = [0.0, 90.0, 90.0, 0.0]\nbase_below = [45.0, -45.0]",
    ),
    ("layup", "ply_mm = 0.4\nsublaminate = [0.0]"),
    ("layup", "ply_mm = 1e-300\nsublaminate = []"),
    (
        "criterion",
        "kind = \"power-law\"\ng_ic = 100.0\ng_iic = 500.0\nalpha = 1.0\nbeta = 2.0",
    ),
    (
        "criterion",
        "kind = \"benzeggagh-kenane\"\ng_ic = 100.0\ng_iic = 500.0\neta = 2.0",
    ),
    (
        "criterion",
        "kind = \"power-law\"\ng_ic = 0.0\ng_iic = 500.0",
    ),
];

/// `*ELASTIC` blocks that are invalid, degenerate or at the edge of validity.
pub const DECK_MATERIALS: &[&str] = &[
    "*ELASTIC, TYPE=ISO\n200e9, 0.5\n",
    "*ELASTIC, TYPE=ISO\n200e9, -1.0\n",
    "*ELASTIC, TYPE=ISO\n200e9, 0.49999999\n",
    "*ELASTIC, TYPE=ISO\n0.0, 0.3\n",
    "*ELASTIC, TYPE=ISO\n-70e9, 0.3\n",
    "*ELASTIC, TYPE=ISO\n1e-300, 0.3\n",
    "*ELASTIC, TYPE=ISO\n1e300, 0.3\n",
    "*ELASTIC\n70e9\n",
    "*ELASTIC, TYPE=ENGINEERING CONSTANTS\n134e9, 10.2e9, 10.2e9, 5.0, 0.3, 0.49, 5.52e9, 5.52e9\n\
     3.43e9\n",
    "*ELASTIC, TYPE=ENGINEERING CONSTANTS\n134e9, 10.2e9, 10.2e9, 0.3, 0.3, 0.49, 0.0, 5.52e9\n\
     3.43e9\n",
    "*ELASTIC, TYPE=ORTHO\n1, 2, 3, 4, 5, 6, 7, 8, 9\n",
    "*ELASTIC, TYPE=ORTHO\n0, 0, 0, 0, 0, 0, 0, 0, 0\n",
    "*ELASTIC, TYPE=ANISO\n1e9, 1e9, 1e9, 1e9, 1e9, 1e9, 1e9, 1e9\n1e9, 1e9, 1e9, 1e9, 1e9, 1e9, \
     1e9, 1e9\n1e9, 1e9, 1e9, 1e9, 1e9\n",
    "*ELASTIC, TYPE=HYPERELASTIC\n1, 2\n",
];

/// Deck blocks inserted before a keyword line.
pub const DECK_BLOCKS: &[&str] = &[
    "*NSET, NSET=GEN, GENERATE\n1, 20, 1\n",
    "*NSET, NSET=GEN, GENERATE\n1, 9223372036854775807, 1\n",
    "*ELSET, ELSET=GEN, GENERATE\n1, 4, 1\n",
    "*AMPLITUDE, NAME=A2\n0.0, 0.0, 0.5, 2.0, 1.0, 1.0\n",
    "*ORIENTATION, NAME=ORY, SYSTEM=RECTANGULAR\n0.0, 0.0, 1.0, 0.0, 1.0, 0.0\n",
    "*BOUNDARY\n1, 1, 3, 0.001\n",
    "*BOUNDARY\n1, 3, 1\n",
    "*CLOAD\n1, 2, 1e6\n",
    "*CLOAD\n1, 3, 1e300\n",
    "*STEP, NLGEOM\n*STATIC\n0.5, 1.0\n*CLOAD\n1, 3, 1e3\n*END STEP\n",
    "*STEP\n*STATIC\n*END STEP\n",
    "*MATERIAL, NAME=EXTRA\n*ELASTIC\n1e9, 0.2\n",
    "*SOLID SECTION, ELSET=NOSUCH, MATERIAL=EXTRA\n",
    "*ELEMENT, TYPE=C3D8, ELSET=EXTRA\n900, 1, 2, 3, 4, 5, 6, 7, 8\n",
    "*ELEMENT, TYPE=C3D8, ELSET=EXTRA\n901, 1, 1, 1, 1, 1, 1, 1, 1\n",
    "*NODE\n900, 0.0, 0.0, 0.0\n",
    "*NODE\n901, 1e308, -1e308, 1e308\n",
    "*UNKNOWN KEYWORD\n1, 2\n",
    "*END STEP\n",
    "*STEP\n",
    "*\n",
];

/// Replacement values for deck keyword parameters, by key (others: [`GENERIC_PARAMS`]).
pub const PARAM_VALUES: &[(&str, &[&str])] = &[
    (
        "TYPE",
        &[
            "C3D8",
            "C3D20",
            "C3D20R",
            "C3D8R",
            "C3D10",
            "ISO",
            "ORTHO",
            "ANISO",
            "ENGINEERING CONSTANTS",
            "ELEMENT",
            "",
        ],
    ),
    ("SYSTEM", &["RECTANGULAR", "CYLINDRICAL", ""]),
    ("INC", &["0", "1", "9223372036854775807", "-1", "x"]),
    ("NLGEOM", &["YES", "NO", ""]),
    ("AMPLITUDE", &["RAMP", "NOSUCH", ""]),
];
pub const GENERIC_PARAMS: &[&str] = &["NOSUCH", "", "ALL", "NALL"];
pub const ADDED_PARAMS: &[&str] = &[
    " NLGEOM",
    " GENERATE",
    " NLGEOM=NO",
    " INC=0",
    " AMPLITUDE=NOSUCH",
    " TYPE=C3D8",
    " SYSTEM=CYLINDRICAL",
    " ORIENTATION=NOSUCH",
    " NSET=EXTRA",
];
