//! What a scene must satisfy before anything is meshed, checked in the scene's own words: field
//! names as written in the TOML (`geometry.w_mm`, `mesh.slices`) and lengths in mm. The mesh
//! generators check their parameters too, but in SI units and with their internal names; a scene
//! that passes these checks never reaches those messages. [`Scene::validate`] and
//! [`Scene::warnings`] live here.

use crate::Error;
use crate::scene::{ElementName, Geometry, MaterialSpec, PartitionName, Scene, Shape};
use nonlin3d_mesh::EmbeddedParams;

/// Element counts above this along one mesh axis are refused before anything is allocated
/// (10 000 slices alone would give about 10⁸ nodes).
pub const MAX_COUNT: usize = 10_000;

/// Strain magnitudes above this are refused (`loads.strains`): the analysis of such a level
/// ground on for minutes at the smallest increments before failing (fuzz cases with ε = −0.5,
/// −3 and +2 on a 10 000-DOF mesh), and no laminate survives a tenth of it.
pub const MAX_STRAIN: f64 = 0.1;

/// Solver threads above this are refused (machines this runs on have far fewer cores).
pub const MAX_THREADS: usize = 1024;
/// Most increment attempts a scene may allow for one level (`analysis.max_attempts`).
pub const MAX_ATTEMPTS: usize = 100_000;

/// Largest ratio of an orthotropic material's largest to smallest modulus (E11 … G23). Fibre
/// composites lie near 40 (E11/G23 of graphite/epoxy: 134/3.43); the tangent's condition
/// number grows with the ratio times the mesh's own (10⁴–10⁶), so beyond 10⁶ double precision
/// keeps no digit: a 10¹² ratio (fuzz case 50177 of seed 31415) failed after 31 s of cutbacks.
pub const MAX_MODULUS_RATIO: f64 = 1e6;

fn bad<T>(message: String) -> Result<T, Error> {
    Err(Error::Scene(message))
}

fn positive(name: &str, v: f64) -> Result<(), Error> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        bad(format!("{name} = {v}: must be positive and finite"))
    }
}

impl Scene {
    /// Checks what the type system cannot, in the scene's words (field names as written, mm):
    /// positive sizes, a delamination that fits the model, mesh counts in range, loads present
    /// and used, sensible options (`checks.rs`).
    pub fn validate(&self) -> Result<(), Error> {
        scene(self)
    }

    /// Legal but suspicious input (tensile strains on a buckling model, a sublaminate thicker
    /// than the base or its span, strains out of order): the run goes ahead; the command line
    /// prints these and results.json keeps them.
    pub fn warnings(&self) -> Vec<String> {
        warnings(self)
    }
}

/// All checks of [`Scene::validate`].
pub(crate) fn scene(s: &Scene) -> Result<(), Error> {
    for (name, v) in s.geometry.lengths_mm() {
        positive(&format!("geometry.{name}"), v)?;
        // Far outside this, coordinates in metres lose their digits or the cells' Jacobians
        // underflow (a 1e-308 mm sublaminate meshes to det J = 0).
        if !(1e-6..=1e6).contains(&v) {
            return bad(format!(
                "geometry.{name} = {v} mm: lengths must lie between 1e-6 mm and 1e6 mm"
            ));
        }
    }
    geometry_fits(&s.geometry)?;
    material(&s.material)?;
    mesh_controls(s)?;
    layup(s)?;
    loads(s)?;
    crate::scene::check_contact(&s.contact)?;
    let a = &s.analysis;
    if let Some(t) = a.tolerance_n {
        positive("analysis.tolerance_n", t)?;
    }
    positive("analysis.max_increment", a.max_increment)?;
    let smallest = nonlin3d_newton::Stepping::default().min;
    if !(smallest..=1.0).contains(&a.max_increment) {
        return bad(format!(
            "analysis.max_increment = {}: must lie between {smallest} (the smallest increment \
             Newton cuts back to) and 1 (the whole first level)",
            a.max_increment
        ));
    }
    // faer splits its work into this many pieces: 4294967297 ran for minutes (fuzz case 6866).
    if a.threads > MAX_THREADS {
        return bad(format!(
            "analysis.threads = {}: at most {MAX_THREADS} (0: all cores, 1: sequential; \
             the results do not depend on it)",
            a.threads
        ));
    }
    if !(1..=MAX_ATTEMPTS).contains(&a.max_attempts) {
        return bad(format!(
            "analysis.max_attempts = {}: must lie between 1 and {MAX_ATTEMPTS}",
            a.max_attempts
        ));
    }
    if a.refactor_every == 0 {
        return bad("analysis.refactor_every = 0: must be at least 1".into());
    }
    if let Some(c) = &s.criterion {
        c.criterion()
            .validate()
            .map_err(|e| Error::Scene(format!("criterion: {e}")))?;
    }
    thin_film(s)?;
    substructure(s)
}

