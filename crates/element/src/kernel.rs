//! The two NONLIN3D kernels: B0BL3D (strains, stresses, internal forces, eq. 2.1.4, 2.3.1) and
//! ESTIF3D (tangent K = Σ TᵀT + geometric stiffness, eq. 2.3.2–2.3.4, 2.4.2.6–2.4.2.7), with
//! their linear (small-strain) variants, in one pass over the stations of a [`ShapeTable`].
//!
//! Total Lagrangian: strains are Green–Lagrange (eq. 2.1.4), stresses second Piola–Kirchhoff,
//! σ = C ε, both referred to the undeformed configuration.

use crate::material::{AsMaterial, CylindricalAxes};
use crate::prefetch::Prefetch;
use crate::simd::{acc3, comb3, dot};
use crate::{ElementError, ElementKind, ShapeTable};
use nonlin3d_laminate::Stiffness;

mod point;
mod tangent;
use point::{Fixed, PointMaterial, Turning};

/// Strain–displacement relations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Kinematics {
    /// Green–Lagrange strains (eq. 2.1.4), B of eq. 2.2.3, geometric stiffness (eq. 2.2.5).
    #[default]
    Nonlinear,
    /// Small strains ε = sym ∇u, constant B, no geometric stiffness: linear substructures and
    /// the VCCT forces of a linear region (§2.6, §2.8).
    Linear,
}

/// What the kernels produce for one element. Allocate once with [`ElementOutput::new`] and
/// reuse: [`evaluate`] writes every field it is asked for without allocating.
#[derive(Debug, Clone, PartialEq)]
pub struct ElementOutput {
    /// Strains at each station, thesis order (xx, yy, zz, γxy, γyz, γxz).
    pub strains: Vec<[f64; 6]>,
    /// Stresses σ = C ε at each station on the components integrated there (the others are
    /// zero: at the selective-reduced rule's 2×2×2 stations σ5 = σ6 = 0, at its centroid
    /// σ1…σ4 = 0).
    pub stresses: Vec<[f64; 6]>,
    /// Internal nodal forces R^α = Σ_θ (σ_i ∂ε_i/∂q^α |J| W)^θ (eq. 2.3.1 without F^α),
    /// node-major (u, v, w per node).
    pub forces: Vec<f64>,
    /// Strain energy ½ Σ_θ (σ_i ε_i |J| W)^θ (eq. 2.1.1).
    pub energy: f64,
    /// Tangent stiffness, row-major (3·NS)², symmetric; written only when asked for.
    pub tangent: Vec<f64>,
}

impl ElementOutput {
    /// Buffers sized for `table`.
    pub fn new(table: &ShapeTable) -> Self {
        let ns = table.stations().len();
        let nd = table.dofs();
        Self {
            strains: vec![[0.0; 6]; ns],
            stresses: vec![[0.0; 6]; ns],
            forces: vec![0.0; nd],
            energy: 0.0,
            tangent: vec![0.0; nd * nd],
        }
    }
}

/// Borrowed output buffers of one element: what the kernel writes into, so a batch can hand
/// it slices of its own arrays without copying.
pub(crate) struct OutView<'a> {
    pub(crate) strains: &'a mut [[f64; 6]],
    pub(crate) stresses: &'a mut [[f64; 6]],
    pub(crate) forces: &'a mut [f64],
    pub(crate) energy: &'a mut f64,
    pub(crate) tangent: &'a mut [f64],
}

impl ElementOutput {
    pub(crate) fn view(&mut self) -> OutView<'_> {
        OutView {
            strains: &mut self.strains,
            stresses: &mut self.stresses,
            forces: &mut self.forces,
            energy: &mut self.energy,
            tangent: &mut self.tangent,
        }
    }
}

/// Scratch space of the kernels for one table: the stacked T matrix (eq. 2.4.2.3).
#[derive(Debug, Clone)]
pub struct Workspace {
    t: Vec<f64>,
}

impl Workspace {
    /// Scratch sized for `table`.
    pub fn new(table: &ShapeTable) -> Self {
        Self {
            t: vec![0.0; table.t_rows() * table.t_stride()],
        }
    }

    fn fits(&self, table: &ShapeTable) -> bool {
        self.t.len() == table.t_rows() * table.t_stride()
    }
}

