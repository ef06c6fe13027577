//! Deck text → logical lines (comments dropped, continuations joined, `*INCLUDE` expanded) and
//! keyword lines → name and parameters, with the located errors every handler uses.

use crate::MeshError;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// Where a line comes from: the included file (None for the top-level deck) and its line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Loc {
    pub file: Option<String>,
    pub line: usize,
}

impl std::fmt::Display for Loc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.file {
            Some(file) => write!(f, "{file} line {}", self.line),
            None => write!(f, "line {}", self.line),
        }
    }
}

/// One logical line.
#[derive(Debug, Clone)]
pub(crate) struct Line {
    pub at: Loc,
    pub text: String,
}

/// The error at `at` about `what` (a keyword, `*KEYWORD, PARAMETER` or `*KEYWORD data`).
pub(crate) fn deck_error(at: &Loc, what: &str, reason: impl Into<String>) -> MeshError {
    MeshError::Deck {
        at: at.to_string(),
        what: what.to_string(),
        reason: reason.into(),
    }
}

/// Includes nested deeper than this are refused (a file including itself is caught earlier).
const MAX_DEPTH: usize = 16;

/// The logical lines of `text`: `**` comments and blank lines dropped, a data or keyword line
/// ending in a comma joined with the next line of the same kind, `*INCLUDE, INPUT=FILE`
/// replaced by the lines of FILE (relative to the folder of `path`, the file `text` came from;
/// without a path an include is an error).
pub(crate) fn logical_lines(text: &str, path: Option<&Path>) -> Result<Vec<Line>, MeshError> {
    let mut out = Vec::new();
    let mut open = HashSet::new();
    if let Some(p) = path {
        open.insert(canonical(p));
    }
    expand(text, path, None, 0, &mut open, &mut out)?;
    Ok(out)
}

fn canonical(p: &Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
}

fn expand(
    text: &str,
    path: Option<&Path>,
    label: Option<&str>,
    depth: usize,
    open: &mut HashSet<PathBuf>,
    out: &mut Vec<Line>,
) -> Result<(), MeshError> {
    // Joined lines of this file first, then includes expanded in place.
    let mut lines: Vec<Line> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim();
        if l.is_empty() || l.starts_with("**") {
            continue;
        }
        match lines.last_mut() {
            Some(prev)
                if prev.text.ends_with(',') && !l.starts_with('*') && !is_include(&prev.text) =>
            {
                prev.text.push(' ');
                prev.text.push_str(l);
            }
            _ => lines.push(Line {
                at: Loc {
                    file: label.map(str::to_string),
                    line: i + 1,
                },
                text: l.to_string(),
            }),
        }
    }
    for line in lines {
        if !is_include(&line.text) {
            out.push(line);
            continue;
        }
        let kw = Keyword::parse(&line.text, line.at.clone());
        kw.allow(&["INPUT"])?;
        let name = kw
            .get("INPUT")
            .map(|s| s.trim_matches('"'))
            .filter(|s| !s.is_empty())
            .ok_or_else(|| kw.error("INPUT= missing"))?;
        let Some(parent) = path else {
            return Err(kw.param_error(
                "INPUT",
                "an include needs the deck's file to resolve it: read the deck with read_inp_file",
            ));
        };
        if depth + 1 > MAX_DEPTH {
            return Err(kw.param_error(
                "INPUT",
                format!("includes nested more than {MAX_DEPTH} deep"),
            ));
        }
        let file = parent.parent().unwrap_or_else(|| Path::new(".")).join(name);
        let key = canonical(&file);
        if open.contains(&key) {
            return Err(kw.param_error("INPUT", format!("{name} includes itself")));
        }
        let body = std::fs::read_to_string(&file)
            .map_err(|e| kw.param_error("INPUT", format!("cannot read {}: {e}", file.display())))?;
        open.insert(key.clone());
        expand(&body, Some(&file), Some(name), depth + 1, open, out)?;
        open.remove(&key);
    }
    Ok(())
}

fn is_include(text: &str) -> bool {
    text.starts_with('*') && keyword_name(text) == "INCLUDE"
}

fn keyword_name(text: &str) -> String {
    text[1..]
        .split(',')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_uppercase()
}

/// One keyword line: name (upper case, single spaces) and parameters in order (keys upper case
/// with single spaces; values as written, trimmed).
#[derive(Debug, Clone)]
pub(crate) struct Keyword {
    pub name: String,
    pub params: Vec<(String, String)>,
    pub at: Loc,
}

impl Keyword {
    pub fn parse(text: &str, at: Loc) -> Self {
        let name = keyword_name(text);
        let mut params = Vec::new();
        for p in text[1..].split(',').skip(1) {
            let mut kv = p.splitn(2, '=');
            let key = kv
                .next()
                .unwrap_or("")
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
                .to_uppercase();
            let value = kv.next().unwrap_or("").trim().to_string();
            if !key.is_empty() {
                params.push((key, value));
            }
        }
        Self { name, params, at }
    }

    /// `*NAME` as written in messages.
    pub fn what(&self) -> String {
        format!("*{}", self.name)
    }

    /// An error about the keyword line.
    pub fn error(&self, reason: impl Into<String>) -> MeshError {
        deck_error(&self.at, &self.what(), reason)
    }

    /// An error about parameter `key` of the keyword line.
    pub fn param_error(&self, key: &str, reason: impl Into<String>) -> MeshError {
        deck_error(&self.at, &format!("*{}, {key}", self.name), reason)
    }

