//! Seeded mutations of scene (TOML) and deck (.inp) text: byte flips, truncation, numeric
//! extremes, swapped or negated numbers, deleted and duplicated lines and sections, and
//! format-aware ones — other enum values, bad materials, inserted options (scenes); inverted
//! elements, swapped element nodes, removed sets, changed keyword parameters, bad materials,
//! inserted blocks (decks). Each mutation is described in words for the failure report.

use crate::pools::*;
use crate::rng::Rng;

#[path = "mutate/deck.rs"]
mod deck;
use deck::{element_nodes, insert_block, param_swap, remove_set};

/// The two input formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A TOML scene.
    Scene,
    /// An Abaqus/CalculiX deck.
    Deck,
}

impl Format {
    /// By file extension: `.toml` scenes, `.inp` decks.
    pub fn of(path: &std::path::Path) -> Option<Self> {
        match path.extension()?.to_str()? {
            "toml" => Some(Self::Scene),
            "inp" => Some(Self::Deck),
            _ => None,
        }
    }
}

/// A mutated input and what was done to it.
pub struct Mutated {
    /// The bytes (byte flips and truncation may leave invalid UTF-8).
    pub bytes: Vec<u8>,
    /// One line per mutation.
    pub notes: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    ByteFlip,
    Truncate,
    Numeric,
    SwapNumbers,
    DeleteLines,
    DeleteSection,
    DuplicateLines,
    DuplicateSection,
    EnumSwap,
    BadMaterial,
    Insert,
    InvertElement,
    SwapElementNodes,
    RemoveSet,
    ParamSwap,
}

impl Op {
    fn byte_level(self) -> bool {
        matches!(self, Self::ByteFlip | Self::Truncate)
    }
}

const SCENE_OPS: &[(Op, usize)] = &[
    (Op::ByteFlip, 8),
    (Op::Truncate, 5),
    (Op::Numeric, 24),
    (Op::SwapNumbers, 4),
    (Op::DeleteLines, 8),
    (Op::DeleteSection, 5),
    (Op::DuplicateLines, 5),
    (Op::DuplicateSection, 4),
    (Op::EnumSwap, 9),
    (Op::BadMaterial, 8),
    (Op::Insert, 14),
];

const DECK_OPS: &[(Op, usize)] = &[
    (Op::ByteFlip, 8),
    (Op::Truncate, 5),
    (Op::Numeric, 22),
    (Op::SwapNumbers, 3),
    (Op::DeleteLines, 7),
    (Op::DeleteSection, 6),
    (Op::DuplicateLines, 5),
    (Op::DuplicateSection, 5),
    (Op::InvertElement, 6),
    (Op::SwapElementNodes, 4),
    (Op::RemoveSet, 7),
    (Op::ParamSwap, 6),
    (Op::BadMaterial, 6),
    (Op::Insert, 8),
];

/// Applies one to three mutations (60 %, 25 %, 15 %) to `text`, chosen by `rng`.
pub fn mutate(rng: &mut Rng, text: &str, format: Format) -> Mutated {
    let count = match rng.below(20) {
        0..=11 => 1,
        12..=16 => 2,
        _ => 3,
    };
    let table = match format {
        Format::Scene => SCENE_OPS,
        Format::Deck => DECK_OPS,
    };
    let total: usize = table.iter().map(|t| t.1).sum();
    let mut ops: Vec<Op> = (0..count)
        .map(|_| {
            let mut r = rng.below(total);
            let mut chosen = table[0].0;
            for &(op, w) in table {
                if r < w {
                    chosen = op;
                    break;
                }
                r -= w;
            }
            chosen
        })
        .collect();
    // Text-level mutations first: byte flips and truncation may leave invalid UTF-8.
    ops.sort_by_key(|o| o.byte_level());
    let mut text = text.to_string();
    let mut notes = Vec::new();
    let mut bytes: Option<Vec<u8>> = None;
    for op in ops {
        if op.byte_level() {
            let b = bytes.get_or_insert_with(|| text.as_bytes().to_vec());
            notes.push(bytewise(op, rng, b));
        } else {
            // A mutation with nothing to act on (no element lines in a scene) falls back to
            // a numeric extreme, then to deleting a line.
            let done = textual(op, rng, &text, format)
                .or_else(|| textual(Op::Numeric, rng, &text, format))
                .or_else(|| textual(Op::DeleteLines, rng, &text, format));
            if let Some((t, n)) = done {
                text = t;
                notes.push(n);
            }
        }
    }
    Mutated {
        bytes: bytes.unwrap_or_else(|| text.into_bytes()),
        notes,
    }
}

