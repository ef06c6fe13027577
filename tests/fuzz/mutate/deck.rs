//! The deck-only mutations of `super`: inserted blocks, inverted elements and swapped element
//! nodes, removed sets, changed keyword parameters.

use super::*;

pub(super) fn insert_block(rng: &mut Rng, lines: &[&str]) -> Option<(String, String)> {
    let block = *rng.pick(DECK_BLOCKS);
    let heads: Vec<usize> = (0..lines.len())
        .filter(|&k| is_header(lines[k], Format::Deck))
        .chain([lines.len()])
        .collect();
    let at = *rng.pick(&heads);
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    if at == out.len()
        && let Some(last) = out.last_mut()
        && !last.ends_with('\n')
    {
        last.push('\n');
    }
    out.insert(at, block.to_string());
    let note = format!(
        "inserted {} before line {}",
        quote(&block.replace('\n', "; ")),
        at + 1
    );
    Some((out.concat(), note))
}

/// Data lines of `*ELEMENT` blocks, each with whether it starts an element (holds its id).
pub(super) fn element_lines(lines: &[&str]) -> Vec<(usize, bool)> {
    let mut out = Vec::new();
    for (a, b) in sections(lines, Format::Deck) {
        if !lines[a].trim().to_uppercase().starts_with("*ELEMENT") {
            continue;
        }
        let mut starts = true;
        for k in a + 1..b {
            let t = lines[k].trim();
            if t.is_empty() || t.starts_with("**") {
                continue;
            }
            out.push((k, starts));
            starts = !t.ends_with(',');
        }
    }
    out
}

/// Inverts an element (its first four corners swapped with the other four: det J < 0) or
/// swaps two node ids of an element line.
pub(super) fn element_nodes(rng: &mut Rng, lines: &[&str], op: Op) -> Option<(String, String)> {
    let all = element_lines(lines);
    let candidates: Vec<(usize, bool)> = if op == Op::InvertElement {
        all.into_iter().filter(|&(_, s)| s).collect()
    } else {
        all
    };
    let &(k, starts) = rng.pick(non_empty(&candidates)?);
    let line = lines[k];
    let body = line.trim_end_matches(['\n', '\r']);
    let ending = &line[body.len()..];
    let mut f: Vec<String> = body.split(',').map(str::to_string).collect();
    let first = usize::from(starts);
    let note = if op == Op::InvertElement {
        if f.len() < 9 {
            return None;
        }
        for i in 1..=4 {
            f.swap(i, i + 4);
        }
        format!(
            "line {} {}: corners 1–4 ↔ 5–8 (inverted)",
            k + 1,
            quote(line)
        )
    } else {
        let usable: Vec<usize> = (first..f.len())
            .filter(|&i| !f[i].trim().is_empty())
            .collect();
        if usable.len() < 2 {
            return None;
        }
        let i = *rng.pick(&usable);
        let j = *rng.pick(&usable);
        if i == j {
            return None;
        }
        f.swap(i, j);
        format!("line {} {}: node fields {i} ↔ {j}", k + 1, quote(line))
    };
    let new = format!("{}{ending}", f.join(","));
    Some((replace_line(lines, k, &new), note))
}

/// Deletes a `*NSET`/`*ELSET` block or renames one reference to a set.
pub(super) fn remove_set(rng: &mut Rng, lines: &[&str]) -> Option<(String, String)> {
    let secs = sections(lines, Format::Deck);
    if rng.chance(0.5) {
        let sets: Vec<(usize, usize)> = secs
            .iter()
            .copied()
            .filter(|&(a, _)| {
                let t = lines[a].trim().to_uppercase();
                t.starts_with("*NSET") || t.starts_with("*ELSET")
            })
            .collect();
        let &(a, b) = rng.pick(non_empty(&sets)?);
        let mut out = lines.to_vec();
        out.drain(a..b);
        let note = format!("set {} deleted (lines {}–{b})", quote(lines[a]), a + 1);
        return Some((out.concat(), note));
    }
    // References: NSET=/ELSET= parameter values, and set names first on *BOUNDARY/*CLOAD lines.
    let mut refs: Vec<(usize, usize, usize)> = Vec::new();
    for (a, b) in secs {
        let head = lines[a].to_uppercase();
        if head.len() != lines[a].len() {
            continue;
        }
        for key in ["NSET=", "ELSET="] {
            if let Some(p) = head.find(key) {
                let from = p + key.len();
                let to = from
                    + head[from..]
                        .find([',', '\n', '\r'])
                        .unwrap_or(head.len() - from);
                refs.push((a, from, to));
            }
        }
        if head.starts_with("*BOUNDARY") || head.starts_with("*CLOAD") {
            for k in a + 1..b {
                let first = lines[k].split(',').next().unwrap_or("");
                let name = first.trim();
                if !name.is_empty() && name.parse::<f64>().is_err() && !name.starts_with('*') {
                    let from = lines[k].find(name).unwrap_or(0);
                    refs.push((k, from, from + name.len()));
                }
            }
        }
    }
    let &(k, from, to) = rng.pick(non_empty(&refs)?);
    let line = lines[k];
    let new = format!("{}NOSUCHSET{}", &line[..from], &line[to..]);
    let note = format!(
        "line {} {}: set '{}' → 'NOSUCHSET'",
        k + 1,
        quote(line),
        &line[from..to]
    );
    Some((replace_line(lines, k, &new), note))
}

/// Changes, deletes or adds a keyword parameter.
pub(super) fn param_swap(rng: &mut Rng, lines: &[&str]) -> Option<(String, String)> {
    let heads: Vec<usize> = (0..lines.len())
        .filter(|&k| is_header(lines[k], Format::Deck))
        .collect();
    let k = *rng.pick(non_empty(&heads)?);
    let line = lines[k];
    let body = line.trim_end_matches(['\n', '\r']);
    let ending = &line[body.len()..];
    let mut parts: Vec<String> = body.split(',').map(str::to_string).collect();
    let change;
    if parts.len() > 1 && rng.chance(0.6) {
        let i = 1 + rng.below(parts.len() - 1);
        let old = parts[i].clone();
        match old.split_once('=') {
            Some((key, _)) if rng.chance(0.8) => {
                let k = key.trim().to_uppercase();
                let pool = PARAM_VALUES
                    .iter()
                    .find(|(name, _)| *name == k)
                    .map_or(GENERIC_PARAMS, |p| p.1);
                parts[i] = format!("{key}={}", rng.pick(pool));
                change = format!("{} → {}", old.trim(), parts[i].trim());
            }
            _ => {
                parts.remove(i);
                change = format!("{} removed", old.trim());
            }
        }
    } else {
        let add = *rng.pick(ADDED_PARAMS);
        parts.push(add.to_string());
        change = format!("{} added", add.trim());
    }
    let new = format!("{}{ending}", parts.join(","));
    let note = format!("line {} {}: {change}", k + 1, quote(line));
    Some((replace_line(lines, k, &new), note))
}
