//! Parametric studies in one scene (docs/SCENES.md, `[sweep]`): a scene whose `[sweep]` table
//! lists values for some of its own fields, by their TOML path, becomes one scene per
//! combination of those values (a case), each run into its own folder and merged into one
//! table and plot.
//!
//! ```toml
//! [sweep]
//! "geometry.a_mm" = [10, 15, 20, 30]
//! "geometry.h_mm" = [0.2, 0.4]
//! "geometry.b_mm" = [10, 15, 20, 30]
//! zip = [["geometry.a_mm", "geometry.b_mm"]]   # these vary together (circles)
//! x = "geometry.a_mm"                          # the plot's abscissa
//! ```
//!
//! The lists combine as a Cartesian product, the last field varying fastest; the fields of a
//! `zip` group vary together (lists of one length) and count as one factor. A study is three
//! steps on disk, each of which can be repeated or run elsewhere ([`plan()`], [`run()`],
//! [`merge()`]): `DIR/plan.json` with the resolved scenes `DIR/cases/NNNN/scene.toml`; each
//! case's results (results.json, front CSVs, …) beside its scene, written as `nonlin3d run`
//! writes them (a case whose results.json says `"complete": true` is never run again); and
//! `DIR/study.csv`, `DIR/study.json`, `DIR/study.svg` (and the wall times, `DIR/study-wall.csv`).

pub mod cli;
pub mod cluster;
pub mod merge;
pub mod plan;
mod plot;
mod row;
pub mod run;
pub mod slurm;

pub use merge::merge;
pub use plan::{Case, Plan, plan};
pub use row::Row;
pub use run::{CaseState, RunOptions, run, status};

use crate::Error;
use toml::{Table, Value};

/// The name of the table in a scene.
pub const TABLE: &str = "sweep";

/// A `[sweep]` table, read.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSpec {
    /// Each swept field with its values, sorted by path.
    pub fields: Vec<(String, Vec<Value>)>,
    /// Factors of the product, in order: groups of indices into `fields` that vary together
    /// (a field alone, or a `zip` group).
    pub factors: Vec<Vec<usize>>,
    /// The field against which the study is plotted.
    pub x: String,
}

fn bad<T>(message: String) -> Result<T, Error> {
    Err(Error::Sweep(format!("[sweep] {message}")))
}

/// Whether a scene's text has a `[sweep]` table (it is a study, not one run); false for text
/// that is not TOML (the scene reader then says why).
pub fn has_sweep(text: &str) -> bool {
    text.parse::<Table>().is_ok_and(|t| t.contains_key(TABLE))
}

/// Splits a scene's text into the scene without `[sweep]` and the sweep read from it.
pub fn split(text: &str) -> Result<(Table, SweepSpec), Error> {
    let mut table: Table = text.parse().map_err(|e| Error::Scene(format!("{e}")))?;
    let Some(sweep) = table.remove(TABLE) else {
        return bad("missing: the scene has no [sweep] table".into());
    };
    let Value::Table(sweep) = sweep else {
        return bad("must be a table of field paths and lists of values".into());
    };
    Ok((table, read_spec(sweep)?))
}

