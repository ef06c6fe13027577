//! Contact on the embedded delamination mesh of the generators (thesis §3.1–3.2: a circular
//! delamination, quarter model, sublaminate bonded outside the front), coarse Hex8: the set
//! closes from empty when the sublaminate is pushed into its base, and opens to empty when it
//! is pulled away.

use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_contact::{Contact, ContactSettings, CrackFaces, LevelSettings, Reserve};
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d_laminate::{ShearCoupling, materials};
use nonlin3d_mesh::names::{CRACK_UPPER, X0, Y0, Z0};
use nonlin3d_mesh::{EmbeddedParams, Imperfection, Mesh, embedded_delamination};
use nonlin3d_newton::{NewtonSettings, NonlinearProblem, PathSolver, Stepping, StructuralProblem};

/// A 30 mm circle under a 0.4 mm sublaminate on a 2 mm base, W = 30 mm, Hex8, 2 slices, two
/// rings inside the front: a few hundred nodes.
fn mesh() -> Mesh {
    mesh_of(2, 2)
}

/// [`mesh`] with `slices` slices and `rings` rings inside the front.
fn mesh_of(slices: usize, rings: usize) -> Mesh {
    let p = EmbeddedParams {
        kind: ElementKind::Hex8,
        slices,
        radial_inside: rings,
        radial_outside: 1,
        base: 2e-3,
        w: 30e-3,
        base_layers: 1,
        ..EmbeddedParams::thesis_reference()
    };
    embedded_delamination(&p).unwrap()
}

/// The distance of pair `i`'s upper node from the circle's centre (m).
fn radius(mesh: &Mesh, faces: &CrackFaces, i: usize) -> f64 {
    let x = mesh.nodes[faces.pairs()[i].upper];
    x[0].hypot(x[1])
}

/// Steel; w = 0 on z = 0, symmetry on x = 0 and y = 0; `load` (N, +z up) spread over the
/// sublaminate's top nodes above the crack (those over a `crack_upper` node). The contact's
/// reserve is reserved.
fn problem(mesh: &Mesh, contact: &Contact, load: f64) -> StructuralProblem {
    let steel = materials::steel().stiffness().unwrap();
    let solid = Assembler::new(
        mesh,
        &[steel],
        ShearCoupling::Exact,
        IntegrationRule::Gauss2,
        IntegrationRule::Gauss2,
        Kinematics::Nonlinear,
    )
    .unwrap();
    let mut c = Constraints::new(solid.n());
    c.fix_nodes(&mesh.node_sets[Z0], 2).unwrap();
    c.fix_nodes(&mesh.node_sets[X0], 0).unwrap();
    c.fix_nodes(&mesh.node_sets[Y0], 1).unwrap();
    let top_z = mesh.nodes.iter().fold(0.0f64, |m, x| m.max(x[2]));
    let over: Vec<usize> = mesh.node_sets[CRACK_UPPER]
        .iter()
        .filter_map(|&v| {
            let x = mesh.nodes[v];
            (0..mesh.nodes.len()).find(|&t| {
                let y = mesh.nodes[t];
                (y[2] - top_z).abs() < 1e-12
                    && (y[0] - x[0]).abs() < 1e-12
                    && (y[1] - x[1]).abs() < 1e-12
            })
        })
        .collect();
    assert!(!over.is_empty());
    for &v in &over {
        c.add_load(3 * v + 2, load / over.len() as f64).unwrap();
    }
    StructuralProblem::with_contributions(solid, Vec::new(), c, |b| contact.reserve(b)).unwrap()
}

