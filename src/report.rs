//! Writing a run's outputs: `results.json`, `front_K.csv` per level, a VTU/PVD series of the
//! deformed model, SVG plots, and the short table the command line prints.

use crate::Error;
use crate::results::Results;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A CSV text written through the `csv` crate: RFC 4180 quoting of any field that holds a
/// comma, quote or line break, `\n` line ends. Numbers are formatted by the caller (`{:e}` for
/// G and lengths derived from the solution: the shortest form that reads back to the same
/// f64).
pub(crate) struct Csv(csv::Writer<Vec<u8>>);

impl Csv {
    /// A table with its header row.
    pub(crate) fn new(header: &[&str]) -> Self {
        let mut w = Self(
            csv::WriterBuilder::new()
                .flexible(true)
                .from_writer(Vec::new()),
        );
        w.row(header);
        w
    }

    /// One row.
    pub(crate) fn row<S: AsRef<[u8]>>(&mut self, fields: impl IntoIterator<Item = S>) {
        // Into a Vec<u8>, with flexible record lengths, a write cannot fail.
        let _ = self.0.write_record(fields);
    }

    /// One record alone, with its line end (a line appended to a file as a run goes).
    pub(crate) fn line<S: AsRef<[u8]>>(fields: impl IntoIterator<Item = S>) -> String {
        let mut w = Self(
            csv::WriterBuilder::new()
                .flexible(true)
                .from_writer(Vec::new()),
        );
        w.row(fields);
        w.finish()
    }

    /// The text.
    pub(crate) fn finish(self) -> String {
        let bytes = self.0.into_inner().unwrap_or_default();
        String::from_utf8_lossy(&bytes).into_owned()
    }
}

/// The CSV of one level's front table (G in J/m², lengths in mm, areas in mm²).
pub fn front_csv(results: &Results, level: usize) -> String {
    let mut t = Csv::new(&[
        "s_mm",
        "theta_deg",
        "x_mm",
        "y_mm",
        "delta_a_mm",
        "g_i_j_m2",
        "g_ii_j_m2",
        "g_iii_j_m2",
        "g_t_j_m2",
        "faces",
        "opening_mm",
        "area_mm2",
        "node",
        "failure_index",
        "g_i_error_j_m2",
        "g_ii_error_j_m2",
        "g_iii_error_j_m2",
        "g_t_error_j_m2",
    ]);
    if let Some(l) = results.levels.get(level) {
        for r in &l.front {
            t.row(
                [
                    r.s_mm.to_string(),
                    r.theta_deg.to_string(),
                    r.x_mm.to_string(),
                    r.y_mm.to_string(),
                    r.delta_a_mm.to_string(),
                    format!("{:e}", r.g_i),
                    format!("{:e}", r.g_ii),
                    format!("{:e}", r.g_iii),
                    format!("{:e}", r.g_t),
                    r.faces.as_str().to_string(),
                    format!("{:e}", r.opening_mm),
                    format!("{:e}", r.area_mm2),
                    r.node.to_string(),
                    r.failure_index.map_or(String::new(), |f| format!("{f:e}")),
                ]
                .into_iter()
                .chain(error_fields(r)),
            );
        }
    }
    t.finish()
}

/// The ± columns of a front row (J/m², empty without an estimate), after the old columns so
/// that readers of the old layout keep working.
fn error_fields(r: &crate::results::FrontRow) -> [String; 4] {
    match r.error {
        Some(e) => [e.g_i, e.g_ii, e.g_iii, e.g_t].map(|v| format!("{v:e}")),
        None => Default::default(),
    }
}

/// `yes`, `NO` (unstable: negative pivots) or `?` (not computed).
fn stability_word(l: &crate::results::LevelResult) -> &'static str {
    match l.convergence.stable {
        Some(true) => "yes",
        Some(false) => "NO",
        None => "?",
    }
}

