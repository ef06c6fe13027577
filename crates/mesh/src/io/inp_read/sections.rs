//! `*ORIENTATION` axes and `*SOLID SECTION` resolution: each cell's material and material axes.

use super::Reader;
use super::lexer::{Keyword, Line, Loc, deck_error, fields, float, int};
use crate::MeshError;
use nonlin3d_element::CylindricalAxes;

/// The material axes an `*ORIENTATION` defines.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Axes {
    /// A rectangular system: columns are the local axes in global coordinates.
    Fixed([[f64; 3]; 3]),
    /// A cylindrical system: the axes vary with the position.
    Cylindrical(CylindricalAxes),
}

/// A `*SOLID SECTION`, resolved after the whole deck is read.
pub(crate) struct Section {
    pub at: Loc,
    pub elset: String,
    pub material: String,
    pub orientation: Option<String>,
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

/// The axes of a rectangular `*ORIENTATION` (CalculiX's definition): local 1 along point a,
/// local 2 in the plane of a and b, towards b, normal to 1; local 3 = 1 × 2. An optional
/// second line `axis, angle` then turns the system about its local axis (1, 2 or 3) by angle
/// degrees, right-handed. Returned as columns (the local axes in global coordinates).
pub(crate) fn rectangular_axes(kw: &Keyword, data: &[Line]) -> Result<[[f64; 3]; 3], MeshError> {
    let l = data.first().ok_or_else(|| kw.error("data line missing"))?;
    let f = fields(&l.text);
    if f.len() != 6 {
        return Err(kw.data_error(&l.at, "expected a1, a2, a3, b1, b2, b3"));
    }
    let v: Vec<f64> = f
        .iter()
        .map(|x| float(kw, &l.at, x))
        .collect::<Result<_, _>>()?;
    let e1 =
        unit([v[0], v[1], v[2]]).ok_or_else(|| kw.data_error(&l.at, "point a is the origin"))?;
    let b = [v[3], v[4], v[5]];
    let d = b[0] * e1[0] + b[1] * e1[1] + b[2] * e1[2];
    let e2 = unit([b[0] - d * e1[0], b[1] - d * e1[1], b[2] - d * e1[2]])
        .filter(|_| {
            let nb = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
            (nb * nb - d * d).max(0.0).sqrt() > 1e-12 * nb
        })
        .ok_or_else(|| kw.data_error(&l.at, "point b lies on the axis through a"))?;
    let mut e = [e1, e2, cross(e1, e2)];
    if let Some(l2) = data.get(1) {
        let f = fields(&l2.text);
        if f.len() != 2 {
            return Err(kw.data_error(&l2.at, "expected: local axis (1, 2 or 3), angle in degrees"));
        }
        let axis = int(kw, &l2.at, f[0])?;
        if !(1..=3).contains(&axis) {
            return Err(kw.data_error(&l2.at, format!("axis {axis}: expected 1, 2 or 3")));
        }
        let (s, c) = float(kw, &l2.at, f[1])?.to_radians().sin_cos();
        // Rotating about axis k turns the other two (i, j) = (k+1, k+2) cyclically.
        let (i, j) = (axis % 3, (axis + 1) % 3);
        let (ei, ej) = (e[i], e[j]);
        for r in 0..3 {
            e[i][r] = c * ei[r] + s * ej[r];
            e[j][r] = -s * ei[r] + c * ej[r];
        }
    }
    if data.len() > 2 {
        return Err(kw.data_error(&data[2].at, "at most two data lines"));
    }
    Ok([
        [e[0][0], e[1][0], e[2][0]],
        [e[0][1], e[1][1], e[2][1]],
        [e[0][2], e[1][2], e[2][2]],
    ])
}

/// The axis of a cylindrical `*ORIENTATION` (CalculiX's definition): the data line gives
/// points a and b on the axis; local 1 is radial, 3 axial from a to b, 2 = 3 × 1 tangential.
/// CalculiX allows the second line (a rotation about a local axis) only for rectangular
/// systems: one here is refused by its line.
pub(crate) fn cylindrical_axes(kw: &Keyword, data: &[Line]) -> Result<CylindricalAxes, MeshError> {
    let l = data.first().ok_or_else(|| kw.error("data line missing"))?;
    let f = fields(&l.text);
    if f.len() != 6 {
        return Err(kw.data_error(
            &l.at,
            "expected a1, a2, a3, b1, b2, b3 (two points on the axis)",
        ));
    }
    let v: Vec<f64> = f
        .iter()
        .map(|x| float(kw, &l.at, x))
        .collect::<Result<_, _>>()?;
    if let Some(l2) = data.get(1) {
        return Err(kw.data_error(
            &l2.at,
            "a second data line (a rotation about a local axis) is defined for rectangular \
             systems only; a cylindrical system takes the two points on its axis alone",
        ));
    }
    CylindricalAxes::new([v[0], v[1], v[2]], [v[3], v[4], v[5]])
        .ok_or_else(|| kw.data_error(&l.at, "points a and b coincide: they define no axis"))
}

/// The angle about z (degrees) of axes whose local 3 is global z, else None.
fn angle_about_z(r: &[[f64; 3]; 3]) -> Option<f64> {
    let z = [r[0][2], r[1][2], r[2][2]];
    (z[0].abs() < 1e-12 && z[1].abs() < 1e-12 && (z[2] - 1.0).abs() < 1e-12)
        .then(|| r[1][0].atan2(r[0][0]).to_degrees())
}

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl Reader {
    /// Each cell's material, axes and (for rotations about z) ply angle from its section.
    pub(crate) fn resolve_sections(&mut self) -> Result<(), MeshError> {
        let cells = self.m.mesh.cells.len();
        self.m.orientations = vec![IDENTITY; cells];
        self.m.orientation_names = vec![None; cells];
        self.m.cylindrical = vec![None; cells];
        let sections = std::mem::take(&mut self.sections);
        let mut assigned = vec![false; cells];
        for sec in &sections {
            let what = "*SOLID SECTION";
            let mi = self.material_index(&sec.material).ok_or_else(|| {
                deck_error(
                    &sec.at,
                    what,
                    format!("material '{}' not defined", sec.material),
                )
            })?;
            if !self.elastic_given[mi] {
                return Err(deck_error(
                    &sec.at,
                    what,
                    format!("material '{}' has no *ELASTIC", sec.material),
                ));
            }
            let axes = match &sec.orientation {
                None => None,
                Some(or) => Some(*self.orientations.get(or).ok_or_else(|| {
                    deck_error(&sec.at, what, format!("orientation '{or}' not defined"))
                })?),
            };
            let set = self
                .cell_set(&sec.elset)
                .and_then(|s| self.m.mesh.cell_sets.get(s))
                .cloned()
                .ok_or_else(|| {
                    deck_error(
                        &sec.at,
                        what,
                        format!("element set '{}' not defined", sec.elset),
                    )
                })?;
            for c in set {
                if assigned[c] {
                    return Err(deck_error(
                        &sec.at,
                        what,
                        format!("element {} already has a section", self.m.element_ids[c]),
                    ));
                }
                assigned[c] = true;
                let cell = &mut self.m.mesh.cells[c];
                cell.material = mi;
                match axes {
                    None => {}
                    Some(Axes::Fixed(r)) => {
                        cell.ply_angle_deg = angle_about_z(&r).unwrap_or(0.0);
                        self.m.orientations[c] = r;
                    }
                    Some(Axes::Cylindrical(a)) => self.m.cylindrical[c] = Some(a),
                }
                if axes.is_some() {
                    self.m.orientation_names[c] = sec.orientation.clone();
                }
            }
        }
        if let Some(c) = assigned.iter().position(|a| !a) {
            return Err(deck_error(
                &self.element_at[c],
                "*ELEMENT data",
                format!("element {} has no *SOLID SECTION", self.m.element_ids[c]),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::inp_read::lexer::logical_lines;

    fn axes(text: &str) -> [[f64; 3]; 3] {
        let lines = logical_lines(text, None).unwrap();
        let kw = Keyword::parse(&lines[0].text, lines[0].at.clone());
        rectangular_axes(&kw, &lines[1..]).unwrap()
    }

    #[test]
    fn rectangular_axes_follow_points_and_the_extra_rotation() {
        let (s, c) = 30f64.to_radians().sin_cos();
        let a = axes(&format!(
            "*ORIENTATION, NAME=A\n{c}, {s}, 0, {}, {c}, 0\n",
            -s
        ));
        assert!((a[0][0] - c).abs() < 1e-15 && (a[1][0] - s).abs() < 1e-15);
        assert_eq!(
            angle_about_z(&a).map(|x| (x - 30.0).abs() < 1e-12),
            Some(true)
        );
        // The same system as identity points plus 30° about local 3.
        let b = axes("*ORIENTATION, NAME=A\n1, 0, 0, 0, 1, 0\n3, 30\n");
        for r in 0..3 {
            for k in 0..3 {
                assert!((a[r][k] - b[r][k]).abs() < 1e-15);
            }
        }
        // b need not be normal to a; a tilted system is orthonormal and right-handed.
        let t = axes("*ORIENTATION, NAME=T\n1, 1, 1, 0, 1, 0\n");
        let col = |k: usize| [t[0][k], t[1][k], t[2][k]];
        assert!((cross(col(0), col(1))[2] - col(2)[2]).abs() < 1e-15);
        assert!(angle_about_z(&t).is_none());
    }

    fn cylindrical(text: &str) -> Result<CylindricalAxes, MeshError> {
        let lines = logical_lines(text, None).unwrap();
        let kw = Keyword::parse(&lines[0].text, lines[0].at.clone());
        cylindrical_axes(&kw, &lines[1..])
    }

    /// Two points on the axis; a rotation line or a degenerate axis is refused by its line.
    #[test]
    fn cylindrical_axes_take_two_points_and_nothing_else() {
        let a =
            cylindrical("*ORIENTATION, NAME=C, SYSTEM=CYLINDRICAL\n0, 0, 1, 0, 0, 3\n").unwrap();
        assert_eq!(a.direction(), [0.0, 0.0, 1.0]);
        assert_eq!(a.origin(), [0.0, 0.0, 1.0]);
        let e = cylindrical("*ORIENTATION, NAME=C, SYSTEM=C\n0, 0, 0, 1, 0, 0\n3, 30.\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 3") && e.contains("rectangular systems only"),
            "{e}"
        );
        let e = cylindrical("*ORIENTATION, NAME=C, SYSTEM=C\n1, 2, 3, 1, 2, 3\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("line 2") && e.contains("coincide"), "{e}");
    }
}
