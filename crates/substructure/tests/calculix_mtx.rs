//! `mtx_text` and K_red against CalculiX 2.20 for the same linear region (thesis §2.6: K_red =
//! K_bb − K_bi K_ii⁻¹ K_ib on the retained DOFs). Runs `ccx` when it is on the PATH (CI installs
//! it); says so and passes when it is not.
//!
//! CalculiX 2.20's `*SUBSTRUCTURE GENERATE` writes K_bb, the retained block of K, without
//! eliminating the free interior DOFs (measured: on the 2 × 2 × 1 Hex8 region below its
//! diagonal for a corner node is one element's, 0.4865e9 N/m, while its own static solution
//! with that DOF displaced by 1 and the other retained DOFs held gives the reaction 0.3524e9 N/m,
//! our K_red's entry). So the file is compared where nothing is condensed (K_red = K_bb), and
//! the condensation against CalculiX's static reactions.

mod common;

use common::{cells_below, steel};
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::{BoxParams, names, structured_box};
use nonlin3d_substructure::{CondenseSettings, Partition, condense, mtx_text};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

/// A DOF as (node id, direction 1–3).
type Dof = (usize, usize);

/// K's entries by (row DOF, column DOF).
type Entries = HashMap<(Dof, Dof), f64>;

/// The entries of an `.mtx` file keyed by ((node, direction), (node, direction)), both
/// triangles.
fn parse(text: &str) -> Entries {
    let mut lines = text.lines();
    let mut nodes = Vec::new();
    for l in lines.by_ref() {
        if l.starts_with("** ELEMENT NODES") {
            break;
        }
    }
    let mut dirs = Vec::new();
    for l in lines.by_ref() {
        if let Some(rest) = l.strip_prefix("**") {
            nodes.extend(
                rest.split(',')
                    .filter_map(|t| t.trim().parse::<usize>().ok()),
            );
        } else if l.starts_with("*MATRIX") {
            break;
        } else {
            // "d" for DOF 1, "k, d" after it: the direction is the last field.
            dirs.push(
                l.split(',')
                    .next_back()
                    .unwrap()
                    .trim()
                    .parse::<usize>()
                    .unwrap(),
            );
        }
    }
    assert_eq!(nodes.len(), dirs.len());
    let dof: Vec<(usize, usize)> = nodes.into_iter().zip(dirs).collect();
    let values: Vec<f64> = lines
        .flat_map(|l| l.split(','))
        .filter_map(|t| {
            let t = t.trim();
            (!t.is_empty()).then(|| t.parse::<f64>().unwrap())
        })
        .collect();
    let mut k = HashMap::new();
    let mut next = values.into_iter();
    for j in 0..dof.len() {
        for i in 0..=j {
            let v = next.next().expect("fewer values than the triangle holds");
            k.insert((dof[i], dof[j]), v);
            k.insert((dof[j], dof[i]), v);
        }
    }
    assert!(next.next().is_none(), "more values than the triangle holds");
    k
}

/// A CalculiX deck of the linear region of `p` (node and element ids: the full mesh's + 1),
/// clamped on x = 0, with `step`.
fn deck(p: &Partition, full: &nonlin3d_mesh::Mesh, element: &str, step: &str) -> String {
    let m = p.linear_mesh();
    let id = |l: usize| p.from_linear(l).unwrap() + 1;
    let mut s = String::from("*NODE\n");
    for (l, x) in m.nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {:e}, {:e}, {:e}", id(l), x[0], x[1], x[2]);
    }
    let _ = writeln!(s, "*ELEMENT, TYPE={element}, ELSET=EALL");
    for (c, cell) in m.cells.iter().enumerate() {
        let ids: Vec<String> = std::iter::once(c + 1)
            .chain(cell.nodes.iter().map(|&n| id(n)))
            .map(|v| v.to_string())
            .collect();
        // At most 16 entries a line; a trailing comma continues the line.
        let _ = writeln!(
            s,
            "{}",
            ids.chunks(10)
                .map(|c| c.join(", "))
                .collect::<Vec<_>>()
                .join(",\n")
        );
    }
    let fixed: Vec<String> = full.node_sets[names::X0]
        .iter()
        .map(|v| (v + 1).to_string())
        .collect();
    let _ = writeln!(s, "*NSET, NSET=FIX\n{}", fixed.join(",\n"));
    let retained: Vec<String> = p.interface().iter().map(|v| (v + 1).to_string()).collect();
    let _ = writeln!(s, "*NSET, NSET=RET\n{}", retained.join(",\n"));
    s.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n207e9, 0.3\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n\
         *BOUNDARY\nFIX, 1, 3\n",
    );
    s + step
}

