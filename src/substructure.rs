//! The pipeline with a superelement (thesis §2.6, §3.2 and Fig. 3.2.2, §4.5): the full model
//! is built as without one; the mesh crate's partition picks the nonlinear cells
//! ([`nonlinear_region`]); the linear region is condensed once onto the interface
//! (K_red = K_bb − K_bi K_ii⁻¹ K_ib, and its load per unit λ: the prescribed end u = W·ε lies
//! in the linear region, so the strain sweep needs no new condensation); Newton solves the
//! nonlinear sub-mesh with the superelement as one more contribution; after each level the
//! linear region is recovered, u_i = K_ii⁻¹ (f_i − K_ib u_b − K_ip u_p), and VCCT runs on the
//! full field.
//!
//! With crack-face contact (`auto`/`on`, the sublaminate partition only) the nonlinear region
//! also holds the base cells under the delamination, so that both faces of every pair are
//! Newton's DOFs, and the contact stage runs on the nonlinear problem (`ContactHost`).
//!
//! VCCT forces (§2.8): the front's nodal forces come from the cells above the front, each
//! with the kinematics of its region: a linear cell's are K_e u_e (small strain, what the
//! thesis used with the front in the linear region and what the superelement assumed), a
//! nonlinear cell's those the scene's `analysis.vcct_forces` asks for.

use crate::Error;
use crate::model::Model;
use crate::problem::{constraints, load_factors};
use crate::scene::{ForceKinematics, PartitionName, Scene};
use nonlin3d_assembly::{Assembler, Constraints, SystemBuilder};
use nonlin3d_element::Kinematics;
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::{Mesh, Partition as Cells, nonlinear_region};
use nonlin3d_newton::StructuralProblem;
use nonlin3d_substructure::{
    CondenseSettings, Partition, Recovery, Superelement, condense, mtx_text,
};

/// The file `[substructure] write_matrix = true` writes K_red to, in the output folder.
pub const MATRIX_FILE: &str = "superelement.mtx";
use nonlin3d_vcct::{FrontRelease, cells_above, release_rates};
use serde::Serialize;

/// One superelement: its sizes and the cost of its condensation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuperelementSummary {
    /// Interface DOFs (the superelement's order).
    pub interface_dofs: usize,
    /// Free interior DOFs condensed out.
    pub interior_dofs: usize,
    /// Prescribed interior DOFs (supports and the loaded end).
    pub prescribed_dofs: usize,
    /// Entries of K_ii's factor.
    pub factor_entries: usize,
    /// Seconds: assembly of K, factorisation of K_ii, block solves and products; and their sum.
    pub seconds: [f64; 3],
    /// Condensation time, s.
    pub condensation_s: f64,
    /// max |K_red − K_redᵀ| / max |K_red| before symmetrising.
    pub asymmetry: f64,
    /// The file K_red was written to (`[substructure] write_matrix = true`), in the output
    /// folder.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matrix_file: Option<String>,
    /// K_red as CalculiX's `.mtx` text (N/m), written by the output stage.
    #[serde(skip)]
    pub mtx: Option<String>,
}

/// What substructuring did, for the CLI and results.json.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SubstructureSummary {
    /// `thesis` or `sublaminate`.
    pub partition: String,
    /// ℓ asked for, mm (thesis's partition).
    pub offset_mm: Option<f64>,
    /// Smallest and largest inside distance of the interface nodes from the front, mm (the ℓ
    /// realised on the mesh; ≤ 0 for the sublaminate partition).
    pub realised_offset_mm: Option<[f64; 2]>,
    /// DOFs of the full model.
    pub full_dofs: usize,
    /// DOFs of the nonlinear problem Newton solves.
    pub nonlinear_dofs: usize,
    /// Nonlinear cells.
    pub nonlinear_cells: usize,
    /// Of those, base cells under the delamination (with crack-face contact; 0 without).
    pub crack_base_cells: usize,
    /// Linear cells.
    pub linear_cells: usize,
    /// One entry per superelement.
    pub superelements: Vec<SuperelementSummary>,
}

