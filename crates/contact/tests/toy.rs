//! The acceptance toy of issue 19 (thesis Fig. 2.7.1): a square sublaminate (a quarter, by
//! symmetry) resting on its base with coincident face nodes, pressed onto it by a transverse
//! load. The sublaminate is a free body in z: only contact holds it, so the contact forces
//! carry the whole load.

use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_contact::{
    Contact, ContactError, ContactLevel, ContactSettings, CrackFaces, LevelSettings, Mode, Reserve,
};
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d_laminate::{ShearCoupling, materials};
use nonlin3d_mesh::{BoxParams, Mesh, structured_box};
use nonlin3d_newton::{NewtonSettings, NonlinearProblem, PathSolver, Stepping, StructuralProblem};

/// Base 10 × 10 × 2 mm (4 × 4 × 2 Hex8), plate 5 × 5 × 1 mm (2 × 2 × 1 Hex8) on its corner at
/// the origin (the quarter model's symmetry planes x = 0, y = 0), own nodes on z = 2 mm.
/// Returns the mesh with the paired sets (upper: the plate's bottom; lower: the base's top
/// under it) and the plate's top nodes.
fn toy() -> (Mesh, Vec<usize>, Vec<usize>, Vec<usize>) {
    toy_of(ElementKind::Hex8)
}

/// [`toy`] with cells of `kind`.
fn toy_of(kind: ElementKind) -> (Mesh, Vec<usize>, Vec<usize>, Vec<usize>) {
    let mm = 1e-3;
    let base = structured_box(&BoxParams::new(
        kind,
        [4, 4, 2],
        [10.0 * mm, 10.0 * mm, 2.0 * mm],
    ))
    .unwrap();
    let plate = structured_box(&BoxParams::new(
        kind,
        [2, 2, 1],
        [5.0 * mm, 5.0 * mm, 1.0 * mm],
    ))
    .unwrap();
    let mut mesh = base.clone();
    let shift = mesh.nodes.len();
    mesh.nodes
        .extend(plate.nodes.iter().map(|x| [x[0], x[1], x[2] + 2.0 * mm]));
    for c in &plate.cells {
        let mut c = c.clone();
        c.nodes.iter_mut().for_each(|v| *v += shift);
        mesh.cells.push(c);
    }
    for name in ["x0", "y0"] {
        let mut set = base.node_sets[name].clone();
        set.extend(plate.node_sets[name].iter().map(|v| v + shift));
        mesh.node_sets.insert(name.into(), set);
    }
    mesh.face_sets.clear();
    mesh.cell_sets.clear();
    let upper: Vec<usize> = plate.node_sets["z0"].iter().map(|v| v + shift).collect();
    let lower: Vec<usize> = upper
        .iter()
        .map(|&v| {
            let x = mesh.nodes[v];
            base.node_sets["z1"]
                .iter()
                .copied()
                .find(|&b| (0..3).all(|k| (mesh.nodes[b][k] - x[k]).abs() < 1e-12))
                .unwrap()
        })
        .collect();
    let top: Vec<usize> = plate.node_sets["z1"].iter().map(|v| v + shift).collect();
    (mesh, upper, lower, top)
}

/// Steel, nonlinear kinematics; base on w = 0 at z = 0; symmetry u = 0 on x = 0, v = 0 on
/// y = 0 for both bodies; `load` (N, downward, whole quarter) on the plate's top, spread by
/// `weights`. The candidate pairs reserved.
fn problem(
    mesh: &Mesh,
    contact: &Contact,
    top: &[usize],
    weights: &[f64],
    load: f64,
) -> StructuralProblem {
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
    let bottom: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&v| mesh.nodes[v][2] == 0.0)
        .collect();
    c.fix_nodes(&bottom, 2).unwrap();
    c.fix_nodes(&mesh.node_sets["x0"], 0).unwrap();
    c.fix_nodes(&mesh.node_sets["y0"], 1).unwrap();
    let total: f64 = weights.iter().sum();
    for (&v, w) in top.iter().zip(weights) {
        c.add_load(3 * v + 2, -load * w / total).unwrap();
    }
    StructuralProblem::with_contributions(solid, Vec::new(), c, |b| contact.reserve(b)).unwrap()
}