/// Evaluates one element: strains, stresses, internal forces and energy, and the tangent when
/// `tangent` is true. `coords` and `disp` hold one triple per node in Abaqus order.
///
/// `material` is a [`Stiffness`] (uniform) or a [`Material`](crate::Material) (uniform, or
/// in axes that vary with the position: its stiffness is turned to the axes at each station).
///
/// Errors: wrong lengths, non-finite input, det J ≤ 0 at a station (named), a material that
/// couples the transverse shears under the selective-reduced rule, or one that is no longer
/// positive definite once turned to a station's axes.
#[allow(clippy::too_many_arguments)]
pub fn evaluate<M: AsMaterial + ?Sized>(
    table: &ShapeTable,
    coords: &[[f64; 3]],
    disp: &[[f64; 3]],
    material: &M,
    kinematics: Kinematics,
    tangent: bool,
    workspace: &mut Workspace,
    out: &mut ElementOutput,
) -> Result<(), ElementError> {
    check_lengths(table, coords, disp, workspace, out)?;
    check_finite(coords, "coordinates")?;
    check_finite(disp, "displacements")?;
    let (material, axes) = material.parts();
    if axes.is_none() {
        check_material(table, material, 0)?;
    }
    let nonlinear = kinematics == Kinematics::Nonlinear;
    let job = Job {
        table,
        coords,
        disp,
        material,
        axes,
        index: 0,
        nonlinear,
        tangent,
        prefetch: Prefetch::NONE,
    };
    run(job, workspace, out.view())
}

/// One element's inputs as the internal dispatch passes them along.
#[derive(Clone, Copy)]
pub(crate) struct Job<'a> {
    pub(crate) table: &'a ShapeTable,
    pub(crate) coords: &'a [[f64; 3]],
    pub(crate) disp: &'a [[f64; 3]],
    /// The stiffness: in global axes, or in the local axes of `axes` when those are given.
    pub(crate) material: &'a Stiffness,
    /// Axes that vary with the position (None: `material` holds everywhere).
    pub(crate) axes: Option<&'a CylindricalAxes>,
    /// Index of the material (for messages).
    pub(crate) index: usize,
    pub(crate) nonlinear: bool,
    pub(crate) tangent: bool,
    /// Lines the consumer will need, prefetched during the tangent product.
    pub(crate) prefetch: Prefetch<'a>,
}

/// Monomorphised dispatch on the element kind (node count as a const generic).
pub(crate) fn run(job: Job<'_>, ws: &mut Workspace, out: OutView<'_>) -> Result<(), ElementError> {
    match job.table.kind() {
        ElementKind::Hex8 => dispatch::<8>(job, ws, out),
        ElementKind::Hex20 => dispatch::<20>(job, ws, out),
    }
}

/// Allocates buffers and evaluates one element (the convenience tier over [`evaluate`]).
fn evaluate_owned(
    table: &ShapeTable,
    coords: &[[f64; 3]],
    disp: &[[f64; 3]],
    material: &Stiffness,
    kinematics: Kinematics,
    tangent: bool,
) -> Result<ElementOutput, ElementError> {
    let mut out = ElementOutput::new(table);
    let mut ws = Workspace::new(table);
    evaluate(
        table, coords, disp, material, kinematics, tangent, &mut ws, &mut out,
    )?;
    Ok(out)
}

/// B0BL3D: strains, stresses, internal forces and energy of one element (allocating wrapper).
pub fn b0bl3d(
    table: &ShapeTable,
    coords: &[[f64; 3]],
    disp: &[[f64; 3]],
    material: &Stiffness,
) -> Result<ElementOutput, ElementError> {
    evaluate_owned(table, coords, disp, material, Kinematics::Nonlinear, false)
}

/// ESTIF3D: the tangent stiffness of one element at displacements `disp`, row-major
/// (allocating wrapper).
pub fn estif3d(
    table: &ShapeTable,
    coords: &[[f64; 3]],
    disp: &[[f64; 3]],
    material: &Stiffness,
) -> Result<Vec<f64>, ElementError> {
    Ok(evaluate_owned(table, coords, disp, material, Kinematics::Nonlinear, true)?.tangent)
}

/// The linear (small-strain) stiffness K = Σ B₀ᵀ C B₀ |J| W = Σ TᵀT of one element.
pub fn linear_stiffness(
    table: &ShapeTable,
    coords: &[[f64; 3]],
    material: &Stiffness,
) -> Result<Vec<f64>, ElementError> {
    let zero = vec![[0.0; 3]; table.nodes()];
    Ok(evaluate_owned(table, coords, &zero, material, Kinematics::Linear, true)?.tangent)
}