/// Line number (1-based) of byte `at`.
fn line_of(bytes: &[u8], at: usize) -> usize {
    1 + bytes[..at.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// A line as quoted in a note: trimmed, at most 60 characters.
fn quote(line: &str) -> String {
    let t = line.trim();
    let mut q: String = t.chars().take(60).collect();
    if t.chars().count() > 60 {
        q.push('…');
    }
    format!("`{q}`")
}

fn bytewise(op: Op, rng: &mut Rng, b: &mut Vec<u8>) -> String {
    if b.is_empty() {
        return "nothing to flip or truncate (empty input)".into();
    }
    let at = rng.below(b.len());
    let line = line_of(b, at);
    if op == Op::Truncate {
        let n = b.len();
        b.truncate(at);
        return format!("truncated to {at} of {n} bytes (inside line {line})");
    }
    let old = b[at];
    b[at] = if old.is_ascii() && rng.chance(0.85) {
        old ^ (1 << rng.below(7))
    } else {
        rng.below(256) as u8
    };
    format!(
        "byte {at} (line {line}) {:?} → {:?}",
        old as char, b[at] as char
    )
}

fn textual(op: Op, rng: &mut Rng, text: &str, format: Format) -> Option<(String, String)> {
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    match op {
        Op::Numeric => numeric(rng, text, format),
        Op::SwapNumbers => swap_numbers(rng, text, format),
        Op::DeleteLines => {
            let candidates: Vec<usize> = (0..lines.len())
                .filter(|&k| !lines[k].trim().is_empty())
                .collect();
            let k = *rng.pick(non_empty(&candidates)?);
            let n = (1 + rng.below(3) * usize::from(rng.chance(0.3))).min(lines.len() - k);
            let note = format!(
                "deleted {n} line(s) from line {}: {}",
                k + 1,
                quote(lines[k])
            );
            let mut out = lines.clone();
            out.drain(k..k + n);
            Some((out.concat(), note))
        }
        Op::DuplicateLines => {
            let k = rng.below(non_empty(&lines)?.len());
            let to = if rng.chance(0.7) {
                k + 1
            } else {
                rng.below(lines.len() + 1)
            };
            let mut out = lines.clone();
            let mut copy = lines[k].to_string();
            if !copy.ends_with('\n') {
                copy.push('\n');
            }
            out.insert(to, &copy);
            let note = format!(
                "line {} {} copied to line {}",
                k + 1,
                quote(lines[k]),
                to + 1
            );
            Some((out.concat(), note))
        }
        Op::DeleteSection | Op::DuplicateSection => {
            let secs = sections(&lines, format);
            let &(a, b) = rng.pick(non_empty(&secs)?);
            let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
            let note = if op == Op::DeleteSection {
                out.drain(a..b);
                format!("deleted section {} (lines {}–{b})", quote(lines[a]), a + 1)
            } else {
                let mut block: Vec<String> = out[a..b].to_vec();
                if let Some(last) = block.last_mut()
                    && !last.ends_with('\n')
                {
                    last.push('\n');
                }
                let at = if rng.chance(0.7) { b } else { out.len() };
                if at == out.len()
                    && let Some(last) = out.last_mut()
                    && !last.ends_with('\n')
                {
                    last.push('\n');
                }
                out.splice(at..at, block);
                format!(
                    "section {} (lines {}–{b}) duplicated",
                    quote(lines[a]),
                    a + 1
                )
            };
            Some((out.concat(), note))
        }
        Op::EnumSwap => enum_swap(rng, &lines),
        Op::BadMaterial => bad_material(rng, &lines, format),
        Op::Insert => match format {
            Format::Scene => insert_option(rng, &lines),
            Format::Deck => insert_block(rng, &lines),
        },
        Op::InvertElement | Op::SwapElementNodes => element_nodes(rng, &lines, op),
        Op::RemoveSet => remove_set(rng, &lines),
        Op::ParamSwap => param_swap(rng, &lines),
        Op::ByteFlip | Op::Truncate => None,
    }
}

fn non_empty<T>(v: &[T]) -> Option<&[T]> {
    (!v.is_empty()).then_some(v)
}

fn is_header(line: &str, format: Format) -> bool {
    let t = line.trim_start();
    match format {
        Format::Scene => t.starts_with('['),
        Format::Deck => t.starts_with('*') && !t.starts_with("**"),
    }
}

/// Sections as [first line, end) ranges: a TOML table header or a deck keyword and its data.
fn sections(lines: &[&str], format: Format) -> Vec<(usize, usize)> {
    let heads: Vec<usize> = (0..lines.len())
        .filter(|&k| is_header(lines[k], format))
        .collect();
    heads
        .iter()
        .enumerate()
        .map(|(i, &a)| (a, heads.get(i + 1).copied().unwrap_or(lines.len())))
        .collect()
}

/// Byte ranges of the numbers in `text`, outside comments, strings and deck headings, and not
/// part of a name (`x0`, `C3D20`, `nu12`).
fn numbers(text: &str, format: Format) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut offset = 0;
    let mut after_heading = false;
    for line in text.split_inclusive('\n') {
        let t = line.trim();
        let skip = format == Format::Deck && (t.starts_with("**") || after_heading);
        after_heading = format == Format::Deck && t.eq_ignore_ascii_case("*HEADING");
        if !skip {
            let b = line.as_bytes();
            let (mut i, mut in_string) = (0, false);
            while i < b.len() {
                if format == Format::Scene {
                    if b[i] == b'"' {
                        in_string = !in_string;
                    }
                    if b[i] == b'#' && !in_string {
                        break;
                    }
                }
                let free =
                    i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b"_.".contains(&b[i - 1]));
                if !in_string
                    && free
                    && let Some(n) = number_len(&b[i..])
                {
                    out.push((offset + i, offset + i + n));
                    i += n;
                    continue;
                }
                i += 1;
            }
        }
        offset += line.len();
    }
    out
}

