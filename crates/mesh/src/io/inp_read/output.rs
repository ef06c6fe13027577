//! Output requests: `*NODE PRINT`, `*NODE FILE` (`*NODE OUTPUT`), `*EL PRINT`, `*EL FILE`
//! (`*ELEMENT OUTPUT`), as CalculiX carries them from step to step.

use super::lexer::{Keyword, Line, fields, int_param};
use super::{OutputKind, OutputRequest, OutputVariable, Reader, Totals};
use crate::MeshError;

impl Reader {
    /// `*NODE PRINT`, `*NODE FILE`, `*EL PRINT`, `*EL FILE` (CalculiX's rules: the first card
    /// of a kind in a step replaces the requests of that kind carried from earlier steps;
    /// `FREQUENCY=` sets the one output frequency; `FREQUENCY=0` drops the card).
    pub(crate) fn output(
        &mut self,
        kw: &Keyword,
        data: &[Line],
        kind: OutputKind,
    ) -> Result<(), MeshError> {
        let (set_key, mut allowed): (&str, Vec<&str>) = match kind {
            OutputKind::NodePrint => ("NSET", vec!["NSET", "FREQUENCY", "TOTALS", "GLOBAL"]),
            OutputKind::NodeFile => ("NSET", vec!["NSET", "FREQUENCY", "GLOBAL", "OUTPUT"]),
            OutputKind::ElPrint => ("ELSET", vec!["ELSET", "FREQUENCY", "GLOBAL"]),
            OutputKind::ElFile => ("ELSET", vec!["FREQUENCY", "GLOBAL", "OUTPUT"]),
        };
        allowed.sort_unstable();
        kw.allow(&allowed)?;
        let st = self.current(kw)?;
        if !st.seen_outputs.contains(&kind) {
            st.seen_outputs.push(kind);
            self.carried.outputs.retain(|o| o.kind != kind);
        }
        let frequency = int_param(kw, "FREQUENCY")?;
        if frequency == Some(0) {
            return Ok(());
        }
        if let Some(f) = frequency {
            self.carried.frequency = f;
        }
        // Element variables in material axes: CalculiX's default for *EL PRINT, GLOBAL=NO for
        // *EL FILE; node variables have no local systems here (*TRANSFORM is refused).
        if let (OutputKind::NodePrint | OutputKind::NodeFile, Some(g)) = (kind, kw.get("GLOBAL")) {
            self.not_used(
                &kw.at,
                format!("{}, GLOBAL={g}", kw.what()),
                "no node has a local system (*TRANSFORM is refused): global either way",
            );
        }
        let local_axes = matches!(
            (kind, kw.choice("GLOBAL", &["YES", "NO"])?.as_deref()),
            (OutputKind::ElPrint, None) | (OutputKind::ElPrint | OutputKind::ElFile, Some("NO"))
        );
        if let Some(o) = kw.choice("OUTPUT", &["2D", "3D"])? {
            self.not_used(
                &kw.at,
                format!("{}, OUTPUT={o}", kw.what()),
                "expansion of 1-D/2-D elements: solids are written as they are",
            );
        }
        let totals = match kw.choice("TOTALS", &["YES", "NO", "ONLY"])?.as_deref() {
            Some("YES") => Totals::Yes,
            Some("ONLY") => Totals::Only,
            _ => Totals::No,
        };
        let set = match kw.get(set_key) {
            None if matches!(kind, OutputKind::NodePrint | OutputKind::ElPrint) => {
                return Err(kw.error(format!("{set_key}= missing")));
            }
            None => None,
            Some(name) => Some(
                if set_key == "NSET" {
                    self.node_set(name)
                } else {
                    self.cell_set(name)
                }
                .cloned()
                .ok_or_else(|| kw.param_error(set_key, format!("set '{name}' is not defined")))?,
            ),
        };
        if let Some(name) = &set {
            let what = format!("{}, {set_key}", kw.what());
            self.use_set(&kw.at, what, set_key == "NSET", name);
        }
        let mut variables = Vec::new();
        for l in data {
            for v in fields(&l.text).into_iter().filter(|s| !s.is_empty()) {
                let var = match (v.to_uppercase().as_str(), kind) {
                    ("U", OutputKind::NodePrint | OutputKind::NodeFile) => OutputVariable::U,
                    ("RF", OutputKind::NodePrint | OutputKind::NodeFile) => OutputVariable::Rf,
                    ("S", OutputKind::ElPrint | OutputKind::ElFile) => OutputVariable::S,
                    (other, _) => {
                        return Err(kw.data_error(
                            &l.at,
                            format!(
                                "output variable {other} not supported here (nodes: U, RF; \
                                 elements: S)"
                            ),
                        ));
                    }
                };
                if !variables.contains(&var) {
                    variables.push(var);
                }
            }
        }
        if variables.is_empty() {
            return Err(kw.error("no output variable listed"));
        }
        if totals != Totals::No && variables != [OutputVariable::Rf] {
            return Err(kw.param_error("TOTALS", "only with RF alone"));
        }
        // A later file card replaces the set of a variable an earlier one of the step named.
        if matches!(kind, OutputKind::NodeFile | OutputKind::ElFile) {
            for o in self.carried.outputs.iter_mut().filter(|o| o.kind == kind) {
                o.variables.retain(|v| !variables.contains(v));
            }
            self.carried.outputs.retain(|o| !o.variables.is_empty());
        }
        self.carried.outputs.push(OutputRequest {
            kind,
            set,
            variables,
            totals,
            local_axes,
            line: kw.at.line,
        });
        Ok(())
    }
}