/// The thin-film model (§5.3) is the sublaminate alone: no linear region to condense
/// (`[substructure]` partition `none`), and no cells under the lower crack face for the
/// contact stage (`[contact] crack_faces = "off"`, overlaps reported as `overlapped`).
fn thin_film(s: &Scene) -> Result<(), Error> {
    if !matches!(s.geometry, Geometry::ThinFilm { .. }) {
        return Ok(());
    }
    let partition = s.substructure.partition;
    if partition != PartitionName::None {
        return bad(format!(
            "substructure.partition = \"{}\" with geometry.kind = \"thin-film\": the \
             thin-film model is the sublaminate alone (the base is prescribed), so there is no \
             linear region to condense; set partition = \"none\"",
            partition.name()
        ));
    }
    let faces = s.contact.crack_faces;
    if faces != crate::scene::CrackFacesName::Off {
        return bad(format!(
            "contact.crack_faces = \"{}\" (the default is \"auto\") with geometry.kind = \
             \"thin-film\": the thin film's lower crack face is the base's prescribed motion, \
             with no cells for the contact stage; write [contact] crack_faces = \"off\" \
             (overlapping faces are then reported as overlapped)",
            faces.name()
        ));
    }
    Ok(())
}

/// `[substructure]`: ℓ positive and finite, given only with the thesis's partition (the other
/// partitions have no offset; a key read and ignored would hide a mistake). Whether some
/// sublaminate cell lies ℓ inside the front is the mesh's check (it names the largest ℓ that
/// leaves cells).
fn substructure(s: &Scene) -> Result<(), Error> {
    let sub = &s.substructure;
    match (sub.partition, sub.offset_mm) {
        (PartitionName::Thesis, Some(l)) => positive("substructure.offset_mm", l),
        (p, Some(l)) if p != PartitionName::Thesis => bad(format!(
            "substructure.offset_mm = {l}: only the thesis's partition (partition = \"thesis\") \
             has an offset ℓ"
        )),
        _ => Ok(()),
    }?;
    if sub.write_matrix && sub.partition == PartitionName::None {
        return bad(
            "substructure.write_matrix = true with partition = \"none\": there is no \
             superelement to write; choose partition = \"thesis\" or \"sublaminate\""
                .into(),
        );
    }
    // Contact acts on the nonlinear region's DOFs (src/substructure.rs): the sublaminate
    // partition takes the base cells under the delamination in; the thesis's keeps the
    // sublaminate's strip next to the front, crack faces included, in the linear region.
    if sub.partition == PartitionName::Thesis
        && s.contact.crack_faces != crate::scene::CrackFacesName::Off
    {
        return bad(format!(
            "substructure.partition = \"thesis\" with contact.crack_faces = \"{}\": the \
             thesis's partition condenses the crack faces next to the front, where contact \
             would act; choose partition = \"sublaminate\" (its nonlinear region then holds \
             both crack faces) or set [contact] crack_faces = \"off\"",
            s.contact.crack_faces.name()
        ));
    }
    Ok(())
}

/// An orthotropic material's moduli within [`MAX_MODULUS_RATIO`] of each other (their signs
/// and the positive definiteness are the laminate crate's checks).
fn material(m: &MaterialSpec) -> Result<(), Error> {
    let MaterialSpec::Orthotropic {
        e11_gpa,
        e22_gpa,
        e33_gpa,
        g12_gpa,
        g13_gpa,
        g23_gpa,
        ..
    } = *m
    else {
        return Ok(());
    };
    let moduli = [
        ("e11_gpa", e11_gpa),
        ("e22_gpa", e22_gpa),
        ("e33_gpa", e33_gpa),
        ("g12_gpa", g12_gpa),
        ("g13_gpa", g13_gpa),
        ("g23_gpa", g23_gpa),
    ];
    for (name, v) in moduli {
        positive(&format!("material.{name}"), v)?;
    }
    let by = |a: &(&str, f64), b: &(&str, f64)| a.1.total_cmp(&b.1);
    let (lo, lo_v) = moduli.iter().copied().min_by(by).unwrap_or(("", 1.0));
    let (hi, hi_v) = moduli.iter().copied().max_by(by).unwrap_or(("", 1.0));
    if hi_v / lo_v > MAX_MODULUS_RATIO {
        return bad(format!(
            "material: {hi} = {hi_v} GPa is {:.3e} times {lo} = {lo_v} GPa: moduli more than \
             {MAX_MODULUS_RATIO:e} apart leave the stiffness matrix without a digit in double \
             precision",
            hi_v / lo_v
        ));
    }
    Ok(())
}

