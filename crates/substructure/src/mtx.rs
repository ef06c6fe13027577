//! A superelement's condensed stiffness K_red (thesis §2.6: column j holds the restraint forces
//! on the interface for a unit displacement of interface DOF j) in the `.mtx` text CalculiX
//! 2.20 writes for `*SUBSTRUCTURE MATRIX OUTPUT, STIFFNESS=YES` (its routine
//! `writesubmatrix`), so that the two can be compared entry by entry:
//!
//! ```text
//! **
//! ** GENERATION OF SUBSTRUCTURE
//! *USER ELEMENT,NODES=         n,LINEAR          n = retained DOFs (3 per interface node)
//! ** ELEMENT NODES
//! **     node1,     node1,     node1,     node2, … the node of each DOF, 10 a line
//!          1                                     direction of DOF 1 (1 = x, 2 = y, 3 = z)
//!          2,         2                          DOF k, its direction; k = 2 … n
//! *MATRIX,TYPE=STIFFNESS
//! K₁₁,                                           column j's rows 1 … j (the upper triangle
//! K₁₂, K₂₂,                                      by columns = the lower by rows), 4 a line
//! ```
//!
//! Numbers are Fortran `E20.13` (`-0.1682692307692E+05`), integers `I10`. Node ids are the
//! full mesh's indices + 1, as in the decks nonlin3d writes (`nonlin3d export`). Values are in
//! the library's units (N/m) times `scale`: a deck has no units, so a deck in N and mm
//! compares with `scale = 1e-3`.

use crate::{Partition, Superelement};
use std::fmt::Write as _;

/// The `.mtx` text of `superelement`'s K_red, condensed on `partition`'s interface (module
/// docs), each value multiplied by `scale`.
///
/// ```
/// use nonlin3d_assembly::{Assembler, Constraints};
/// use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
/// use nonlin3d_laminate::ShearCoupling;
/// use nonlin3d_mesh::{BoxParams, names, structured_box};
/// use nonlin3d_substructure::{CondenseSettings, Partition, condense, mtx_text};
/// let mesh = structured_box(&BoxParams::new(ElementKind::Hex8, [2, 1, 1], [2.0, 1.0, 1.0])).unwrap();
/// let steel = nonlin3d_laminate::materials::steel().stiffness().unwrap();
/// let p = Partition::from_linear_cells(&mesh, &[0]).unwrap();
/// let mut c = Constraints::new(3 * mesh.nodes.len());
/// for r in 0..3 { c.fix_nodes(&mesh.node_sets[names::X0], r).unwrap(); }
/// let a = Assembler::new(p.linear_mesh(), &[steel], ShearCoupling::Exact,
///     IntegrationRule::Gauss2, IntegrationRule::Gauss2, Kinematics::Linear).unwrap();
/// let done = condense(&p, &a, &c, &CondenseSettings::default()).unwrap();
/// let text = mtx_text(&p, &done.superelement, 1.0);
/// assert!(text.contains("*USER ELEMENT,NODES=         12,LINEAR"));
/// // Column j (1-based) of the upper triangle on ⌈j/4⌉ lines.
/// let lines: usize = (1..=12).map(|j: usize| j.div_ceil(4)).sum();
/// assert_eq!(text.lines().skip_while(|l| !l.starts_with("*MATRIX")).count(), 1 + lines);
/// ```
pub fn mtx_text(partition: &Partition, superelement: &Superelement, scale: f64) -> String {
    let nodes: Vec<usize> = partition
        .interface()
        .iter()
        .flat_map(|&v| [v + 1; 3])
        .collect();
    let n = nodes.len();
    let k = superelement.stiffness();
    let mut s = String::with_capacity(64 + 24 * n * (n + 1) / 2);
    s.push_str("**\n** GENERATION OF SUBSTRUCTURE\n");
    let _ = writeln!(s, "*USER ELEMENT,NODES= {n:>10},LINEAR");
    s.push_str("** ELEMENT NODES\n");
    for line in nodes.chunks(10) {
        s.push_str("**");
        for v in line {
            let _ = write!(s, "{v:>10},");
        }
        s.push('\n');
    }
    // Direction of DOF 1 alone, then "k, direction" for k = 2 … n (CalculiX's layout).
    if n > 0 {
        let _ = writeln!(s, "{:>10}", 1);
    }
    for d in 1..n {
        let _ = writeln!(s, "{:>10},{:>10}", d + 1, d % 3 + 1);
    }
    s.push_str("*MATRIX,TYPE=STIFFNESS\n");
    for j in 0..n {
        for line in (0..=j).collect::<Vec<_>>().chunks(4) {
            for &i in line {
                s.push_str(&fortran_e20_13(scale * k[i * n + j]));
                s.push(',');
            }
            s.push('\n');
        }
    }
    s
}

/// Fortran's `E20.13`: sign (blank when positive), `0.` and 13 digits, the exponent as `E±dd`
/// (`±ddd` without the E past 99, as Fortran does), 20 characters; non-finite values as
/// Fortran prints them, right-aligned.
pub(crate) fn fortran_e20_13(v: f64) -> String {
    if !v.is_finite() {
        return format!(
            "{:>20}",
            if v.is_nan() {
                "NaN"
            } else if v > 0.0 {
                "Infinity"
            } else {
                "-Infinity"
            }
        );
    }
    let sign = if v.is_sign_negative() && v != 0.0 {
        '-'
    } else {
        ' '
    };
    if v == 0.0 {
        return format!("{sign}0.0000000000000E+00");
    }
    // d.dddddddddddde±x (13 significant digits, rounded once) → 0.ddddddddddddd × 10^(x+1).
    let text = format!("{:.12e}", v.abs());
    let (mantissa, exp) = text.split_once('e').unwrap_or((&text, "0"));
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    let e = exp.parse::<i32>().unwrap_or(0) + 1;
    let exponent = if e.abs() <= 99 {
        format!("E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
    } else {
        format!("{}{:03}", if e < 0 { '-' } else { '+' }, e.abs())
    };
    format!("{sign}0.{digits}{exponent}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The digits CalculiX printed for the two-cell box of docs/DECKS.md (E = 210 000,
    /// ν = 0.3): the same text, character by character, including the sign column and zero.
    #[test]
    fn numbers_print_as_fortran_e20_13() {
        assert_eq!(fortran_e20_13(49358.97435897436), " 0.4935897435897E+05");
        assert_eq!(fortran_e20_13(-16826.92307692308), "-0.1682692307692E+05");
        assert_eq!(fortran_e20_13(0.0), " 0.0000000000000E+00");
        assert_eq!(fortran_e20_13(1.5e-120), " 0.1500000000000-119");
        assert_eq!(fortran_e20_13(9.99999999999999e9), " 0.1000000000000E+11");
        for v in [1.0, -2.5e-7, 3.0e300] {
            assert_eq!(fortran_e20_13(v).len(), 20);
        }
    }
}
