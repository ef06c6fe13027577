//! CalculiX's .dat output and nonlin3d's output tables as the same blocks, for the deck tests:
//! (what, set, total time) with rows keyed by node or (element, integration point).

use nonlin3d::deck::StepResult;
use std::collections::BTreeMap;

/// One printed block.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// `displacements`, `forces`, `total force` or `stresses`.
    pub what: String,
    /// Set name, upper case.
    pub set: String,
    /// Total time.
    pub time: f64,
    /// How many earlier blocks have the same what, set and time (a step with TIME RESET
    /// repeats times).
    pub repeat: usize,
    /// Values by key (node, or element and point; empty for totals).
    pub rows: BTreeMap<Vec<usize>, Vec<f64>>,
}

/// The blocks of a CalculiX .dat file.
pub fn parse_dat(text: &str) -> Vec<Block> {
    let mut blocks: Vec<Block> = Vec::new();
    for line in text.lines() {
        if let Some((head, rest)) = line.split_once(" for set ") {
            let what = head.split('(').next().unwrap_or("").trim().to_string();
            let mut words = rest.split_whitespace();
            let set = words.next().unwrap_or("").to_uppercase();
            let time = words
                .last()
                .and_then(|t| t.parse().ok())
                .unwrap_or(f64::NAN);
            blocks.push(Block {
                what,
                set,
                time,
                repeat: 0,
                rows: BTreeMap::new(),
            });
            continue;
        }
        let Some(b) = blocks.last_mut() else { continue };
        let tokens: Vec<&str> = line.split_whitespace().collect();
        if tokens.is_empty() {
            continue;
        }
        let ids = match b.what.as_str() {
            "total force" => 0,
            "stresses" => 2,
            _ => 1,
        };
        let key: Vec<usize> = tokens[..ids].iter().map(|t| t.parse().unwrap()).collect();
        // Stress rows end with the orientation name, if any.
        let values: Vec<f64> = tokens[ids..]
            .iter()
            .filter_map(|t| t.parse().ok())
            .collect();
        b.rows.insert(key, values);
    }
    number_repeats(&mut blocks);
    blocks
}

fn number_repeats(blocks: &mut [Block]) {
    for i in 0..blocks.len() {
        blocks[i].repeat = blocks[..i]
            .iter()
            .filter(|b| {
                b.what == blocks[i].what && b.set == blocks[i].set && b.time == blocks[i].time
            })
            .count();
    }
}

/// nonlin3d's output tables of `results` as blocks.
pub fn our_blocks(results: &[StepResult]) -> Vec<Block> {
    let mut all: Vec<Block> = Vec::new();
    for r in results {
        let mut out: Vec<Block> = Vec::new();
        for t in &r.outputs {
            let set = t
                .file
                .trim_end_matches(".csv")
                .trim_end_matches("-totals")
                .splitn(3, '-')
                .nth(2)
                .unwrap_or("")
                .to_uppercase();
            let mut lines = t.csv.lines();
            let header: Vec<&str> = lines.next().unwrap().split(',').collect();
            let totals = t.file.ends_with("-totals.csv");
            let element = header.contains(&"element");
            for line in lines {
                let f: Vec<&str> = line.split(',').collect();
                let time: f64 = f[2].parse().unwrap();
                let (key, first): (Vec<usize>, usize) = if totals {
                    (vec![], 3)
                } else if element {
                    (vec![f[3].parse().unwrap(), f[4].parse().unwrap()], 5)
                } else {
                    (vec![f[3].parse().unwrap()], 4)
                };
                let mut groups: Vec<(&str, Vec<f64>)> = Vec::new();
                for (col, v) in header.iter().zip(&f).skip(first) {
                    let what = match (totals, element, col.starts_with('u')) {
                        (true, _, _) => "total force",
                        (_, true, _) => "stresses",
                        (_, _, true) => "displacements",
                        _ => "forces",
                    };
                    match groups.last_mut() {
                        Some(g) if g.0 == what => g.1.push(v.parse().unwrap()),
                        _ => groups.push((what, vec![v.parse().unwrap()])),
                    }
                }
                for (what, values) in groups {
                    let found = out
                        .iter()
                        .position(|b| b.what == what && b.set == set && b.time == time);
                    let b = match found {
                        Some(i) => &mut out[i],
                        None => {
                            out.push(Block {
                                what: what.into(),
                                set: set.clone(),
                                time,
                                repeat: 0,
                                rows: BTreeMap::new(),
                            });
                            out.last_mut().unwrap()
                        }
                    };
                    b.rows.insert(key.clone(), values);
                }
            }
        }
        all.extend(out);
    }
    number_repeats(&mut all);
    all
}

/// Largest |ours − theirs| over a block relative to the block's largest |theirs|, for every
/// CalculiX block; panics if a block has no counterpart or the printed times differ.
pub fn compare(name: &str, ours: &[Block], theirs: &[Block]) -> Vec<(String, f64)> {
    let key = |b: &Block| format!("{} {} t={:.6e} #{}", b.what, b.set, b.time, b.repeat);
    let mut ours_keys: Vec<String> = ours.iter().map(key).collect();
    let mut theirs_keys: Vec<String> = theirs.iter().map(key).collect();
    ours_keys.sort();
    theirs_keys.sort();
    assert_eq!(ours_keys, theirs_keys, "{name}: the blocks written differ");
    let mut out = Vec::new();
    for t in theirs {
        let o = ours
            .iter()
            .find(|b| {
                b.what == t.what
                    && b.set == t.set
                    && b.repeat == t.repeat
                    && (b.time - t.time).abs() < 1e-9
            })
            .unwrap();
        assert_eq!(
            o.rows.keys().collect::<Vec<_>>(),
            t.rows.keys().collect::<Vec<_>>(),
            "{name}: {}",
            key(t)
        );
        let scale = t
            .rows
            .values()
            .flatten()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        let diff = t
            .rows
            .iter()
            .flat_map(|(k, v)| v.iter().zip(&o.rows[k]).map(|(a, b)| (a - b).abs()))
            .fold(0.0f64, f64::max);
        assert_eq!(
            t.rows.values().map(Vec::len).sum::<usize>(),
            o.rows.values().map(Vec::len).sum::<usize>()
        );
        out.push((key(t), diff / scale));
    }
    out
}
