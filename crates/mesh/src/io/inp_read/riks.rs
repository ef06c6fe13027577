//! `*STATIC, RIKS` (Abaqus's arc-length step): its data line and what a Riks step refuses.

use super::lexer::{Keyword, Line, Loc, fields, float, int};
use super::{ReadStep, Reader, StaticData};
use crate::MeshError;

impl Reader {
    /// `*STATIC, RIKS` (Abaqus): the data line Δl_in, l_period, Δl_min, Δl_max, λ_end, node,
    /// DOF, value with Abaqus's defaults (l_period 0 → 1; Δl_in 0 → l_period; Δl_min 0 →
    /// min(Δl_in, 1e-5·l_period); Δl_max none → unbounded); node, DOF and value given together.
    pub(crate) fn riks_procedure(&mut self, kw: &Keyword, data: &[Line]) -> Result<(), MeshError> {
        kw.allow(&["RIKS", "DIRECT", "SOLVER"])?;
        if kw.get("RIKS").is_some_and(|v| !v.is_empty()) {
            return Err(kw.param_error("RIKS", "a flag (no value)"));
        }
        let direct = kw.flag("DIRECT")?;
        if let Some(s) = kw.get("SOLVER") {
            self.not_used(
                &kw.at,
                format!("*STATIC, SOLVER={s}"),
                "nonlin3d uses its own sparse direct solver",
            );
        }
        if data.len() > 1 {
            return Err(kw.data_error(&data[1].at, "one data line expected"));
        }
        let mut riks = super::RiksData {
            initial: 1.0,
            period: 1.0,
            min: 1e-5,
            max: f64::INFINITY,
            max_lpf: None,
            monitor: None,
            direct,
        };
        if let Some(l) = data.first() {
            let f = fields(&l.text);
            if f.len() > 8 {
                return Err(kw.data_error(
                    &l.at,
                    "expected: initial arc length, total arc length, minimum, maximum, maximum \
                     load proportionality factor, node, DOF, value",
                ));
            }
            let given = |i: usize| f.get(i).is_some_and(|s| !s.is_empty());
            let get = |i: usize| -> Result<f64, MeshError> {
                if given(i) {
                    float(kw, &l.at, f[i])
                } else {
                    Ok(0.0)
                }
            };
            let (initial, period, min, max) = (get(0)?, get(1)?, get(2)?, get(3)?);
            if initial < 0.0 || period < 0.0 || min < 0.0 || max < 0.0 {
                return Err(kw.data_error(&l.at, "negative arc length"));
            }
            riks.period = if period > 0.0 { period } else { 1.0 };
            riks.initial = if initial > 0.0 { initial } else { riks.period };
            riks.min = if min > 0.0 {
                min
            } else {
                riks.initial.min(1e-5 * riks.period)
            };
            riks.max = if max > 0.0 { max } else { f64::INFINITY };
            if riks.min > riks.initial || riks.initial > riks.max {
                return Err(kw.data_error(
                    &l.at,
                    format!(
                        "arc lengths out of order: minimum {} ≤ initial {} ≤ maximum {} expected",
                        riks.min, riks.initial, riks.max
                    ),
                ));
            }
            if given(4) {
                riks.max_lpf = Some(get(4)?.abs());
            }
            match (given(5), given(6), given(7)) {
                (false, false, false) => {}
                (true, true, true) => {
                    let id = int(kw, &l.at, f[5])?;
                    let node = *self
                        .node_index
                        .get(&id)
                        .ok_or_else(|| kw.data_error(&l.at, format!("node {id} is not defined")))?;
                    let dof = int(kw, &l.at, f[6])?;
                    if !(1..=3).contains(&dof) {
                        return Err(kw.data_error(
                            &l.at,
                            format!("DOF {dof}: 1, 2 or 3 (solids have no rotations)"),
                        ));
                    }
                    riks.monitor = Some((node, dof as u8, get(7)?));
                }
                _ => {
                    return Err(kw.data_error(
                        &l.at,
                        "the node, DOF and value of the displacement that ends the step go \
                         together (fields 6–8)",
                    ));
                }
            }
        }
        let st = self.current(kw)?;
        if st.has_static {
            return Err(kw.error("a second *STATIC in one step"));
        }
        st.has_static = true;
        st.step.procedure = StaticData {
            direct,
            riks: Some(riks),
            ..StaticData::default()
        };
        Ok(())
    }
}

/// Refuses `AMPLITUDE=` on a Riks step's loads and boundary conditions, by line: its loads
/// scale with the load proportionality factor (Abaqus ignores amplitudes there).
pub(crate) fn riks_without_amplitudes(at: &Loc, step: &ReadStep) -> Result<(), MeshError> {
    let lines = step
        .boundaries
        .iter()
        .filter(|b| b.amplitude.is_some())
        .map(|b| (b.line, "*BOUNDARY"))
        .chain(
            step.cloads
                .iter()
                .filter(|c| c.amplitude.is_some())
                .map(|c| (c.line, "*CLOAD")),
        );
    if let Some((line, what)) = lines.min() {
        let at = Loc { line, ..at.clone() };
        return Err(super::lexer::deck_error(
            &at,
            &format!("{what} data"),
            "AMPLITUDE= in a *STATIC, RIKS step, which scales its loads by the load \
             proportionality factor",
        ));
    }
    Ok(())
}