/// The CSV of the levels: applied value, deflections (mm), largest G_I/G_II/G_T over the open
/// front points (J/m²), overlapped points, negative pivots, stability and Newton iterations.
pub fn levels_csv(results: &Results) -> String {
    let mut t = Csv::new(&[
        results.quantity.as_str(),
        "centre_deflection_mm",
        "max_face_separation_mm",
        "g_i_max_j_m2",
        "g_ii_max_j_m2",
        "g_t_max_j_m2",
        "overlapped_points",
        "front_points",
        "negative_pivots",
        "stable",
        "iterations",
    ]);
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    for l in &results.levels {
        t.row([
            l.value.to_string(),
            format!("{:e}", l.centre_deflection_mm),
            format!("{:e}", l.max_face_separation_mm),
            opt(l.peak(|r| r.g_i).map(|r| r.g_i)),
            opt(l.peak(|r| r.g_ii).map(|r| r.g_ii)),
            opt(l.peak(|r| r.g_t).map(|r| r.g_t)),
            l.overlapped().to_string(),
            l.front.len().to_string(),
            l.convergence
                .negative_pivots
                .map_or(String::new(), |p| p.to_string()),
            l.convergence
                .stable
                .map_or(String::new(), |b| b.to_string()),
            l.convergence.iterations.to_string(),
        ]);
    }
    t.finish()
}

/// Writes everything into `dir` (created if needed), each file atomically
/// ([`crate::output::write_atomic`]) and `results.json` last, and records the time in
/// `results.timings.output_s`.
pub fn write_all(results: &mut Results, dir: &Path) -> Result<(), Error> {
    write_all_but(results, dir, |_| false)
}

/// [`write_all`], except the `model_K.vtu` of the levels `current` says are already in `dir`
/// as they would be written (a run's output folder, written level by level: the state of a
/// converged level does not change after it).
pub(crate) fn write_all_but(
    results: &mut Results,
    dir: &Path,
    current: impl Fn(usize) -> bool,
) -> Result<(), Error> {
    use crate::atomic::{atomically, write_atomic};
    let t = Instant::now();
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    write_atomic(&dir.join("levels.csv"), levels_csv(results).as_bytes())?;
    for k in 0..results.levels.len() {
        let p = dir.join(format!("front_{k}.csv"));
        write_atomic(&p, front_csv(results, k).as_bytes())?;
    }
    if let Some(model) = &results.model_data {
        for (k, l) in results.levels.iter().enumerate() {
            if !current(k) {
                crate::fields::write_model_vtu(dir, model, l, k)?;
            }
            crate::fields::write_front_vtu(dir, model, l, k)?;
        }
        crate::fields::write_pvds(dir, &results.levels)?;
    }
    type Plot = (
        &'static str,
        &'static str,
        fn(&crate::results::FrontRow) -> f64,
    );
    let plots: [Plot; 3] = [
        ("g_i.svg", "G_I", |r| r.g_i),
        ("g_ii.svg", "G_II", |r| r.g_ii),
        ("g_t.svg", "G_T", |r| r.g_t),
    ];
    for (file, label, g) in plots {
        atomically(&dir.join(file), |tmp| {
            crate::plot::release_rate_plot(results, tmp, label, g)
        })?;
    }
    atomically(&dir.join("deflection.svg"), |tmp| {
        crate::plot::deflection_plot(results, tmp)
    })?;
    atomically(&dir.join("overview.svg"), |tmp| {
        crate::plot::overview_plot(results, tmp)
    })?;
    let indexed = results
        .levels
        .iter()
        .any(|l| l.front.iter().any(|r| r.failure_index.is_some()));
    if indexed {
        atomically(&dir.join("failure_index.svg"), |tmp| {
            crate::plot::failure_index_plot(results, tmp)
        })?;
    }
    // `[substructure] write_matrix = true`: K_red as CalculiX's .mtx.
    let matrices = results
        .model
        .substructure
        .iter()
        .flat_map(|s| &s.superelements);
    for e in matrices {
        if let (Some(file), Some(text)) = (&e.matrix_file, &e.mtx) {
            write_atomic(&dir.join(file), text.as_bytes())?;
        }
    }
    results.timings.output_s = t.elapsed().as_secs_f64();
    let json = serde_json::to_string_pretty(results)?;
    write_atomic(&dir.join("results.json"), json.as_bytes())
}