/// The trapezoidal weights of a uniform pressure on the plate's top (quarter model: a node on
/// a symmetry plane or the free edge carries half, the corners a quarter).
fn pressure_weights(mesh: &Mesh, top: &[usize]) -> Vec<f64> {
    let edge = |x: f64| {
        if x.abs() < 1e-9 || (x - 5e-3).abs() < 1e-9 {
            0.5
        } else {
            1.0
        }
    };
    top.iter()
        .map(|&v| edge(mesh.nodes[v][0]) * edge(mesh.nodes[v][1]))
        .collect()
}

/// Everything one run gives: the level's report, the displacements, the problem.
struct Run {
    level: ContactLevel,
    u: Vec<f64>,
    problem: StructuralProblem,
    session: PathSolver,
    /// Pairs reserved in the pattern at the end.
    reserved: usize,
}

/// One level 0 → 1 starting with every pair closed (the free plate needs contact to be held
/// at all).
fn run(mesh: &Mesh, faces: CrackFaces, top: &[usize], weights: &[f64], mode: Mode) -> Run {
    let all = vec![true; faces.len()];
    run_from(mesh, faces, top, weights, mode, &all)
}

/// [`run`] starting with the pairs of `initial` closed.
fn run_from(
    mesh: &Mesh,
    faces: CrackFaces,
    top: &[usize],
    weights: &[f64],
    mode: Mode,
    initial: &[bool],
) -> Run {
    let settings = ContactSettings {
        mode,
        ..ContactSettings::default()
    };
    run_with(mesh, faces, top, weights, settings, initial).unwrap()
}

/// [`run_from`] with the loop's settings given; the loop's error if it fails.
fn run_with(
    mesh: &Mesh,
    faces: CrackFaces,
    top: &[usize],
    weights: &[f64],
    settings: ContactSettings,
    initial: &[bool],
) -> Result<Run, ContactError> {
    let mut contact = Contact::with_faces(faces, settings).unwrap();
    let mut problem = problem(mesh, &contact, top, weights, LOAD);
    let newton = NewtonSettings::default();
    let mut u = vec![0.0; problem.n()];
    // The initial set grows the reserve (none at build by default): the session is analysed
    // for the pattern it leaves.
    contact.install(&mut problem, &u, initial).unwrap();
    let mut session = PathSolver::new(&problem, newton.solver).unwrap();
    let level = contact.solve_level(
        &mut problem,
        &mut session,
        &mut u,
        (0.0, 1.0),
        &LevelSettings {
            newton: &newton,
            stepping: &Stepping::default(),
            perturbation: &[],
        },
    )?;
    Ok(Run {
        level,
        u,
        problem,
        session,
        reserved: contact.reserved().iter().filter(|&&r| r).count(),
    })
}

/// The applied load, N (a quarter of 4 kN: about 160 MPa over the 5 × 5 mm quarter).
const LOAD: f64 = 1000.0;

/// The residual tolerance of the converged state (ε_r·F, F its force scale).
fn residual_tolerance(run: &mut Run) -> f64 {
    let mut r = vec![0.0; run.problem.n()];
    let scale = run.problem.evaluate(&run.u, 1.0, &mut r, None).unwrap();
    NewtonSettings::default().relative_tolerance * scale
}

/// Checks the acceptance conditions and returns Σ p·n_z. No overlap beyond the gap
/// tolerance, every force compressive within the force tolerance, and Σ p·n_z = F: the plate's
/// element forces sum to zero in z (translation invariance), its supports react in x and y
/// only, so Σ over its nodes of r_z = f_int − f_ext is F exactly; at a tied upper node r_z is
/// p·n_z (the slave's reaction, or the master's unfolded residual (n_z/n_k)·R_s minus its
/// folded remainder ≤ tol), elsewhere the folded residual ≤ tol: |Σ p·n_z − F| ≤ N·tol over the
/// plate's N nodes.
fn check(run: &mut Run, plate_nodes: usize) -> f64 {
    let tol = residual_tolerance(run);
    let s = &run.level.state;
    let gap_tol = ContactSettings::default().gap_tolerance;
    assert!(s.gaps.iter().all(|&g| g >= -gap_tol), "{:?}", s.gaps);
    // The release test's quantity: the recovered forces (the nodal ones on Hex8 faces).
    assert!(
        s.recovered.iter().all(|&p| p >= -s.force_tolerance),
        "{:?}",
        s.recovered
    );
    let total = s.total_force()[2];
    assert!(
        (total - LOAD).abs() <= plate_nodes as f64 * tol,
        "Σ p n_z = {total} N against {LOAD} N (tolerance {} N)",
        plate_nodes as f64 * tol
    );
    total
}

