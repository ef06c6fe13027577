//! `nonlin3d sweep plan`: a scene with `[sweep]` expanded into one resolved scene per case
//! (`DIR/cases/NNNN/scene.toml`, every default filled in) and `DIR/plan.json` (case id →
//! parameters, the scene's SHA-256, the swept fields). The folder is written under a temporary
//! name beside DIR and renamed into place, so a failed plan leaves nothing behind.

use super::{SweepSpec, bad, show, split, substitute};
use crate::provenance::sha256_hex;
use crate::{Error, Scene};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::{Table, Value};

/// The plan's file in a study folder.
pub const PLAN: &str = "plan.json";

/// Most cases one plan may hold (a product of long lists grows fast).
pub const MAX_CASES: usize = 100_000;

/// One case of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Case {
    /// 0-based id (the job-array index).
    pub id: usize,
    /// Its folder, relative to the study folder (`cases/0007`).
    pub folder: String,
    /// Each swept field's value in this case, by path.
    pub parameters: BTreeMap<String, serde_json::Value>,
    /// SHA-256 of the case's `scene.toml`.
    pub scene_sha256: String,
}

impl Case {
    /// `geometry.a_mm = 10, geometry.h_mm = 0.2`.
    pub fn label(&self) -> String {
        self.parameters
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// `DIR/plan.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// `nonlin3d VERSION` that planned it.
    pub program: String,
    /// The scene's title (without the case's parameters).
    pub title: String,
    /// The scene file as given.
    pub scene: String,
    /// SHA-256 of the scene file's bytes.
    pub scene_sha256: String,
    /// Swept fields, by path, sorted.
    pub fields: Vec<String>,
    /// Groups of fields that vary together (`zip`).
    pub zip: Vec<Vec<String>>,
    /// The plot's abscissa.
    pub x: String,
    /// The cases, by id.
    pub cases: Vec<Case>,
}

impl Plan {
    /// Reads `DIR/plan.json`.
    pub fn read(dir: &Path) -> Result<Self, Error> {
        let path = dir.join(PLAN);
        let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
            path: path.clone(),
            source,
        })?;
        serde_json::from_str(&text).map_err(|e| {
            Error::Sweep(format!(
                "{}: not a study's plan ({e}); plan one with `nonlin3d sweep plan`",
                path.display()
            ))
        })
    }

    /// A case's folder.
    pub fn case_dir(&self, dir: &Path, case: &Case) -> PathBuf {
        dir.join(&case.folder)
    }
}

/// One case, resolved: its parameters and scene.
#[derive(Debug, Clone)]
pub struct Resolved {
    /// Field path → value.
    pub parameters: Vec<(String, Value)>,
    /// The scene, validated.
    pub scene: Scene,
    /// Its TOML text (every default filled in).
    pub text: String,
}

/// The cases of a scene with `[sweep]`: each field's values checked on their own first (an
/// unknown field or a value of the wrong type is named by its path), then every combination
/// substituted and validated as a scene (errors name the case and its values).
pub fn expand(text: &str) -> Result<(SweepSpec, Vec<Resolved>), Error> {
    let (base, spec) = split(text)?;
    for (path, values) in &spec.fields {
        for v in values {
            let mut t = base.clone();
            substitute(&mut t, path, v.clone())?;
            if let Err(e) = Value::Table(t).try_into::<Scene>() {
                return bad(format!("\"{path}\" = {}: {}", show(v), e.message()));
            }
        }
    }
    let count = spec
        .factors
        .iter()
        .try_fold(1_usize, |n, f| n.checked_mul(spec.fields[f[0]].1.len()))
        .filter(|&n| n <= MAX_CASES);
    let Some(count) = count else {
        return bad(format!("more than {MAX_CASES} cases: shorten the lists"));
    };
    let title = base
        .get("title")
        .and_then(Value::as_str)
        .unwrap_or_default()
        .to_string();
    let titled = !spec.fields.iter().any(|f| f.0 == "title");
    let mut cases = Vec::with_capacity(count);
    for id in 0..count {
        let parameters = combination(&spec, id);
        let label = parameters
            .iter()
            .map(|(k, v)| format!("{k} = {}", show(v)))
            .collect::<Vec<_>>()
            .join(", ");
        let mut t = base.clone();
        for (path, v) in &parameters {
            substitute(&mut t, path, v.clone())?;
        }
        if titled {
            t.insert("title".into(), Value::String(format!("{title} [{label}]")));
        }
        let scene = Scene::from_toml(&t.to_string()).map_err(|e| {
            let what = match e {
                Error::Scene(m) => m,
                other => other.to_string(),
            };
            Error::Sweep(format!("[sweep] case {id} ({label}): {what}"))
        })?;
        let text = scene.to_toml()?;
        cases.push(Resolved {
            parameters,
            scene,
            text,
        });
    }
    Ok((spec, cases))
}

