//! The run's error estimate, its target and the default mesh (issue 25; docs/ACCURACY.md §2f
//! and §3, docs/MESH.md "Accuracy" and "The default mesh"): orchestration only. The mesh a
//! target picks is the mesh crate's table ([`nonlin3d_mesh::AccuracyRow`]), the default mesh
//! its [`nonlin3d_mesh::DEFAULT_MESH`], the companion mesh its `coarsened()` parameters, the
//! estimate per point [`nonlin3d_vcct::estimate::companion`].

use crate::Error;
use crate::model::{embedded_params, through_width_params};
use crate::results::{
    AccuracyReport, CoarserRun, GError, LevelError, LevelResult, MeshChoice, MeshRule, Results,
};
use crate::scene::{
    ElementName, ErrorEstimateName, Geometry, MeshControls, PartitionName, Scene, Shape,
};
use nonlin3d_mesh::{
    AccuracyRow, CompanionKind, DEFAULT_MESH, EmbeddedParams, MidEdges, ThroughWidthParams,
};
use nonlin3d_vcct::estimate::{self, FrontG, Modes};
use std::time::Instant;

/// A millimetre in metres.
const MM: f64 = 1e-3;

/// The embedded generator's parameters of a scene (embedded, edge, thin-film, plate), or
/// `None` for a through-width strip.
fn embedded_of(scene: &Scene) -> Option<EmbeddedParams> {
    match scene.geometry {
        Geometry::Embedded {
            shape,
            a_mm,
            b_mm,
            h_mm,
            base_mm,
            w_mm,
        }
        | Geometry::Edge {
            shape,
            a_mm,
            b_mm,
            h_mm,
            base_mm,
            w_mm,
        }
        | Geometry::ThinFilm {
            shape,
            a_mm,
            b_mm,
            h_mm,
            base_mm,
            w_mm,
        } => Some(embedded_params(
            scene, shape, a_mm, b_mm, h_mm, base_mm, w_mm,
        )),
        Geometry::Plate {
            a_mm,
            h_mm,
            base_mm,
            w_mm,
        } => Some(embedded_params(
            scene,
            Shape::Ellipse,
            a_mm,
            a_mm,
            h_mm,
            base_mm,
            w_mm,
        )),
        Geometry::ThroughWidth { .. } => None,
    }
}

/// Writes the embedded parameters' knobs into mesh controls (every field set).
fn set_controls(c: &mut MeshControls, p: &EmbeddedParams) {
    c.slices = Some(p.slices);
    c.inside = Some(p.radial_inside);
    c.outside = Some(p.radial_outside);
    c.sub_layers = Some(p.sub_layers);
    c.base_layers = Some(p.base_layers);
    c.front_grading = Some(p.front_grading);
    c.front_element_mm = p.front_element.map(|e| e / MM);
    c.front_band = p.front_band.map(|b| [b.inside, b.outside]);
    c.layer_band = p.layer_band.map(|b| [b.inside, b.outside]);
    c.curved_edges = Some(p.mid_edges == MidEdges::Mapped);
}

/// `p` with the scene's own `curved_edges`, where it gives one, over the table row's.
fn with_scene_edges(p: EmbeddedParams, scene: &Scene) -> EmbeddedParams {
    let mid_edges = match scene.mesh.curved_edges {
        Some(true) => MidEdges::Mapped,
        Some(false) => MidEdges::Chords,
        None => p.mid_edges,
    };
    EmbeddedParams { mid_edges, ..p }
}

/// Whether a scene takes the default mesh ([`nonlin3d_mesh::DEFAULT_MESH`]): an embedded or
/// edge delamination of homogenised Hex20 layers, without substructuring, whose `[mesh]` gives
/// no knob that shapes the mesh and no target. Any knob given keeps the thesis's reference
/// mesh under it (the thesis scenes give `slices = 8`); plates, thin films, ply-level layups,
/// Hex8 and substructured models keep it too (the default mesh was measured on none of them).
fn takes_default_mesh(scene: &Scene) -> bool {
    let m = &scene.mesh;
    matches!(
        scene.geometry,
        Geometry::Embedded { .. } | Geometry::Edge { .. }
    ) && !m.gives_mesh_knobs()
        && scene.layup.is_none()
        && scene.substructure.partition == PartitionName::None
        && matches!(m.element, None | Some(ElementName::Hex20))
}

/// The strip generator's parameters of a through-width scene (its knobs over the generator's
/// example), or `None` for any other model, as [`embedded_of`] is for the others.
fn strip_of(scene: &Scene) -> Option<Result<ThroughWidthParams, Error>> {
    let Geometry::ThroughWidth {
        a_mm,
        length_mm,
        width_mm,
        h_mm,
        base_mm,
    } = scene.geometry
    else {
        return None;
    };
    Some(through_width_params(
        scene, a_mm, length_mm, width_mm, h_mm, base_mm,
    ))
}

