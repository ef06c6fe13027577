//! Contact keywords: `*SURFACE`, `*SURFACE INTERACTION`, `*SURFACE BEHAVIOR`, `*FRICTION` and
//! `*CONTACT PAIR`, read for frictionless contact of node pairs on matching faces (thesis
//! §2.7: each slave node coincides with a master node; nonlin3d holds the pairs exactly by
//! its active set).
//!
//! Read: `*SURFACE, NAME=, TYPE=ELEMENT|NODE` (element faces `elem or elset, S1`…`S6`; nodes
//! `node or nset`); `*SURFACE INTERACTION, NAME=`; `*SURFACE BEHAVIOR,
//! PRESSURE-OVERCLOSURE=HARD` (a data line, CalculiX's penalty K, σ∞, c₀, is listed as not
//! used: the pairs are held exactly); `*CONTACT PAIR, INTERACTION=, TYPE=NODE TO SURFACE|SURFACE
//! TO SURFACE` with `slave, master` data lines. Refused, each at its line: other
//! pressure-overclosure laws (a penalty or a tie changes the answer), `*FRICTION` with μ ≠ 0,
//! a master that is not an element surface, and a slave node with no master node at its
//! position (non-matching faces). A surface no pair uses is listed as not used.

use super::Reader;
use super::lexer::{Keyword, Line, Loc, deck_error, fields, float, int};
use crate::MeshError;
use crate::inp::face_nodes;
use std::collections::{BTreeMap, HashMap, HashSet};

/// Why a surface that no contact pair uses does not matter.
const UNUSED_SURFACE: &str = "no surface load or contact refers to it";

/// Node pairs of one `*CONTACT PAIR` data line: `slave[i]` coincides with `master[i]` (0-based
/// mesh indices); nodes on both surfaces (bonded, e.g. a crack front) are left out.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ContactPairs {
    /// Where the pair was given (`line N`, or `FILE line N`), for messages.
    pub at: String,
    /// Slave nodes.
    pub slave: Vec<usize>,
    /// The master node at each slave node's position.
    pub master: Vec<usize>,
}

/// A surface as read.
#[derive(Debug, Clone)]
pub(crate) enum Surface {
    /// Element faces (cell, Abaqus face 0..6).
    Faces(Vec<(usize, u8)>),
    /// Nodes.
    Nodes(Vec<usize>),
}

/// The contact cards read so far.
#[derive(Default)]
pub(crate) struct ContactCards {
    /// Upper-case name → (where, surface).
    surfaces: BTreeMap<String, (Loc, Surface)>,
    /// Upper-case interaction names with whether a `*SURFACE BEHAVIOR` was given.
    interactions: HashMap<String, bool>,
    /// The interaction the next `*SURFACE BEHAVIOR` / `*FRICTION` belongs to.
    current: Option<String>,
    /// `*CONTACT PAIR` data lines: (line, interaction, slave, master), upper-case names.
    pairs: Vec<(Loc, String, String, String)>,
}

impl Reader {
    /// Handles `kw` if it is a contact keyword; Ok(false) otherwise.
    pub(crate) fn contact_keyword(
        &mut self,
        kw: &Keyword,
        data: &[Line],
    ) -> Result<bool, MeshError> {
        let contact = matches!(
            kw.name.as_str(),
            "SURFACE" | "SURFACE INTERACTION" | "SURFACE BEHAVIOR" | "FRICTION" | "CONTACT PAIR"
        );
        if !contact {
            return Ok(false);
        }
        if self.step.is_some() || !self.m.steps.is_empty() {
            return Err(kw.error("model data after the first *STEP (contact is defined once)"));
        }
        if kw.name != "SURFACE BEHAVIOR" && kw.name != "FRICTION" {
            self.contact.current = None;
        }
        match kw.name.as_str() {
            "SURFACE" => self.surface(kw, data)?,
            "SURFACE INTERACTION" => {
                kw.allow(&["NAME"])?;
                let name = kw.require("NAME")?.to_uppercase();
                if self
                    .contact
                    .interactions
                    .insert(name.clone(), false)
                    .is_some()
                {
                    return Err(kw.error(format!("interaction {name} defined twice")));
                }
                if let Some(l) = data.first() {
                    self.not_used(
                        &l.at,
                        "*SURFACE INTERACTION data".into(),
                        "out-of-plane thickness of 2-D models: solids do not use it",
                    );
                }
                self.contact.current = Some(name);
            }
            "SURFACE BEHAVIOR" => {
                let name = self.interaction_of(kw)?;
                kw.allow(&["PRESSURE-OVERCLOSURE"])?;
                match kw.require("PRESSURE-OVERCLOSURE")?.to_uppercase().as_str() {
                    "HARD" => {}
                    other => {
                        return Err(kw.param_error(
                            "PRESSURE-OVERCLOSURE",
                            format!(
                                "'{other}' not supported: nonlin3d holds contact pairs exactly \
                                 (HARD); a penalty, table or tie law would change the answer"
                            ),
                        ));
                    }
                }
                if let Some(l) = data.first() {
                    self.not_used(
                        &l.at,
                        "*SURFACE BEHAVIOR data".into(),
                        "CalculiX's penalty (K, σ∞, c₀) for HARD: nonlin3d holds the pairs exactly",
                    );
                }
                self.contact.interactions.insert(name, true);
            }
            "FRICTION" => {
                self.interaction_of(kw)?;
                kw.allow(&[])?;
                let mu = match data.first() {
                    Some(l) => float(kw, &l.at, fields(&l.text).first().copied().unwrap_or(""))?,
                    None => return Err(kw.error("data line (μ) missing")),
                };
                if mu != 0.0 {
                    return Err(kw.error(format!(
                        "friction μ = {mu} not supported: nonlin3d's contact is frictionless \
                         (give μ = 0 or remove *FRICTION)"
                    )));
                }
                self.not_used(
                    &kw.at,
                    kw.what(),
                    "μ = 0: frictionless, as nonlin3d's contact",
                );
            }
            _ => self.contact_pair(kw, data)?,
        }
        Ok(true)
    }

