//! Boundary conditions and loads over steps, as CalculiX defines them (its `tempload`,
//! `bounadd`, `forcadd`): per DOF a target value, the value it had at the end of the previous
//! step, and an optional amplitude. At step time t of a static step the value is
//! value·A(t) with an amplitude, else old + (value − old)·t/period (a ramp).
//!
//! - A boundary condition given for a DOF replaces its value and amplitude; a DOF constrained
//!   for the first time ramps from where it is. `OP=NEW` on the step's first `*BOUNDARY`
//!   frees every DOF constrained before (at once, as CalculiX does). Model-data boundary
//!   conditions ramp from zero in the first step.
//! - A load given in a step replaces the earlier value (a second load on the same DOF within the
//!   step adds to it, with the same amplitude); `OP=NEW` sets every earlier load's value to zero
//!   (ramped down unless it has an amplitude).

use crate::Error;
use nonlin3d_assembly::Constraints;
use nonlin3d_mesh::{Amplitude, InpModel, NodeRef, ReadBoundary, ReadCload, ReadStep};
use std::collections::BTreeMap;

/// One prescribed or loaded DOF.
#[derive(Debug, Clone, PartialEq)]
struct Entry {
    value: f64,
    old: f64,
    amplitude: Option<String>,
    /// Loads: given in the current step (a second definition adds).
    defined: bool,
}

/// The prescribed and loaded DOFs in force.
#[derive(Debug, Clone, Default)]
pub(crate) struct History {
    bcs: BTreeMap<usize, Entry>,
    loads: BTreeMap<usize, Entry>,
}

/// The time frame of a step: its period and the total time at its start.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    pub period: f64,
    pub start: f64,
}

fn nodes_of(model: &InpModel, target: &NodeRef) -> Vec<usize> {
    match target {
        NodeRef::Node(n) => vec![*n],
        NodeRef::Set(name) => model.mesh.node_sets.get(name).cloned().unwrap_or_default(),
    }
}

impl History {
    /// The model-data boundary conditions (values at the start 0, ramped in step 1).
    pub fn new(model: &InpModel) -> Self {
        let mut h = Self::default();
        let zero = vec![0.0; 3 * model.mesh.nodes.len()];
        for b in &model.initial_boundaries {
            h.boundary(model, b, &zero);
        }
        h
    }

    fn boundary(&mut self, model: &InpModel, b: &ReadBoundary, u: &[f64]) {
        for node in nodes_of(model, &b.target) {
            for dof in b.first..=b.last {
                let d = 3 * node + dof as usize - 1;
                let value = if b.fixed { u[d] } else { b.value };
                let e = self.bcs.entry(d).or_insert(Entry {
                    value,
                    old: u[d],
                    amplitude: None,
                    defined: true,
                });
                e.value = value;
                e.amplitude = b.amplitude.clone();
            }
        }
    }

    fn cload(&mut self, model: &InpModel, c: &ReadCload) -> Result<(), Error> {
        for node in nodes_of(model, &c.target) {
            let d = 3 * node + c.dof as usize - 1;
            let e = self.loads.entry(d).or_insert(Entry {
                value: 0.0,
                old: 0.0,
                amplitude: None,
                defined: false,
            });
            if e.defined {
                if e.amplitude != c.amplitude {
                    return Err(Error::LoadedTwice {
                        line: c.line,
                        node: model.node_ids[node],
                        dof: c.dof,
                    });
                }
                e.value += c.value;
            } else {
                e.value = c.value;
                e.defined = true;
                e.amplitude = c.amplitude.clone();
            }
        }
        Ok(())
    }

    /// Applies the definitions of `step` at its start, `u` the displacements then.
    pub fn begin_step(
        &mut self,
        model: &InpModel,
        step: &ReadStep,
        u: &[f64],
    ) -> Result<(), Error> {
        if step.boundary_op_new {
            self.bcs.clear();
        }
        for e in self.loads.values_mut() {
            e.defined = false;
            if step.cload_op_new {
                e.value = 0.0;
            }
        }
        for b in &step.boundaries {
            self.boundary(model, b, u);
        }
        for c in &step.cloads {
            self.cload(model, c)?;
        }
        Ok(())
    }