const GENERATE: &str = "*STEP\n*SUBSTRUCTURE GENERATE\n*RETAINED NODAL DOFS\nRET, 1, 3\n\
    *SUBSTRUCTURE MATRIX OUTPUT, STIFFNESS=YES, OUTPUT FILE=USER DEFINED, FILE NAME=region\n\
    *END STEP\n";

/// The box [3, 2, 1] cells over 30 × 20 × 10 mm, its cells with centre x ≤ `x` linear,
/// clamped on x = 0, condensed with `rule`.
fn region(
    kind: ElementKind,
    rule: IntegrationRule,
    x: f64,
) -> (
    nonlin3d_mesh::Mesh,
    Partition,
    nonlin3d_substructure::Superelement,
) {
    let mesh = structured_box(&BoxParams::new(kind, [3, 2, 1], [0.03, 0.02, 0.01])).unwrap();
    let p = Partition::from_linear_cells(&mesh, &cells_below(&mesh, 0, x)).unwrap();
    let mut c = Constraints::new(3 * mesh.nodes.len());
    for r in 0..3 {
        c.fix_nodes(&mesh.node_sets[names::X0], r).unwrap();
    }
    let a = Assembler::new(
        p.linear_mesh(),
        &[steel()],
        ShearCoupling::Exact,
        rule,
        rule,
        Kinematics::Linear,
    )
    .unwrap();
    let done = condense(&p, &a, &c, &CondenseSettings::default()).unwrap();
    (mesh, p, done.superelement)
}

/// Runs `ccx -i job` on `text` in `dir`.
fn ccx(dir: &Path, job: &str, text: &str) {
    std::fs::write(dir.join(format!("{job}.inp")), text).unwrap();
    let run = Command::new("ccx")
        .args(["-i", job])
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "ccx: {}",
        String::from_utf8_lossy(&run.stdout)
    );
}