/// A through-width scene without mesh knobs with the default strip mesh's written in
/// (`nonlin3d_mesh::ThroughWidthParams::with_default_mesh`, docs/MESH.md "The default mesh");
/// None for any other scene (and for a strip the build refuses: it reports why).
fn default_strip(scene: &Scene) -> Option<Scene> {
    if scene.mesh.gives_mesh_knobs() {
        return None;
    }
    let p = strip_of(scene)?.ok()?.with_default_mesh();
    let mut out = scene.clone();
    set_strip_controls(&mut out.mesh, &p);
    Some(out)
}

/// Writes a strip's knobs into mesh controls (every field the strip generator takes).
fn set_strip_controls(c: &mut MeshControls, p: &ThroughWidthParams) {
    c.inside = Some(p.inside);
    c.outside = Some(p.outside);
    c.front_grading = Some(p.front_grading);
    c.across = Some(p.across);
    c.sub_layers = Some(p.sub_layers);
    c.base_layers = Some(p.base_layers);
}

/// The scene with its mesh resolved to knobs, and what was chosen: `[mesh] accuracy` by the
/// table's row scaled to the model (the knobs the scene gives itself override the row's); a
/// scene that [takes the default mesh](takes_default_mesh) by
/// [`nonlin3d_mesh::DEFAULT_MESH`] scaled alike. Any other scene comes back unchanged.
/// Through-width strips have no table: a target for one is refused.
pub(crate) fn resolve_mesh(scene: &Scene) -> Result<(Scene, Option<MeshChoice>), Error> {
    if let Some(strip) = default_strip(scene) {
        return Ok((strip, None));
    }
    if takes_default_mesh(scene)
        && let Some(p) = embedded_of(scene)
    {
        let chosen = with_scene_edges(p.with_accuracy_row(&DEFAULT_MESH), scene);
        let mut out = scene.clone();
        set_controls(&mut out.mesh, &chosen);
        let choice = MeshChoice::of(&chosen, &DEFAULT_MESH, true, MeshRule::Default, Vec::new());
        return Ok((out, Some(choice)));
    }
    let Some(target) = scene.mesh.accuracy else {
        return Ok((scene.clone(), None));
    };
    let mut plain = scene.clone();
    plain.mesh = MeshControls {
        element: scene.mesh.element,
        elliptic_map: scene.mesh.elliptic_map,
        curved_edges: scene.mesh.curved_edges,
        ..MeshControls::default()
    };
    let Some(p) = embedded_of(&plain) else {
        return Err(Error::Scene(format!(
            "mesh.accuracy = {target}: the accuracy table is measured for embedded, edge and \
             plate models; a through-width strip takes inside, outside and front_grading"
        )));
    };
    let (row, meets) = AccuracyRow::for_target(target);
    let chosen = with_scene_edges(p.with_accuracy_row(&row), scene);
    let given = &scene.mesh;
    let overridden: Vec<String> = [
        ("slices", given.slices.is_some()),
        ("inside", given.inside.is_some()),
        ("outside", given.outside.is_some()),
        ("sub_layers", given.sub_layers.is_some()),
        ("base_layers", given.base_layers.is_some()),
        ("front_grading", given.front_grading.is_some()),
        ("front_element_mm", given.front_element_mm.is_some()),
        ("front_band", given.front_band.is_some()),
    ]
    .iter()
    .filter(|(_, set)| *set)
    .map(|(n, _)| (*n).to_string())
    .collect();
    let mut c = MeshControls::default();
    set_controls(&mut c, &chosen);
    // The scene's own knobs win, field by field.
    let mut out = scene.clone();
    let m = &mut out.mesh;
    m.slices = given.slices.or(c.slices);
    m.inside = given.inside.or(c.inside);
    m.outside = given.outside.or(c.outside);
    m.sub_layers = given.sub_layers.or(c.sub_layers);
    m.base_layers = given.base_layers.or(c.base_layers);
    m.front_element_mm = given.front_element_mm.or(c.front_element_mm);
    m.front_band = given.front_band.or(c.front_band);
    m.curved_edges = c.curved_edges;
    // A band the explicit ring counts no longer hold is dropped.
    if let (Some([bi, bo]), Some(i), Some(o)) = (m.front_band, m.inside, m.outside)
        && (bi >= i || bo >= o)
        && given.front_band.is_none()
    {
        m.front_band = None;
    }
    let choice = MeshChoice {
        rule: MeshRule::Target,
        table_error: row.worst,
        table_meets_target: meets,
        slices: m.slices.unwrap_or(chosen.slices),
        inside: m.inside.unwrap_or(chosen.radial_inside),
        outside: m.outside.unwrap_or(chosen.radial_outside),
        sub_layers: m.sub_layers.unwrap_or(chosen.sub_layers),
        base_layers: m.base_layers.unwrap_or(chosen.base_layers),
        front_element_mm: m.front_element_mm,
        front_band: m.front_band,
        layer_band: m.layer_band,
        curved_edges: chosen.mid_edges == MidEdges::Mapped,
        overridden,
    };
    Ok((out, Some(choice)))
}

