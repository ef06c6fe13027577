//! The generated meshes, their fronts and the written `.inp`/VTU text, pinned bit for bit.
//!
//! Each case hashes (FNV-1a, 64 bit) every node coordinate's bits, every cell (kind, nodes,
//! material, ply angle bits), every node, cell and face set (name and members, in the
//! `BTreeMap`'s order), and for the delamination models every front point (nodes, flags and the
//! bits of Δa, x, y, tangent, normal, θ, S). A refactor of the generators or writers must leave
//! these hashes unchanged: it moves code, not nodes.
//!
//! A DELIBERATE change of a mesh (a new node order, a new set, a different grading) updates the
//! hashes below: run `cargo test --release -p nonlin3d-mesh --test pinned`, check that only the
//! cases the change should touch moved, and paste the printed table into `PINNED`.

use nonlin3d_element::ElementKind;
use nonlin3d_laminate::{ShearCoupling, materials};
use nonlin3d_mesh::inp::{
    InpBoundary, InpCload, InpDeck, InpElastic, InpMaterial, InpStep, inp_string,
};
use nonlin3d_mesh::vtu::{Field, pvd_string, vtu_string};
use nonlin3d_mesh::{
    BoxParams, Centre, EllipticMap, EmbeddedParams, Front, Mesh, PlyLayout, ThroughWidthParams,
    edge_delamination, embedded_delamination, embedded_delamination_with_front, structured_box,
    thin_film, through_width_delamination,
};

/// FNV-1a over a byte stream: fixed, documented, with no dependency and no per-process seed.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    fn u(&mut self, v: usize) {
        self.bytes(&(v as u64).to_le_bytes());
    }
    fn f(&mut self, v: f64) {
        self.bytes(&v.to_bits().to_le_bytes());
    }
    fn s(&mut self, v: &str) {
        self.u(v.len());
        self.bytes(v.as_bytes());
    }
    fn opt(&mut self, v: Option<usize>) {
        self.u(v.map_or(usize::MAX, |n| n));
    }
}

fn hash_mesh(h: &mut Fnv, m: &Mesh) {
    h.u(m.nodes.len());
    for x in &m.nodes {
        x.iter().for_each(|&c| h.f(c));
    }
    h.u(m.cells.len());
    for c in &m.cells {
        h.u(c.kind.nodes());
        h.u(c.nodes.len());
        c.nodes.iter().for_each(|&n| h.u(n));
        h.u(c.material);
        h.f(c.ply_angle_deg);
    }
    for sets in [&m.node_sets, &m.cell_sets] {
        h.u(sets.len());
        for (name, set) in sets {
            h.s(name);
            h.u(set.len());
            set.iter().for_each(|&n| h.u(n));
        }
    }
    h.u(m.face_sets.len());
    for (name, set) in &m.face_sets {
        h.s(name);
        h.u(set.len());
        for &(c, f) in set {
            h.u(c);
            h.u(usize::from(f));
        }
    }
}

fn hash_front(h: &mut Fnv, front: &Front) {
    h.u(front.points.len());
    for p in &front.points {
        for n in [p.c, usize::from(p.corner), p.a_upper, p.a_lower] {
            h.u(n);
        }
        for n in [p.b_upper, p.b_lower, p.d] {
            h.opt(n);
        }
        h.u(p.cells_above.len());
        p.cells_above.iter().for_each(|&c| h.u(c));
        for v in [p.delta_a, p.x, p.y, p.tangent[0], p.tangent[1]] {
            h.f(v);
        }
        for v in [p.normal[0], p.normal[1], p.theta_deg, p.s] {
            h.f(v);
        }
    }
}

fn mesh_hash(m: &Mesh) -> u64 {
    let mut h = Fnv::new();
    hash_mesh(&mut h, m);
    h.0
}

fn with_front(m: &Mesh, front: &Front) -> u64 {
    let mut h = Fnv::new();
    hash_mesh(&mut h, m);
    hash_front(&mut h, front);
    h.0
}

fn text_hash(s: &str) -> u64 {
    let mut h = Fnv::new();
    h.s(s);
    h.0
}

fn embedded(f: impl FnOnce(&mut EmbeddedParams)) -> EmbeddedParams {
    let mut p = EmbeddedParams::thesis_reference();
    f(&mut p);
    p
}

fn embedded_case(p: &EmbeddedParams) -> u64 {
    let (m, front) = embedded_delamination_with_front(p).unwrap();
    with_front(&m, &front)
}

fn through_width_case(kind: ElementKind, across: usize) -> u64 {
    let p = ThroughWidthParams {
        kind,
        across,
        ..ThroughWidthParams::example()
    };
    let (m, front) = through_width_delamination(&p).unwrap();
    with_front(&m, &front)
}

