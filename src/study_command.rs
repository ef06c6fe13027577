//! `nonlin3d study` on the command line: the knobs file's cases run with a bar over the cases
//! (on a terminal), the files written, the table printed ([`nonlin3d::study`] does the work).

use crate::progress::Verbosity;
use crate::{Failure, read_scene};
use std::path::Path;

/// `nonlin3d study`: runs the cases with a bar (on a terminal), writes the files, prints the
/// table.
pub(crate) fn study(
    scene: &Path,
    knobs: &Path,
    out: &Path,
    jobs: usize,
    verbosity: Verbosity,
) -> Result<(), Failure> {
    use nonlin3d::study::Event;
    use std::io::IsTerminal;
    let base = read_scene(Some(scene)).map_err(Failure::Input)?;
    let plan = nonlin3d::study::Plan::read(knobs).map_err(Failure::Input)?;
    plan.scenes(&base).map_err(Failure::Input)?;
    let loud = verbosity != Verbosity::Quiet;
    let bar = indicatif::ProgressBar::new(plan.cases.len() as u64);
    if !(loud && std::io::stderr().is_terminal()) {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} cases, {elapsed}  {wide_msg}")
    {
        bar.set_style(style);
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let running = std::sync::Mutex::new(Vec::<String>::new());
    let progress = |e: Event| {
        let mut names = running.lock().unwrap_or_else(|e| e.into_inner());
        match e {
            Event::Started { name, .. } => names.push(name.to_string()),
            Event::Finished { case, done, .. } => {
                names.retain(|n| *n != case.name);
                bar.set_position(done as u64);
                if verbosity == Verbosity::Verbose {
                    bar.println(format!(
                        "{}: {} DOF, {:.2} s",
                        case.name, case.dofs, case.wall_s
                    ));
                }
            }
        }
        bar.set_message(format!("running {}", names.join(", ")));
    };
    let result = nonlin3d::study::run(&base, &plan, jobs, &progress).map_err(Failure::Run);
    bar.finish_and_clear();
    let result = result?;
    nonlin3d::study::write_all(&result, out).map_err(Failure::Run)?;
    if loud {
        print!("{}", nonlin3d::study::table(&result));
        println!("results in {}", out.display());
    }
    Ok(())
}