    /// Each value at the end of the step becomes the next step's starting value.
    pub fn end_step(&mut self, model: &InpModel, frame: Frame) {
        for e in self.bcs.values_mut().chain(self.loads.values_mut()) {
            e.old = value_at(model, e, frame.period, frame);
        }
    }

    /// Constraints taking every prescribed DOF from its value at step time `t0` (λ = 0) to its
    /// value at `t1` (λ = 1), and the loads likewise (dead part at t0, the change scaled by λ).
    pub fn constraints(
        &self,
        model: &InpModel,
        frame: Frame,
        t0: f64,
        t1: f64,
    ) -> Result<Constraints, Error> {
        let mut c = Constraints::new(3 * model.mesh.nodes.len());
        for (&d, e) in &self.bcs {
            c.prescribe_ramp(
                d,
                value_at(model, e, t0, frame),
                value_at(model, e, t1, frame),
            )?;
        }
        for (&d, e) in &self.loads {
            let (f0, f1) = (value_at(model, e, t0, frame), value_at(model, e, t1, frame));
            c.set_dead_load(d, f0)?;
            if f1 != f0 {
                c.add_load(d, f1 - f0)?;
            }
        }
        Ok(c)
    }
}

fn value_at(model: &InpModel, e: &Entry, t: f64, frame: Frame) -> f64 {
    match e.amplitude.as_ref().and_then(|a| model.amplitudes.get(a)) {
        Some(a) => e.value * Amplitude::at(a, t, frame.start),
        None => e.old + (e.value - e.old) * (t / frame.period),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn model() -> InpModel {
        nonlin3d_mesh::read_inp(
            "*NODE, NSET=ALL\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n\
             7, 1, 1, 1\n8, 0, 1, 1\n*ELEMENT, TYPE=C3D8, ELSET=E\n1, 1, 2, 3, 4, 5, 6, 7, 8\n\
             *NSET, NSET=A\n1, 2\n*NSET, NSET=B\n2, 3\n*MATERIAL, NAME=M\n*ELASTIC\n1e5, 0.3\n\
             *SOLID SECTION, ELSET=E, MATERIAL=M\n*AMPLITUDE, NAME=UP\n0, 0, 1, 2\n\
             *STEP\n*STATIC\n*CLOAD\nA, 3, 1.\nB, 3, 10.\n*END STEP\n\
             *STEP\n*STATIC\n*CLOAD, AMPLITUDE=UP\n1, 3, 5.\n*END STEP\n\
             *STEP\n*STATIC\n*CLOAD, OP=NEW\n*END STEP\n",
        )
        .unwrap()
    }

    /// CalculiX's rules: two loads on one DOF in a step add; a later step replaces the value;
    /// an amplitude scales the value (no ramp from the old one); OP=NEW ramps the rest to 0.
    #[test]
    fn loads_add_within_a_step_and_replace_across_steps() {
        let m = model();
        let u = vec![0.0; 24];
        let frame = Frame {
            period: 1.0,
            start: 0.0,
        };
        let mut h = History::new(&m);
        let force = |h: &History, t: f64| {
            let c = h.constraints(&m, frame, t, t).unwrap();
            let mut f = vec![0.0; 24];
            c.external(1.0, &mut f);
            (f[2], f[5], f[8])
        };
        h.begin_step(&m, &m.steps[0], &u).unwrap();
        assert_eq!(force(&h, 1.0), (1.0, 11.0, 10.0));
        assert_eq!(force(&h, 0.5), (0.5, 5.5, 5.0));
        h.end_step(&m, frame);
        h.begin_step(&m, &m.steps[1], &u).unwrap();
        // Node 1 now follows UP (2·t·5 at t = 0.25 → 2.5); the others hold.
        assert_eq!(force(&h, 0.25), (2.5, 11.0, 10.0));
        h.end_step(&m, frame);
        h.begin_step(&m, &m.steps[2], &u).unwrap();
        // OP=NEW: values 0; node 1 keeps its amplitude (0·A), the others ramp down.
        assert_eq!(force(&h, 0.5), (0.0, 5.5, 5.0));
        assert_eq!(force(&h, 1.0), (0.0, 0.0, 0.0));
    }
}