/// Every `InpElastic` variant, so the writer's four material branches are pinned.
fn four_materials() -> Vec<InpMaterial> {
    let ply = materials::generic_graphite_epoxy();
    let stiffness = ply.stiffness().unwrap();
    let rotated = stiffness
        .rotated_about_z(30f64.to_radians(), ShearCoupling::Exact)
        .unwrap();
    let elastic = [
        InpElastic::Isotropic { e: 207e9, nu: 0.3 },
        InpElastic::Engineering(ply),
        InpElastic::Orthotropic(Box::new(stiffness)),
        InpElastic::Anisotropic(Box::new(rotated)),
    ];
    elastic
        .into_iter()
        .enumerate()
        .map(|(k, elastic)| InpMaterial {
            name: format!("M{k}"),
            elastic,
        })
        .collect()
}

fn steps() -> Vec<InpStep> {
    let boundary = |nset: &str, first, last, value| InpBoundary {
        nset: nset.into(),
        first,
        last,
        value,
    };
    vec![
        InpStep {
            nlgeom: false,
            increment: 1.0,
            period: 1.0,
            boundaries: vec![boundary("x0", 1, 3, 0.0)],
            cloads: vec![],
        },
        InpStep {
            nlgeom: true,
            increment: 0.1,
            period: 1.0,
            boundaries: vec![boundary("x0", 1, 1, 0.0), boundary("x1", 1, 1, -1e-5)],
            cloads: vec![InpCload {
                node: 3,
                dof: 3,
                value: -2.5,
            }],
        },
    ]
}

/// The embedded model with ply layers, cells spread over the four materials by index.
fn inp_case() -> u64 {
    let p = embedded(|p| {
        p.kind = ElementKind::Hex8;
        p.slices = 4;
        p.plies = Some(PlyLayout {
            ply_thickness: 0.1e-3,
            sublaminate: vec![0.0, 90.0, 90.0, 0.0],
            base_below: vec![45.0, -45.0],
        });
    });
    let mut mesh = embedded_delamination(&p).unwrap();
    for (c, cell) in mesh.cells.iter_mut().enumerate() {
        cell.material = c % 4;
    }
    let mats = four_materials();
    let deck = InpDeck {
        heading: "pinned\ndeck".into(),
        mesh: &mesh,
        materials: &mats,
        steps: steps(),
    };
    text_hash(&inp_string(&deck).unwrap())
}

fn vtu_case() -> u64 {
    let mesh = structured_box(&BoxParams::new(
        ElementKind::Hex20,
        [2, 2, 1],
        [2.0, 2.0, 0.5],
    ))
    .unwrap();
    let u: Vec<f64> = (0..3 * mesh.nodes.len()).map(|k| k as f64 / 7.0).collect();
    let s: Vec<f64> = (0..mesh.cells.len()).map(|k| -(k as f64)).collect();
    let point = [Field {
        name: "U",
        components: 3,
        values: &u,
    }];
    let cell = [Field {
        name: "S",
        components: 1,
        values: &s,
    }];
    let vtu = vtu_string(&mesh, &point, &cell).unwrap();
    let pvd = pvd_string(&[(0.0, "a.vtu".into()), (0.5, "b.vtu".into())]).unwrap();
    text_hash(&(vtu + &pvd))
}

