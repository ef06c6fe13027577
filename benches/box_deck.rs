//! A clamped Hex20 box deck for `nonlin3d solve` (issue 20's 1 M-DOF linear static solve), and
//! the factor its stiffness needs under each ordering, from the symbolic analysis alone.
//!
//! Write a deck: `cargo bench --bench box_deck -- 44 44 44 out=box.inp` (cells along x, y, z;
//! `size=LX,LY,LZ` in mm, default 5 mm cubic cells; `load=F` in N, default 1000).
//! Estimate only: `cargo bench --bench box_deck -- 44 44 44 estimate` prints, for AMD, our
//! nested dissection and METIS: nnz(L), faer's factor entries, the flops Σ c² and the factor's
//! size in f64 and f32, and each ordering's time (`estimate=metis` runs METIS alone). No matrix
//! is assembled; the pattern is the deck's (clamped DOFs included, as the solver keeps them).
//! The deck itself: `benches/box_deck/deck.rs`.

#[path = "box_deck/deck.rs"]
mod deck;

use deck::BoxDeck;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Side, perm::PermRef};
use nonlin3d::solver::{
    Permutation, SymmetricPattern, approximate_minimum_degree, metis_nested_dissection,
    nested_dissection,
};
use std::time::Instant;

/// Entries per column of the factor (diagonal included).
fn column_counts(symbolic: &SymbolicCholesky<usize>) -> Vec<usize> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let cp = s.col_ptr();
            (0..s.nrows()).map(|k| cp[k + 1] - cp[k]).collect()
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let mut counts = Vec::with_capacity(s.nrows());
            for k in 0..s.n_supernodes() {
                let width = s.supernode_end()[k] - s.supernode_begin()[k];
                let below = s.supernode(k).pattern().len();
                counts.extend((0..width).map(|c| width - c + below));
            }
            counts
        }
    }
}

fn estimate(pattern: &SymmetricPattern, which: &str) {
    let n = pattern.n();
    let a = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
    type Orderer = fn(&SymmetricPattern) -> Result<Permutation, nonlin3d::solver::SolverError>;
    let all: [(&str, Orderer); 3] = [
        ("AMD", approximate_minimum_degree),
        ("ND", nested_dissection),
        ("METIS", metis_nested_dissection),
    ];
    println!(
        "| ordering | ordering s | symbolic s | nnz(L) | factor entries | GFLOP (Σ c²) | factor GiB f64 | f32 |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for (name, order) in all {
        if which != "all" && !name.eq_ignore_ascii_case(which) {
            continue;
        }
        let t = Instant::now();
        let perm = order(pattern).unwrap_or_else(|e| panic!("{name}: {e}"));
        let ordering = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let p = PermRef::new_checked(perm.forward(), perm.inverse(), n);
        let symbolic = factorize_symbolic_cholesky(
            a,
            Side::Lower,
            SymmetricOrdering::Custom(p),
            CholeskySymbolicParams::default(),
        )
        .unwrap_or_else(|e| panic!("{name}: {e:?}"));
        let symbolic_s = t.elapsed().as_secs_f64();
        let counts = column_counts(&symbolic);
        let nnz: usize = counts.iter().sum();
        let flops: f64 = counts.iter().map(|&c| (c as f64) * (c as f64)).sum();
        let entries = symbolic.len_val();
        let gib = |bytes: f64| bytes / (1u64 << 30) as f64;
        println!(
            "| {name} | {ordering:.2} | {symbolic_s:.2} | {:.1} M | {:.1} M | {:.0} | {:.2} | {:.2} |",
            nnz as f64 / 1e6,
            entries as f64 / 1e6,
            flops / 1e9,
            gib(8.0 * entries as f64),
            gib(4.0 * entries as f64),
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cells: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let [nx, ny, nz] = cells[..] else {
        eprintln!(
            "usage: box_deck NX NY NZ [size=LX,LY,LZ] [load=F] [out=FILE] [estimate[=ORDERING]]"
        );
        std::process::exit(2);
    };
    let value = |key: &str| {
        args.iter()
            .find_map(|a| a.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
    };
    let size = value("size").map_or([5.0 * nx as f64, 5.0 * ny as f64, 5.0 * nz as f64], |s| {
        let v: Vec<f64> = s.split(',').filter_map(|x| x.parse().ok()).collect();
        [v[0], v[1], v[2]]
    });
    let load = value("load").and_then(|v| v.parse().ok()).unwrap_or(1000.0);
    let deck = BoxDeck {
        cells: [nx, ny, nz],
        size,
        load,
    };
    let (dofs, lists) = deck.dof_lists();
    println!(
        "box {nx} × {ny} × {nz} Hex20, {} × {} × {} mm: {dofs} DOF",
        size[0], size[1], size[2]
    );
    if let Some(path) = value("out") {
        let file = std::fs::File::create(path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let mut w = std::io::BufWriter::new(file);
        deck.write(&mut w).unwrap_or_else(|e| panic!("{path}: {e}"));
        println!("wrote {path}");
    }
    let which = if args.iter().any(|a| a == "estimate") {
        Some("all")
    } else {
        value("estimate")
    };
    if let Some(which) = which {
        let t = Instant::now();
        let pattern =
            SymmetricPattern::from_dof_lists(dofs, &lists).unwrap_or_else(|e| panic!("{e}"));
        drop(lists);
        println!(
            "pattern: {} lower entries, {:.2} s",
            pattern.nnz_lower(),
            t.elapsed().as_secs_f64()
        );
        estimate(&pattern, which);
    }
}