/// The values of case `id`: the factors' indices in mixed radix, the last factor fastest.
fn combination(spec: &SweepSpec, id: usize) -> Vec<(String, Value)> {
    let mut rest = id;
    let mut pick = vec![0; spec.fields.len()];
    for factor in spec.factors.iter().rev() {
        let n = spec.fields[factor[0]].1.len();
        for &i in factor {
            pick[i] = rest % n;
        }
        rest /= n;
    }
    spec.fields
        .iter()
        .zip(pick)
        .map(|((path, values), k)| (path.clone(), values[k].clone()))
        .collect()
}

/// The case folder's name: `0007` (wider when there are more than 10 000 cases).
fn folder(id: usize, count: usize) -> String {
    let width = count.saturating_sub(1).to_string().len().max(4);
    format!("cases/{id:0width$}")
}

/// Plans the study of `scene` (a file with `[sweep]`) into `out`. An `out` holding the same
/// plan already is kept as it is (its results too: the study resumes), a deleted case folder
/// planned again; one holding anything else is refused.
pub fn plan(scene: &Path, out: &Path) -> Result<Plan, Error> {
    plan_with(scene, out, None)
}

/// What is written into a study folder with its plan (the Slurm script,
/// [`super::slurm::write`]): called with the folder being written (a temporary one, renamed
/// into place after, or the study folder itself when it holds this plan already), the study
/// folder's absolute path, the plan and its cases. An error leaves nothing planned.
pub type Extra<'a> = &'a dyn Fn(&Path, &Path, &Plan, &[Resolved]) -> Result<(), Error>;