/// A uniform pressure: every pair stays closed with a compressive force, the forces carry the
/// load, and the set is right at the first solve (no pass). The initial install reserved the
/// pairs (the pattern's second build, [`nonlin3d_contact::Reserve::Grow`]); nothing after it
/// made a new pattern or symbolic analysis.
#[test]
fn a_pressed_plate_is_held_by_compressive_contact_forces() {
    let (mesh, up, lo, top) = toy();
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let weights = pressure_weights(&mesh, &top);
    let mut run = run(&mesh, faces, &top, &weights, Mode::TwoBody);
    let total = check(&mut run, 18);
    let s = &run.level.state;
    assert!(s.active.iter().all(|&a| a));
    assert!(s.forces.iter().all(|&p| p > 0.0));
    println!(
        "pressure: Σ p n_z = {total} N, passes {}, Newton iterations {}, forces {:?}",
        run.level.passes.len(),
        run.level.newton_iterations(),
        s.forces
    );
    assert_eq!(run.problem.system().pattern_builds(), 2);
    assert_eq!(run.session.analyses(), 1);
}

/// A point load at the plate's centre (the quarter's corner node): the plate bends and its
/// outer pairs pull on the base when all are tied; those are released pass by pass until every
/// remaining force is compressive, the released faces open, and the forces still carry the
/// load. The passes change the tie group without a new pattern or symbolic analysis (the one
/// rebuild is the initial install's, which reserved every pair). Reversing
/// the order of the pairs gives the same set, the same forces and gaps: both runs are converged
/// to tol = ε_r·F, so their residuals differ by at most 2·tol per DOF and a force by at most
/// what that moves over the plate's 18 nodes, 36·tol; the gaps then differ by that force times
/// the compliance (6e-10 m/N from the pressed test's 6e-7 m under 1 kN): ~1e-13 m, bounded here
/// by the gap tolerance (1e-9 m).
#[test]
fn a_point_load_lifts_the_plate_edges_and_the_order_does_not_matter() {
    let (mesh, up, lo, top) = toy();
    let centre: Vec<f64> = top
        .iter()
        .map(|&v| (mesh.nodes[v][0] == 0.0 && mesh.nodes[v][1] == 0.0) as u8 as f64)
        .collect();
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let mut run1 = run(&mesh, faces, &top, &centre, Mode::TwoBody);
    let total = check(&mut run1, 18);
    let s = &run1.level.state;
    println!(
        "point load: Σ p n_z = {total} N, passes {}, closed {}, opened {}, Newton iterations {}, \
         active {:?}, forces {:?}, gaps {:?}",
        run1.level.passes.len(),
        run1.level.closed(),
        run1.level.opened(),
        run1.level.newton_iterations(),
        s.active,
        s.forces,
        s.gaps
    );
    assert!(run1.level.opened() > 0, "no pair opened");
    assert!(s.active.iter().any(|&a| a) && s.active.iter().any(|&a| !a));
    for (g, a) in s.gaps.iter().zip(&s.active) {
        if !a {
            assert!(*g > 0.0);
        }
    }
    assert_eq!(run1.problem.system().pattern_builds(), 2);
    assert_eq!(run1.session.analyses(), 1);

    let (rup, rlo): (Vec<usize>, Vec<usize>) = (up.iter().rev().copied().collect(), {
        lo.iter().rev().copied().collect()
    });
    let faces = CrackFaces::from_sets(&mesh, &rup, &rlo).unwrap();
    let run2 = run(&mesh, faces, &top, &centre, Mode::TwoBody);
    let tol = residual_tolerance(&mut run1);
    let gap_tol = ContactSettings::default().gap_tolerance;
    let (s1, s2) = (&run1.level.state, &run2.level.state);
    let n = s1.forces.len();
    for i in 0..n {
        let j = n - 1 - i;
        assert_eq!(s1.active[i], s2.active[j]);
        assert!((s1.forces[i] - s2.forces[j]).abs() <= 36.0 * tol);
        assert!((s1.gaps[i] - s2.gaps[j]).abs() <= gap_tol);
    }
    assert_eq!(run1.level.passes.len(), run2.level.passes.len());
}