fn check_lengths(
    table: &ShapeTable,
    coords: &[[f64; 3]],
    disp: &[[f64; 3]],
    ws: &Workspace,
    out: &ElementOutput,
) -> Result<(), ElementError> {
    let nn = table.nodes();
    let nd = table.dofs();
    let ns = table.stations().len();
    let checks = [
        ("coordinates", nn, coords.len()),
        ("displacements", nn, disp.len()),
        ("output forces", nd, out.forces.len()),
        ("output tangent", nd * nd, out.tangent.len()),
        ("output strains", ns, out.strains.len()),
        ("output stresses", ns, out.stresses.len()),
    ];
    for (what, expected, got) in checks {
        if expected != got {
            return Err(ElementError::LengthMismatch {
                what,
                expected,
                got,
            });
        }
    }
    if !ws.fits(table) {
        return Err(ElementError::LengthMismatch {
            what: "workspace (built for another table)",
            expected: table.t_rows() * table.t_stride(),
            got: ws.t.len(),
        });
    }
    Ok(())
}

pub(crate) fn check_finite(v: &[[f64; 3]], what: &'static str) -> Result<(), ElementError> {
    match v.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        Some(node) => Err(ElementError::NonFiniteInput {
            element: None,
            what,
            node,
            value: v[node],
        }),
        None => Ok(()),
    }
}

/// The selective-reduced rule integrates ε1–ε4 and ε5–ε6 at different points; that splits the
/// energy only if C couples neither group with the other. 1e-12 relative is round-off.
pub(crate) fn check_material(
    table: &ShapeTable,
    material: &Stiffness,
    index: usize,
) -> Result<(), ElementError> {
    if table.rule() == crate::IntegrationRule::SelectiveReduced {
        let coupling = material.transverse_shear_coupling();
        if coupling > 1e-12 {
            return Err(ElementError::CoupledTransverseShear {
                element: None,
                material: index,
                coupling,
            });
        }
    }
    Ok(())
}

/// Runs the kernel compiled for AVX2 + FMA when the CPU has them, portable code otherwise.
/// Both give results within round-off of each other; a given machine always takes the same
/// path, so results are reproducible run to run and thread count to thread count.
#[inline]
fn dispatch<const NS: usize>(
    job: Job<'_>,
    ws: &mut Workspace,
    out: OutView<'_>,
) -> Result<(), ElementError> {
    let (Ok(x), Ok(u)) = (
        <&[[f64; 3]; NS]>::try_from(job.coords),
        <&[[f64; 3]; NS]>::try_from(job.disp),
    ) else {
        return Err(ElementError::LengthMismatch {
            what: "coordinates",
            expected: NS,
            got: job.coords.len(),
        });
    };
    match job.axes {
        None => with_simd::<NS, _>(job, Fixed(job.material), x, u, ws, out),
        Some(axes) => {
            let turning = Turning {
                local: job.material,
                axes,
                index: job.index,
                selective: job.table.rule() == crate::IntegrationRule::SelectiveReduced,
                here: *job.material,
            };
            with_simd::<NS, _>(job, turning, x, u, ws, out)
        }
    }
}