/// The companion scene at `depth` (1: the error estimate's companion of `scene`; 2: the
/// companion's own, whose `scene` is the companion's, src/analysis_seed.rs "Nested
/// companions"): the same scene on the companion mesh — at depth 1 `coarsened()` of the mesh
/// crate (in-plane counts halved, the front's through-thickness mesh kept where it resolves
/// the mode split, the rings outside a front band kept: `companion_kind()`), deeper `coarsened_along_front()` (the slices halved, an error when they
/// cannot; a strip has none) — without an estimate or target of its own.
pub(crate) fn companion_scene(scene: &Scene, depth: usize) -> Result<Scene, Error> {
    let mut c = scene.clone();
    c.mesh.error_estimate = Some(ErrorEstimateName::Off);
    c.mesh.accuracy = None;
    match embedded_of(scene) {
        Some(p) if depth > 1 => match p.coarsened_along_front() {
            Some(q) => set_controls(&mut c.mesh, &q),
            None => return Err(Error::Scene("no slices to halve".into())),
        },
        Some(p) => set_controls(&mut c.mesh, &p.coarsened()),
        None if depth > 1 => return Err(Error::Scene("a strip has no slices to halve".into())),
        None => {
            let p = strip_of(scene)
                .ok_or_else(|| Error::Scene("no mesh to coarsen".into()))??
                .coarsened();
            set_strip_controls(&mut c.mesh, &p);
        }
    }
    Ok(c)
}

/// A level's front as positions along it (S over the front's length), G, and whether each
/// point's faces are open.
fn front_g(level: &LevelResult) -> (Vec<f64>, Vec<Modes>, Vec<bool>) {
    let end = level.front.last().map_or(0.0, |r| r.s_mm);
    let at = level
        .front
        .iter()
        .map(|r| if end > 0.0 { r.s_mm / end } else { 0.0 })
        .collect();
    let g = level
        .front
        .iter()
        .map(|r| Modes {
            g_i: r.g_i,
            g_ii: r.g_ii,
            g_iii: r.g_iii,
            g_t: r.g_t,
        })
        .collect();
    let open = level.front.iter().map(|r| r.is_open()).collect();
    (at, g, open)
}

/// The warning of an estimate whose rule wants the coarser companion's term (§3d) and has
/// none, saying why: no coarser companion ran (`start = "path"`), it failed (its error), or
/// it stopped before the last level.
fn missing_coarser_term(coarser: Option<&CoarserRun>, levels: usize) -> String {
    let why = match coarser {
        None => "it runs with [analysis] start = \"companion\", the default, and did not here"
            .to_string(),
        Some(CoarserRun {
            failure: Some(e), ..
        }) => format!("the coarser companion mesh failed: {e}"),
        Some(r) => format!(
            "the coarser companion mesh ({} DOFs) solved {} levels of {levels}",
            r.dofs,
            r.levels.len()
        ),
    };
    format!(
        "the error estimate lacks its coarser companion's term ({why}): just past buckling its \
         ± can be 3× too small (docs/ACCURACY.md §3d)"
    )
}

