//! The VTU/PVD fields of `nonlin3d run` and `nonlin3d solve` (docs/SCENES.md, docs/DECKS.md):
//! names, sizes and finiteness read back from the files with a minimal XML reader; the stress
//! of a uniaxially compressed box before buckling against E·ε; the front files' G against
//! results.json's; reactions against the applied end force; stale front files removed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// RFC 4648 base64, padded (VTK's inline binary data).
fn base64_decode(text: &str) -> Vec<u8> {
    let alphabet = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = Vec::new();
    for quad in text.as_bytes().chunks(4) {
        let pad = quad.iter().filter(|&&c| c == b'=').count();
        let v = quad.iter().fold(0u32, |v, &c| {
            let d = alphabet.iter().position(|&a| a == c).unwrap_or(0) as u32;
            (v << 6) | d
        });
        out.extend_from_slice(&v.to_be_bytes()[1..4 - pad]);
    }
    out
}

/// An inline binary `DataArray`'s values as f64: its base64 stream decoded, the UInt64 byte
/// count (the file's `header_type`) checked against the bytes after it, read as `vtk_type`.
fn binary_values(vtk_type: &str, body: &str) -> Vec<f64> {
    let bytes = base64_decode(body);
    let count = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    assert_eq!(count, bytes.len() - 8, "a DataArray's byte count");
    let data = &bytes[8..];
    match vtk_type {
        "Float64" => data
            .chunks(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
            .collect(),
        "Int64" => data
            .chunks(8)
            .map(|b| i64::from_le_bytes(b.try_into().unwrap()) as f64)
            .collect(),
        "Int32" => data
            .chunks(4)
            .map(|b| f64::from(i32::from_le_bytes(b.try_into().unwrap())))
            .collect(),
        "UInt8" => data.iter().map(|&b| f64::from(b)).collect(),
        other => panic!("DataArray type {other}"),
    }
}

/// A VTU file's arrays: (section, name) → (components, values); section "PointData",
/// "CellData" or "Points".
struct Vtu {
    points: usize,
    cells: usize,
    arrays: BTreeMap<(String, String), (usize, Vec<f64>)>,
}

impl Vtu {
    fn read(path: &Path) -> Self {
        let text = std::fs::read_to_string(path).unwrap();
        let attr = |tag: &str, key: &str| -> String {
            let start = tag.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
            tag[start..start + tag[start..].find('"').unwrap()].to_string()
        };
        let piece = &text[text.find("<Piece").unwrap()..];
        let piece_tag = &piece[..piece.find('>').unwrap()];
        let mut arrays = BTreeMap::new();
        let mut section = String::new();
        let mut rest = text.as_str();
        while let Some(i) = rest.find('<') {
            rest = &rest[i..];
            let end = rest.find('>').unwrap();
            let tag = &rest[1..end];
            for s in ["PointData", "CellData", "Points", "Cells"] {
                if tag == s {
                    section = s.to_string();
                }
            }
            if tag.starts_with("DataArray") {
                let body = &rest[end + 1..];
                let body = &body[..body.find("</DataArray>").unwrap()];
                let components = if tag.contains("NumberOfComponents") {
                    attr(tag, "NumberOfComponents").parse().unwrap()
                } else {
                    1
                };
                let values = binary_values(&attr(tag, "type"), body.trim());
                arrays.insert((section.clone(), attr(tag, "Name")), (components, values));
            }
            rest = &rest[end..];
        }
        Self {
            points: attr(piece_tag, "NumberOfPoints").parse().unwrap(),
            cells: attr(piece_tag, "NumberOfCells").parse().unwrap(),
            arrays,
        }
    }

    /// A point or cell array, checked for its size (count × components) and finiteness.
    fn array(&self, section: &str, name: &str, components: usize) -> &[f64] {
        let (c, v) = self
            .arrays
            .get(&(section.to_string(), name.to_string()))
            .unwrap_or_else(|| panic!("{section} {name} missing"));
        let count = if section == "CellData" {
            self.cells
        } else {
            self.points
        };
        assert_eq!(*c, components, "{name}");
        assert_eq!(v.len(), count * components, "{name}");
        assert!(v.iter().all(|x| x.is_finite()), "{name}");
        v
    }
}

fn pvd_files(path: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter(|l| l.contains("<DataSet"))
        .map(|l| {
            let get = |k: &str| {
                let s = l.find(&format!("{k}=\"")).unwrap() + k.len() + 2;
                l[s..s + l[s..].find('"').unwrap()].to_string()
            };
            (get("timestep").parse().unwrap(), get("file"))
        })
        .collect()
}

/// `nonlin3d solve` on a 20 × 10 × 2 mm isotropic box (E = 70 000 MPa, ν = 0.3; C3D20, 3×3×3
/// points) on symmetry rollers, end-shortened by ε = −0.001 in two NLGEOM increments: a
/// homogeneous uniaxial stress state, u = (ε x, ε_y y, ε_z z) exactly in the element space,
/// so at every point E_xx = ε + ε²/2 (Green–Lagrange) and S_xx = E·E_xx (St. Venant–Kirchhoff
/// with S_yy = S_zz = 0), all other components zero. Newton stops at ‖r‖∞ ≤ 1e-8 of the end
/// force, far inside the 1e-6 asked; the extrapolation and averaging add only round-off.
/// The reactions on x = 0 sum to the end force P_xx·W·T = (1 + ε)·S_xx·W·T (first
/// Piola–Kirchhoff stress on the reference area).
#[test]
fn solve_writes_fields_and_the_stress_is_e_times_strain() {
    let dir = tmp("fields-solve");
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/uniaxial_box.inp");
    let out = dir.join("out");
    let st = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["solve", "--out"])
        .arg(&out)
        .arg(&deck)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let steps = pvd_files(&out.join("model.pvd"));
    assert_eq!(
        steps,
        [(0.5, "model_0.vtu".into()), (1.0, "model_1.vtu".into())]
    );
    let (e_mod, eps, w, t) = (70_000.0, -0.001, 10.0, 2.0);
    for (k, (time, file)) in steps.iter().enumerate() {
        let v = Vtu::read(&out.join(file));
        assert_eq!((v.points, v.cells), (32, 2), "one region: no split points");
        let x = v.array("Points", "Points", 3);
        let node = v.array("PointData", "node", 1);
        assert_eq!(node[0], 1.0, "deck node ids");
        let u = v.array("PointData", "displacement", 3);
        let strain = v.array("PointData", "strain_green_lagrange", 6);
        let pk2 = v.array("PointData", "stress_pk2", 6);
        let cauchy = v.array("PointData", "stress_cauchy", 6);
        let rf = v.array("PointData", "reaction", 3);
        for name in ["strain_green_lagrange", "stress_pk2", "stress_cauchy"] {
            v.array("CellData", name, 6);
        }
        v.array("CellData", "material", 1);
        let e = time * eps;
        let e_xx = e + e * e / 2.0;
        let s_xx = e_mod * e_xx;
        let mut force = 0.0;
        for p in 0..v.points {
            let (s, g, c) = (
                &pk2[6 * p..6 * p + 6],
                &strain[6 * p..6 * p + 6],
                &cauchy[6 * p..],
            );
            assert!(
                (g[0] - e_xx).abs() < 1e-6 * e_xx.abs(),
                "step {k} point {p}"
            );
            assert!(
                (s[0] - e_mod * g[0]).abs() < 1e-6 * s_xx.abs(),
                "{s:?} {g:?}"
            );
            assert!((s[0] - s_xx).abs() < 1e-6 * s_xx.abs());
            assert!(s[1..].iter().all(|c| c.abs() < 1e-6 * s_xx.abs()), "{s:?}");
            // σ_xx = F_xx² S_xx / J with J = F_xx F_yy F_zz: lateral stretch from u.
            assert!(c[1].abs() < 1e-6 * s_xx.abs());
            assert!((u[3 * p] - e * x[3 * p]).abs() < 1e-9 * 20.0);
            if x[3 * p] == 0.0 {
                force += rf[3 * p];
            }
        }
        let p_xx = (1.0 + e) * s_xx * w * t;
        assert!(
            (force + p_xx).abs() < 1e-6 * p_xx.abs(),
            "{force} vs {p_xx}"
        );
    }
}

