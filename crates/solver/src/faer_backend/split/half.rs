//! One half of the split (`split.rs`): Mᵢ = [Aᵢᵢ Aᵢₛ; Aₛᵢ Aₛₛ] in its own numbering, its
//! factor up to the separator (f64 or f32, one thread, `partial.rs`), which leaves
//! S′ᵢ = Aₛₛ − Aₛᵢ Aᵢᵢ⁻¹ Aᵢₛ in the separator's columns, and the sweeps over its interior
//! columns that the split solve needs.

use super::partial;
use super::*;

/// One half with the separator appended, in its own numbering: interior DOFs (in the
/// nested-dissection order), then the separator's.
pub(super) struct Half {
    /// Local index → DOF of A.
    pub(super) dofs: Vec<usize>,
    /// Interior DOFs (the first `interior` local indices).
    pub(super) interior: usize,
    /// The factor-order equation of the first interior DOF in the unsplit LDLᵀ.
    pub(super) first: usize,
    pub(super) pattern: SymmetricPattern,
    /// Local value k is A's value `gather[k]`.
    pub(super) gather: Vec<usize>,
    pub(super) symbolic: SymbolicCholesky<usize>,
    pub(super) l: Stored,
    pub(super) buffer: MemBuffer,
    /// Each supernode's descendants, for [`partial::factorize`].
    descendants: partial::Descendants,
}

