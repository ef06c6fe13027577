//! The thesis's reference case (30 mm circle, §5.1) with and without crack-face contact
//! (§2.7, §5.4): the facade's model, problem and settings, the sweep driven level by level by
//! `nonlin3d_contact::Contact::solve_level` instead of the facade's own loop, G along the front
//! by the facade's VCCT table with `vcct::respect_contact` (G_I = 0 at closed points). Prints per
//! level: passes, pairs closed and opened, Newton iterations, closed pairs, the largest overlap,
//! time; and at the last level G_I, G_II and the face state along the front without contact
//! (the same sweep with the contact loop left out), with two-body contact, and with the thesis's
//! external-force approximation (Fig. 2.7.1c).
//!
//! Run: `cargo run --release --example contact_circle [strains…]` (default −0.001 … −0.005).

use nonlin3d::analysis::{build_problem, front_table, load_factors, settings};
use nonlin3d::model::{build_model, perturbation_force, perturbation_loads};
use nonlin3d::newton::{NonlinearProblem, PathSolver, StructuralProblem, solve_level};
use nonlin3d::vcct::{FaceState, FrontRelease, respect_contact};
use nonlin3d::{Scene, mesh::names};
use nonlin3d_contact::{Contact, ContactSettings, LevelSettings, Mode};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string("examples/scenes/fig_5_1_3_circle_30mm.toml")?;
    let mut scene = Scene::from_toml(&text)?;
    let strains: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    if !strains.is_empty() {
        scene.loads.strains = strains;
    }
    let model = build_model(&scene)?;
    let (factors, _) = load_factors(&scene);
    let (newton, stepping) = settings(&scene);
    let force = perturbation_force(&scene, &model)?;
    let perturbation = perturbation_loads(&model, force)?;
    let (up, lo) = (
        &model.mesh.node_sets[names::CRACK_UPPER],
        &model.mesh.node_sets[names::CRACK_LOWER],
    );
    println!(
        "{} nodes, {} crack-face pairs, {} front points",
        model.mesh.nodes.len(),
        up.len(),
        model.front.points.len()
    );
    let mut last: Vec<(Vec<FrontRelease>, Vec<FaceState>)> = Vec::new();
    for mode in [None, Some(Mode::TwoBody), Some(Mode::External)] {
        let with_contact = mode.is_some();
        let (assembler, constraints) = build_problem(&scene, &model)?.into_parts()?;
        let settings = ContactSettings {
            mode: mode.unwrap_or_default(),
            ..ContactSettings::default()
        };
        let mut contact = Contact::new(&model.mesh, settings)?;
        let mut problem =
            StructuralProblem::with_contributions(assembler, Vec::new(), constraints, |b| {
                contact.reserve(b)
            })?;
        let mut session = PathSolver::new(&problem, newton.solver)?;
        let mut u = vec![0.0; problem.n()];
        let (mut from, mut perturbed) = (0.0, false);
        let t_all = Instant::now();
        println!(
            "\ncontact {}:",
            match mode {
                None => "off",
                Some(Mode::TwoBody) => "on, two-body",
                Some(Mode::External) => "on, the thesis's external force",
            }
        );
        for (&lambda, strain) in factors.iter().zip(&scene.loads.strains) {
            let t = Instant::now();
            let pert: &[(usize, f64)] = if perturbed { &[] } else { &perturbation };
            let (passes, closed, opened, iterations) = if with_contact {
                let level = contact.solve_level(
                    &mut problem,
                    &mut session,
                    &mut u,
                    (from, lambda),
                    &LevelSettings {
                        newton: &newton,
                        stepping: &stepping,
                        perturbation: pert,
                    },
                )?;
                perturbed |= level.first.perturbed;
                (
                    level.passes.len(),
                    level.closed(),
                    level.opened(),
                    level.newton_iterations(),
                )
            } else {
                let level = solve_level(
                    &mut problem,
                    &mut u,
                    from,
                    lambda,
                    pert,
                    &newton,
                    &stepping,
                    &mut session,
                )?;
                perturbed |= level.perturbed;
                let it = level.attempts.iter().map(|a| a.iterations.len()).sum();
                (0, 0, 0, it)
            };
            let seconds = t.elapsed().as_secs_f64();
            let overlap = up
                .iter()
                .zip(lo)
                .map(|(&a, &b)| u[3 * a + 2] - u[3 * b + 2])
                .fold(0.0f64, f64::min);
            let active = contact.active();
            let mut front = front_table(&scene, &model, &problem, &u)?;
            // Closed: the pair one element behind the point is in the active set.
            let closed_upper: std::collections::HashSet<usize> = up
                .iter()
                .zip(&active)
                .filter(|(_, a)| **a)
                .map(|(&v, _)| v)
                .collect();
            let states =
                respect_contact(&mut front, &model.front, |a, _| closed_upper.contains(&a));
            let count = |s: FaceState| states.iter().filter(|&&x| x == s).count();
            println!(
                "ε = {strain}: passes {passes}, closed {closed}, opened {opened}, Newton \
                 iterations {iterations}, pairs in contact {}, min w_up − w_low {:.3e} mm, front points open/closed/overlap {}/{}/{}, {seconds:.2} s",
                active.iter().filter(|&&a| a).count(),
                overlap * 1e3,
                count(FaceState::Open),
                count(FaceState::Closed),
                count(FaceState::Overlap),
            );
            if lambda == *factors.last().unwrap_or(&lambda) {
                last.push((front, states));
            }
            from = lambda;
        }
        println!("sweep {:.2} s", t_all.elapsed().as_secs_f64());
    }
    if let [(off, s_off), (on, s_on), (ext, s_ext)] = &last[..] {
        println!(
            "\nlast level, along the front: S mm | off: G_I G_II state | two-body: G_I G_II state \
             | external force: G_I G_II state"
        );
        for i in 0..off.len() {
            let row = |r: &FrontRelease, s: &FaceState| {
                format!("{:8.2} {:8.2} {:7}", r.g_i, r.g_ii, s.to_string())
            };
            println!(
                "{:6.2} | {} | {} | {}",
                off[i].s * 1e3,
                row(&off[i], &s_off[i]),
                row(&on[i], &s_on[i]),
                row(&ext[i], &s_ext[i])
            );
        }
    }
    Ok(())
}