/// A named case and the function that hashes it.
type Case = (&'static str, Box<dyn Fn() -> u64>);

/// (case, hash). Update only for a deliberate mesh change (see the module doc).
const PINNED: &[(&str, u64)] = &[
    ("embedded circle Hex20", 0x562a44aae021d7e4),
    ("embedded circle Hex8, 12 slices", 0x2474170abb6ec7f6),
    ("ellipse a > b, eq. 3.1.2", 0x995ed685ee5e6eb7),
    ("ellipse a < b, eq. 3.1.1", 0x38b84f7c74f86f8c),
    ("rectangle a < b", 0x9b3354a0c629b37f),
    ("thesis arc centre, Hex20", 0x3917de267a16bd38),
    ("ply layers, Hex20", 0x4c8a888ac05d9e1f),
    ("edge, semi-ellipse a > b", 0xfccb5f3d5a33a080),
    ("thin film, Hex20", 0x01b8865056585aab),
    ("thin film, ellipse a > b, Hex8", 0xdcf808ae29dcf479),
    ("through width Hex20, 1 across", 0xc38a612aab718c54),
    ("through width Hex8, 3 across", 0xe38f16cc642ac7a4),
    ("structured box Hex8, graded", 0xfcf26641b00a8c86),
    ("structured box Hex20", 0x1dfbbb8f2001f2e5),
    ("inp deck, four materials", 0x04ebbc82d2d632cb),
    ("vtu and pvd", 0x5f7000d5a34ce57b),
];

#[test]
fn meshes_fronts_and_decks_are_bitwise_unchanged() {
    let ellipse = |a: f64, b: f64, map: fn(f64, f64) -> EllipticMap| {
        embedded(|p| {
            p.a = a;
            p.b = b;
            p.map = map(a, b);
            p.radial_inside = EmbeddedParams::radial_inside_for(a, b);
        })
    };
    let cases: Vec<Case> = vec![
        (
            "embedded circle Hex20",
            Box::new(|| embedded_case(&EmbeddedParams::thesis_reference())),
        ),
        (
            "embedded circle Hex8, 12 slices",
            Box::new(|| {
                embedded_case(&embedded(|p| {
                    p.kind = ElementKind::Hex8;
                    p.slices = 12;
                }))
            }),
        ),
        (
            "ellipse a > b, eq. 3.1.2",
            Box::new(move || embedded_case(&ellipse(20e-3, 10e-3, EllipticMap::modified_for))),
        ),
        (
            "ellipse a < b, eq. 3.1.1",
            Box::new(move || embedded_case(&ellipse(10e-3, 25e-3, |_, _| EllipticMap::Conformal))),
        ),
        (
            "rectangle a < b",
            Box::new(move || embedded_case(&ellipse(10e-3, 20e-3, |_, _| EllipticMap::Rectangle))),
        ),
        (
            "thesis arc centre, Hex20",
            Box::new(|| embedded_case(&embedded(|p| p.centre = Centre::ThesisArc))),
        ),
        (
            "ply layers, Hex20",
            Box::new(|| {
                embedded_case(&embedded(|p| {
                    p.slices = 4;
                    p.plies = Some(PlyLayout {
                        ply_thickness: 0.1e-3,
                        sublaminate: vec![0.0, 90.0, 90.0, 0.0],
                        base_below: vec![45.0, -45.0, 0.0],
                    });
                }))
            }),
        ),
        (
            "edge, semi-ellipse a > b",
            Box::new(|| {
                let (m, front) = edge_delamination(&embedded(|p| {
                    p.a = 20e-3;
                    p.b = 12e-3;
                    p.map = EllipticMap::modified_for(p.a, p.b);
                }))
                .unwrap();
                with_front(&m, &front)
            }),
        ),
        (
            "thin film, Hex20",
            Box::new(|| mesh_hash(&thin_film(&EmbeddedParams::thesis_reference()).unwrap())),
        ),
        (
            "thin film, ellipse a > b, Hex8",
            Box::new(|| {
                mesh_hash(
                    &thin_film(&embedded(|p| {
                        p.kind = ElementKind::Hex8;
                        p.a = 20e-3;
                        p.b = 10e-3;
                    }))
                    .unwrap(),
                )
            }),
        ),
        (
            "through width Hex20, 1 across",
            Box::new(|| through_width_case(ElementKind::Hex20, 1)),
        ),
        (
            "through width Hex8, 3 across",
            Box::new(|| through_width_case(ElementKind::Hex8, 3)),
        ),
        (
            "structured box Hex8, graded",
            Box::new(|| {
                let mut p = BoxParams::new(ElementKind::Hex8, [3, 2, 4], [3e-3, 2e-3, 1e-3]);
                p.grading = [0.5, 1.0, 2.0];
                p.material = 2;
                mesh_hash(&structured_box(&p).unwrap())
            }),
        ),
        (
            "structured box Hex20",
            Box::new(|| {
                let p = BoxParams::new(ElementKind::Hex20, [2, 3, 2], [4e-3, 3e-3, 1e-3]);
                mesh_hash(&structured_box(&p).unwrap())
            }),
        ),
        ("inp deck, four materials", Box::new(inp_case)),
        ("vtu and pvd", Box::new(vtu_case)),
    ];
    let actual: Vec<(&str, u64)> = cases.iter().map(|(name, f)| (*name, f())).collect();
    let table: String = actual
        .iter()
        .map(|(name, h)| format!("    (\"{name}\", 0x{h:016x}),\n"))
        .collect();
    let differ: Vec<&str> = actual
        .iter()
        .filter(|(name, h)| PINNED.iter().find(|(n, _)| n == name).map(|(_, p)| p) != Some(h))
        .map(|(name, _)| *name)
        .collect();
    assert!(
        differ.is_empty() && PINNED.len() == actual.len(),
        "changed or unpinned: {differ:?}\nthe table today:\n{table}"
    );
}