/// The uniaxial modulus of a scene's (first) material, MPa: E_x = 1/(C⁻¹)₁₁, C in Pa.
fn uniaxial_modulus(scene: &str) -> f64 {
    let c = nonlin3d::Scene::from_toml(scene)
        .unwrap()
        .stiffnesses()
        .unwrap()[0]
        .c()
        .to_owned();
    // Gauss–Jordan on [C | e₁]: the first column of C⁻¹.
    let mut a: Vec<Vec<f64>> = (0..6)
        .map(|i| {
            let mut r = c[i].to_vec();
            r.push(if i == 0 { 1.0 } else { 0.0 });
            r
        })
        .collect();
    for col in 0..6 {
        let p = (col..6)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap();
        a.swap(col, p);
        let d = a[col][col];
        a[col].iter_mut().for_each(|x| *x /= d);
        for r in 0..6 {
            if r != col {
                let f = a[r][col];
                let pivot = a[col].clone();
                a[r].iter_mut().zip(&pivot).for_each(|(x, q)| *x -= f * q);
            }
        }
    }
    1e-6 / a[0][6]
}

/// The reference scene at ε = −0.001, before the perturbation and buckling: the sublaminate
/// and base are compressed together, a homogeneous uniaxial stress state of the homogenised
/// laminate (the end shortened, the other faces on rollers or free, the crack faces carrying
/// nothing), so at every point E_xx = ε + ε²/2 and S_xx = E_x·E_xx, the other stresses zero.
/// Newton's 1e-8 relative residual and round-off keep all of it far inside 1e-6.
fn prebuckling_stress_is_e_times_strain(v: &Vtu, e_x: f64, eps: f64) {
    let strain = v.array("PointData", "strain_green_lagrange", 6);
    let pk2 = v.array("PointData", "stress_pk2_MPa", 6);
    let e_xx = eps + eps * eps / 2.0;
    let s_xx = e_x * e_xx;
    for p in 0..v.points {
        let (s, g) = (&pk2[6 * p..6 * p + 6], &strain[6 * p..6 * p + 6]);
        assert!((g[0] - e_xx).abs() < 1e-6 * e_xx.abs(), "point {p}: {g:?}");
        assert!(
            (s[0] - s_xx).abs() < 1e-6 * s_xx.abs(),
            "point {p}: {s:?} vs {s_xx}"
        );
        assert!(s[1..].iter().all(|c| c.abs() < 1e-6 * s_xx.abs()), "{s:?}");
    }
}