/// The thesis's approximation (Fig. 2.7.1c) on the pressed plate: the same set, the external
/// forces carry the load, and the base is not loaded (its top stays where it was: w = 0 to the
/// round-off of an unloaded solve); the error it makes against two-body contact is the base's
/// deflection under the plate, printed.
#[test]
fn the_external_force_approximation_leaves_the_base_unloaded() {
    let (mesh, up, lo, top) = toy();
    let weights = pressure_weights(&mesh, &top);
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let mut two = run(&mesh, faces.clone(), &top, &weights, Mode::TwoBody);
    let mut ext = run(&mesh, faces, &top, &weights, Mode::External);
    check(&mut two, 18);
    check(&mut ext, 18);
    let w = |r: &Run, v: usize| r.u[3 * v + 2];
    let base_two = lo.iter().map(|&v| w(&two, v)).fold(0.0f64, f64::min);
    let base_ext = lo.iter().map(|&v| w(&ext, v).abs()).fold(0.0f64, f64::max);
    let top_two = top.iter().map(|&v| w(&two, v)).fold(0.0f64, f64::min);
    let top_ext = top.iter().map(|&v| w(&ext, v)).fold(0.0f64, f64::min);
    println!(
        "two-body: base top w_min {base_two:e} m, plate top w_min {top_two:e} m; external: base \
         |w|max {base_ext:e} m, plate top w_min {top_ext:e} m; error of the approximation \
         {:.1} % of the plate's deflection",
        100.0 * (top_ext - top_two).abs() / top_two.abs()
    );
    assert!(base_two < 0.0);
    assert!(base_ext <= 1e-12 * base_two.abs(), "{base_ext:e}");
}

/// The consistent nodal loads of a uniform pressure on the Hex20 plate's top (2 × 2 facets of
/// 2.5 mm, quarter model): per facet ∫N = −A/12 at a corner and A/3 at a mid-edge node; a node
/// inside the top along an axis has 2 facets there, on the rim 1.
fn serendipity_weights(mesh: &Mesh, top: &[usize]) -> Vec<f64> {
    let step = 2.5e-3;
    let count = |c: f64| {
        if c.abs() < 1e-9 || (c - 5e-3).abs() < 1e-9 {
            1.0
        } else {
            2.0
        }
    };
    let on_grid = |c: f64| ((c / step).round() * step - c).abs() < 1e-9;
    top.iter()
        .map(|&v| {
            let [x, y, _] = mesh.nodes[v];
            match (on_grid(x), on_grid(y)) {
                (true, true) => -count(x) * count(y) / 12.0,
                (false, true) => count(y) / 3.0,
                (true, false) => count(x) / 3.0,
                (false, false) => unreachable!("a serendipity face has no centre node"),
            }
        })
        .collect()
}

/// Hex20 (issue 19, defect 1): a uniform pressure on quadratic faces gives tensile nodal
/// contact forces at the corner pairs (∫N_corner = −A/12 per facet). The release test on the
/// recovered forces f̂ keeps every pair closed; the corner forces are indeed tensile (so a test
/// on them would open those pairs), the load is carried (Σ p n_z = F, as in [`check`], over
/// the plate's 2 × 2 × 1 Hex20 = 45 nodes), and the recovered pressure is within 15 % of the
/// mean F / A = 40 MPa at every pair (the base under the plate is not rigid and wider than the
/// plate, so the pressure is not uniform; measured 38.5–44.7 MPa, at most 12 % off).
#[test]
fn a_pressed_hex20_plate_keeps_its_corner_pairs_closed() {
    let (mesh, up, lo, top) = toy_of(ElementKind::Hex20);
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let weights = serendipity_weights(&mesh, &top);
    let mut run = run(&mesh, faces, &top, &weights, Mode::TwoBody);
    check(&mut run, 45);
    let s = &run.level.state;
    println!(
        "Hex20 pressure: passes {}, forces {:?}, pressures (MPa) {:?}",
        run.level.passes.len(),
        s.forces,
        s.pressures.iter().map(|p| p * 1e-6).collect::<Vec<_>>()
    );
    assert!(s.active.iter().all(|&a| a), "{:?}", s.active);
    assert!(s.forces.iter().any(|&p| p < -s.force_tolerance));
    assert!(s.recovered.iter().all(|&p| p > 0.0));
    let mean = LOAD / 25e-6;
    for &p in &s.pressures {
        assert!((p - mean).abs() < 0.15 * mean, "{} MPa", p * 1e-6);
    }
}