/// The kernel with AVX2 + FMA when the CPU has them, portable otherwise.
#[inline(always)]
fn with_simd<const NS: usize, P: PointMaterial>(
    job: Job<'_>,
    points: P,
    x: &[[f64; 3]; NS],
    u: &[[f64; 3]; NS],
    ws: &mut Workspace,
    out: OutView<'_>,
) -> Result<(), ElementError> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: `kernel_avx2` only needs the AVX2 and FMA instruction sets, which were
            // detected on this CPU just above.
            return unsafe { kernel_avx2::<NS, P>(job, points, x, u, ws, out) };
        }
    }
    kernel::<NS, false, P>(job, points, x, u, ws, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn kernel_avx2<const NS: usize, P: PointMaterial>(
    job: Job<'_>,
    points: P,
    x: &[[f64; 3]; NS],
    u: &[[f64; 3]; NS],
    ws: &mut Workspace,
    out: OutView<'_>,
) -> Result<(), ElementError> {
    kernel::<NS, true, P>(job, points, x, u, ws, out)
}

/// Green–Lagrange strains from H = ∂u/∂x (eq. 2.1.4), or ε = sym H when `nonlinear` is false:
/// ε1 = u_x + ½(u_x² + v_x² + w_x²), …, ε4 = u_y + v_x + (u_x u_y + v_x v_y + w_x w_y), …
#[inline(always)]
pub(crate) fn strains(h: &[[f64; 3]; 3], nonlinear: bool) -> [f64; 6] {
    let lin = [
        h[0][0],
        h[1][1],
        h[2][2],
        h[0][1] + h[1][0],
        h[1][2] + h[2][1],
        h[0][2] + h[2][0],
    ];
    if !nonlinear {
        return lin;
    }
    let col = |a: usize, b: usize| h[0][a] * h[0][b] + h[1][a] * h[1][b] + h[2][a] * h[2][b];
    [
        lin[0] + 0.5 * col(0, 0),
        lin[1] + 0.5 * col(1, 1),
        lin[2] + 0.5 * col(2, 2),
        lin[3] + col(0, 1),
        lin[4] + col(1, 2),
        lin[5] + col(0, 2),
    ]
}

/// Inverse (by cofactors) and determinant of a 3×3 matrix.
#[inline(always)]
pub(crate) fn invert(j: &[[f64; 3]; 3]) -> ([[f64; 3]; 3], f64) {
    let cof = [
        [
            j[1][1] * j[2][2] - j[1][2] * j[2][1],
            j[0][2] * j[2][1] - j[0][1] * j[2][2],
            j[0][1] * j[1][2] - j[0][2] * j[1][1],
        ],
        [
            j[1][2] * j[2][0] - j[1][0] * j[2][2],
            j[0][0] * j[2][2] - j[0][2] * j[2][0],
            j[0][2] * j[1][0] - j[0][0] * j[1][2],
        ],
        [
            j[1][0] * j[2][1] - j[1][1] * j[2][0],
            j[0][1] * j[2][0] - j[0][0] * j[2][1],
            j[0][0] * j[1][1] - j[0][1] * j[1][0],
        ],
    ];
    let det = j[0][0] * cof[0][0] + j[0][1] * cof[1][0] + j[0][2] * cof[2][0];
    let inv_det = 1.0 / det;
    let mut inv = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            inv[r][c] = cof[r][c] * inv_det;
        }
    }
    (inv, det)
}

/// The three runs of a structure-of-arrays slice of length 3·NS as arrays.
#[inline(always)]
fn runs<const NS: usize>(v: &[f64]) -> Option<[&[f64; NS]; 3]> {
    let (a, rest) = v.split_first_chunk::<NS>()?;
    let (b, rest) = rest.split_first_chunk::<NS>()?;
    let (c, _) = rest.split_first_chunk::<NS>()?;
    Some([a, b, c])
}