/// Pushing the sublaminate down (no pair closed at first): the first solve overlaps, the
/// overlapping pairs close, and passes follow until the set is stable: then no overlap beyond
/// the gap tolerance and every force compressive. With every pair reserved up front
/// ([`Reserve::All`]): one pattern, one symbolic analysis.
#[test]
fn a_pushed_sublaminate_closes_onto_its_base() {
    let mesh = mesh();
    let settings = ContactSettings {
        reserve: Reserve::All,
        ..ContactSettings::default()
    };
    let mut contact = Contact::new(&mesh, settings).unwrap();
    let mut problem = problem(&mesh, &contact, -200.0);
    let newton = NewtonSettings::default();
    let mut session = PathSolver::new(&problem, newton.solver).unwrap();
    let mut u = vec![0.0; problem.system().n()];
    let level = contact
        .solve_level(
            &mut problem,
            &mut session,
            &mut u,
            (0.0, 1.0),
            &LevelSettings {
                newton: &newton,
                stepping: &Stepping::default(),
                perturbation: &[],
            },
        )
        .unwrap();
    let s = &level.state;
    println!(
        "{} nodes, {} pairs: passes {}, closed {}, opened {}, Newton iterations {}, active {}, \
         Σ p n_z {:.3} N, min gap {:e} m",
        mesh.nodes.len(),
        s.active.len(),
        level.passes.len(),
        level.closed(),
        level.opened(),
        level.newton_iterations(),
        s.active.iter().filter(|&&a| a).count(),
        s.total_force()[2],
        s.gaps.iter().fold(f64::INFINITY, |m, &g| m.min(g))
    );
    assert!(level.closed() > 0);
    assert!(s.active.iter().any(|&a| a));
    let tol = ContactSettings::default().gap_tolerance;
    assert!(s.gaps.iter().all(|&g| g >= -tol));
    assert!(s.forces.iter().all(|&p| p >= -s.force_tolerance));
    assert!(s.total_force()[2] > 0.0 && s.total_force()[2] < 200.0);
    assert_eq!(problem.system().pattern_builds(), 1);
    assert_eq!(session.analyses(), 1);
}

/// Pulling the sublaminate away with every pair closed at first: every force is tensile, all
/// pairs are released at once, and after the re-solve the faces are apart (every gap > 0): the
/// set ends empty.
#[test]
fn a_pulled_sublaminate_opens_every_pair() {
    let mesh = mesh();
    let mut contact = Contact::new(&mesh, ContactSettings::default()).unwrap();
    let mut problem = problem(&mesh, &contact, 200.0);
    let newton = NewtonSettings::default();
    let mut session = PathSolver::new(&problem, newton.solver).unwrap();
    let mut u = vec![0.0; problem.system().n()];
    let all = vec![true; contact.faces().len()];
    contact.install(&mut problem, &u, &all).unwrap();
    let level = contact
        .solve_level(
            &mut problem,
            &mut session,
            &mut u,
            (0.0, 1.0),
            &LevelSettings {
                newton: &newton,
                stepping: &Stepping::default(),
                perturbation: &[],
            },
        )
        .unwrap();
    let s = &level.state;
    println!(
        "pulled: passes {}, opened {}, Newton iterations {}",
        level.passes.len(),
        level.opened(),
        level.newton_iterations()
    );
    assert_eq!(level.passes.len(), 1);
    assert_eq!(level.opened(), s.active.len());
    assert!(s.active.iter().all(|&a| !a));
    assert!(s.gaps.iter().all(|&g| g > 0.0));
    assert!(s.forces.iter().all(|&p| p == 0.0));
}

/// An initial gap (the sublaminate lifted by a 2 µm bubble, as the scenes' imperfection does,
/// the lower face kept): the pairs that close are held at zero deformed gap at every level
/// (the tie offset −g₀/n_k is a geometric fact, not scaled by λ: at λ = 0.5 a scaled one would
/// hold them g₀/2 apart, up to 1 µm), and open pairs do not overlap.
#[test]
fn an_initial_gap_is_closed_at_every_level() {
    let mut mesh = mesh();
    let shape = Imperfection::Bubble { a: 15e-3, b: 15e-3 };
    mesh.apply_imperfection(2e-3, nonlin3d_mesh::names::CRACK_LOWER, shape, 2e-6)
        .unwrap();
    let mut contact = Contact::new(&mesh, ContactSettings::default()).unwrap();
    let g0 = contact.faces().initial_gaps(
        &contact
            .faces()
            .normals(&vec![0.0; 3 * mesh.nodes.len()])
            .unwrap(),
    );
    assert!(g0.iter().any(|&g| g > 1e-6));
    let mut problem = problem(&mesh, &contact, -400.0);
    let newton = NewtonSettings::default();
    let mut session = PathSolver::new(&problem, newton.solver).unwrap();
    let mut u = vec![0.0; problem.system().n()];
    let tol = ContactSettings::default().gap_tolerance;
    let mut from = 0.0;
    for to in [0.5, 1.0] {
        let level = contact
            .solve_level(
                &mut problem,
                &mut session,
                &mut u,
                (from, to),
                &LevelSettings {
                    newton: &newton,
                    stepping: &Stepping::default(),
                    perturbation: &[],
                },
            )
            .unwrap();
        let s = &level.state;
        println!(
            "λ = {to}: passes {}, closed {}, opened {}, active {}, Newton iterations {}",
            level.passes.len(),
            level.closed(),
            level.opened(),
            s.active.iter().filter(|&&a| a).count(),
            level.newton_iterations()
        );
        assert!(s.active.iter().any(|&a| a));
        for (g, a) in s.gaps.iter().zip(&s.active) {
            assert!(*g >= -tol, "λ = {to}: gap {g:e} m");
            if *a {
                assert!(g.abs() <= tol, "λ = {to}: a closed pair {g:e} m apart");
            }
        }
        from = to;
    }
}