/// Hex20 under a point load at the plate's centre (issue 19, defect 1: closing and release in
/// one basis). The plate's rim lifts; the stable set is the one complementarity of
/// docs/THEORY.md ("One basis for closing and release"): every closed pair has weighted gap
/// g̃ = 0 (its tie, to the gap tolerance 1e-9 m), every open pair carries no recovered force
/// (f̂ = 0 to the force tolerance ε_r·F: an open corner at the end of a closed mid-edge pair
/// carries the nodal force −α p, which T cancels), f̂ ≥ 0 and g̃ ≥ 0 within the tolerances.
/// Started from every pair closed and from only the pairs within 2.5 mm of the centre closed
/// (the plate must be held from the start), the loop ends on the same set: the set does not
/// depend on where the loop starts. (Releasing on f̂ and closing on nodal gaps, an open corner
/// next to a closed mid-edge pair has f̂_c = α f_m > 0 and fails the first check.)
#[test]
fn a_point_loaded_hex20_plate_ends_on_one_complementary_set_from_any_start() {
    let (mesh, up, lo, top) = toy_of(ElementKind::Hex20);
    let centre: Vec<f64> = top
        .iter()
        .map(|&v| (mesh.nodes[v][0] == 0.0 && mesh.nodes[v][1] == 0.0) as u8 as f64)
        .collect();
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let near: Vec<bool> = up
        .iter()
        .map(|&v| mesh.nodes[v][0].hypot(mesh.nodes[v][1]) <= 2.5e-3 + 1e-12)
        .collect();
    let all = vec![true; faces.len()];
    let mut sets = Vec::new();
    for initial in [&all, &near] {
        let mut r = run_from(&mesh, faces.clone(), &top, &centre, Mode::TwoBody, initial);
        check(&mut r, 45);
        let s = &r.level.state;
        let gap_tol = ContactSettings::default().gap_tolerance;
        println!(
            "Hex20 point load from {} closed: passes {}, closed {}, opened {}, active {:?}",
            initial.iter().filter(|&&a| a).count(),
            r.level.passes.len(),
            r.level.closed(),
            r.level.opened(),
            s.active
        );
        for i in 0..s.active.len() {
            let (f, g) = (s.recovered[i], s.weighted_gaps[i]);
            assert!(
                f >= -s.force_tolerance && g >= -gap_tol,
                "pair {i}: f̂ {f}, g̃ {g}"
            );
            if s.active[i] {
                assert!(g.abs() <= gap_tol, "closed pair {i}: g̃ {g:e}");
            } else {
                assert!(f.abs() <= s.force_tolerance, "open pair {i}: f̂ {f:e}");
            }
        }
        assert!(s.active.iter().any(|&a| !a) && s.active.iter().any(|&a| a));
        sets.push(s.active.clone());
    }
    assert_eq!(sets[0], sets[1]);
}

/// The point-loaded Hex20 plate of the test above, started from the pairs within 2.5 mm of the
/// centre closed: its loop closes and releases pairs over several passes.
fn point_loaded_hex20(settings: ContactSettings) -> Result<Run, ContactError> {
    let (mesh, up, lo, top) = toy_of(ElementKind::Hex20);
    let centre: Vec<f64> = top
        .iter()
        .map(|&v| (mesh.nodes[v][0] == 0.0 && mesh.nodes[v][1] == 0.0) as u8 as f64)
        .collect();
    let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
    let near: Vec<bool> = up
        .iter()
        .map(|&v| mesh.nodes[v][0].hypot(mesh.nodes[v][1]) <= 2.5e-3 + 1e-12)
        .collect();
    run_with(&mesh, faces, &top, &centre, settings, &near)
}