/// Fills each level's per-point errors and summary from the companion's matching level, with
/// the estimate's factors for what the companion coarsens, and from the companion's own
/// coarser companion's level where the rule uses it (`coarser`).
fn fill_level(
    level: &mut LevelResult,
    companion: &LevelResult,
    coarser: Option<&LevelResult>,
    rule: estimate::Rule,
) -> Result<(), Error> {
    let (at, g, open) = front_g(level);
    let (cat, cg, _) = front_g(companion);
    let mut est = estimate::companion(
        FrontG {
            at: &at,
            g: &g,
            open: Some(&open),
        },
        FrontG {
            at: &cat,
            g: &cg,
            open: None,
        },
        rule,
    )
    .map_err(|e| Error::Scene(e.to_string()))?;
    if let (Some(b), Some(coarser)) = (rule.coarser, coarser) {
        let (kat, kg, _) = front_g(coarser);
        let second = estimate::coarser(
            &at,
            FrontG {
                at: &cat,
                g: &cg,
                open: None,
            },
            FrontG {
                at: &kat,
                g: &kg,
                open: None,
            },
            b,
        )
        .map_err(|e| Error::Scene(e.to_string()))?;
        for (e, s) in est.iter_mut().zip(second) {
            *e = e.larger(s);
        }
    }
    for (row, e) in level.front.iter_mut().zip(&est) {
        row.error = Some(GError {
            g_i: e.g_i,
            g_ii: e.g_ii,
            g_iii: e.g_iii,
            g_t: e.g_t,
        });
    }
    // The summary over the physical points only (none open, or an unbuckled level: no
    // summary, no verdict).
    let open = level.front.iter().filter(|r| r.is_open());
    if open.clone().next().is_none() {
        return Ok(());
    }
    let max = open
        .clone()
        .filter_map(|r| r.error)
        .map(|e| e.g_i.max(e.g_ii).max(e.g_iii).max(e.g_t))
        .fold(0.0, f64::max);
    let g_t_max = open.map(|r| r.g_t).fold(0.0, f64::max);
    if g_t_max < ROUND_OFF_G {
        return Ok(());
    }
    level.error_estimate = Some(LevelError {
        max_j_m2: max,
        g_t_max_j_m2: g_t_max,
        relative: if g_t_max > 0.0 { max / g_t_max } else { 0.0 },
    });
    Ok(())
}

/// A level whose G_T max (over its open points) is below this, J/m², is unbuckled: its G is
/// round-off (2e-22 J/m² on the reference scene's ε = −0.001), and so is its error, whose
/// ratio to it (0.40 there) would be read as the level's relative error and fail any
/// `[mesh] accuracy` target. Such a level keeps its per-point ± but gets no summary. Real
/// release rates are many orders above it (0.01–1 J/m² at the first buckled levels measured).
const ROUND_OFF_G: f64 = 1e-9;

/// The companion's run: its results (or why it failed) and its wall seconds.
pub(crate) type CompanionRun = (Result<Results, Error>, f64);

/// Whether the scene asks for the companion's estimate.
pub(crate) fn wanted(scene: &Scene) -> bool {
    scene.mesh.error_estimate.unwrap_or_default() == ErrorEstimateName::Companion
}

/// The span a companion at `depth` runs in (crate::log: its Newton events are told apart
/// from the run's, and a coarser companion's from the companion's, on any thread).
fn companion_span(depth: usize) -> tracing::Span {
    if depth > 1 {
        tracing::info_span!(crate::log::COARSER_COMPANION_SPAN)
    } else {
        tracing::info_span!(crate::log::COMPANION_SPAN)
    }
}

/// The companion mesh's run ([`companion_scene`], then [`super::run_at`] on it at `depth`,
/// silently): an independent run, so it may go on beside the main one (`super::run` does so
/// with two or more threads); its results do not depend on when or on which thread it runs.
pub(crate) fn run_companion(scene: &Scene, depth: usize) -> CompanionRun {
    let _span = companion_span(depth).entered();
    let t = Instant::now();
    let run = companion_scene(scene, depth).and_then(|c| super::run_at(&c, &mut |_| Ok(()), depth));
    (run, t.elapsed().as_secs_f64())
}

/// [`run_companion`], each converged level sent on `to` as it comes (nested iteration:
/// src/analysis_seed.rs); `to` is dropped when the run ends, so a listener waiting for a
/// level the run never reaches is told.
pub(crate) fn run_companion_sending(
    scene: &Scene,
    to: std::sync::mpsc::Sender<super::seed::SeedLevel>,
    depth: usize,
) -> CompanionRun {
    let _span = companion_span(depth).entered();
    let t = Instant::now();
    let run = companion_scene(scene, depth).and_then(|c| {
        super::run_at(
            &c,
            &mut |p| {
                if let super::Progress::Level { index, result, .. } = p {
                    super::seed::SeedLevel::send(index, result, &to);
                }
                Ok(())
            },
            depth,
        )
    });
    drop(to);
    (run, t.elapsed().as_secs_f64())
}