/// The short table: per level the applied value, the centre deflection, the largest crack-face
/// separation, the largest G_I and G_II over the points whose faces are open and where, the
/// count of overlapped points, and the Newton iterations; a note when any point overlaps; when
/// crack-face contact acted, per level the pairs closed, the active-set passes (of which
/// refreshes of the normals), the level's Newton iterations and the largest contact pressure.
pub fn table(results: &Results) -> String {
    let mut s = String::new();
    let head = if results.quantity == "strain" {
        "strain"
    } else {
        "P (N)"
    };
    let _ = writeln!(
        s,
        "{head:>9} | w centre top (mm) | max face separation (mm) | G_I max (J/m²) at S (mm) | G_II max (J/m²) at S (mm) | overlapped | stable | iterations"
    );
    // The ± column only when the levels carry an error estimate.
    let estimated = results.levels.iter().any(|l| l.error_estimate.is_some());
    if estimated {
        s.pop();
        s.push_str(" | ± G max (J/m², % of G_T max)\n");
    }
    // The contact column only when contact acted at some level (a run without contact prints
    // the table it always did).
    let contact = results.levels.iter().any(|l| l.contact.is_some());
    if contact {
        s.pop();
        s.push_str(" | contact: pairs closed, passes (refreshes), iterations, max p (MPa)\n");
    }
    let cell = |row: Option<&crate::results::FrontRow>, g: fn(&crate::results::FrontRow) -> f64| {
        row.map_or(format!("{:>24}", "— (no open point)"), |r| {
            format!("{:>13.2} at {:>7.2}", g(r), r.s_mm)
        })
    };
    // Round-off below the printed digits shows as 0, not −0.0000.
    let tidy = |v: f64| if v.abs() < 5e-5 { 0.0 } else { v };
    for l in &results.levels {
        let _ = writeln!(
            s,
            "{:>9.5} | {:>16.4} | {:>24.4} | {} | {} | {:>10} | {:>6} | {:>10}",
            l.value,
            tidy(l.centre_deflection_mm),
            tidy(l.max_face_separation_mm),
            cell(l.peak(|r| r.g_i), |r| r.g_i),
            cell(l.peak(|r| r.g_ii), |r| r.g_ii),
            format!("{}/{}", l.overlapped(), l.front.len()),
            stability_word(l),
            l.convergence.iterations
        );
        if estimated {
            s.pop();
            let e = l.error_estimate.map_or("—".to_string(), |e| {
                format!("±{:.1} ({:.1} %)", e.max_j_m2, 100.0 * e.relative)
            });
            let _ = writeln!(s, " | {e:>27}");
        }
        if contact {
            s.pop();
            let c = l.contact.as_ref().map_or("—".to_string(), |c| {
                let refreshes = c.pass_log.iter().filter(|p| p.refresh).count();
                format!(
                    "{}, {} ({refreshes}), {}, {:.2}",
                    c.pairs_closed, c.passes, c.iterations, c.max_pressure_mpa
                )
            });
            let _ = writeln!(s, " | {c:>12}");
        }
    }
    if results.levels.iter().any(|l| l.overlapped() > 0) {
        let _ = writeln!(
            s,
            "overlapped: front points where the crack faces pass through each other (no contact \
             is modelled); their G is not physical and is left out of the maxima above and of \
             the growth criterion (faces = overlapped in front_K.csv and results.json)"
        );
    }
    if let Some(m) = results
        .accuracy
        .as_ref()
        .and_then(|a| a.chosen_mesh.as_ref())
    {
        let _ = writeln!(s, "{}", mesh_line(m, results.model.dofs));
    }
    if let Some(a) = results.accuracy.as_ref()
        && let Some(dofs) = a.companion_dofs
    {
        let coarser = a.coarser_companion_dofs.map_or(String::new(), |k| {
            format!(" and on its own coarser companion ({k} DOFs)")
        });
        let _ = writeln!(
            s,
            "± G max: the largest estimated discretisation error of G_I, G_II, G_III, G_T over \
             the front, from the same levels on a coarser companion mesh ({dofs} DOFs){coarser} \
             (per point in front_K.csv and results.json)"
        );
    }
    let what = head;
    let companion = |seeded: bool| if seeded { " on the companion mesh" } else { "" };
    for l in &results.levels {
        if let Some(b) = l.convergence.bifurcation {
            let _ = writeln!(
                s,
                "bifurcation crossed between {what} {:.6} and {:.6} (negative pivots {} → {}){}",
                b.from,
                b.to,
                b.negative_pivots_before,
                b.negative_pivots_after,
                companion(l.convergence.seeded)
            );
        }
    }
    if let Some(at) = results.model.perturbed_at {
        let seeded = results
            .levels
            .iter()
            .any(|l| l.value == at && l.convergence.seeded);
        let _ = writeln!(
            s,
            "perturbation applied at {what} {at}{} (§3.2 protocol)",
            companion(seeded)
        );
    }
    // The values of the levels whose convergence record says `flag`.
    let levels_where = |flag: fn(&crate::results::Convergence) -> bool| -> Vec<String> {
        (results.levels.iter())
            .filter(|l| flag(&l.convergence))
            .map(|l| format!("{}", l.value))
            .collect()
    };
    let seeded = levels_where(|c| c.seeded);
    if !seeded.is_empty() {
        let _ = writeln!(
            s,
            "levels started from the companion mesh's converged states (nested iteration, \
             [analysis] start): {what} {}",
            seeded.join(", ")
        );
    }
    let followed = levels_where(|c| c.companion_set);
    if !followed.is_empty() {
        let _ = writeln!(
            s,
            "levels followed from the companion mesh's contact set: {what} {}",
            followed.join(", ")
        );
    }
    for w in &results.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    if let Some(c) = results.critical {
        let at = match c.after {
            Some(after) => format!(
                "between strain {after} (unbuckled, nothing released) and {} (add levels between \
                 them to locate it)",
                c.strain
            ),
            None => format!("at strain {:.5}", c.strain),
        };
        let _ = writeln!(
            s,
            "growth onset by the criterion {at}, S = {:.2} mm; there at level {} ({head} {}): \
             failure index {:.3}, mode mix (G_II + G_III)/G_T = {:.3} (G_I {:.2}, G_II {:.2}, \
             G_III {:.2} J/m²)",
            c.s_mm,
            c.level,
            results.levels.get(c.level).map_or(f64::NAN, |l| l.value),
            c.index,
            c.mode_mix,
            c.g_i,
            c.g_ii,
            c.g_iii
        );
    }
    let t = &results.timings;
    let _ = writeln!(
        s,
        "{} nodes, {} DOFs; mesh {:.2} s, setup {:.2} s, solve {:.2} s, VCCT {:.3} s",
        results.model.nodes, results.model.dofs, t.mesh_s, t.setup_s, t.solve_s, t.vcct_s
    );
    for f in &t.factor {
        let _ = writeln!(s, "  {}", f.line());
    }
    if let Some(sub) = &results.model.substructure {
        let realised = sub.realised_offset_mm.map_or(String::new(), |[lo, hi]| {
            format!(", realised ℓ {lo:.3}–{hi:.3} mm")
        });
        let _ = writeln!(
            s,
            "substructure \"{}\": Newton on {} of {} DOFs{realised}",
            sub.partition, sub.nonlinear_dofs, sub.full_dofs
        );
        for (k, e) in sub.superelements.iter().enumerate() {
            let _ = writeln!(
                s,
                "  superelement {}: {} interior DOFs onto {} interface DOFs, condensed in {:.2} s",
                k + 1,
                e.interior_dofs,
                e.interface_dofs,
                e.condensation_s
            );
        }
    }
    s
}

