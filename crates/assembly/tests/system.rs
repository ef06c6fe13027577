//! The constrained system (issue 17): contributions summed on one pattern, constraints applied
//! once, tie groups replaced and prescribed DOFs released without a new pattern or a new
//! symbolic analysis.

use nonlin3d_assembly::{
    Assembler, AssemblyError, Constraints, Contribution, System, Tie, TieGroup,
};
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d_laminate::{ShearCoupling, Stiffness};
use nonlin3d_mesh::{BoxParams, Mesh, structured_box};
use nonlin3d_solver::{
    Analysis, Factorization, FaerMode, FaerSolver, LinearSolver, SolverError, SymmetricMatrix,
    SymmetricPattern,
};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A linear spring of stiffness `k` between DOFs `a` and `b`: E = k (u_a − u_b)² / 2.
struct Spring {
    a: usize,
    b: usize,
    k: f64,
}

impl Contribution for Spring {
    fn couplings(&self) -> Vec<Vec<usize>> {
        vec![vec![self.a, self.b]]
    }

    fn add(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError> {
        let s = u[self.a] - u[self.b];
        internal[self.a] += self.k * s;
        internal[self.b] -= self.k * s;
        if let Some(t) = tangent {
            t.add(self.a, self.a, self.k)?;
            t.add(self.b, self.b, self.k)?;
            t.add(self.a, self.b, -self.k)?;
        }
        Ok(0.5 * self.k * s * s)
    }

    fn add_product(&self, _u: &[f64], v: &[f64], y: &mut [f64]) -> Result<(), AssemblyError> {
        let s = v[self.a] - v[self.b];
        y[self.a] += self.k * s;
        y[self.b] -= self.k * s;
        Ok(())
    }
}

/// A constant dense stiffness over `dofs` (row-major `k`, symmetric) with a load `load` on
/// them scaled by λ: a superelement's condensed stiffness and load.
struct Block {
    dofs: Vec<usize>,
    k: Vec<f64>,
    load: Vec<f64>,
}

impl Block {
    /// K_b·u restricted to the block.
    fn product(&self, u: &[f64]) -> Vec<f64> {
        let nd = self.dofs.len();
        (0..nd)
            .map(|a| (0..nd).map(|b| self.k[a * nd + b] * u[self.dofs[b]]).sum())
            .collect()
    }
}

impl Contribution for Block {
    fn couplings(&self) -> Vec<Vec<usize>> {
        vec![self.dofs.clone()]
    }