/// The substructured model's state beside the nonlinear problem: the partition, what recovers
/// the linear region, and the full model's assembler for VCCT.
pub struct Substructured {
    partition: Partition,
    recovery: Recovery,
    full: Assembler,
    /// What the contact stage works on (with crack-face contact), until it takes it.
    contact: Option<ContactHost>,
    /// What was done.
    pub summary: SubstructureSummary,
}

/// What the contact stage (src/contact.rs) works on in a substructured model: the nonlinear
/// sub-mesh (both crack faces in it), its nodes' numbers in the full mesh, and the parts of
/// its problem.
pub(crate) struct ContactHost {
    /// The nonlinear sub-mesh.
    pub(crate) mesh: Mesh,
    /// Its node → the full mesh's node.
    pub(crate) to_full: Vec<usize>,
    superelement: Superelement,
    constraints: Constraints,
}

impl ContactHost {
    /// The nonlinear problem (its solid, the superelement, its constraints) with `reserve`
    /// (the contact pairs) in its pattern.
    pub(crate) fn problem(
        &self,
        scene: &Scene,
        model: &Model,
        reserve: impl FnOnce(SystemBuilder) -> SystemBuilder,
    ) -> Result<StructuralProblem, Error> {
        Ok(StructuralProblem::with_contributions(
            assembler(scene, model, &self.mesh)?,
            vec![Box::new(self.superelement.clone())],
            self.constraints.clone(),
            reserve,
        )?)
    }
}

/// The nonlinear-kinematics assembler of `mesh` (the full mesh or a sub-mesh of it) with the
/// model's materials and the scene's rule.
fn assembler(scene: &Scene, model: &Model, mesh: &Mesh) -> Result<Assembler, Error> {
    let rule = scene.analysis.integration.rule();
    Ok(Assembler::new(
        mesh,
        &model.materials,
        ShearCoupling::Exact,
        rule,
        rule,
        Kinematics::Nonlinear,
    )?)
}

/// The nonlinear problem and its [`Substructured`] companion for a scene whose
/// `[substructure] partition` is not `none` (`None` otherwise).
pub fn build(
    scene: &Scene,
    model: &Model,
) -> Result<Option<(StructuralProblem, Substructured)>, Error> {
    let options = scene.substructure;
    let contact = scene.contact.enabled();
    let (cells, name) = match options.partition {
        PartitionName::None => return Ok(None),
        PartitionName::Thesis => {
            let offset_m = options.offset_mm.map_or(model.h, |l| l * 1e-3);
            (Cells::Thesis { offset_m }, "thesis")
        }
        PartitionName::Sublaminate if contact => (Cells::SublaminateAndCrackBase, "sublaminate"),
        PartitionName::Sublaminate => (Cells::Sublaminate, "sublaminate"),
    };
    let region = nonlinear_region(&model.mesh, &model.front_shape, cells)?;
    let partition = Partition::from_nonlinear_cells(&model.mesh, &region.cells)?;
    let build = |mesh: &Mesh| assembler(scene, model, mesh);
    let (_, reference) = load_factors(scene);
    let c = constraints(model, reference)?;
    let threads = match scene.analysis.threads {
        0 => rayon::current_num_threads(),
        n => n,
    };
    let settings = CondenseSettings {
        threads,
        ..CondenseSettings::default()
    };
    let done = condense(&partition, &build(partition.linear_mesh())?, &c, &settings)?;
    let mtx = options
        .write_matrix
        .then(|| mtx_text(&partition, &done.superelement, 1.0));
    let constraints = partition.nonlinear_constraints(&c)?;
    let host = contact.then(|| ContactHost {
        mesh: partition.nonlinear_mesh().clone(),
        to_full: partition.nonlinear_nodes().to_vec(),
        superelement: done.superelement.clone(),
        constraints: constraints.clone(),
    });
    let problem = StructuralProblem::with_contributions(
        build(partition.nonlinear_mesh())?,
        vec![Box::new(done.superelement)],
        constraints,
        |b| b,
    )?;
    let r = &done.report;
    let summary = SubstructureSummary {
        partition: name.into(),
        offset_mm: match cells {
            Cells::Thesis { offset_m } => Some(offset_m * 1e3),
            Cells::Sublaminate | Cells::SublaminateAndCrackBase => None,
        },
        realised_offset_mm: region
            .realised_offset_m
            .map(|(lo, hi)| [lo * 1e3, hi * 1e3]),
        full_dofs: 3 * model.mesh.nodes.len(),
        nonlinear_dofs: problem.assembler().n(),
        nonlinear_cells: partition.nonlinear_cells().len(),
        crack_base_cells: match cells {
            Cells::SublaminateAndCrackBase => model
                .mesh
                .cell_sets
                .get(nonlin3d_mesh::names::SUBLAMINATE)
                .map_or(0, |sub| region.cells.len().saturating_sub(sub.len())),
            _ => 0,
        },
        linear_cells: partition.linear_cells().len(),
        superelements: vec![SuperelementSummary {
            interface_dofs: r.interface_dofs,
            interior_dofs: r.interior_dofs,
            prescribed_dofs: r.prescribed_dofs,
            factor_entries: r.factor_entries,
            seconds: r.seconds,
            condensation_s: r.seconds.iter().sum(),
            asymmetry: r.asymmetry,
            matrix_file: mtx.as_ref().map(|_| MATRIX_FILE.into()),
            mtx,
        }],
    };
    let full = build(&model.mesh)?;
    let sub = Substructured {
        partition,
        recovery: done.recovery,
        full,
        contact: host,
        summary,
    };
    Ok(Some((problem, sub)))
}