    /// The interaction a `*SURFACE BEHAVIOR` or `*FRICTION` belongs to (the last `*SURFACE
    /// INTERACTION`, with only these keywords between).
    fn interaction_of(&self, kw: &Keyword) -> Result<String, MeshError> {
        self.contact
            .current
            .clone()
            .ok_or_else(|| kw.error("must follow a *SURFACE INTERACTION"))
    }

    /// `*SURFACE, NAME=, TYPE=ELEMENT|NODE`.
    fn surface(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["NAME", "TYPE"])?;
        let name = kw.require("NAME")?.to_string();
        let nodes = kw.choice("TYPE", &["ELEMENT", "NODE"])?.as_deref() == Some("NODE");
        let mut faces = Vec::new();
        let mut list = Vec::new();
        for l in data {
            let f: Vec<&str> = fields(&l.text)
                .into_iter()
                .filter(|s| !s.is_empty())
                .collect();
            let Some(&first) = f.first() else { continue };
            if nodes {
                list.extend(self.members(kw, &l.at, true, first)?);
                continue;
            }
            let face = match f.get(1).map(|s| s.to_uppercase()) {
                Some(s) if s.len() == 2 && s.starts_with('S') => match s[1..].parse::<u8>() {
                    Ok(k @ 1..=6) => k - 1,
                    _ => return Err(kw.data_error(&l.at, format!("face '{s}': S1–S6 expected"))),
                },
                _ => return Err(kw.data_error(&l.at, "expected: element or element set, S1–S6")),
            };
            for c in self.members(kw, &l.at, false, first)? {
                faces.push((c, face));
            }
        }
        let surface = if nodes {
            Surface::Nodes(list)
        } else {
            Surface::Faces(faces)
        };
        let key = name.to_uppercase();
        if self.contact.surfaces.contains_key(&key) {
            return Err(kw.error(format!("surface {name} defined twice")));
        }
        self.contact.surfaces.insert(key, (kw.at.clone(), surface));
        // Listed as not used until a contact pair uses it (then taken off the list).
        self.not_used(&kw.at, kw.what(), UNUSED_SURFACE);
        Ok(())
    }

    /// A node or element id, or the members of a set of that kind.
    fn members(
        &self,
        kw: &Keyword,
        at: &Loc,
        nodes: bool,
        item: &str,
    ) -> Result<Vec<usize>, MeshError> {
        let what = if nodes { "node" } else { "element" };
        if item.chars().all(|c| c.is_ascii_digit()) {
            let id = int(kw, at, item)?;
            let index = if nodes {
                self.node_index.get(&id)
            } else {
                self.elem_index.get(&id)
            };
            return index
                .map(|&i| vec![i])
                .ok_or_else(|| kw.data_error(at, format!("{what} {id} is not defined")));
        }
        let set = if nodes {
            self.node_set(item)
                .and_then(|s| self.m.mesh.node_sets.get(s))
        } else {
            self.cell_set(item)
                .and_then(|s| self.m.mesh.cell_sets.get(s))
        };
        set.cloned().ok_or_else(|| {
            kw.data_error(
                at,
                format!("'{item}' is neither a {what} id nor a defined {what} set"),
            )
        })
    }

    /// `*CONTACT PAIR, INTERACTION=, TYPE=`: its data lines, resolved at the end of the deck.
    fn contact_pair(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["INTERACTION", "TYPE", "SMALL SLIDING", "ADJUST"])?;
        kw.choice("TYPE", &["NODE TO SURFACE", "SURFACE TO SURFACE"])?;
        if kw.get("ADJUST").is_some() {
            return Err(kw.param_error(
                "ADJUST",
                "moving slave nodes onto the master is not supported (pairs must match)",
            ));
        }
        if kw.get("SMALL SLIDING").is_some() {
            self.not_used(
                &kw.at,
                "*CONTACT PAIR, SMALL SLIDING".into(),
                "node-to-node pairs do not slide",
            );
        }
        let interaction = kw.require("INTERACTION")?.to_uppercase();
        if data.is_empty() {
            return Err(kw.error("no data line (slave, master)"));
        }
        for l in data {
            let f: Vec<&str> = fields(&l.text);
            if f.len() != 2 || f.iter().any(|s| s.is_empty()) {
                return Err(kw.data_error(&l.at, "expected: slave surface, master surface"));
            }
            self.contact.pairs.push((
                l.at.clone(),
                interaction.clone(),
                f[0].to_uppercase(),
                f[1].to_uppercase(),
            ));
        }
        Ok(())
    }

    /// The node pairs of every `*CONTACT PAIR` line, and the surfaces no pair uses listed as
    /// not used.
    pub(crate) fn resolve_contact(&mut self) -> Result<(), MeshError> {
        let pairs = std::mem::take(&mut self.contact.pairs);
        let mut used = HashSet::new();
        let mut taken = HashSet::new();
        for (at, interaction, slave, master) in &pairs {
            let what = "*CONTACT PAIR data";
            match self.contact.interactions.get(interaction) {
                None => {
                    return Err(deck_error(
                        at,
                        what,
                        format!("interaction {interaction} is not defined"),
                    ));
                }
                Some(false) => {
                    return Err(deck_error(
                        at,
                        what,
                        format!("interaction {interaction} has no *SURFACE BEHAVIOR"),
                    ));
                }
                Some(true) => {}
            }
            let surface = |name: &String| {
                self.contact
                    .surfaces
                    .get(name)
                    .map(|(_, s)| s)
                    .ok_or_else(|| deck_error(at, what, format!("surface {name} is not defined")))
            };
            let slave_nodes = self.surface_nodes(surface(slave)?);
            let Surface::Faces(_) = surface(master)? else {
                return Err(deck_error(
                    at,
                    what,
                    format!("master {master} must be an element (face) surface"),
                ));
            };
            let master_nodes = self.surface_nodes(surface(master)?);
            used.insert(slave.clone());
            used.insert(master.clone());
            let read = self.match_nodes(at, &slave_nodes, &master_nodes, &mut taken)?;
            self.m.contact.push(read);
        }
        let used_at: HashSet<String> = used
            .iter()
            .filter_map(|n| self.contact.surfaces.get(n))
            .map(|(at, _)| at.to_string())
            .collect();
        self.m
            .not_used
            .retain(|n| !(n.keyword == "*SURFACE" && used_at.contains(&n.at)));
        Ok(())
    }

    /// The nodes of a surface, ascending.
    fn surface_nodes(&self, s: &Surface) -> Vec<usize> {
        let mut out: Vec<usize> = match s {
            Surface::Nodes(n) => n.clone(),
            Surface::Faces(f) => f
                .iter()
                .flat_map(|&(c, k)| face_nodes(&self.m.mesh, c, k))
                .collect(),
        };
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Each slave node (not itself a master node) with the master node at its position, within
    /// 1e-9 of the model's size; a slave without one is refused (non-matching faces), and so is
    /// a node that a pair already uses.
    fn match_nodes(
        &self,
        at: &Loc,
        slave: &[usize],
        master: &[usize],
        taken: &mut HashSet<usize>,
    ) -> Result<ContactPairs, MeshError> {
        let x = &self.m.mesh.nodes;
        let size = x
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0f64, |a, &b| a.max(b.abs()));
        let tol = 1e-9 * size.max(f64::MIN_POSITIVE);
        let mut sorted: Vec<usize> = master.to_vec();
        sorted.sort_by(|&a, &b| x[a][0].total_cmp(&x[b][0]));
        let on_master: HashSet<usize> = master.iter().copied().collect();
        let id = |v: usize| self.m.node_ids[v];
        let mut out = ContactPairs {
            at: at.to_string(),
            ..ContactPairs::default()
        };
        for &s in slave.iter().filter(|s| !on_master.contains(s)) {
            let p = x[s];
            let from = sorted.partition_point(|&m| x[m][0] < p[0] - tol);
            let found = sorted[from..]
                .iter()
                .take_while(|&&m| x[m][0] <= p[0] + tol)
                .find(|&&m| (0..3).all(|k| (x[m][k] - p[k]).abs() <= tol));
            let Some(&m) = found else {
                return Err(deck_error(
                    at,
                    "*CONTACT PAIR data",
                    format!(
                        "slave node {} at ({:e}, {:e}, {:e}) has no master node at its position \
                         (within {tol:.1e} in the deck's length unit): nonlin3d reads node-to-node \
                         contact on matching faces only",
                        id(s),
                        p[0],
                        p[1],
                        p[2]
                    ),
                ));
            };
            for v in [s, m] {
                if !taken.insert(v) {
                    return Err(deck_error(
                        at,
                        "*CONTACT PAIR data",
                        format!("node {} is in more than one contact pair", id(v)),
                    ));
                }
            }
            out.slave.push(s);
            out.master.push(m);
        }
        Ok(out)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use crate::read_inp;

    /// Two unit C3D8 cubes stacked, with their own nodes on z = 1 (5–8 below, 9–12 above):
    /// the contact cards `cards` between the mesh and a linear step.
    fn deck(cards: &str) -> String {
        let mut s = String::from("*NODE\n");
        let mut id = 1;
        for z in [0.0, 1.0, 1.0, 2.0] {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                s += &format!("{id}, {x}, {y}, {z}\n");
                id += 1;
            }
        }
        s += "*ELEMENT, TYPE=C3D8, ELSET=ALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n\
              2, 9, 10, 11, 12, 13, 14, 15, 16\n\
              *NSET, NSET=UP\n9, 10, 11, 12\n\
              *MATERIAL, NAME=M\n*ELASTIC\n1e9, 0.3\n*SOLID SECTION, ELSET=ALL, MATERIAL=M\n";
        s += cards;
        s += "*STEP\n*STATIC\n*END STEP\n";
        s
    }

    const SURFACES: &str = "*SURFACE, NAME=S_UP, TYPE=NODE\nUP\n\
                            *SURFACE, NAME=M_LOW, TYPE=ELEMENT\n1, S2\n\
                            *SURFACE, NAME=UNUSED, TYPE=ELEMENT\n2, S2\n";

    /// Matching faces: each upper node with the lower node at its position; the used surfaces
    /// leave the not-used list, the unused one and the penalty data line stay on it.
    #[test]
    fn matching_faces_give_node_pairs() {
        let cards = format!(
            "{SURFACES}*SURFACE INTERACTION, NAME=SI\n\
             *SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD\n1e12, 1.0\n\
             *CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE\nS_UP, M_LOW\n"
        );
        let m = read_inp(&deck(&cards)).unwrap();
        assert_eq!(m.contact.len(), 1);
        assert_eq!(m.contact[0].slave, vec![8, 9, 10, 11]);
        assert_eq!(m.contact[0].master, vec![4, 5, 6, 7]);
        let listed: Vec<&str> = m.not_used.iter().map(|n| n.keyword.as_str()).collect();
        assert_eq!(
            listed.iter().filter(|k| **k == "*SURFACE").count(),
            1,
            "{listed:?}"
        );
        assert!(listed.contains(&"*SURFACE BEHAVIOR data"));
    }

    /// The error of a deck with `cards`, as text.
    fn refused(cards: &str) -> String {
        read_inp(&deck(cards)).unwrap_err().to_string()
    }

    /// Friction, a penalty law, a moved node (non-matching faces) and a node master are each
    /// refused at their line.
    #[test]
    fn what_cannot_be_held_exactly_is_refused_by_line() {
        let head = format!("{SURFACES}*SURFACE INTERACTION, NAME=SI\n");
        // The mesh is 26 lines, SURFACES 6: *SURFACE INTERACTION at line 33.
        let e = refused(&format!(
            "{head}*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD\n*FRICTION\n0.3\n"
        ));
        assert!(e.contains("line 35") && e.contains("frictionless"), "{e}");
        let e = refused(&format!(
            "{head}*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n1e12\n"
        ));
        assert!(e.contains("line 34") && e.contains("LINEAR"), "{e}");
        let pair = "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD\n\
                    *CONTACT PAIR, INTERACTION=SI\n";
        let moved = deck(&format!("{head}{pair}S_UP, M_LOW\n"))
            .replace("\n9, 0, 0, 1\n", "\n9, 0, 0, 1.001\n");
        let e = read_inp(&moved).unwrap_err().to_string();
        assert!(
            e.contains("line 36") && e.contains("slave node 9") && e.contains("matching"),
            "{e}"
        );
        let e = refused(&format!("{head}{pair}M_LOW, S_UP\n"));
        assert!(
            e.contains("line 36") && e.contains("element (face) surface"),
            "{e}"
        );
    }
}