/// Reads `[sweep]`: fields by path (`"geometry.a_mm" = […]` or nested tables, which are the
/// same in TOML), `zip` and `x`.
fn read_spec(mut sweep: Table) -> Result<SweepSpec, Error> {
    let zip = sweep.remove("zip");
    let x = sweep.remove("x");
    let mut fields = Vec::new();
    flatten(&sweep, "", &mut fields)?;
    if fields.is_empty() {
        return bad("lists no field: write e.g. \"geometry.a_mm\" = [10.0, 15.0]".into());
    }
    fields.sort_by(|a, b| a.0.cmp(&b.0));
    let index = |name: &str| fields.iter().position(|(p, _)| p == name);
    let mut grouped = vec![false; fields.len()];
    let mut factors = Vec::new();
    for group in zip_groups(zip)? {
        let mut members = Vec::new();
        for name in &group {
            let Some(i) = index(name) else {
                return bad(format!("zip names '{name}', which is not a swept field"));
            };
            if grouped[i] {
                return bad(format!("zip names '{name}' twice"));
            }
            grouped[i] = true;
            members.push(i);
        }
        let n = fields[members[0]].1.len();
        if let Some(&j) = members.iter().find(|&&j| fields[j].1.len() != n) {
            return bad(format!(
                "zip: '{}' has {n} values and '{}' {}: fields zipped together need lists of \
                 one length",
                fields[members[0]].0,
                fields[j].0,
                fields[j].1.len()
            ));
        }
        factors.push(members);
    }
    factors.extend((0..fields.len()).filter(|&i| !grouped[i]).map(|i| vec![i]));
    factors.sort();
    let x = match x {
        None => {
            // The field with the most values (the first by path among equals).
            let most = fields.iter().map(|f| f.1.len()).max().unwrap_or(0);
            fields
                .iter()
                .find(|f| f.1.len() == most)
                .map(|f| f.0.clone())
                .unwrap_or_default()
        }
        Some(Value::String(s)) if index(&s).is_some() => s,
        Some(other) => {
            return bad(format!(
                "x = {other}: the path of a swept field (one of {})",
                fields
                    .iter()
                    .map(|f| f.0.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    };
    Ok(SweepSpec { fields, factors, x })
}

/// `zip = [["a", "b"], …]`: the groups, each of two or more paths.
fn zip_groups(zip: Option<Value>) -> Result<Vec<Vec<String>>, Error> {
    let Some(zip) = zip else {
        return Ok(Vec::new());
    };
    let shape = || {
        bad("zip must be a list of lists of field paths, e.g. [[\"geometry.a_mm\", \"geometry.b_mm\"]]".into())
    };
    let Value::Array(groups) = zip else {
        return shape();
    };
    let mut out = Vec::new();
    for g in groups {
        let Value::Array(names) = g else {
            return shape();
        };
        let names: Option<Vec<String>> = names
            .into_iter()
            .map(|n| n.as_str().map(str::to_string))
            .collect();
        match names {
            Some(n) if n.len() >= 2 => out.push(n),
            Some(_) => return bad("zip: a group names two fields or more".into()),
            None => return shape(),
        }
    }
    Ok(out)
}

/// Every array under `table` as a field `prefix.key`.
fn flatten(table: &Table, prefix: &str, out: &mut Vec<(String, Vec<Value>)>) -> Result<(), Error> {
    for (key, value) in table {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match value {
            Value::Table(t) => flatten(t, &path, out)?,
            Value::Array(values) if values.is_empty() => {
                return bad(format!(
                    "\"{path}\" = []: an empty list (give one value or more)"
                ));
            }
            Value::Array(values) => out.push((path, values.clone())),
            other => {
                return bad(format!(
                    "\"{path}\" = {other}: a list of values, e.g. \"{path}\" = [{other}]"
                ));
            }
        }
    }
    Ok(())
}

/// `table` with `value` at the dotted `path` (tables on the way made when missing).
pub fn substitute(table: &mut Table, path: &str, value: Value) -> Result<(), Error> {
    let mut parts: Vec<&str> = path.split('.').collect();
    let last = parts.pop().unwrap_or_default();
    let mut at = table;
    for (k, part) in parts.iter().enumerate() {
        let entry = at
            .entry(part.to_string())
            .or_insert_with(|| Value::Table(Table::new()));
        at = match entry {
            Value::Table(t) => t,
            _ => {
                return bad(format!(
                    "\"{path}\": '{}' is a value in the scene, not a table",
                    parts[..=k].join(".")
                ));
            }
        };
    }
    at.insert(last.to_string(), value);
    Ok(())
}

/// A value as written in TOML (`15.0`, `"hex8"`, `[0.0, 90.0]`).
pub fn show(value: &Value) -> String {
    value.to_string()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn spec(text: &str) -> Result<SweepSpec, Error> {
        split(&format!("title = \"t\"\n[sweep]\n{text}")).map(|s| s.1)
    }

    #[test]
    fn fields_zip_and_x_are_read() {
        let s = spec(
            "\"geometry.a_mm\" = [10, 20]\ngeometry.b_mm = [10, 20]\n\"geometry.h_mm\" = [0.2, 0.3, 0.4]\n\
             zip = [[\"geometry.a_mm\", \"geometry.b_mm\"]]",
        )
        .unwrap();
        let names: Vec<&str> = s.fields.iter().map(|f| f.0.as_str()).collect();
        assert_eq!(names, ["geometry.a_mm", "geometry.b_mm", "geometry.h_mm"]);
        assert_eq!(s.factors, [vec![0, 1], vec![2]]);
        assert_eq!(s.x, "geometry.h_mm");
    }

    #[test]
    fn bad_tables_are_named() {
        for (text, words) in [
            ("\"geometry.a_mm\" = []", "\"geometry.a_mm\" = []"),
            ("\"geometry.a_mm\" = 3.0", "a list of values"),
            (
                "a = [1]\nb = [1, 2]\nzip = [[\"a\", \"b\"]]",
                "lists of one length",
            ),
            ("a = [1]\nzip = [[\"a\", \"c\"]]", "'c'"),
            ("a = [1]\nx = \"b\"", "x = \"b\""),
            ("", "lists no field"),
        ] {
            let e = spec(text).unwrap_err().to_string();
            assert!(e.contains(words), "{text}: {e}");
        }
    }

    #[test]
    fn substitution_walks_and_makes_tables() {
        let mut t: Table = "[geometry]\na_mm = 1.0\n".parse().unwrap();
        substitute(&mut t, "geometry.a_mm", Value::Float(2.0)).unwrap();
        substitute(&mut t, "mesh.slices", Value::Integer(4)).unwrap();
        assert_eq!(t["geometry"]["a_mm"].as_float(), Some(2.0));
        assert_eq!(t["mesh"]["slices"].as_integer(), Some(4));
        let e = substitute(&mut t, "geometry.a_mm.x", Value::Integer(1)).unwrap_err();
        assert!(e.to_string().contains("geometry.a_mm"), "{e}");
    }
}