impl Half {
    /// The pattern of A on `dofs` (renumbered), its gather map and faer's supernodal symbolic
    /// factor in that order.
    pub(super) fn new(
        a: &SymmetricPattern,
        dofs: Vec<usize>,
        interior: usize,
        first: usize,
    ) -> Result<Self, SolverError> {
        let n = a.n();
        let m = dofs.len();
        let mut local = vec![usize::MAX; n];
        for (k, &d) in dofs.iter().enumerate() {
            local[d] = k;
        }
        // Mᵢ's lower triangle in compressed columns, built by counting: each entry of A's lower
        // triangle between two DOFs of the half is one entry of Mᵢ (row max, column min of
        // their local indices), kept with its position in A's values (the gather map). The
        // entries are bucketed by row first, then moved to their columns row by row, so each
        // column's rows come out in increasing order without a sort (two counting sorts).
        let each = |visit: &mut dyn FnMut(usize, usize, usize)| {
            for (j, &lj) in local.iter().enumerate() {
                if lj == usize::MAX {
                    continue;
                }
                let start = a.col_ptr()[j];
                for (p, &i) in a.column(j).iter().enumerate() {
                    let li = local[i];
                    if li != usize::MAX {
                        visit(li.max(lj), li.min(lj), start + p);
                    }
                }
            }
        };
        let mut row_ptr = vec![0usize; m + 1];
        let mut col_ptr = vec![0usize; m + 1];
        each(&mut |r, c, _| {
            row_ptr[r + 1] += 1;
            col_ptr[c + 1] += 1;
        });
        for k in 0..m {
            row_ptr[k + 1] += row_ptr[k];
            col_ptr[k + 1] += col_ptr[k];
        }
        let nnz = col_ptr[m];
        // (column, source) by row.
        let mut by_row = vec![(0usize, 0usize); nnz];
        let mut next = row_ptr.clone();
        each(&mut |r, c, source| {
            by_row[next[r]] = (c, source);
            next[r] += 1;
        });
        let mut rows = vec![0usize; nnz];
        let mut gather = vec![0usize; nnz];
        next.copy_from_slice(&col_ptr);
        for r in 0..m {
            for &(c, source) in &by_row[row_ptr[r]..row_ptr[r + 1]] {
                rows[next[c]] = r;
                gather[next[c]] = source;
                next[c] += 1;
            }
        }
        drop((by_row, next, row_ptr));
        // A's diagonal is stored, so each column starts at its own.
        let pattern = SymmetricPattern::from_sorted_lower(m, col_ptr, rows)?;
        let sym =
            SymbolicSparseColMatRef::new_checked(m, m, pattern.col_ptr(), None, pattern.row_idx());
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        // The identity as a custom order: faer's `Identity` reads the pattern as its upper
        // triangle, a custom order transposes the lower one first.
        let id: Vec<usize> = (0..m).collect();
        let order = SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&id, &id, m));
        let symbolic = factorize_symbolic_cholesky(sym, Side::Lower, order, params)
            .map_err(|e| SolverError::Faer(format!("split half, symbolic: {e:?}")))?;
        // Forced supernodal, faer still answers an empty matrix with a simplicial structure;
        // the sweeps below read supernodes.
        if !matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)) {
            return Err(SolverError::Faer(format!(
                "split half of {m} DOFs: faer gave a simplicial structure"
            )));
        }
        // Scratch for the factorisation on one thread or on the pool's (`factorize`'s `par`).
        let pool = Par::rayon(rayon::current_num_threads().max(1));
        let req = symbolic
            .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.factorize_numeric_ldlt_scratch::<f64>(pool, Default::default()))
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let buffer = MemBuffer::try_new(req).map_err(|_| SolverError::OutOfMemory {
            what: "a split half's workspace",
            bytes: req.size_bytes(),
        })?;
        let descendants = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) => partial::Descendants::new(sn),
            SymbolicCholeskyRaw::Simplicial(_) => unreachable!("checked above"),
        };
        Ok(Self {
            dofs,
            interior,
            first,
            pattern,
            gather,
            symbolic,
            l: Stored::Empty,
            buffer,
            descendants,
        })
    }

    fn supernodal(&self) -> &supernodal::SymbolicSupernodalCholesky<usize> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            SymbolicCholeskyRaw::Simplicial(_) => unreachable!("split halves are supernodal"),
        }
    }

    /// Factors Mᵢ's interior columns in precision `T` with faer's dense kernels on `par` (their
    /// tiles may be taken by a thread the other half has left free; the bits do not depend on
    /// it), judges the interior pivots by `rule` against A's diagonal and returns how many are
    /// negative. The separator's columns are left holding S′ᵢ
    /// ([`add_separator_block`](Self::add_separator_block)).
    pub(super) fn factorize<T: Real>(
        &mut self,
        a: &[f64],
        diag: &[f64],
        rule: PivotRule,
        par: Par,
    ) -> Attempt<usize> {
        let l = T::slot(&mut self.l, self.symbolic.len_val())?;
        // The half's own numbering is its elimination order (identity permutation) and its
        // pattern is the lower triangle, so the loop reads Mᵢ as it is stored.
        let SymbolicCholeskyRaw::Supernodal(sn) = self.symbolic.raw() else {
            unreachable!("split halves are supernodal")
        };
        let lower = partial::Lower {
            col_ptr: self.pattern.col_ptr(),
            rows: self.pattern.row_idx(),
            gather: &self.gather,
            a,
        };
        let ni = self.interior;
        let done = partial::factorize(
            sn,
            &self.descendants,
            lower,
            ni,
            l,
            par,
            MemStack::new(&mut self.buffer),
        );
        match done {
            Ok(()) => {}
            Err(_) if rule.single() => return Ok(Err("f32 elimination met a zero pivot")),
            Err(index) => {
                let dof = self.dofs[index];
                return Err(SolverError::ZeroPivot {
                    equation: self.first + index,
                    dof,
                    pivot: 0.0,
                    diagonal: diag[dof].abs(),
                });
            }
        };
        let l = T::view(&self.l);
        let d = factor_diagonal(&self.symbolic, l);
        let negative = match negative_pivots(
            d[..ni].iter().copied(),
            self.first,
            |k| self.dofs[k],
            diag,
            rule,
        )? {
            Ok(count) => count,
            Err(reason) => return Ok(Err(reason)),
        };
        Ok(Ok(negative))
    }

    /// out += S′ᵢ = Aₛₛ − Aₛᵢ Aᵢᵢ⁻¹ Aᵢₛ on the lower triangle (nₛ × nₛ), read from the separator's
    /// columns that the last factorisation (in precision `T`) updated and left unfactored.
    pub(super) fn add_separator_block<T: Real>(&self, out: MatMut<'_, f64>) {
        partial::add_separator_block(self.supernodal(), T::view(&self.l), self.interior, out);
    }

    /// Supernode k's values (column-major: its width plus its pattern's rows per column), its
    /// first column, its width and the rows below its diagonal block.
    fn supernode_values<'a, T>(
        &'a self,
        l: &'a [T],
        k: usize,
    ) -> (&'a [T], usize, usize, &'a [usize]) {
        let sn = self.supernodal();
        let (b, e) = (sn.supernode_begin()[k], sn.supernode_end()[k]);
        let values = &l[sn.col_ptr_for_val()[k]..sn.col_ptr_for_val()[k + 1]];
        (values, b, e - b, sn.supernode(k).pattern())
    }

    /// z ← D⁻¹L⁻¹z over the interior columns; the separator rows of z collect −Lₛᵢ y
    /// (= −Aₛᵢ Aᵢᵢ⁻¹ bᵢ when z's separator rows start at zero). Per supernode, its interior
    /// columns by [`Sweep::forward`] on y: the supernode's rows, its interior columns' values of
    /// z, then zeros for its own separator columns and its pattern, added to z afterwards.
    pub(super) fn forward<T: Real>(&self, l: &[T], z: &mut [T]) {
        let ni = self.interior;
        let mut y = Vec::new();
        for k in 0..self.supernodal().n_supernodes() {
            let (values, b, w, pattern) = self.supernode_values(l, k);
            if b >= ni {
                break;
            }
            // The supernode's interior columns b..b + m: all of it, or up to the separator.
            let m = w.min(ni - b);
            let rows = w + pattern.len();
            y.clear();
            y.extend_from_slice(&z[b..b + m]);
            y.resize(rows, T::narrow(0.0));
            T::forward(values, rows, m, &mut y);
            z[b..b + m].copy_from_slice(&y[..m]);
            // The rows below: the supernode's own separator columns, then its pattern.
            let below = (b + m..b + w).chain(pattern.iter().copied());
            for (row, &v) in below.zip(&y[m..]) {
                z[row] += v;
            }
            for c in 0..m {
                z[b + c] /= values[c * rows + c];
            }
        }
    }

    /// z ← L⁻ᵀz over the interior columns, the separator rows of z holding xₛ (the
    /// transposed sweep of `forward`): per supernode, [`Sweep::backward`] on its rows' values.
    pub(super) fn backward<T: Real>(&self, l: &[T], z: &mut [T]) {
        let ni = self.interior;
        let mut y = Vec::new();
        for k in (0..self.supernodal().n_supernodes()).rev() {
            let (values, b, w, pattern) = self.supernode_values(l, k);
            if b >= ni {
                continue;
            }
            let m = w.min(ni - b);
            let rows = w + pattern.len();
            y.clear();
            y.extend_from_slice(&z[b..b + m]);
            y.extend(
                (b + m..b + w)
                    .chain(pattern.iter().copied())
                    .map(|row| z[row]),
            );
            T::backward(values, rows, m, &mut y);
            z[b..b + m].copy_from_slice(&y[..m]);
        }
    }
}