/// The terminal's line on a mesh the run chose itself (`[mesh] accuracy` or the default mesh).
fn mesh_line(m: &crate::results::MeshChoice, dofs: usize) -> String {
    let band = m.front_band.map_or(String::new(), |[i, o]| {
        format!(
            " → {} in a band of {i} + {o} rings at the front",
            3 * m.slices
        )
    });
    let element = m
        .front_element_mm
        .map_or(String::new(), |e| format!(", front element {e} mm"));
    let layers = match m.layer_band {
        Some(_) => format!(
            "{} + {} layers at the front, fewer away from it",
            m.sub_layers, m.base_layers
        ),
        None => format!("{} + {} layers", m.sub_layers, m.base_layers),
    };
    let why = match m.rule {
        crate::results::MeshRule::Default => {
            "the default mesh (no [mesh] knobs; any knob, e.g. slices = 8, runs the thesis's mesh)"
        }
        crate::results::MeshRule::Target => "picked by [mesh] accuracy",
    };
    let curved = match (m.curved_edges, m.front_band) {
        (true, Some(_)) => ", the band's rings curved",
        (true, None) => ", the rings curved",
        (false, _) => "",
    };
    format!(
        "mesh: {why}: {} slices{band}, {} + {} rings{element}, {layers}{curved}; {dofs} DOFs",
        m.slices, m.inside, m.outside
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A field with a comma, a quote or a line break is quoted (RFC 4180), others are not; a
    /// record ends in `\n`.
    #[test]
    fn csv_fields_are_quoted_where_needed() {
        assert_eq!(
            Csv::line(["1", "a,b", "say \"no\""]),
            "1,\"a,b\",\"say \"\"no\"\"\"\n"
        );
        let mut t = Csv::new(&["x_mm", "note"]);
        t.row(["2.5", ""]);
        assert_eq!(t.finish(), "x_mm,note\n2.5,\n");
    }
}
