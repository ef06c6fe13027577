//! Batched kernels over many elements of one kind and rule: the modern form of thesis §2.4.
//!
//! The shape data are tabulated once ([`ShapeTable`]); each element's work runs over all its
//! stations at once (T stacked over NSTR·NG rows, eq. 2.4.2.3) in SIMD code; chunks of elements
//! run on the rayon pool of the caller, each chunk with its own [`Workspace`]. The per-element
//! arithmetic is the single-element kernel's, so results are bitwise identical to
//! [`evaluate`](crate::evaluate) and independent of the number of threads.

use crate::kernel::{Job, OutView, check_finite, check_material, run};
use crate::prefetch::Prefetch;
use crate::{AsMaterial, ElementError, ElementOutput, Kinematics, ShapeTable, Workspace};
use nonlin3d_laminate::Stiffness;
use rayon::prelude::*;

/// Elements per rayon task: large enough to amortise task overhead (~1 µs) against
/// ~10 µs per Hex20, small enough to balance 2–64 threads on meshes of a few thousand cells.
const CHUNK: usize = 32;

/// Inputs of a batch: all elements share the table; each has a material index. The materials
/// are [`Stiffness`]es (uniform), or [`Material`](crate::Material)s, of which some may vary
/// with the position.
#[derive(Debug, Clone, Copy)]
pub struct BatchInput<'a, M = Stiffness> {
    /// Node coordinates, `nodes()` triples per element, element after element.
    pub coords: &'a [[f64; 3]],
    /// Nodal displacements, same layout as `coords`.
    pub disp: &'a [[f64; 3]],
    /// The materials (already rotated to each cell's ply angle).
    pub materials: &'a [M],
    /// Index into `materials` for each element.
    pub material_of: &'a [usize],
}

/// Results of a batch, element after element.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BatchOutput {
    /// Internal forces, `dofs()` per element.
    pub forces: Vec<f64>,
    /// Tangents, `dofs()²` per element (empty unless requested).
    pub tangents: Vec<f64>,
    /// Strains, one per station per element.
    pub strains: Vec<[f64; 6]>,
    /// Stresses, one per station per element.
    pub stresses: Vec<[f64; 6]>,
    /// Strain energy per element.
    pub energy: Vec<f64>,
}

impl BatchOutput {
    /// Output buffers for `elements` elements of `table` (tangent storage only if asked).
    pub fn new(table: &ShapeTable, elements: usize, tangent: bool) -> Self {
        let nd = table.dofs();
        let ns = table.stations().len();
        Self {
            forces: vec![0.0; elements * nd],
            tangents: if tangent {
                vec![0.0; elements * nd * nd]
            } else {
                Vec::new()
            },
            strains: vec![[0.0; 6]; elements * ns],
            stresses: vec![[0.0; 6]; elements * ns],
            energy: vec![0.0; elements],
        }
    }
}

impl<M: AsMaterial> BatchInput<'_, M> {
    /// Checks the input lengths against `table`, the material indices, and each material
    /// against the rule (see [`ElementError::CoupledTransverseShear`]).
    fn validate(&self, table: &ShapeTable) -> Result<(), ElementError> {
        let nn = table.nodes();
        let n = self.material_of.len();
        for (what, expected, got) in [
            ("batch coordinates", n * nn, self.coords.len()),
            ("batch displacements", n * nn, self.disp.len()),
        ] {
            if expected != got {
                return Err(ElementError::LengthMismatch {
                    what,
                    expected,
                    got,
                });
            }
        }
        let count = self.materials.len();
        if let Some((element, &material)) = self
            .material_of
            .iter()
            .enumerate()
            .find(|(_, m)| **m >= count)
        {
            return Err(ElementError::MaterialIndex {
                element,
                material,
                count,
            });
        }
        for (i, m) in self.materials.iter().enumerate() {
            // A material in varying axes is checked at each station, as it is turned.
            if let (m, None) = m.parts() {
                check_material(table, m, i)?;
            }
        }
        Ok(())
    }

    /// Evaluates element `e` into `out`; errors name the element.
    #[allow(clippy::too_many_arguments)]
    fn run_element(
        &self,
        table: &ShapeTable,
        e: usize,
        nonlinear: bool,
        tangent: bool,
        prefetch: Prefetch<'_>,
        ws: &mut Workspace,
        out: OutView<'_>,
    ) -> Result<(), ElementError> {
        let nn = table.nodes();
        let coords = &self.coords[e * nn..(e + 1) * nn];
        let disp = &self.disp[e * nn..(e + 1) * nn];
        let index = self.material_of[e];
        let (material, axes) = self.materials[index].parts();
        let job = Job {
            table,
            coords,
            disp,
            material,
            axes,
            index,
            nonlinear,
            tangent,
            prefetch,
        };
        check_finite(coords, "coordinates")
            .and_then(|_| check_finite(disp, "displacements"))
            .and_then(|_| run(job, ws, out))
            .map_err(|err| err.at_element(e))
    }
}

