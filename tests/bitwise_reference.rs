//! Bitwise pins of the results, so that a restructuring (pure motion of code) can be shown to
//! change nothing: the reference scene (thesis Fig. 5.1.3, every level: G_I, G_II, G_III, G_T
//! along the front and the displacement field) and two CalculiX-checked decks (displacements
//! of every node at the end of every step) must reproduce the committed numbers bit for bit.
//!
//! The numbers were written by the code before the constrained-system split (issue 17) with
//! `NONLIN3D_WRITE_REFERENCE=1 cargo test --release --test bitwise_reference`. A deliberate
//! change of the numerics (a new default, a different summation order) rewrites them the same
//! way, and says why in its commit; anything else that changes them is a regression.
//!
//! Bits are a property of one binary on one instruction set: the element kernels take an
//! AVX2/FMA path when the CPU has it and faer dispatches on the CPU's vector width. The files
//! record the instruction-set extensions of the machine that wrote them; on a machine with
//! other extensions the numbers are compared to 1e-9 relative instead (a different rounding
//! order of the same sums; the Newton tolerance is 1e-8 of the force scale) and the test says so.
//!
//! Floating-point numbers are written in Rust's shortest round-trip form (`{:?}`), so parsing
//! them back gives the same bits. The displacement field of the scene is pinned by a 64-bit
//! FNV-1a hash of its bits at every level and written out in full at the last level.

use nonlin3d::deck::{StepOptions, solve_deck};
use nonlin3d::scene::Scene;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const REFERENCE_SCENE: &str = "examples/scenes/fig_5_1_3_circle_30mm.toml";
const DECKS: [&str; 2] = ["cantilever_nlgeom_2steps", "ortho_tilted_nlgeom"];

fn reference_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/bitwise")
}

/// FNV-1a over the little-endian bytes of each number's bits.
fn fnv(values: &[f64]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in values {
        for b in v.to_bits().to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// The vector extensions that decide which code paths run.
fn isa() -> String {
    let mut have = Vec::new();
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            have.push("avx2");
        }
        if std::arch::is_x86_feature_detected!("fma") {
            have.push("fma");
        }
        if std::arch::is_x86_feature_detected!("avx512f") {
            have.push("avx512f");
        }
    }
    format!("isa: {} {}", std::env::consts::ARCH, have.join(" "))
}

fn scene_text() -> String {
    let mut scene = Scene::from_toml(
        &std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(REFERENCE_SCENE))
            .unwrap(),
    )
    .unwrap();
    // The pins are of the analysis without contact (the faces overlap from ε = −0.003 on):
    // `crack_faces = "off"` must reproduce the numbers written before contact existed.
    scene.contact.crack_faces = nonlin3d::contact::CrackFacesName::Off;
    // And of every level followed on this mesh: nested iteration (`start = "companion"`, the
    // default since) reaches the same states from other iterates (tests/nested.rs).
    scene.analysis.start = nonlin3d::scene::StartName::Path;
    let results = nonlin3d::analysis::run(&scene, &mut |_| Ok(())).unwrap();
    let mut out = String::new();
    for (k, level) in results.levels.iter().enumerate() {
        writeln!(
            out,
            "level {k} value {:?} centre {:?} separation {:?} u-hash {:016x}",
            level.value,
            level.centre_deflection_mm,
            level.max_face_separation_mm,
            fnv(&level.displacements)
        )
        .unwrap();
        for r in &level.front {
            writeln!(
                out,
                "front s {:?} g_i {:?} g_ii {:?} g_iii {:?} g_t {:?}",
                r.s_mm, r.g_i, r.g_ii, r.g_iii, r.g_t
            )
            .unwrap();
        }
    }
    if let Some(last) = results.levels.last() {
        writeln!(out, "displacements of the last level, m").unwrap();
        for u in &last.displacements {
            writeln!(out, "{u:?}").unwrap();
        }
    }
    out
}

fn deck_text(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/decks/{name}.inp"));
    let model = nonlin3d::mesh::read_inp_file(&path).unwrap();
    let steps = solve_deck(&model, &StepOptions::default()).unwrap();
    let mut out = String::new();
    for s in &steps {
        writeln!(out, "step {} increments {}", s.step, s.increments.len()).unwrap();
        for (n, u) in s.displacements.iter().enumerate() {
            writeln!(out, "{n} {:?} {:?} {:?}", u[0], u[1], u[2]).unwrap();
        }
    }
    out
}

/// Compares `ours` with the committed file line by line (or writes it when asked), naming the
/// first line that differs: bit for bit on the instruction set that wrote the file, else to
/// 1e-9 relative per number (hash fields skipped).
fn check(file: &str, ours: &str) {
    let path = reference_dir().join(file);
    let ours = format!("{}\n{ours}", isa());
    if std::env::var_os("NONLIN3D_WRITE_REFERENCE").is_some() {
        std::fs::create_dir_all(reference_dir()).unwrap();
        std::fs::write(&path, ours).unwrap();
        return;
    }
    let theirs = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (write it with NONLIN3D_WRITE_REFERENCE=1)",
            path.display()
        )
    });
    let same_isa = theirs.lines().next() == ours.lines().next();
    if !same_isa {
        eprintln!(
            "{file}: written on '{}', this machine has '{}': comparing to 1e-9 relative, not bits",
            theirs.lines().next().unwrap_or(""),
            isa()
        );
    }
    for (k, (a, b)) in ours.lines().zip(theirs.lines()).enumerate().skip(1) {
        if same_isa {
            assert_eq!(a, b, "{file} line {}: ours ≠ committed", k + 1);
        } else {
            close(a, b, &format!("{file} line {}", k + 1));
        }
    }
    assert_eq!(
        ours.lines().count(),
        theirs.lines().count(),
        "{file}: line counts differ"
    );
}

/// Word by word: numbers to 1e-9 relative (of the larger, or absolute below 1e-30), hashes
/// skipped, other words equal.
fn close(a: &str, b: &str, at: &str) {
    let (wa, wb): (Vec<&str>, Vec<&str>) = (
        a.split_whitespace().collect(),
        b.split_whitespace().collect(),
    );
    assert_eq!(wa.len(), wb.len(), "{at}: {a} vs {b}");
    for (k, (x, y)) in wa.iter().zip(&wb).enumerate() {
        if k > 0 && wa[k - 1] == "u-hash" {
            continue;
        }
        match (x.parse::<f64>(), y.parse::<f64>()) {
            (Ok(p), Ok(q)) => assert!(
                (p - q).abs() <= 1e-9 * p.abs().max(q.abs()) + 1e-30,
                "{at}: {p} vs {q}"
            ),
            _ => assert_eq!(x, y, "{at}"),
        }
    }
}

#[test]
fn the_reference_scene_reproduces_its_committed_bits() {
    check("fig_5_1_3_circle_30mm.txt", &scene_text());
}

#[test]
fn calculix_checked_decks_reproduce_their_committed_bits() {
    for name in DECKS {
        check(&format!("{name}.txt"), &deck_text(name));
    }
}

#[test]
fn the_hash_sees_one_bit() {
    let a: [f64; 3] = [1.0, -2.5, 3.25e-7];
    let mut b = a;
    b[2] = f64::from_bits(b[2].to_bits() ^ 1);
    assert_ne!(fnv(&a), fnv(&b));
    assert_eq!(fnv(&a), fnv(&a.clone()));
}