/// The delamination must fit in the model: the embedded and edge meshes keep the rings around
/// the front elliptic out to `transition` (1.4) times the larger semi-axis and then blend into
/// the square boundary, so W must exceed that; the through-width front must lie inside the slab.
fn geometry_fits(g: &Geometry) -> Result<(), Error> {
    let transition = EmbeddedParams::thesis_reference().transition;
    let room = |a: f64, b: f64, w: f64, axes: &str| {
        let need = transition * a.max(b);
        if need < w {
            Ok(())
        } else {
            bad(format!(
                "geometry.w_mm = {w} mm is too small for the delamination: the mesh needs \
                 w_mm > {transition} × {axes} = {transition} × {} = {need} mm (the rings around \
                 the front stay elliptic out to {transition} times the larger semi-axis); raise \
                 w_mm or make the delamination smaller",
                a.max(b)
            ))
        }
    };
    match *g {
        Geometry::Embedded {
            a_mm, b_mm, w_mm, ..
        }
        | Geometry::Edge {
            a_mm, b_mm, w_mm, ..
        }
        | Geometry::ThinFilm {
            a_mm, b_mm, w_mm, ..
        } => room(a_mm, b_mm, w_mm, "max(a_mm, b_mm)"),
        Geometry::Plate { a_mm, w_mm, .. } => room(a_mm, a_mm, w_mm, "a_mm"),
        Geometry::ThroughWidth {
            a_mm, length_mm, ..
        } => {
            if a_mm < length_mm {
                Ok(())
            } else {
                bad(format!(
                    "geometry.a_mm = {a_mm} mm must be smaller than geometry.length_mm = \
                     {length_mm} mm: the front x = a_mm has to lie inside the model"
                ))
            }
        }
    }
}

/// Mesh controls: counts at least 1 (slices even) and at most [`MAX_COUNT`], the grading
/// positive, and no control that the scene's model does not use (it would be ignored).
fn mesh_controls(s: &Scene) -> Result<(), Error> {
    let c = &s.mesh;
    let through = matches!(s.geometry, Geometry::ThroughWidth { .. });
    if through && let Some(n) = c.slices {
        return bad(format!(
            "mesh.slices = {n}: a through-width model has a straight front; its elements across \
             the width are set by mesh.across"
        ));
    }
    let elliptic = matches!(
        s.geometry,
        Geometry::Embedded {
            shape: Shape::Ellipse,
            ..
        } | Geometry::Edge {
            shape: Shape::Ellipse,
            ..
        } | Geometry::ThinFilm {
            shape: Shape::Ellipse,
            ..
        }
    );
    if !elliptic && c.elliptic_map.is_some() {
        return bad(
            "mesh.elliptic_map: only elliptic embedded and edge delaminations are mapped (the \
             plate is circular, rectangles and through-width fronts are not elliptic)"
                .into(),
        );
    }
    if c.curved_edges == Some(true) && (through || c.element == Some(ElementName::Hex8)) {
        return bad(
            "mesh.curved_edges = true: curved edges are built for Hex20 meshes of embedded, edge \
             and plate models (a Hex8 has no mid-edge nodes, a through-width front is straight)"
                .into(),
        );
    }
    if !through && let Some(n) = c.across {
        return bad(format!(
            "mesh.across = {n}: only through-width models have elements across a width; \
             embedded, edge and plate models are refined along the front by mesh.slices"
        ));
    }
    for (name, n) in [
        ("slices", c.slices),
        ("inside", c.inside),
        ("outside", c.outside),
        ("sub_layers", c.sub_layers),
        ("base_layers", c.base_layers),
        ("across", c.across),
    ] {
        let Some(n) = n else { continue };
        if n == 0 || n > MAX_COUNT {
            return bad(format!(
                "mesh.{name} = {n}: must lie between 1 and {MAX_COUNT} elements"
            ));
        }
    }
    if let Some(n) = c.slices
        && n % 2 == 1
    {
        return bad(format!(
            "mesh.slices = {n}: must be even (the centre's O-grid takes slices/2 cells a side)"
        ));
    }
    if let Some(e) = c.front_element_mm {
        if through {
            return bad(format!(
                "mesh.front_element_mm = {e}: the front-resolving grading is built for embedded, \
                 edge and plate models; through-width models take inside, outside and \
                 front_grading"
            ));
        }
        if !(e.is_finite() && e > 0.0) {
            return bad(format!(
                "mesh.front_element_mm = {e}: must be positive (the element size at the front, mm)"
            ));
        }
    }
    if through && let Some([i, o]) = c.front_band {
        return bad(format!(
            "mesh.front_band = [{i}, {o}]: the band of finer slices is built for embedded, edge \
             and plate models; a through-width front is straight (refine it with across)"
        ));
    }
    if through && let Some([i, o]) = c.layer_band {
        return bad(format!(
            "mesh.layer_band = [{i}, {o}]: the band of full layers is built for embedded, edge \
             and plate models; a through-width model takes sub_layers and base_layers"
        ));
    }
    if let Some(t) = c.accuracy
        && !(t.is_finite() && t > 0.0 && t < 1.0)
    {
        return bad(format!(
            "mesh.accuracy = {t}: must lie between 0 and 1 (the target relative error of G at \
             the front, e.g. 0.02)"
        ));
    }
    if let Some(g) = c.front_grading
        && !(g.is_finite() && g > 0.0)
    {
        return bad(format!(
            "mesh.front_grading = {g}: must be positive (the element next to the front over the \
             one farthest from it; below 1 refines towards the front)"
        ));
    }
    Ok(())
}