fn scratch(name: &str) -> Option<std::path::PathBuf> {
    if Command::new("ccx").arg("-v").output().is_err() {
        println!("ccx not on the PATH: the comparison with CalculiX is skipped");
        return None;
    }
    let dir = std::env::temp_dir().join(format!("nonlin3d-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    Some(dir)
}

/// Where nothing is condensed (one column of Hex8 cells: every node clamped on x = 0 or on
/// the interface x = 10 mm, so K_red = K_bb), our file and CalculiX's hold the same DOFs
/// and values. (CalculiX stops on a region with no free interior DOF, so its deck also holds
/// one cube far away, clamped on one face and connected to nothing: free DOFs with K_bi = 0.) Hex8 with 2×2×2 Gauss is C3D8. Tolerance 1e-12 of the largest entry: both
/// print 13 significant digits (5e-14 relative) of the same element integrals summed in
/// another order (1e-16); a wrong layout, a transposed node order or another integration
/// rule (entries change by ~1e-2) fails by far.
#[test]
fn our_mtx_file_matches_calculix_where_nothing_is_condensed() {
    let Some(dir) = scratch("mtx") else { return };
    let (mesh, p, se) = region(ElementKind::Hex8, IntegrationRule::Gauss2, 0.01);
    let ours = parse(&mtx_text(&p, &se, 1.0));
    let cube = "*NODE\n1001, 1, 0, 0\n1002, 1.01, 0, 0\n1003, 1.01, 0.01, 0\n1004, 1, 0.01, 0\n\
        1005, 1, 0, 0.01\n1006, 1.01, 0, 0.01\n1007, 1.01, 0.01, 0.01\n1008, 1, 0.01, 0.01\n\
        *ELEMENT, TYPE=C3D8, ELSET=CUBE\n1001, 1001, 1002, 1003, 1004, 1005, 1006, 1007, 1008\n\
        *SOLID SECTION, ELSET=CUBE, MATERIAL=STEEL\n*BOUNDARY\n1001, 1, 3\n1004, 1, 3\n\
        1005, 1, 3\n1008, 1, 3\n";
    ccx(
        &dir,
        "region",
        &deck(&p, &mesh, "C3D8", &format!("{cube}{GENERATE}")),
    );
    let theirs = parse(&std::fs::read_to_string(dir.join("region.mtx")).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(ours.len(), theirs.len(), "retained DOFs differ");
    let scale = theirs.values().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = ours
        .iter()
        .map(|(key, v)| (v - theirs[key]).abs())
        .fold(0.0f64, f64::max);
    println!(
        "{} entries, max |ΔK| / max |K| = {:.1e}",
        ours.len(),
        worst / scale
    );
    assert!(worst <= 1e-12 * scale, "{worst:e} of {scale:e}");
}

/// The reaction forces "x y z" per node of the first `*NODE PRINT` table in a `.dat`.
fn reactions(dat: &str) -> HashMap<usize, [f64; 3]> {
    dat.lines()
        .skip_while(|l| !l.contains("forces (fx,fy,fz)"))
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.len() == 4).then(|| {
                let v = |k: usize| f[k].parse::<f64>().unwrap();
                (f[0].parse::<usize>().unwrap(), [v(1), v(2), v(3)])
            })
        })
        .collect()
}

/// The condensation against CalculiX's own static solution (§2.6's definition of a column
/// of K_red: the restraint forces on the interface for a unit displacement of one interface
/// DOF, the others held, the interior free): two columns of cells linear, for C3D8 (Hex8,
/// 2×2×2 Gauss) and C3D20 (Hex20, 3×3×3 Gauss), three interface DOFs each. Tolerance 1e-6 of
/// the column's largest entry: CalculiX prints reactions with 7 significant digits (5e-7
/// relative); the two direct solves agree to ~1e-12. Not condensing (K_bb instead of K_red)
/// is off by 0.4 of the diagonal.
#[test]
fn k_red_columns_match_calculix_reactions() {
    let Some(dir) = scratch("reactions") else {
        return;
    };
    for (kind, rule, element) in [
        (ElementKind::Hex8, IntegrationRule::Gauss2, "C3D8"),
        (ElementKind::Hex20, IntegrationRule::Gauss3, "C3D20"),
    ] {
        let (mesh, p, se) = region(kind, rule, 0.02);
        let n = 3 * p.interface().len();
        let k = se.stiffness();
        for j in [0, 4, n - 1] {
            let (node, dir_j) = (p.interface()[j / 3] + 1, j % 3 + 1);
            let step = format!(
                "*STEP\n*STATIC\n*BOUNDARY\nRET, 1, 3, 0.0\n*BOUNDARY\n{node}, {dir_j}, {dir_j}, 1.0\n\
                 *NODE PRINT, NSET=RET\nRF\n*END STEP\n"
            );
            ccx(&dir, "column", &deck(&p, &mesh, element, &step));
            let rf = reactions(&std::fs::read_to_string(dir.join("column.dat")).unwrap());
            let col: Vec<f64> = (0..n).map(|i| k[i * n + j]).collect();
            let scale = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let worst = (0..n)
                .map(|i| (col[i] - rf[&(p.interface()[i / 3] + 1)][i % 3]).abs())
                .fold(0.0f64, f64::max);
            println!(
                "{element}, column {j}: max |ΔK| / max |K| = {:.1e}",
                worst / scale
            );
            assert!(
                worst <= 1e-6 * scale,
                "{element}, column {j}: {worst:e} of {scale:e}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