/// Evaluates every element of the batch into `out` (sized by [`BatchOutput::new`]), in
/// parallel on the current rayon pool. The tangents are computed when `out.tangents` is
/// non-empty. The first failing element (lowest index) is reported.
pub fn evaluate_batch<M: AsMaterial>(
    table: &ShapeTable,
    input: &BatchInput<'_, M>,
    kinematics: Kinematics,
    out: &mut BatchOutput,
) -> Result<(), ElementError> {
    input.validate(table)?;
    let nd = table.dofs();
    let ns = table.stations().len();
    let n = input.material_of.len();
    let tangent = !out.tangents.is_empty();
    let kd = if tangent { nd * nd } else { 0 };
    for (what, expected, got) in [
        ("batch forces", n * nd, out.forces.len()),
        ("batch strains", n * ns, out.strains.len()),
        ("batch stresses", n * ns, out.stresses.len()),
        ("batch energy", n, out.energy.len()),
        ("batch tangents", n * kd, out.tangents.len()),
    ] {
        if expected != got {
            return Err(ElementError::LengthMismatch {
                what,
                expected,
                got,
            });
        }
    }
    let nonlinear = kinematics == Kinematics::Nonlinear;
    // Split the outputs into per-chunk pieces up front (sequential and cheap), then run the
    // chunks in parallel; `collect` keeps chunk order, so the first error is the lowest index.
    let mut tangent_chunks: Vec<&mut [f64]> = if tangent {
        out.tangents.chunks_mut(CHUNK * kd).collect()
    } else {
        Vec::new()
    };
    tangent_chunks.resize_with(n.div_ceil(CHUNK), Default::default);
    let chunks: Vec<_> = out
        .forces
        .chunks_mut(CHUNK * nd)
        .zip(out.strains.chunks_mut(CHUNK * ns))
        .zip(out.stresses.chunks_mut(CHUNK * ns))
        .zip(out.energy.chunks_mut(CHUNK))
        .zip(tangent_chunks)
        .collect();
    let results: Vec<Result<(), ElementError>> = chunks
        .into_par_iter()
        .enumerate()
        .map(
            |(chunk, ((((forces, strains), stresses), energy), tangents))| {
                let mut ws = Workspace::new(table);
                for (i, e_energy) in energy.iter_mut().enumerate() {
                    let view = OutView {
                        strains: &mut strains[i * ns..(i + 1) * ns],
                        stresses: &mut stresses[i * ns..(i + 1) * ns],
                        forces: &mut forces[i * nd..(i + 1) * nd],
                        energy: e_energy,
                        tangent: if tangent {
                            &mut tangents[i * kd..(i + 1) * kd]
                        } else {
                            &mut []
                        },
                    };
                    input.run_element(
                        table,
                        chunk * CHUNK + i,
                        nonlinear,
                        tangent,
                        Prefetch::NONE,
                        &mut ws,
                        view,
                    )?;
                }
                Ok(())
            },
        )
        .collect();
    results.into_iter().collect()
}