/// [`plan()`], with `extra` written into the folder before it is renamed into place.
pub fn plan_with(scene: &Path, out: &Path, extra: Option<Extra>) -> Result<Plan, Error> {
    let bytes = std::fs::read(scene).map_err(|source| Error::Io {
        path: scene.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    let (spec, resolved) = expand(&text).map_err(|e| match e {
        Error::Sweep(m) | Error::Scene(m) => Error::Sweep(format!("{}: {m}", scene.display())),
        other => other,
    })?;
    let count = resolved.len();
    let cases: Vec<Case> = resolved
        .iter()
        .enumerate()
        .map(|(id, r)| Case {
            id,
            folder: folder(id, count),
            parameters: r
                .parameters
                .iter()
                .map(|(k, v)| (k.clone(), serde_json::to_value(v).unwrap_or_default()))
                .collect(),
            scene_sha256: sha256_hex(r.text.as_bytes()),
        })
        .collect();
    let plan = Plan {
        program: format!("nonlin3d {}", env!("CARGO_PKG_VERSION")),
        title: text
            .parse::<Table>()
            .ok()
            .and_then(|t| t.get("title").and_then(Value::as_str).map(str::to_string))
            .unwrap_or_default(),
        scene: scene.display().to_string(),
        scene_sha256: sha256_hex(&bytes),
        fields: spec.fields.iter().map(|f| f.0.clone()).collect(),
        zip: spec
            .factors
            .iter()
            .filter(|f| f.len() > 1)
            .map(|f| f.iter().map(|&i| spec.fields[i].0.clone()).collect())
            .collect(),
        x: spec.x.clone(),
        cases,
    };
    if out.join(PLAN).is_file() {
        let old = Plan::read(out)?;
        if old.cases == plan.cases {
            // The same study: a case folder deleted since is planned again (and run next).
            for (case, r) in old.cases.iter().zip(&resolved) {
                let d = old.case_dir(out, case);
                if !d.join("scene.toml").is_file() {
                    std::fs::create_dir_all(&d).map_err(|source| Error::Io {
                        path: d.clone(),
                        source,
                    })?;
                    crate::output::write_atomic(&d.join("scene.toml"), r.text.as_bytes())?;
                }
            }
            if let Some(extra) = extra {
                let abs = out.canonicalize().map_err(|source| Error::Io {
                    path: out.to_path_buf(),
                    source,
                })?;
                extra(out, &abs, &old, &resolved)?;
            }
            return Ok(old);
        }
        return bad(format!(
            "{} holds another study's plan: remove it or plan into another folder",
            out.display()
        ));
    }
    write(out, &plan, &resolved, extra)?;
    Ok(plan)
}

/// Writes the plan into a temporary folder beside `out` and renames it into place.
fn write(
    out: &Path,
    plan: &Plan,
    resolved: &[Resolved],
    extra: Option<Extra>,
) -> Result<(), Error> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| Error::Io { path, source }
    };
    let name = out
        .file_name()
        .map_or_else(|| "study".into(), |n| n.to_string_lossy().into_owned());
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(io(&parent))?;
    let tmp = parent.join(format!(".{name}.plan-{}.partial", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let result = (|| {
        for (case, r) in plan.cases.iter().zip(resolved) {
            let d = tmp.join(&case.folder);
            std::fs::create_dir_all(&d).map_err(io(&d))?;
            let p = d.join("scene.toml");
            std::fs::write(&p, r.text.as_bytes()).map_err(io(&p))?;
        }
        let p = tmp.join(PLAN);
        std::fs::write(&p, serde_json::to_string_pretty(plan)?).map_err(io(&p))?;
        if let Some(extra) = extra {
            let abs = parent.canonicalize().map_err(io(&parent))?.join(&name);
            extra(&tmp, &abs, plan, resolved)?;
        }
        // An empty `out` is replaced; anything else in it is refused by the rename.
        std::fs::rename(&tmp, out).map_err(|source| {
            Error::Sweep(format!(
                "{}: {source} (plan into a new or empty folder)",
                out.display()
            ))
        })
    })();
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    result
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::scene::THESIS_SCENE;

    fn study(sweep: &str) -> String {
        format!("{THESIS_SCENE}\n[sweep]\n{sweep}\n")
    }

    #[test]
    fn the_product_runs_the_last_factor_fastest() {
        let text = study("\"geometry.a_mm\" = [10, 12]\n\"geometry.h_mm\" = [0.3, 0.4, 0.5]");
        let (_, cases) = expand(&text).unwrap();
        assert_eq!(cases.len(), 6);
        let pick = |c: &Resolved| match c.scene.geometry {
            crate::scene::Geometry::Embedded { a_mm, h_mm, .. } => (a_mm, h_mm),
            _ => unreachable!(),
        };
        assert_eq!(pick(&cases[0]), (10.0, 0.3));
        assert_eq!(pick(&cases[2]), (10.0, 0.5));
        assert_eq!(pick(&cases[3]), (12.0, 0.3));
        assert!(cases[4].scene.title.contains("geometry.a_mm = 12"));
    }

    #[test]
    fn zipped_fields_vary_together() {
        let text = study(
            "\"geometry.a_mm\" = [10, 12]\n\"geometry.b_mm\" = [10, 12]\n\
             zip = [[\"geometry.a_mm\", \"geometry.b_mm\"]]",
        );
        let (_, cases) = expand(&text).unwrap();
        assert_eq!(cases.len(), 2);
        assert!(cases[1].text.contains("b_mm = 12.0"), "{}", cases[1].text);
    }

    #[test]
    fn unknown_fields_wrong_types_and_bad_cases_are_named() {
        for (sweep, words) in [
            ("\"geometry.aa_mm\" = [1.0]", "geometry.aa_mm"),
            ("\"mesh.slices\" = [4.5]", "\"mesh.slices\" = 4.5"),
            (
                "\"geometry.a_mm\" = [\"big\"]",
                "\"geometry.a_mm\" = \"big\"",
            ),
            (
                "\"geometry.a_mm\" = [10.0, 80.0]",
                "case 1 (geometry.a_mm = 80.0)",
            ),
        ] {
            let e = expand(&study(sweep)).unwrap_err().to_string();
            assert!(e.contains(words), "{sweep}: {e}");
        }
    }
}