/// Length of the number at the start of `b` ([sign] digits [. digits] [e|d [sign] digits]).
fn number_len(b: &[u8]) -> Option<usize> {
    let digits = |from: usize| from + b[from..].iter().take_while(|c| c.is_ascii_digit()).count();
    let mut j = usize::from(matches!(b.first(), Some(b'-' | b'+')));
    let int_end = digits(j);
    let mut count = int_end - j;
    j = int_end;
    if b.get(j) == Some(&b'.') {
        let frac_end = digits(j + 1);
        count += frac_end - j - 1;
        j = frac_end;
    }
    if count == 0 {
        return None;
    }
    if matches!(b.get(j), Some(b'e' | b'E' | b'd' | b'D')) {
        let k = j + 1 + usize::from(matches!(b.get(j + 1), Some(b'-' | b'+')));
        let e = digits(k);
        if e > k {
            j = e;
        }
    }
    if b.get(j)
        .is_some_and(|c| c.is_ascii_alphabetic() || *c == b'_')
    {
        return None;
    }
    Some(j)
}

fn numeric(rng: &mut Rng, text: &str, format: Format) -> Option<(String, String)> {
    let spans = numbers(text, format);
    let &(a, b) = rng.pick(non_empty(&spans)?);
    let pool = match format {
        Format::Scene => SCENE_EXTREMES,
        Format::Deck => DECK_EXTREMES,
    };
    let old = &text[a..b];
    let mut new = *rng.pick(pool);
    if new == old {
        new = pool[0];
    }
    let line = line_of(text.as_bytes(), a);
    let whole = text.split_inclusive('\n').nth(line - 1).unwrap_or("");
    let note = format!("line {line} {}: {old} → {new}", quote(whole));
    Some((format!("{}{new}{}", &text[..a], &text[b..]), note))
}

fn swap_numbers(rng: &mut Rng, text: &str, format: Format) -> Option<(String, String)> {
    let spans = numbers(text, format);
    let &(a, b) = rng.pick(non_empty(&spans)?);
    let old = &text[a..b];
    if spans.len() < 2 || rng.chance(0.5) {
        let new = match old.strip_prefix('-') {
            Some(rest) => rest.to_string(),
            None => format!("-{}", old.trim_start_matches('+')),
        };
        let line = line_of(text.as_bytes(), a);
        let note = format!("line {line}: {old} negated to {new}");
        return Some((format!("{}{new}{}", &text[..a], &text[b..]), note));
    }
    let &(c, d) = rng.pick(&spans);
    if c == a {
        return None;
    }
    let ((a, b), (c, d)) = if a < c {
        ((a, b), (c, d))
    } else {
        ((c, d), (a, b))
    };
    let (x, y) = (&text[a..b], &text[c..d]);
    let note = format!(
        "numbers swapped: {x} (line {}) ↔ {y} (line {})",
        line_of(text.as_bytes(), a),
        line_of(text.as_bytes(), c)
    );
    Some((
        format!("{}{y}{}{x}{}", &text[..a], &text[b..c], &text[d..]),
        note,
    ))
}