/// Evaluates the `elements` listed (indices into the batch, in the order given) one after
/// another on the calling thread, handing each output to `consume(element, output)` while it is
/// in cache. The building block of an owner-computes assembly, where each thread runs its own
/// list and scatters into its own part of the global arrays. The per-element arithmetic is that
/// of [`evaluate`](crate::evaluate); the first failing element stops the run and is named.
pub fn evaluate_listed_with<M: AsMaterial, F>(
    table: &ShapeTable,
    input: &BatchInput<'_, M>,
    kinematics: Kinematics,
    tangent: bool,
    elements: &[usize],
    consume: F,
) -> Result<(), ElementError>
where
    F: FnMut(usize, &ElementOutput),
{
    evaluate_listed_prefetching(
        table,
        input,
        kinematics,
        tangent,
        elements,
        |_| Prefetch::NONE,
        consume,
    )
}

/// [`evaluate_listed_with`], with `ahead(k)` giving cache lines that `consume` will touch after
/// the k-th listed element (k counts from 0 along `elements`): they are prefetched during that
/// element's tangent product, so their misses overlap its arithmetic instead of stalling the
/// consumer. Results are the same as without hints, bit for bit.
pub fn evaluate_listed_prefetching<'p, M: AsMaterial, A, F>(
    table: &ShapeTable,
    input: &BatchInput<'_, M>,
    kinematics: Kinematics,
    tangent: bool,
    elements: &[usize],
    mut ahead: A,
    mut consume: F,
) -> Result<(), ElementError>
where
    A: FnMut(usize) -> Prefetch<'p>,
    F: FnMut(usize, &ElementOutput),
{
    input.validate(table)?;
    let n = input.material_of.len();
    let nonlinear = kinematics == Kinematics::Nonlinear;
    let mut ws = Workspace::new(table);
    let mut one = ElementOutput::new(table);
    for (k, &e) in elements.iter().enumerate() {
        if e >= n {
            return Err(ElementError::LengthMismatch {
                what: "listed element index (batch size)",
                expected: n,
                got: e,
            });
        }
        let hints = if tangent { ahead(k) } else { Prefetch::NONE };
        input.run_element(table, e, nonlinear, tangent, hints, &mut ws, one.view())?;
        consume(e, &one);
    }
    Ok(())
}

/// Evaluates every element of the batch and hands each result to `consume` while it is still
/// in cache, instead of storing all of them (a Hex20 tangent is 28.8 kB: storing a thousand
/// of them makes the batch memory-bound). Elements are processed in chunks on the current
/// rayon pool; each chunk starts from `init()` and its states are returned in chunk order, so
/// a caller that reduces them in that order gets results independent of the thread count.
///
/// `consume(state, element, output)` sees the element's strains, stresses, forces, energy and,
/// when `tangent` is true, its tangent.
pub fn evaluate_batch_with<M: AsMaterial, S, I, F>(
    table: &ShapeTable,
    input: &BatchInput<'_, M>,
    kinematics: Kinematics,
    tangent: bool,
    init: I,
    consume: F,
) -> Result<Vec<S>, ElementError>
where
    S: Send,
    I: Fn() -> S + Sync,
    F: Fn(&mut S, usize, &ElementOutput) + Sync,
{
    input.validate(table)?;
    let n = input.material_of.len();
    let nonlinear = kinematics == Kinematics::Nonlinear;
    (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|chunk| {
            let mut state = init();
            let mut ws = Workspace::new(table);
            let mut one = ElementOutput::new(table);
            for e in chunk * CHUNK..((chunk + 1) * CHUNK).min(n) {
                input.run_element(
                    table,
                    e,
                    nonlinear,
                    tangent,
                    Prefetch::NONE,
                    &mut ws,
                    one.view(),
                )?;
                consume(&mut state, e, &one);
            }
            Ok(state)
        })
        .collect()
}