/// A layup's plies must make up the sublaminate exactly and leave some homogenised base.
fn layup(s: &Scene) -> Result<(), Error> {
    let Some(l) = &s.layup else { return Ok(()) };
    if matches!(s.geometry, Geometry::ThroughWidth { .. }) {
        return bad(
            "layup: ply-level layers are available for embedded, edge and plate models only".into(),
        );
    }
    positive("layup.ply_mm", l.ply_mm)?;
    if l.sublaminate.is_empty() {
        return bad("layup.sublaminate: at least one ply angle".into());
    }
    if let Some(a) = l
        .sublaminate
        .iter()
        .chain(&l.base_below)
        .find(|a| !a.is_finite())
    {
        return bad(format!("layup: ply angle {a}: must be finite (degrees)"));
    }
    let h = match s.geometry {
        Geometry::Embedded { h_mm, .. }
        | Geometry::Edge { h_mm, .. }
        | Geometry::ThinFilm { h_mm, .. }
        | Geometry::Plate { h_mm, .. }
        | Geometry::ThroughWidth { h_mm, .. } => h_mm,
    };
    let plies = l.sublaminate.len() as f64 * l.ply_mm;
    if (plies - h).abs() > 1e-9 * h {
        return bad(format!(
            "layup: {} sublaminate plies × ply_mm = {} mm make {plies} mm, but geometry.h_mm = \
             {h} mm",
            l.sublaminate.len(),
            l.ply_mm
        ));
    }
    let below = l.base_below.len() as f64 * l.ply_mm;
    let base = s.geometry.base_mm();
    if below >= base {
        return bad(format!(
            "layup.base_below: {} plies × {} mm = {below} mm leave nothing of geometry.base_mm = \
             {base} mm to homogenise",
            l.base_below.len(),
            l.ply_mm
        ));
    }
    Ok(())
}