impl Substructured {
    /// What the contact stage works on (None without crack-face contact, or once taken).
    pub(crate) fn take_contact_host(&mut self) -> Option<ContactHost> {
        self.contact.take()
    }

    /// Nodal loads in the full mesh's numbering renumbered to the nonlinear sub-mesh's (the
    /// perturbation, §3.2: it acts on the sublaminate's centre, in the nonlinear region).
    pub fn to_nonlinear(&self, loads: &[(usize, f64)]) -> Result<Vec<(usize, f64)>, Error> {
        loads
            .iter()
            .map(|&(d, v)| match self.partition.to_nonlinear(d / 3) {
                Some(s) => Ok((3 * s + d % 3, v)),
                None => Err(Error::Scene(format!(
                    "substructure: the perturbation load at node {} lies in the linear \
                     region; choose a partition whose nonlinear region holds the \
                     sublaminate's centre",
                    d / 3
                ))),
            })
            .collect()
    }

    /// The full model's displacements for the nonlinear region's `u` at load factor λ (§2.6:
    /// the linear region recovered from the interface displacements).
    pub fn recover(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>, Error> {
        Ok(self.recovery.recover(u, lambda)?.displacements)
    }

    /// G along the front at the full state `u` (module docs: each cell above the front with
    /// its region's kinematics).
    pub fn front_table(
        &self,
        scene: &Scene,
        model: &Model,
        u: &[f64],
    ) -> Result<Vec<FrontRelease>, Error> {
        let nonlinear_kin = match scene.analysis.vcct_forces {
            ForceKinematics::Nonlinear => Kinematics::Nonlinear,
            ForceKinematics::Linear => Kinematics::Linear,
        };
        let linear = self.partition.linear_cells();
        let (lin, nonlin): (Vec<usize>, Vec<usize>) = cells_above(&model.front)
            .into_iter()
            .partition(|c| linear.binary_search(c).is_ok());
        let mut f = vec![0.0; u.len()];
        for (cells, kin) in [(lin, Kinematics::Linear), (nonlin, nonlinear_kin)] {
            if !cells.is_empty() {
                let part = self.full.partial_internal(&cells, u, kin)?;
                f.iter_mut().zip(part).for_each(|(a, b)| *a += b);
            }
        }
        Ok(release_rates(&model.front, &model.mesh.nodes, u, &f)?)
    }
}