fn enum_swap(rng: &mut Rng, lines: &[&str]) -> Option<(String, String)> {
    let candidates: Vec<usize> = (0..lines.len())
        .filter(|&k| {
            let t = lines[k].trim_start();
            !t.starts_with('#') && !t.starts_with("title") && t.contains("= \"")
        })
        .collect();
    let k = *rng.pick(non_empty(&candidates)?);
    let line = lines[k];
    let open = line.find("= \"")? + 3;
    let close = open + line[open..].find('"')?;
    let new = *rng.pick(ENUM_VALUES);
    let out = format!("{}{new}{}", &line[..open], &line[close..]);
    let note = format!(
        "line {} {}: \"{}\" → \"{new}\"",
        k + 1,
        quote(line),
        &line[open..close]
    );
    Some((replace_line(lines, k, &out), note))
}

fn replace_line(lines: &[&str], k: usize, new: &str) -> String {
    let mut out: Vec<&str> = lines.to_vec();
    out[k] = new;
    out.concat()
}

fn bad_material(rng: &mut Rng, lines: &[&str], format: Format) -> Option<(String, String)> {
    let secs = sections(lines, format);
    let (name, pool) = match format {
        Format::Scene => ("[material]", SCENE_MATERIALS),
        Format::Deck => ("*ELASTIC", DECK_MATERIALS),
    };
    let targets: Vec<(usize, usize)> = secs
        .into_iter()
        .filter(|&(a, _)| {
            lines[a]
                .trim()
                .to_uppercase()
                .starts_with(&name.to_uppercase())
        })
        .collect();
    let &(a, b) = rng.pick(non_empty(&targets)?);
    let new = *rng.pick(pool);
    let mut out: Vec<&str> = lines[..a].to_vec();
    out.push(new);
    out.extend(&lines[b..]);
    let note = format!(
        "material block at line {} replaced by {}",
        a + 1,
        quote(&new.replace('\n', "; "))
    );
    Some((out.concat(), note))
}

fn insert_option(rng: &mut Rng, lines: &[&str]) -> Option<(String, String)> {
    let &(section, body) = rng.pick(SCENE_OPTIONS);
    let header = format!("[{section}]");
    let secs = sections(lines, Format::Scene);
    let note = format!("[{section}] {}", quote(&body.replace('\n', "; ")));
    let Some(&(a, b)) = secs.iter().find(|&&(a, _)| lines[a].trim() == header) else {
        let mut out = lines.concat();
        if !out.ends_with('\n') {
            out.push('\n');
        }
        out.push_str(&format!("\n{header}\n{body}\n"));
        return Some((out, format!("added {note}")));
    };
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    for entry in body.lines() {
        let key = entry.split('=').next().unwrap_or("").trim();
        let existing = (a + 1..b).find(|&k| out[k].split('=').next().unwrap_or("").trim() == key);
        match existing {
            Some(k) => out[k] = format!("{entry}\n"),
            None => out.insert(a + 1, format!("{entry}\n")),
        }
    }
    Some((out.concat(), format!("set {note}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_skip_names_strings_and_comments() {
        let t = "title = \"30 mm\"\n[mesh]\nslices = 8 # 4\nelement = \"hex20\"\nnu12 = -1.5e-3\n";
        let found: Vec<&str> = numbers(t, Format::Scene)
            .iter()
            .map(|&(a, b)| &t[a..b])
            .collect();
        assert_eq!(found, ["8", "-1.5e-3"]);
        let d = "*HEADING\n1 2 3\n*ELEMENT, TYPE=C3D20\n1, 2, 3.5d-2\n** 7\n";
        let found: Vec<&str> = numbers(d, Format::Deck)
            .iter()
            .map(|&(a, b)| &d[a..b])
            .collect();
        assert_eq!(found, ["1", "2", "3.5d-2"]);
    }

    #[test]
    fn the_same_seed_gives_the_same_mutations() {
        let text = include_str!("../../examples/scenes/fig_5_1_3_circle_30mm.toml");
        for case in 0..50 {
            let a = mutate(&mut Rng::for_case(7, case), text, Format::Scene);
            let b = mutate(&mut Rng::for_case(7, case), text, Format::Scene);
            assert_eq!(a.bytes, b.bytes);
            assert_eq!(a.notes, b.notes);
            assert!(!a.notes.is_empty());
        }
    }

    #[test]
    fn inverting_an_element_swaps_its_bottom_and_top_corners() {
        let d = "*ELEMENT, TYPE=C3D8\n1, 1, 2, 3, 4, 5, 6, 7, 8\n";
        let lines: Vec<&str> = d.split_inclusive('\n').collect();
        let (out, _) = element_nodes(&mut Rng::for_case(0, 0), &lines, Op::InvertElement).unwrap();
        assert!(out.ends_with("1, 5, 6, 7, 8, 1, 2, 3, 4\n"), "{out}");
    }
}