/// A coarse reference scene (4 slices, strains −0.001 and −0.003, about 1.5 s): every level's
/// `model_K.vtu` has the documented fields with their sizes, finite; `front_K.vtu` holds
/// results.json's G (both files write shortest round-trip decimals); at the first level, before
/// buckling, S_xx = E_x·E_xx to 1e-6; the largest
/// crack opening w equals results.json's `max_face_separation_mm`; a second run with one level
/// leaves no `front_1.vtu` or `model_1.vtu` behind.
#[test]
fn run_writes_fields_and_the_front_matches_results() {
    let dir = tmp("fields-run");
    let scene = dir.join("coarse.toml");
    let text = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.003]",
        );
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    let run = |scene: &Path| {
        let st = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
            .args(["run", "--quiet", "--out"])
            .arg(&out)
            .arg(scene)
            .output()
            .unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
    };
    run(&scene);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let levels = json["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 2);
    for (stem, pvd) in [("model", "model.pvd"), ("front", "front.pvd")] {
        let files: Vec<String> = pvd_files(&out.join(pvd)).into_iter().map(|s| s.1).collect();
        assert_eq!(files, [format!("{stem}_0.vtu"), format!("{stem}_1.vtu")]);
    }
    let e_x = uniaxial_modulus(&text);
    for (k, level) in levels.iter().enumerate() {
        let v = Vtu::read(&out.join(format!("model_{k}.vtu")));
        if k == 0 {
            prebuckling_stress_is_e_times_strain(&v, e_x, -0.001);
        }
        assert_eq!(v.points, json["model"]["nodes"].as_u64().unwrap() as usize);
        for (name, c) in [
            ("node", 1),
            ("displacement_mm", 3),
            ("strain_green_lagrange", 6),
            ("stress_pk2_MPa", 6),
            ("stress_cauchy_MPa", 6),
            ("reaction_N", 3),
            ("crack_opening_mm", 3),
        ] {
            v.array("PointData", name, c);
        }
        for (name, c) in [
            ("material", 1),
            ("ply_angle_deg", 1),
            ("strain_green_lagrange", 6),
            ("stress_pk2_MPa", 6),
            ("stress_cauchy_MPa", 6),
        ] {
            v.array("CellData", name, c);
        }
        let opening = v.array("PointData", "crack_opening_mm", 3);
        let peak = (0..v.points)
            .map(|p| opening[3 * p + 2])
            .fold(0.0_f64, |m, d| if d.abs() > m.abs() { d } else { m });
        let expected = level["max_face_separation_mm"].as_f64().unwrap();
        assert!(
            (peak - expected).abs() <= 1e-12 * expected.abs(),
            "{peak} vs {expected}"
        );
        let f = Vtu::read(&out.join(format!("front_{k}.vtu")));
        let rows = level["front"].as_array().unwrap();
        assert_eq!((f.points, f.cells), (rows.len(), rows.len() - 1));
        for (name, key) in [
            ("s_mm", "s_mm"),
            ("G_I_J_m2", "g_i"),
            ("G_II_J_m2", "g_ii"),
            ("G_III_J_m2", "g_iii"),
            ("G_T_J_m2", "g_t"),
        ] {
            let got = f.array("PointData", name, 1);
            // Both files hold the same f64 in shortest round-trip form; serde_json's default
            // parser reads decimals to within 1 ulp (it is not correctly rounded without its
            // `float_roundtrip` feature), hence 2 ulp.
            for (g, r) in got.iter().zip(rows) {
                let j = r[key].as_f64().unwrap();
                assert!(
                    (g - j).abs() <= 2.0 * f64::EPSILON * j.abs(),
                    "{name} level {k}: {g} vs {j}"
                );
            }
        }
        let open = f.array("PointData", "open", 1);
        let mix = f.array("PointData", "mode_mix", 1);
        for ((o, m), r) in open.iter().zip(mix).zip(rows) {
            assert_eq!(*o == 1.0, r["faces"] == "open");
            let g = |k: &str| r[k].as_f64().unwrap();
            assert!((m * g("g_t") - g("g_ii") - g("g_iii")).abs() <= 1e-12 * g("g_t").abs());
        }
    }
    // A rerun with one level: the second level's files are gone.
    std::fs::write(
        &scene,
        text.replace("strains = [-0.001, -0.003]", "strains = [-0.001]"),
    )
    .unwrap();
    run(&scene);
    for f in ["front_1.vtu", "model_1.vtu", "front_1.csv"] {
        assert!(!out.join(f).exists(), "{f} left from the first run");
    }
    assert!(out.join("front_0.vtu").exists());
}