/// Fills the per-point errors and the levels' summaries from the companion's run
/// (`companion`: run beside the main one; None: run here, after it, when the scene asks for
/// an estimate), and reports them with the target's choice in `results.accuracy`; a warning
/// when the estimate exceeds the target, or when the companion could not run.
pub(crate) fn attach(
    scene: &Scene,
    choice: Option<MeshChoice>,
    companion: Option<CompanionRun>,
    results: &mut Results,
) -> Result<(), Error> {
    let method = scene.mesh.error_estimate.unwrap_or_default();
    let target = scene.mesh.accuracy;
    if method == ErrorEstimateName::Off && choice.is_none() {
        return Ok(());
    }
    let mut report = AccuracyReport {
        error_estimate: match method {
            ErrorEstimateName::Off => "off",
            ErrorEstimateName::Companion => "companion",
        }
        .into(),
        companion_dofs: None,
        companion_s: None,
        companion_seeded_levels: None,
        coarser_companion_dofs: None,
        unavailable: None,
        worst_relative: None,
        target,
        met: None,
        chosen_mesh: choice,
    };
    if method == ErrorEstimateName::Companion {
        let (run, seconds) = companion.unwrap_or_else(|| run_companion(scene, 1));
        match run {
            Ok(c) if c.levels.len() == results.levels.len() => {
                let kind =
                    embedded_of(scene).map_or(CompanionKind::AllHalved, |p| p.companion_kind());
                let rule = estimate::Rule::for_companion(kind);
                // The coarser companion's levels, where it ran and finished them all.
                let coarser = c
                    .coarser
                    .as_ref()
                    .filter(|k| rule.coarser.is_some() && k.levels.len() == c.levels.len());
                for (k, (level, cl)) in results.levels.iter_mut().zip(&c.levels).enumerate() {
                    fill_level(level, cl, coarser.map(|r| &r.levels[k]), rule)?;
                }
                report.companion_dofs = Some(c.model.dofs);
                report.coarser_companion_dofs = coarser.map(|r| r.dofs);
                if rule.coarser.is_some() && coarser.is_none() {
                    results
                        .warnings
                        .push(missing_coarser_term(c.coarser.as_ref(), c.levels.len()));
                }
                report.companion_s = Some(seconds);
                report.companion_seeded_levels =
                    Some(c.levels.iter().filter(|l| l.convergence.seeded).count());
            }
            Ok(c) => {
                report.unavailable = Some(format!(
                    "the companion mesh solved {} levels of {}",
                    c.levels.len(),
                    results.levels.len()
                ));
            }
            Err(e) => report.unavailable = Some(format!("the companion mesh failed: {e}")),
        }
    }
    let worst = results
        .levels
        .iter()
        .filter_map(|l| l.error_estimate)
        .map(|e| e.relative)
        .reduce(f64::max);
    report.worst_relative = worst;
    report.met = target.zip(worst).map(|(t, w)| w <= t);
    if let Some(why) = &report.unavailable {
        results
            .warnings
            .push(format!("no error estimate of G: {why}"));
    }
    if let (Some(t), Some(false)) = (target, report.met) {
        let (k, l) = results
            .levels
            .iter()
            .enumerate()
            .filter_map(|(k, l)| l.error_estimate.map(|e| (k, e)))
            .max_by(|a, b| a.1.relative.total_cmp(&b.1.relative))
            .unwrap_or((
                0,
                LevelError {
                    max_j_m2: 0.0,
                    g_t_max_j_m2: 0.0,
                    relative: 0.0,
                },
            ));
        results.warnings.push(format!(
            "the estimated error of G exceeds the target mesh.accuracy = {t}: ±{:.1} J/m² at \
             level {k} is {:.1} % of its G_T max {:.1} J/m²; refine the mesh (a smaller \
             accuracy, or front_element_mm, slices, front_band: docs/MESH.md)",
            l.max_j_m2,
            100.0 * l.relative,
            l.g_t_max_j_m2
        ));
    }
    results.accuracy = Some(report);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The warning says why the term is missing: no coarser companion ran, it failed (with its
    /// error), or it stopped short of the run's levels.
    #[test]
    fn the_missing_term_warning_says_why() {
        let none = missing_coarser_term(None, 5);
        assert!(none.contains("lacks its coarser companion's term (it runs with [analysis]"));
        let failed = CoarserRun {
            dofs: 0,
            levels: Vec::new(),
            failure: Some("level 3: no convergence".into()),
        };
        let w = missing_coarser_term(Some(&failed), 5);
        assert!(
            w.contains("(the coarser companion mesh failed: level 3: no convergence)"),
            "{w}"
        );
        let short = CoarserRun {
            dofs: 3345,
            levels: Vec::new(),
            failure: None,
        };
        let w = missing_coarser_term(Some(&short), 5);
        assert!(
            w.contains("(the coarser companion mesh (3345 DOFs) solved 0 levels of 5)"),
            "{w}"
        );
        assert!(w.ends_with("(docs/ACCURACY.md §3d)"));
    }
}