    fn add(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError> {
        let f = self.product(u);
        let mut energy = 0.0;
        for (&d, fd) in self.dofs.iter().zip(&f) {
            internal[d] += fd;
            energy += 0.5 * fd * u[d];
        }
        if let Some(t) = tangent {
            t.scatter_add(&self.dofs, &self.k)?;
        }
        Ok(energy)
    }

    fn add_product(&self, _u: &[f64], v: &[f64], y: &mut [f64]) -> Result<(), AssemblyError> {
        for (&d, x) in self.dofs.iter().zip(self.product(v)) {
            y[d] += x;
        }
        Ok(())
    }

    fn add_external(&self, lambda: f64, f_ext: &mut [f64]) {
        for (&d, l) in self.dofs.iter().zip(&self.load) {
            f_ext[d] += lambda * l;
        }
    }
}

/// A solver that counts its symbolic analyses and numeric factorisations.
struct Counting {
    inner: FaerSolver,
    analyses: Arc<AtomicUsize>,
    factorisations: Arc<AtomicUsize>,
}

impl LinearSolver for Counting {
    fn name(&self) -> &'static str {
        "counting"
    }
    fn analyze(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<Analysis, SolverError> {
        self.analyses.fetch_add(1, Ordering::Relaxed);
        self.inner.analyze(pattern)
    }
    fn factorize(&mut self, a: &SymmetricMatrix) -> Result<Factorization, SolverError> {
        self.factorisations.fetch_add(1, Ordering::Relaxed);
        self.inner.factorize(a)
    }
    fn solve_in_place(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        self.inner.solve_in_place(b, nrhs)
    }
}

fn steel() -> Stiffness {
    nonlin3d_laminate::materials::steel().stiffness().unwrap()
}

/// A Hex20 box of `cells` cells over 4 × 1 × 1 (m).
fn hex20_box(cells: [usize; 3]) -> Mesh {
    structured_box(&BoxParams::new(ElementKind::Hex20, cells, [4.0, 1.0, 1.0])).unwrap()
}

/// The mesh's nodes with only the listed cells (the others' nodes stay, in no cell).
fn only_cells(mesh: &Mesh, cells: &[usize]) -> Mesh {
    let mut m = mesh.clone();
    m.cells = cells.iter().map(|&c| mesh.cells[c].clone()).collect();
    m.cell_sets.clear();
    m.face_sets.clear();
    m
}

/// The solid of `mesh`, steel, Hex20 with full 3×3×3 integration (2×2×2 leaves a box one cell
/// thick with a zero-energy mode, and the solves of the tests need a regular tangent).
fn solid(mesh: &Mesh, kinematics: Kinematics) -> Assembler {
    Assembler::new(
        mesh,
        &[steel()],
        ShearCoupling::Exact,
        IntegrationRule::Gauss3,
        IntegrationRule::Gauss2,
        kinematics,
    )
    .unwrap()
}

/// A displacement field of size `scale` (m), deterministic.
fn field(n: usize, scale: f64) -> Vec<f64> {
    (0..n)
        .map(|d| scale * (((d * 7919) % 23) as f64 / 23.0 - 0.4))
        .collect()
}

/// The nodes of `mesh` on the plane x = `x`.
fn nodes_at_x(mesh: &Mesh, x: f64) -> Vec<usize> {
    (0..mesh.nodes.len())
        .filter(|&v| (mesh.nodes[v][0] - x).abs() < 1e-9)
        .collect()
}

/// Clamped at x = 0, a load at one corner of x = 4: the constraints of the tests.
fn supports(mesh: &Mesh) -> Constraints {
    let mut c = Constraints::new(3 * mesh.nodes.len());
    for r in 0..3 {
        c.fix_nodes(&nodes_at_x(mesh, 0.0), r).unwrap();
    }
    let tip = nodes_at_x(mesh, 4.0)[0];
    c.add_load(3 * tip + 2, -1e6).unwrap();
    c
}

fn largest(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// The System holding only the solid gives bitwise what `Assembler::residual` gives (the
/// engine and the constraint application are the same code), with ties and prescribed DOFs,
/// on 1 and 2 threads; `System::fold` of the unconstrained residual is its residual.
#[test]
fn a_system_of_the_solid_alone_is_the_assembler_bitwise() {
    let mesh = hex20_box([3, 1, 1]);
    let mut c = supports(&mesh);
    let tip = nodes_at_x(&mesh, 4.0);
    c.tie(
        3 * tip[1] + 2,
        &[(3 * tip[0] + 2, 0.5), (3 * tip[2] + 1, 0.25)],
        1e-5,
    )
    .unwrap();
    let mut asm = solid(&mesh, Kinematics::Nonlinear);
    asm.tie(&c).unwrap();
    let system = System::builder(c.clone())
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .build()
        .unwrap();
    assert!(**system.pattern() == **asm.pattern());
    let u = field(asm.n(), 1e-3);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (mut k1, mut k2) = (asm.new_tangent(), system.new_tangent());
        let (r, reactions, energy) = pool
            .install(|| asm.residual(&u, 0.7, &c, Some(&mut k1)))
            .unwrap();
        let e = pool
            .install(|| system.evaluate(&u, 0.7, Some(&mut k2)))
            .unwrap();
        assert!(r == e.residual && reactions == e.reactions && energy == e.energy);
        assert!(
            k1.values() == k2.values(),
            "{threads} threads: tangents differ"
        );
        // The unconstrained sum minus the loads, folded, is the residual (the same operations).
        let mut r = vec![0.0; system.n()];
        system.assemble(&u, &mut r, None).unwrap();
        for (r, f) in r.iter_mut().zip(system.external(0.7)) {
            *r -= f;
        }
        system.fold(&mut r).unwrap();
        assert!(r == e.residual);
    }
}

/// A spring between two DOFs that no cell couples (nodes at both ends of the box) adds its
/// stiffness k to K and k (u_a − u_b) to r: the system with the spring minus the system
/// without equals them, to the round-off of the entries they are added to (1e-15 of the
/// largest entry: one addition each).
#[test]
fn a_spring_contribution_adds_its_stiffness() {
    let mesh = hex20_box([3, 1, 1]);
    let (a, b) = (
        3 * nodes_at_x(&mesh, 4.0)[0],
        3 * nodes_at_x(&mesh, 0.0)[0] + 1,
    );
    let mut c = Constraints::new(3 * mesh.nodes.len());
    c.prescribe(3 * nodes_at_x(&mesh, 0.0)[1], 1e-4).unwrap();
    let k_spring = 3e9;
    let plain = System::builder(c.clone())
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .build()
        .unwrap();
    let sprung = System::builder(c)
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .contribution(Spring { a, b, k: k_spring })
        .build()
        .unwrap();
    assert!(plain.pattern().position(a, b).is_none());
    let u = field(plain.n(), 1e-3);
    let (mut kp, mut ks) = (plain.new_tangent(), sprung.new_tangent());
    let ep = plain.evaluate(&u, 1.0, Some(&mut kp)).unwrap();
    let es = sprung.evaluate(&u, 1.0, Some(&mut ks)).unwrap();
    let tol = 1e-15 * largest(kp.values()).max(k_spring);
    for j in 0..plain.n() {
        for &i in sprung.pattern().column(j) {
            let want = match (i, j) {
                _ if i == j && (i == a || i == b) => k_spring,
                _ if (i, j) == (a.max(b), a.min(b)) => -k_spring,
                _ => 0.0,
            };
            let got = ks.get(i, j) - kp.get(i, j);
            assert!((got - want).abs() <= tol, "({i}, {j}): {got} vs {want}");
        }
    }
    let s = k_spring * (u[a] - u[b]);
    let tol = 1e-15 * largest(&ep.residual).max(s.abs()) * 4.0;
    for d in 0..plain.n() {
        let want = if d == a {
            s
        } else if d == b {
            -s
        } else {
            0.0
        };
        let got = es.residual[d] - ep.residual[d];
        assert!((got - want).abs() <= tol, "DOF {d}: {got} vs {want}");
    }
    // K·v through the contributions: the product has the spring's share too.
    let mut v = vec![0.0; plain.n()];
    v[a] = 1.0;
    let (yp, ys) = (
        plain.tangent_product(&u, &v).unwrap(),
        sprung.tangent_product(&u, &v).unwrap(),
    );
    assert!((ys[b] - yp[b] + k_spring).abs() <= 1e-6 * k_spring);
}

/// A dense block over 276 DOFs (seven Hex20 cells' linear stiffness condensed to one matrix
/// over their 92 nodes, more than the solid's scatter takes in one cell, with a load on its
/// DOFs) added to a System gives the residual and tangent of the same cells added as
/// elements, with clamps, a load and a tie. Linear kinematics, so f_int = K u of each cell
/// exactly in arithmetic; the two paths differ by the order of the sums: a force is a sum of
/// ≲ 300 products (the block's row), each rounded to 1.1e-16 of its size, so ≲ 3.3e-14 of
/// the largest term; 1e-12 of the largest entry or force leaves a margin of 30.
#[test]
fn a_dense_block_equals_the_same_stiffness_as_elements() {
    let mesh = hex20_box([8, 1, 1]);
    let n = 3 * mesh.nodes.len();
    let back_cells: Vec<usize> = (1..8).collect();
    let (front, back) = (only_cells(&mesh, &[0]), only_cells(&mesh, &back_cells));
    // The block: the back cells' tangent at u = 0, over their DOFs.
    let back_solid = solid(&back, Kinematics::Linear);
    let mut kb = back_solid.new_tangent();
    back_solid.assemble(&vec![0.0; n], Some(&mut kb)).unwrap();
    let mut dofs: Vec<usize> = back_solid.cell_dofs().iter().flatten().copied().collect();
    dofs.sort_unstable();
    dofs.dedup();
    assert!(dofs.len() > 91 * 3, "{} DOFs", dofs.len());
    let nd = dofs.len();
    let k: Vec<f64> = (0..nd * nd)
        .map(|p| kb.get(dofs[p / nd], dofs[p % nd]))
        .collect();
    let load: Vec<f64> = (0..nd)
        .map(|a| if a % 7 == 0 { 2e5 } else { 0.0 })
        .collect();
    let mut c = supports(&mesh);
    let tip = nodes_at_x(&mesh, 4.0);
    c.tie(
        3 * tip[1] + 2,
        &[(3 * tip[0] + 2, 0.5), (3 * tip[2] + 1, 0.25)],
        1e-5,
    )
    .unwrap();
    let mut as_elements = c.clone();
    for (&d, l) in dofs.iter().zip(&load) {
        as_elements.add_load(d, *l).unwrap();
    }
    let whole = System::builder(as_elements)
        .contribution(solid(&mesh, Kinematics::Linear))
        .build()
        .unwrap();
    let split = System::builder(c)
        .contribution(solid(&front, Kinematics::Linear))
        .contribution(Block { dofs, k, load })
        .build()
        .unwrap();
    assert_eq!(split.pattern_builds(), 1);
    let u = field(n, 1e-4);
    let (mut kw, mut ks) = (whole.new_tangent(), split.new_tangent());
    let ew = whole.evaluate(&u, 0.8, Some(&mut kw)).unwrap();
    let es = split.evaluate(&u, 0.8, Some(&mut ks)).unwrap();
    let kmax = largest(kw.values());
    for j in 0..n {
        for &i in whole.pattern().column(j) {
            let (x, y) = (kw.get(i, j), ks.get(i, j));
            assert!((x - y).abs() <= 1e-12 * kmax, "K({i}, {j}): {x} vs {y}");
        }
    }
    let fmax = largest(&ew.residual).max(largest(&ew.reactions));
    for d in 0..n {
        let (x, y) = (ew.residual[d], es.residual[d]);
        assert!((x - y).abs() <= 1e-12 * fmax, "r at DOF {d}: {x} vs {y}");
        let (x, y) = (ew.reactions[d], es.reactions[d]);
        assert!(
            (x - y).abs() <= 1e-12 * fmax,
            "reaction at DOF {d}: {x} vs {y}"
        );
    }
    assert!((ew.energy - es.energy).abs() <= 1e-12 * ew.energy.abs());
}

/// Candidate ties reserved up front: replacing the tie group between two evaluations keeps the
/// pattern (one build) and the solver's symbolic analysis (one analysis, two factorisations),
/// and gives what a System built with the new ties from the start gives (its pattern has less
/// fill; the extra entries of the reserved one are zero: the same sums, 1e-14 relative).
#[test]
fn a_replaced_tie_group_reuses_the_pattern_and_the_analysis() {
    let mesh = hex20_box([3, 1, 1]);
    let c = supports(&mesh);
    let tip = nodes_at_x(&mesh, 4.0);
    let mid = nodes_at_x(&mesh, 2.0);
    let tie = |s: usize, m: usize, r: usize| Tie {
        slave: 3 * s + r,
        masters: vec![(3 * m + r, 1.0)],
        offset: 0.0,
    };
    let candidates = [
        tie(tip[1], mid[0], 2),
        tie(tip[3], mid[2], 0),
        tie(tip[4], mid[3], 1),
    ];
    let group = TieGroup(7);
    let mut system = System::builder(c.clone())
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .reserve_ties(&candidates)
        .build()
        .unwrap();
    let (analyses, factorisations) = (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
    let mut solver = Counting {
        inner: FaerSolver::new(FaerMode::Ldlt),
        analyses: analyses.clone(),
        factorisations: factorisations.clone(),
    };
    solver.analyze(system.pattern()).unwrap();
    let pattern = system.pattern().clone();
    let mut k = system.new_tangent();
    let mut u = vec![0.0; system.n()];
    let mut solutions = Vec::new();
    for active in [&candidates[..1], &candidates[1..]] {
        system.replace_tie_group(group, active).unwrap();
        system.prescribe(&mut u, 1.0);
        let e = system.evaluate(&u, 1.0, Some(&mut k)).unwrap();
        solver.factorize(&k).unwrap();
        let mut du: Vec<f64> = e.residual.iter().map(|r| -r).collect();
        solver.solve_in_place(&mut du, 1).unwrap();
        system.expand_increment(&mut du);
        solutions.push(du);
        // The same ties from the start, on a pattern of their own.
        let mut fresh_c = c.clone();
        fresh_c.replace_tie_group(group, active).unwrap();
        let fresh = System::builder(fresh_c)
            .contribution(solid(&mesh, Kinematics::Nonlinear))
            .build()
            .unwrap();
        let mut kf = fresh.new_tangent();
        let ef = fresh.evaluate(&u, 1.0, Some(&mut kf)).unwrap();
        assert!(ef.residual == e.residual && ef.reactions == e.reactions);
        let kmax = largest(kf.values());
        for j in 0..system.n() {
            for &i in system.pattern().column(j) {
                let (x, y) = (k.get(i, j), kf.get(i, j));
                assert!((x - y).abs() <= 1e-14 * kmax, "K({i}, {j}): {x} vs {y}");
            }
        }
    }
    assert!(Arc::ptr_eq(system.pattern(), &pattern));
    assert_eq!(system.pattern_builds(), 1);
    assert_eq!(analyses.load(Ordering::Relaxed), 1);
    assert_eq!(factorisations.load(Ordering::Relaxed), 2);
    // The tie moved the tip: the two solutions differ where the ties differ.
    let s = candidates[0].slave;
    assert!((solutions[0][s] - solutions[0][candidates[0].masters[0].0]).abs() < 1e-12);
    assert!((solutions[1][s] - solutions[1][candidates[0].masters[0].0]).abs() > 1e-9);
    system.replace_tie_group(group, &[]).unwrap();
    assert_eq!(system.constraints().tie_group(group).count(), 0);
}

/// A tie whose fold needs a coupling the pattern does not hold is refused with the DOFs named,
/// and the constraints are left as they were.
#[test]
fn a_tie_outside_the_reserved_couplings_is_refused() {
    let mesh = hex20_box([3, 1, 1]);
    let (far, near) = (nodes_at_x(&mesh, 4.0)[0], nodes_at_x(&mesh, 0.0)[0]);
    let mut system = System::builder(Constraints::new(3 * mesh.nodes.len()))
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .build()
        .unwrap();
    let tie = Tie {
        slave: 3 * far,
        masters: vec![(3 * near, 1.0)],
        offset: 0.0,
    };
    let before = system.constraints().clone();
    match system.replace_tie_group(TieGroup(1), std::slice::from_ref(&tie)) {
        Err(AssemblyError::Unreserved {
            group,
            slave,
            master,
            ..
        }) => {
            assert_eq!((group, slave, master), (TieGroup(1), 3 * far, 3 * near));
        }
        other => panic!("expected Unreserved, got {other:?}"),
    }
    assert!(*system.constraints() == before);
    let message = system
        .replace_tie_group(TieGroup(1), &[tie])
        .unwrap_err()
        .to_string();
    assert!(message.contains(&format!("node {far}")), "{message}");
}

/// Ties reserved after the build: the pattern is built again (a second build) and is the one a
/// system built with them reserved up front has, so the tie group then installed gives the
/// same residual, reactions and tangent bit for bit; ties it holds already change nothing.
#[test]
fn ties_reserved_later_widen_the_pattern_to_the_one_reserved_up_front() {
    let mesh = hex20_box([3, 1, 1]);
    let c = supports(&mesh);
    let (far, near) = (nodes_at_x(&mesh, 4.0)[0], nodes_at_x(&mesh, 0.0)[0]);
    let tie = Tie {
        slave: 3 * far + 2,
        masters: vec![(3 * near + 2, 1.0)],
        offset: 0.0,
    };
    let ties = std::slice::from_ref(&tie);
    let mut later = System::builder(c.clone())
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .build()
        .unwrap();
    let old = later.pattern().clone();
    let mut k_old = later.new_tangent();
    assert!(later.reserve_ties(ties).unwrap());
    assert_eq!(later.pattern_builds(), 2);
    assert!(later.pattern().nnz_lower() > old.nnz_lower());
    let mut early = System::builder(c)
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .reserve_ties(ties)
        .build()
        .unwrap();
    assert!(**later.pattern() == **early.pattern());
    assert!(!later.reserve_ties(ties).unwrap());
    assert!(!early.reserve_ties(ties).unwrap());
    assert_eq!((later.pattern_builds(), early.pattern_builds()), (2, 1));
    let mut u = vec![0.0; later.n()];
    u.iter_mut()
        .enumerate()
        .for_each(|(i, x)| *x = 1e-4 * ((i % 7) as f64 - 3.0));
    for system in [&mut later, &mut early] {
        system.replace_tie_group(TieGroup(3), ties).unwrap();
        system.prescribe(&mut u, 0.5);
    }
    let (mut kl, mut ke) = (later.new_tangent(), early.new_tangent());
    let el = later.evaluate(&u, 0.5, Some(&mut kl)).unwrap();
    let ee = early.evaluate(&u, 0.5, Some(&mut ke)).unwrap();
    assert!(el == ee);
    assert!(kl.values() == ke.values());
    // A tangent made on the old pattern no longer fits.
    assert!(later.evaluate(&u, 0.5, Some(&mut k_old)).is_err());
    // A DOF out of range is refused, and the pattern stays.
    let bad = Tie {
        slave: 3 * mesh.nodes.len(),
        masters: vec![(0, 1.0)],
        offset: 0.0,
    };
    assert!(later.reserve_ties(&[bad]).is_err());
    assert_eq!(later.pattern_builds(), 2);
}

/// A released DOF is free at the next evaluation: the system gives bitwise what a system built
/// without that prescription gives (same pattern, masks found again), and differs from before.
#[test]
fn a_released_dof_is_free() {
    let mesh = hex20_box([2, 1, 1]);
    let c = supports(&mesh);
    let d = 3 * nodes_at_x(&mesh, 0.0)[2] + 1;
    assert!(c.is_constrained(d));
    let mut system = System::builder(c.clone())
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .build()
        .unwrap();
    let u = field(system.n(), 1e-3);
    let mut k = system.new_tangent();
    let held = system.evaluate(&u, 1.0, Some(&mut k)).unwrap();
    assert_eq!(held.residual[d], 0.0);
    assert!(system.release(d));
    assert!(!system.release(d));
    let freed = system.evaluate(&u, 1.0, Some(&mut k)).unwrap();
    let mut without = c;
    without.release(d);
    let fresh = System::builder(without)
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .build()
        .unwrap();
    let mut kf = fresh.new_tangent();
    let want = fresh.evaluate(&u, 1.0, Some(&mut kf)).unwrap();
    assert!(freed == want, "residual, reactions or energy differ");
    assert!(k == kf, "the tangent kept the released row");
    assert!(freed.residual[d] != 0.0 && freed.reactions[d] == 0.0);
    assert!(held.reactions[d] == freed.residual[d]);
    assert_ne!(k.get(d, d), 1.0);
}

/// The solid need not come first: after a spring it adds through scratch (its engine writes
/// every value), and each sum has two terms, so either order gives the same bits (x + y = y + x
/// in floating point).
#[test]
fn the_order_of_the_contributions_does_not_matter() {
    let mesh = hex20_box([2, 1, 1]);
    let (a, b) = (
        3 * nodes_at_x(&mesh, 4.0)[0] + 2,
        3 * nodes_at_x(&mesh, 0.0)[3],
    );
    let spring = || Spring { a, b, k: 5e8 };
    let c = supports(&mesh);
    let first = System::builder(c.clone())
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .contribution(spring())
        .build()
        .unwrap();
    let last = System::builder(c)
        .contribution(spring())
        .contribution(solid(&mesh, Kinematics::Nonlinear))
        .build()
        .unwrap();
    let u = field(first.n(), 1e-3);
    let (mut k1, mut k2) = (first.new_tangent(), last.new_tangent());
    k2.values_mut().fill(f64::NAN);
    let e1 = first.evaluate(&u, 1.0, Some(&mut k1)).unwrap();
    let e2 = last.evaluate(&u, 1.0, Some(&mut k2)).unwrap();
    assert!(e1 == e2, "residual, reactions or energy differ");
    assert!(k1 == k2, "tangents differ");
    assert!(first.find::<Assembler>().is_some() && last.find::<Spring>().is_some());
}