/// At the end of a run the output folder keeps each level's `model_K.vtu` as written when the
/// level converged (the file is not made again: same inode) when the final results hold the
/// same state, and its bytes are those `report::write_all` writes; a level whose state changed
/// after it was written is written anew.
#[test]
fn the_end_of_a_run_keeps_the_model_files_its_levels_wrote() {
    use std::os::unix::fs::MetadataExt;
    let dir = tmp("fields-finish");
    let text = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.002]",
        );
    let scene = nonlin3d::Scene::from_toml(&text).unwrap();
    let results = nonlin3d::analysis::run(&scene, &mut |_| Ok(())).unwrap();
    let model = results.model_data.clone().unwrap();
    let inode = |p: &Path| std::fs::metadata(p).unwrap().ino();
    let write = |name: &str, changed: bool| {
        let out = dir.join(name);
        let mut o = nonlin3d::output::RunOutput::create(&out, &scene.title, "strain").unwrap();
        o.built(&model, results.model.dofs).unwrap();
        for l in &results.levels {
            o.level(l).unwrap();
        }
        let before = [0, 1].map(|k| inode(&out.join(format!("model_{k}.vtu"))));
        let mut fin = results.clone();
        if changed {
            fin.levels[1].displacements[7] += 1e-9;
        }
        o.finish(&mut fin).unwrap();
        let after = [0, 1].map(|k| inode(&out.join(format!("model_{k}.vtu"))));
        (out, before, after)
    };
    let (kept, before, after) = write("kept", false);
    assert_eq!(before, after, "rewritten although unchanged");
    let fresh = dir.join("fresh");
    nonlin3d::report::write_all(&mut results.clone(), &fresh).unwrap();
    for k in 0..2 {
        let f = format!("model_{k}.vtu");
        assert!(std::fs::read(kept.join(&f)).unwrap() == std::fs::read(fresh.join(&f)).unwrap());
    }
    let (changed, before, after) = write("changed", true);
    assert_eq!(before[0], after[0]);
    assert_ne!(before[1], after[1], "a changed state must be written anew");
    assert!(
        std::fs::read(changed.join("model_1.vtu")).unwrap()
            != std::fs::read(fresh.join("model_1.vtu")).unwrap()
    );
}