/// Loads present, finite and non-zero, and only the loads the model uses: strains for the
/// delamination models, transverse loads for the plate (anything else would be ignored).
fn loads(s: &Scene) -> Result<(), Error> {
    let l = &s.loads;
    if matches!(s.geometry, Geometry::Plate { .. }) {
        if l.transverse_n.is_empty() {
            return bad("loads.transverse_n: at least one load for a plate".into());
        }
        if !l.strains.is_empty() {
            return bad(
                "loads.strains: a plate model is loaded by loads.transverse_n only; remove \
                 loads.strains (it would be ignored)"
                    .into(),
            );
        }
        if l.perturbation_n.is_some() {
            return bad(
                "loads.perturbation_n: a plate model is loaded transversely already and gets no \
                 perturbation load; remove it (it would be ignored)"
                    .into(),
            );
        }
    } else {
        if l.strains.is_empty() {
            return bad("loads.strains: at least one strain level".into());
        }
        if !l.transverse_n.is_empty() {
            return bad(
                "loads.transverse_n: only plate models take transverse loads; this model is \
                 loaded by loads.strains (transverse_n would be ignored)"
                    .into(),
            );
        }
    }
    for (k, e) in l.strains.iter().enumerate() {
        if !e.is_finite() || *e == 0.0 {
            return bad(format!(
                "loads.strains[{k}] = {e}: must be finite and non-zero"
            ));
        }
        if e.abs() > MAX_STRAIN {
            return bad(format!(
                "loads.strains[{k}] = {e}: |ε| above {MAX_STRAIN} is outside the material law \
                 (linear elastic in Green–Lagrange strain, §2.2, meant for small strains; in \
                 uniaxial compression it has no stable state beyond ε = −0.42) and far beyond \
                 the failure strain of any laminate (about 0.01)"
            ));
        }
    }
    for (k, p) in l.transverse_n.iter().enumerate() {
        if !p.is_finite() || *p == 0.0 {
            return bad(format!(
                "loads.transverse_n[{k}] = {p}: must be finite and non-zero"
            ));
        }
    }
    if let Some(p) = l.perturbation_n
        && !p.is_finite()
    {
        return bad(format!("loads.perturbation_n = {p}: must be finite"));
    }
    if !l.imperfection_mm.is_finite() {
        return bad(format!(
            "loads.imperfection_mm = {}: must be finite",
            l.imperfection_mm
        ));
    }
    Ok(())
}

/// Legal but suspicious input, in the scene's words: the run goes ahead, and these are printed
/// and kept in results.json.
pub(crate) fn warnings(s: &Scene) -> Vec<String> {
    let mut out = Vec::new();
    let plate = matches!(s.geometry, Geometry::Plate { .. });
    if !plate {
        for (k, e) in s.loads.strains.iter().enumerate() {
            if *e > 0.0 {
                out.push(format!(
                    "loads.strains[{k}] = {e} is tensile: a sublaminate buckles under \
                     compression (negative strains); under tension it stays flat and G = 0"
                ));
            }
            if e.abs() > 0.05 {
                out.push(format!(
                    "loads.strains[{k}] = {e}: |ε| above 5 % is far beyond the failure strain \
                     of any laminate this models"
                ));
            }
        }
        let mut sorted = s.loads.strains.iter().map(|e| e.abs()).collect::<Vec<_>>();
        sorted.dedup();
        if sorted.windows(2).any(|w| w[1] < w[0]) {
            out.push(
                "loads.strains are not in increasing magnitude: the path is followed in the \
                 order given, so a later, smaller level unloads the buckled sublaminate"
                    .into(),
            );
        }
    }
    let (h, base) = match s.geometry {
        Geometry::Embedded { h_mm, base_mm, .. }
        | Geometry::Edge { h_mm, base_mm, .. }
        | Geometry::ThinFilm { h_mm, base_mm, .. }
        | Geometry::Plate { h_mm, base_mm, .. }
        | Geometry::ThroughWidth { h_mm, base_mm, .. } => (h_mm, base_mm),
    };
    let span = match s.geometry {
        Geometry::Embedded { a_mm, b_mm, .. }
        | Geometry::Edge { a_mm, b_mm, .. }
        | Geometry::ThinFilm { a_mm, b_mm, .. } => a_mm.min(b_mm),
        Geometry::Plate { a_mm, .. } | Geometry::ThroughWidth { a_mm, .. } => a_mm,
    };
    if h >= base {
        out.push(format!(
            "geometry.h_mm = {h} mm is not thinner than geometry.base_mm = {base} mm: the \
             models assume a thin sublaminate over a thicker base (thesis §3.2)"
        ));
    }
    if h > 0.25 * span {
        out.push(format!(
            "geometry.h_mm = {h} mm is thick for a delamination of half-span {span} mm (h/a = \
             {:.2}): it buckles, if at all, at strains well beyond any laminate's strength, and \
             plate-like behaviour cannot be expected",
            h / span
        ));
    }
    out
}

#[cfg(test)]
mod tests;