    /// An error about a data line of this keyword.
    pub fn data_error(&self, at: &Loc, reason: impl Into<String>) -> MeshError {
        deck_error(at, &format!("*{} data", self.name), reason)
    }

    /// Refuses any parameter not in `allowed` (naming it) and any given twice.
    pub fn allow(&self, allowed: &[&str]) -> Result<(), MeshError> {
        for (i, (k, _)) in self.params.iter().enumerate() {
            if !allowed.contains(&k.as_str()) {
                return Err(self.param_error(
                    k,
                    format!(
                        "parameter not supported{}",
                        if allowed.is_empty() {
                            " (this keyword takes none)".to_string()
                        } else {
                            format!(" (supported: {})", allowed.join(", "))
                        }
                    ),
                ));
            }
            if self.params[..i].iter().any(|(j, _)| j == k) {
                return Err(self.param_error(k, "parameter given twice"));
            }
        }
        Ok(())
    }

    /// The value of parameter `key`, if given.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// The value of a parameter that must be given and not empty.
    pub fn require(&self, key: &str) -> Result<&str, MeshError> {
        self.get(key)
            .filter(|v| !v.is_empty())
            .ok_or_else(|| self.error(format!("{key}= missing")))
    }

    /// Whether flag parameter `key` is on: given bare or `=YES`; `=NO` is off; other values
    /// are refused.
    pub fn flag(&self, key: &str) -> Result<bool, MeshError> {
        match self.get(key).map(str::to_uppercase).as_deref() {
            None | Some("NO") => Ok(false),
            Some("") | Some("YES") => Ok(true),
            Some(other) => Err(self.param_error(key, format!("expected YES or NO, got '{other}'"))),
        }
    }

    /// The upper-case value of `key` (None if absent), refused unless among `choices`.
    pub fn choice(&self, key: &str, choices: &[&str]) -> Result<Option<String>, MeshError> {
        let Some(v) = self.get(key) else {
            return Ok(None);
        };
        let v = v
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_uppercase();
        if choices.contains(&v.as_str()) {
            Ok(Some(v))
        } else {
            Err(self.param_error(
                key,
                format!("'{v}' not supported (supported: {})", choices.join(", ")),
            ))
        }
    }
}

/// The comma-separated fields of a data line, trimmed; empty fields kept (position matters).
pub(crate) fn fields(line: &str) -> Vec<&str> {
    let mut f: Vec<&str> = line.split(',').map(str::trim).collect();
    while f.last().is_some_and(|s| s.is_empty()) {
        f.pop();
    }
    f
}

/// A real number as Fortran reads it (`1.5d3` too), finite.
pub(crate) fn float(kw: &Keyword, at: &Loc, f: &str) -> Result<f64, MeshError> {
    let v: f64 = f
        .replace(['d', 'D'], "e")
        .parse()
        .map_err(|_| kw.data_error(at, format!("'{f}' is not a number")))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(kw.data_error(at, format!("'{f}' is not finite")))
    }
}

/// A non-negative integer.
pub(crate) fn int(kw: &Keyword, at: &Loc, f: &str) -> Result<usize, MeshError> {
    f.parse()
        .map_err(|_| kw.data_error(at, format!("'{f}' is not a non-negative integer")))
}

/// A real-valued parameter.
pub(crate) fn float_param(kw: &Keyword, key: &str) -> Result<Option<f64>, MeshError> {
    kw.get(key)
        .map(|v| {
            v.replace(['d', 'D'], "e")
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| kw.param_error(key, format!("'{v}' is not a number")))
        })
        .transpose()
}

/// An integer parameter.
pub(crate) fn int_param(kw: &Keyword, key: &str) -> Result<Option<usize>, MeshError> {
    kw.get(key)
        .map(|v| {
            v.parse::<usize>()
                .map_err(|_| kw.param_error(key, format!("'{v}' is not a non-negative integer")))
        })
        .transpose()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keywords_parse_with_spaces_and_case() {
        let kw = Keyword::parse(
            "*Node Print ,  nset = Tip , frequency=2, totals",
            Loc {
                file: None,
                line: 3,
            },
        );
        assert_eq!(kw.name, "NODE PRINT");
        assert_eq!(kw.get("NSET"), Some("Tip"));
        assert_eq!(kw.get("FREQUENCY"), Some("2"));
        assert_eq!(kw.get("TOTALS"), Some(""));
        let e = kw.allow(&["NSET", "FREQUENCY"]).unwrap_err().to_string();
        assert!(
            e.contains("line 3") && e.contains("*NODE PRINT, TOTALS"),
            "{e}"
        );
        let twice = Keyword::parse(
            "*STEP, INC=3, INC=4",
            Loc {
                file: None,
                line: 1,
            },
        );
        assert!(
            twice
                .allow(&["INC"])
                .unwrap_err()
                .to_string()
                .contains("twice")
        );
    }

    #[test]
    fn continuations_join_and_comments_drop() {
        let lines =
            logical_lines("** c\n*ELEMENT, TYPE=C3D8,\n ELSET=E\n1, 2,\n3\n\n", None).unwrap();
        assert_eq!(lines.len(), 2);
        assert_eq!(lines[0].text, "*ELEMENT, TYPE=C3D8, ELSET=E");
        assert_eq!(lines[1].text, "1, 2, 3");
        assert_eq!(lines[1].at.line, 4);
    }

    #[test]
    fn includes_need_a_file() {
        let e = logical_lines("*INCLUDE, INPUT=mesh.inp\n", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 1") && e.contains("*INCLUDE, INPUT") && e.contains("read_inp_file"),
            "{e}"
        );
    }
}