/// Issue 19, defect 2: a held pair's gap is zero along the normal it was tied with, and the
/// re-solve turns the lower face. With a gap tolerance of 1e-13 m (below the 6.7e-13 m that
/// such a turn leaves here with the default 1e-9 m, which needs no refresh) the loop must hold
/// the set again with the current normals (a refresh pass) until every gap, held or open, is
/// within the tolerance along the current normal (measured: one refresh, 7e-19 m left).
#[test]
fn held_pairs_are_refreshed_until_the_penetration_is_within_the_tolerance() {
    let mesh = mesh();
    let settings = ContactSettings {
        gap_tolerance: 1e-13,
        ..ContactSettings::default()
    };
    let mut contact = Contact::new(&mesh, settings).unwrap();
    let mut problem = problem(&mesh, &contact, -200.0);
    let newton = NewtonSettings::default();
    let mut session = PathSolver::new(&problem, newton.solver).unwrap();
    let mut u = vec![0.0; problem.system().n()];
    let level = contact
        .solve_level(
            &mut problem,
            &mut session,
            &mut u,
            (0.0, 1.0),
            &LevelSettings {
                newton: &newton,
                stepping: &Stepping::default(),
                perturbation: &[],
            },
        )
        .unwrap();
    let s = &level.state;
    let refreshes = level.passes.iter().filter(|p| p.refresh).count();
    println!(
        "passes {}, refreshes {refreshes}, penetration {:e} m",
        level.passes.len(),
        s.penetration()
    );
    assert!(refreshes > 0);
    assert!(s.penetration() <= 1e-13, "{:e} m", s.penetration());
    // A refresh keeps the set: no pair closed or opened by it.
    for p in level.passes.iter().filter(|p| p.refresh) {
        assert!(p.closed.is_empty() && p.opened.is_empty());
    }
}