/// The per-element kernel: one pass over the stations (thesis Fig. 2.4.1.1 tasks 1–8 and
/// §2.4.2), then K_L = TᵀT over all stations at once.
///
/// Everything runs along the nodes on structure-of-arrays data (the thesis's vectors of length
/// NS, eq. 2.4.1.2–2.4.1.13): coordinates, displacements and gradients are three runs of NS
/// values. Each T row is three AXPYs of gradient runs (one per direction), interleaved into
/// node-major DOF order as it is written, so K comes out of TᵀT in node-major order.
#[inline(always)]
fn kernel<const NS: usize, const FMA: bool, P: PointMaterial>(
    job: Job<'_>,
    mut points: P,
    x: &[[f64; 3]; NS],
    u: &[[f64; 3]; NS],
    ws: &mut Workspace,
    out: OutView<'_>,
) -> Result<(), ElementError> {
    let Job {
        table,
        nonlinear,
        tangent: want_tangent,
        ..
    } = job;
    let p = table.t_stride();
    let mut xs = [[0.0; NS]; 3];
    let mut us = [[0.0; NS]; 3];
    for m in 0..NS {
        for r in 0..3 {
            xs[r][m] = x[m][r];
            us[r][m] = u[m][r];
        }
    }
    let mut fr = [[0.0; NS]; 3];
    let mut kg = [[0.0; NS]; NS];
    *out.energy = 0.0;
    let mut row0 = 0;
    for (g, st) in table.stations().iter().enumerate() {
        let Some(dl) = runs::<NS>(table.gradients_by_direction(g)) else {
            return Err(ElementError::LengthMismatch {
                what: "shape table",
                expected: 3 * NS,
                got: 0,
            });
        };
        // Tasks 1–2: J_rc = Σ_m ∂N^m/∂ξ_r x^m_c (eq. 2.4.1.1, 2.4.1.9), det and inverse.
        let mut j = [[0.0; 3]; 3];
        for r in 0..3 {
            for cc in 0..3 {
                j[r][cc] = dot::<NS, FMA>(dl[r], &xs[cc]);
            }
        }
        let (inv, det) = invert(&j);
        if !(det > 0.0 && det.is_finite()) {
            return Err(ElementError::NonPositiveJacobian {
                element: None,
                point: g,
                xi: st.xi,
                det,
            });
        }
        // Task 3: global gradients ∂N^m/∂x_k = Σ_r IJ_kr ∂N^m/∂ξ_r (eq. 2.4.1.10–2.4.1.11).
        let mut gr = [[0.0; NS]; 3];
        let dlr = [*dl[0], *dl[1], *dl[2]];
        for k in 0..3 {
            comb3::<NS, FMA>(&mut gr[k], inv[k], &dlr);
        }
        // Task 4: H_ij = ∂u_i/∂x_j = Σ_m u^m_i ∂N^m/∂x_j (eq. 2.4.1.12).
        let mut h = [[0.0; 3]; 3];
        for i in 0..3 {
            for jj in 0..3 {
                h[i][jj] = dot::<NS, FMA>(&us[i], &gr[jj]);
            }
        }
        // Task 5: strains (eq. 2.1.4); stresses on this station's components, with the
        // station's stiffness (the same at every station for a uniform material).
        let material = points.at::<NS, FMA>(g, table.values(g), &xs)?;
        let (c, q) = (material.c(), material.q());
        let e = strains(&h, nonlinear);
        let (lo, hi) = (st.first, st.last);
        let mut s = [0.0; 6];
        for i in lo..hi {
            for k in lo..hi {
                s[i] += c[i][k] * e[k];
            }
        }
        out.strains[g] = e;
        out.stresses[g] = s;
        let w = det * st.weight;
        let mut se = 0.0;
        for i in lo..hi {
            se += s[i] * e[i];
        }
        *out.energy += 0.5 * w * se;
        // Weighted stress σ̂ = σ |J| W as a symmetric tensor, and F = I + H (I when linear).
        let sh = [
            [w * s[0], w * s[3], w * s[5]],
            [w * s[3], w * s[1], w * s[4]],
            [w * s[5], w * s[4], w * s[2]],
        ];
        let mut f = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        if nonlinear {
            for i in 0..3 {
                for jj in 0..3 {
                    f[i][jj] += h[i][jj];
                }
            }
        }
        // Tasks 6–8: R^{mr} += Σ_i B_i^{mr} σ̂_i = Σ_jk F_rj σ̂_jk ∂N^m/∂x_k (eq. 2.3.1, 2.4.1.26).
        for r in 0..3 {
            let mut fs = [0.0; 3];
            for k in 0..3 {
                fs[k] = f[r][0] * sh[0][k] + f[r][1] * sh[1][k] + f[r][2] * sh[2][k];
            }
            acc3::<NS, FMA>(&mut fr[r], fs, &gr);
        }
        if !want_tangent {
            continue;
        }
        // ESTIF3D: T^{sα} = Q_is B_i^α √(|J|W) (eq. 2.3.4, 2.4.2.2–2.4.2.4). B of eq. 2.2.3 is
        // B_i^{mr} = Σ_k β_irk ∂N^m/∂x_k with β_r = rows of F: β_0r = (F_r1, 0, 0), β_1r =
        // (0, F_r2, 0), β_2r = (0, 0, F_r3), β_3r = (F_r2, F_r1, 0), β_4r = (0, F_r3, F_r2),
        // β_5r = (F_r3, 0, F_r1). So T row s, direction r = Σ_k c_srk ∇_k N with
        // c_srk = √w Σ_{i ≥ s} Q_is β_irk: three AXPYs along the nodes.
        let t = &mut ws.t[row0 * p..(row0 + hi - lo) * p];
        tangent::t_rows::<NS, FMA>(t, p, (lo, hi), q, &f, w.sqrt(), &gr);
        row0 += hi - lo;
        if nonlinear {
            tangent::geometric_rows::<NS, FMA>(&mut kg, &sh, &gr);
        }
    }
    for m in 0..NS {
        for r in 0..3 {
            out.forces[3 * m + r] = fr[r][m];
        }
    }
    if want_tangent {
        tangent::finish::<NS, FMA>(
            out.tangent,
            &ws.t,
            row0,
            p,
            job.prefetch,
            nonlinear.then_some(&kg),
        );
    }
    Ok(())
}