/// Inexact updates (issues 20 and 25): the re-solves go one Newton iteration at a time and
/// the set is read at each iterate, so the passes cost fewer Newton iterations than the exact
/// loop's (`inexact_passes = 0`: every re-solve converged), and the loop ends on the same set
/// and the same state: both are converged states (‖r‖∞ ≤ ε_r·F, ε_r = 1e-8) of the same set,
/// so their displacements differ by about ε_r times the displacement (1e-6 of the largest
/// allows a hundredfold amplification by the conditioning of the plate on its ties).
#[test]
fn inexact_updates_reach_the_same_set_in_fewer_iterations() {
    let exact = point_loaded_hex20(ContactSettings {
        inexact_passes: 0,
        ..ContactSettings::default()
    })
    .unwrap();
    let inexact = point_loaded_hex20(ContactSettings::default()).unwrap();
    let log = |r: &Run| {
        r.level
            .passes
            .iter()
            .map(|p| format!("{}/{}:{}", p.closed.len(), p.opened.len(), p.iterations))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!(
        "exact: {} iterations, passes {}; inexact: {} iterations, passes {}",
        exact.level.newton_iterations(),
        log(&exact),
        inexact.level.newton_iterations(),
        log(&inexact)
    );
    assert!(exact.level.passes.iter().all(|p| !p.inexact));
    assert!(inexact.level.passes.iter().any(|p| p.inexact));
    assert!(inexact.level.newton_iterations() < exact.level.newton_iterations());
    assert_eq!(inexact.level.state.active, exact.level.state.active);
    let scale = exact.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = exact
        .u
        .iter()
        .zip(&inexact.u)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff <= 1e-6 * scale, "|Δu| {diff:e} m of {scale:e} m");
}

/// A reserve that grows (issue 20: the crack faces coupled only where pairs close) against
/// every pair reserved, on the point-loaded Hex20 plate started from the pairs near the centre
/// and with no ring of neighbours and no gap rule, so that passes closing pairs outside the
/// reserve grow it while the loop runs: the same passes and set, and the same state to the
/// tolerance of the inexact test above (1e-6 of the largest displacement: two converged states
/// of one set, solved on different patterns whose extra entries are zeros), each pattern
/// analysed once.
/// (The passes here close every pair at some point, so the pattern ends as the full one:
/// `tests/delamination.rs` shows a smaller one.)
#[test]
fn a_reserve_grown_while_the_loop_runs_gives_the_full_reserves_state() {
    let with = |reserve| {
        point_loaded_hex20(ContactSettings {
            reserve,
            ..ContactSettings::default()
        })
        .unwrap()
    };
    let (all, grown) = (
        with(Reserve::All),
        with(Reserve::Grow {
            rings: 0,
            gap_share: 0.0,
        }),
    );
    let builds = grown.problem.system().pattern_builds();
    println!(
        "grown: {builds} builds, {} analyses, {} reserved of {} pairs, {} against {} entries",
        grown.session.analyses(),
        grown.reserved,
        grown.level.state.active.len(),
        grown.problem.system().pattern().nnz_lower(),
        all.problem.system().pattern().nnz_lower()
    );
    assert_eq!(all.level.state.active, grown.level.state.active);
    let log = |r: &Run| {
        let p = &r.level.passes;
        p.iter()
            .map(|p| (p.closed.clone(), p.opened.clone(), p.iterations))
            .collect::<Vec<_>>()
    };
    assert_eq!(log(&all), log(&grown));
    let scale = all.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = all
        .u
        .iter()
        .zip(&grown.u)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff <= 1e-6 * scale, "|Δu| {diff:e} m of {scale:e} m");
    assert_eq!(all.problem.system().pattern_builds(), 1);
    assert!(builds >= 3, "the passes never grew the reserve");
    assert_eq!(grown.session.analyses(), builds - 1);
}

/// The pass limit counts the inexact updates too: a level (one step: `max_step` 1, the limit
/// applies per sub-level) that needs more passes than allowed fails with
/// [`ContactError::Passes`] naming the level and the passes made, also when the passes are
/// inexact updates.
#[test]
fn the_pass_limit_counts_inexact_updates() {
    let whole = ContactSettings {
        max_step: 1.0,
        ..ContactSettings::default()
    };
    let level = point_loaded_hex20(whole.clone()).unwrap().level;
    let needed = level.passes.len();
    println!(
        "one step: passes {:?}",
        level
            .passes
            .iter()
            .map(|p| (p.closed.len(), p.opened.len(), p.iterations, p.inexact))
            .collect::<Vec<_>>()
    );
    assert!(needed >= 3, "{needed} passes");
    assert!(level.passes[1..needed - 1].iter().all(|p| p.inexact));
    let limited = point_loaded_hex20(ContactSettings {
        max_passes: needed - 1,
        ..whole
    });
    match limited {
        Err(ContactError::Passes { lambda, passes, .. }) => {
            assert_eq!((lambda, passes), (1.0, needed - 1));
        }
        Err(e) => panic!("{e}"),
        Ok(r) => panic!(
            "{} passes within a limit of {}",
            r.level.passes.len(),
            needed - 1
        ),
    }
}