/// The reserve grown from none ([`Reserve::Grow`], one ring, no gap rule): installing a set
/// reserves its
/// pairs and their neighbours (one more pattern build), a set inside that reserve builds
/// nothing, a pair outside grows it again; the pattern stays smaller than the one with every
/// pair reserved, and with the same set installed both give the same residual and reactions
/// bit for bit (the same element sums and folds; only the pattern's unused entries differ).
#[test]
fn the_reserve_grows_around_the_closed_pairs_only_when_a_set_leaves_it() {
    let mesh = mesh_of(4, 4);
    let with = |reserve| {
        let settings = ContactSettings {
            reserve,
            ..ContactSettings::default()
        };
        let contact = Contact::new(&mesh, settings).unwrap();
        let problem = problem(&mesh, &contact, -100.0);
        (contact, problem)
    };
    let (mut all, mut all_problem) = with(Reserve::All);
    let (mut grown, mut problem) = with(Reserve::Grow {
        rings: 1,
        gap_share: 0.0,
    });
    let faces = grown.faces().clone();
    let n = faces.len();
    assert!(grown.reserved().iter().all(|&r| !r));
    assert!(all.reserved().iter().all(|&r| r));
    let by_radius =
        |a: &usize, b: &usize| radius(&mesh, &faces, *a).total_cmp(&radius(&mesh, &faces, *b));
    let (centre, rim) = (
        (0..n).min_by(by_radius).unwrap(),
        (0..n).max_by(by_radius).unwrap(),
    );
    let only = |i: usize| (0..n).map(|j| j == i).collect::<Vec<bool>>();
    let u = vec![0.0; problem.system().n()];
    let builds = |p: &StructuralProblem| p.system().pattern_builds();

    grown.install(&mut problem, &u, &only(centre)).unwrap();
    assert_eq!(builds(&problem), 2);
    assert_eq!(grown.reserved(), faces.within(&only(centre), 1).as_slice());
    assert!(faces.near(centre).len() > 1 && grown.reserved().iter().any(|&r| !r));
    // Inside the reserve: the ring around the centre pair, then nothing.
    let ring: Vec<bool> = grown.reserved().to_vec();
    grown.install(&mut problem, &u, &ring).unwrap();
    grown.install(&mut problem, &u, &vec![false; n]).unwrap();
    assert_eq!(builds(&problem), 2);
    // A pair at the rim is outside: the reserve grows around the set, keeping what it had.
    let mut far = ring.clone();
    far[rim] = true;
    grown.install(&mut problem, &u, &far).unwrap();
    assert_eq!(builds(&problem), 3);
    assert!(grown.reserved()[rim] && ring.iter().zip(grown.reserved()).all(|(&a, &b)| !a || b));
    assert!(grown.reserved().iter().any(|&r| !r));
    let (small, full) = (
        problem.system().pattern().nnz_lower(),
        all_problem.system().pattern().nnz_lower(),
    );
    assert!(small < full, "{small} against {full} entries");

    all.install(&mut all_problem, &u, &far).unwrap();
    let mut w = u.clone();
    w.iter_mut()
        .enumerate()
        .for_each(|(i, x)| *x = 1e-7 * ((i % 5) as f64 - 2.0));
    let (mut r1, mut r2) = (vec![0.0; w.len()], vec![0.0; w.len()]);
    problem.evaluate(&w, 0.5, &mut r1, None).unwrap();
    all_problem.evaluate(&w, 0.5, &mut r2, None).unwrap();
    assert!(r1 == r2);
    assert!(problem.reactions() == all_problem.reactions());
}

/// The gap rule of [`Reserve::Grow`]: with the sublaminate's underside lifted in proportion to
/// the distance from the centre (gaps from 0 at the centre to 2 µm at the rim), installing the
/// centre pair alone reserves, besides its ring, exactly the pairs whose gap is within the
/// share of the largest; with no open gap (u = 0, the faces touching everywhere) every pair.
#[test]
fn the_reserve_takes_the_pairs_whose_faces_are_near() {
    let mesh = mesh_of(4, 4);
    let share = 0.3;
    let settings = ContactSettings {
        reserve: Reserve::Grow {
            rings: 1,
            gap_share: share,
        },
        ..ContactSettings::default()
    };
    let mut contact = Contact::new(&mesh, settings.clone()).unwrap();
    let mut lifted = problem(&mesh, &contact, -100.0);
    let faces = contact.faces().clone();
    let n = faces.len();
    let r = |i: usize| radius(&mesh, &faces, i);
    let centre = (0..n).min_by(|&a, &b| r(a).total_cmp(&r(b))).unwrap();
    let only: Vec<bool> = (0..n).map(|j| j == centre).collect();
    let mut u = vec![0.0; lifted.system().n()];
    for i in 0..n {
        u[3 * faces.pairs()[i].upper + 2] = 2e-6 * r(i) / 15e-3;
    }
    contact.install(&mut lifted, &u, &only).unwrap();
    let gaps = faces.gaps(&u, &faces.normals(&u).unwrap());
    let largest = gaps.iter().fold(0.0f64, |m, &g| m.max(g));
    let rings = faces.within(&only, 1);
    let expected: Vec<bool> = (0..n)
        .map(|i| rings[i] || gaps[i] <= share * largest)
        .collect();
    assert_eq!(contact.reserved(), expected.as_slice());
    let taken = expected.iter().filter(|&&e| e).count();
    assert!(
        taken > rings.iter().filter(|&&e| e).count() && taken < n,
        "{taken} of {n}"
    );

    let mut touching = Contact::new(&mesh, settings).unwrap();
    let mut flat = problem(&mesh, &touching, -100.0);
    let zero = vec![0.0; flat.system().n()];
    touching.install(&mut flat, &zero, &only).unwrap();
    assert!(touching.reserved().iter().all(|&r| r));
}
