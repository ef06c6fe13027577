//! One level with crack-face contact (thesis §2.7, Fig. 2.7.2) against the same level without:
//! the reference scene (30 mm circle, Hex20) coarsened to slices = 4 (1 773 DOF), one level
//! ε = −0.005 (the faces overlap without contact from its second quarter on; contact closes a
//! dozen pairs), one thread, the whole run (model, solve, VCCT; no files). Three cases:
//! `off`, `auto` (solved without contact in the loop's steps up to the first that overlaps,
//! then the active-set loop) and `on` (the loop from the start). Read the ratios auto/off and
//! on/off, not the absolute times (docs/PERFORMANCE.md, "Crack-face contact").
//!
//! Run: `cargo bench --bench contact_level`.

use criterion::{Criterion, criterion_group, criterion_main};
use nonlin3d::contact::CrackFacesName;
use nonlin3d::scene::Scene;
use std::path::Path;

fn scene(faces: CrackFacesName) -> Scene {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/fig_5_1_3_circle_30mm.toml");
    let text = std::fs::read_to_string(path).expect("the reference scene");
    let mut s = Scene::from_toml(&text).expect("a valid scene");
    s.mesh.slices = Some(4);
    s.loads.strains = vec![-0.005];
    s.contact.crack_faces = faces;
    s.analysis.threads = 1;
    s
}

fn bench_contact_level(c: &mut Criterion) {
    let mut group = c.benchmark_group("contact_level");
    group.sample_size(10);
    for (name, faces) in [
        ("off", CrackFacesName::Off),
        ("auto", CrackFacesName::Auto),
        ("on", CrackFacesName::On),
    ] {
        let s = scene(faces);
        group.bench_function(name, |b| {
            b.iter(|| nonlin3d::analysis::run(&s, &mut |_| Ok(())).expect("the level solves"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_contact_level);
criterion_main!(benches);
