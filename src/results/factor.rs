//! What a solver's symbolic analysis found (results.json `timings.factor`, summary.json
//! `steps[].factor`): the numbers Abaqus prints in its .msg file and CalculiX on its terminal
//! (equations, factor entries, floating-point operations), and how the work lies on the
//! supernode tree, which bounds what threads can gain (docs/PERFORMANCE.md).

use nonlin3d_solver::Analysis;
use serde::Serialize;

/// One system's factor, as its last symbolic analysis found it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FactorSummary {
    /// Which system: "solid" (the level loop's, or a deck step's), "contact" (the contact
    /// loop's, with its reserve as it last grew).
    pub system: &'static str,
    /// Equations (DOFs of the system, constrained ones included).
    pub equations: usize,
    /// The fill-reducing ordering ("METIS", "nested dissection", "AMD", "RCM").
    pub ordering: &'static str,
    /// Stored entries of the factor, and their size in MiB at 8 bytes (f64; half with the
    /// f32 factor of mixed precision).
    pub factor_entries: usize,
    /// The factor's size in f64, MiB.
    pub factor_mib: f64,
    /// Nonzeros of L's lower triangle, diagonal included (what PARDISO and CHOLMOD report).
    pub lower_nonzeros: usize,
    /// Floating-point operations of one numeric factorisation, 10⁹ (Σ c² over the column
    /// counts).
    pub gflop: f64,
    /// Supernodes of faer's supernodal factor (absent: a simplicial or profile factor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub supernodes: Option<usize>,
    /// Columns of the widest supernode (the top separator's dense block, usually).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub widest_supernode: Option<usize>,
    /// 10⁹ flops of the costliest leaf-to-root chain of supernodes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_path_gflop: Option<f64>,
    /// W / critical path: the most that running subtrees side by side can divide a
    /// factorisation's time by, on any number of threads (threads inside the wide
    /// supernodes' dense blocks come on top of it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tree_parallelism: Option<f64>,
}

impl FactorSummary {
    /// The summary of `analysis` of a system of `equations` DOFs.
    pub fn of(system: &'static str, equations: usize, analysis: &Analysis) -> Self {
        let tree = analysis.tree;
        Self {
            system,
            equations,
            ordering: analysis.ordering,
            factor_entries: analysis.factor_entries,
            factor_mib: analysis.factor_entries as f64 * 8.0 / f64::from(1u32 << 20),
            lower_nonzeros: analysis.lower_nonzeros,
            gflop: analysis.flops * 1e-9,
            supernodes: tree.map(|t| t.supernodes),
            widest_supernode: tree.map(|t| t.widest),
            critical_path_gflop: tree.map(|t| t.critical_path_flops * 1e-9),
            tree_parallelism: tree.map(|t| t.parallelism()),
        }
    }

    /// One line for the terminal and the log, e.g. "contact system: 18393 equations, METIS
    /// order, factor 3.15 M entries (24.0 MiB in f64), 4.26 GFLOP a factorisation, 1006
    /// supernodes (widest 417 columns), subtrees side by side ≤ 3.0×".
    pub fn line(&self) -> String {
        let flops = if self.gflop >= 1.0 {
            format!("{:.2} GFLOP", self.gflop)
        } else {
            format!("{:.1} MFLOP", self.gflop * 1e3)
        };
        let mut s = format!(
            "{} system: {} equations, {} order, factor {:.2} M entries ({:.1} MiB in f64), \
             {flops} a factorisation",
            self.system,
            self.equations,
            self.ordering,
            self.factor_entries as f64 * 1e-6,
            self.factor_mib,
        );
        if let (Some(n), Some(w), Some(p)) = (
            self.supernodes,
            self.widest_supernode,
            self.tree_parallelism,
        ) {
            s.push_str(&format!(
                ", {n} supernodes (widest {w} columns), subtrees side by side ≤ {p:.1}×"
            ));
        }
        s
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use nonlin3d_solver::TreeWork;

    #[test]
    fn a_supernodal_analysis_is_summarised_in_the_users_units() {
        let analysis = Analysis {
            factor_entries: 3 << 20,
            lower_nonzeros: 2_500_000,
            flops: 4.26e9,
            bandwidth: None,
            profile: None,
            ordering: "METIS",
            tree: Some(TreeWork {
                supernodes: 1006,
                widest: 417,
                flops: 4.26e9,
                critical_path_flops: 1.42e9,
                largest_supernode_flops: 0.02e9,
            }),
        };
        let f = FactorSummary::of("contact", 18_393, &analysis);
        assert_eq!(f.factor_mib, 24.0);
        assert!((f.gflop - 4.26).abs() < 1e-12);
        assert!((f.tree_parallelism.unwrap() - 3.0).abs() < 1e-12);
        assert_eq!(
            f.line(),
            "contact system: 18393 equations, METIS order, factor 3.15 M entries (24.0 MiB in \
             f64), 4.26 GFLOP a factorisation, 1006 supernodes (widest 417 columns), subtrees \
             side by side ≤ 3.0×"
        );
        // A profile factor has no tree: the line stops after the flops.
        let profile = Analysis {
            tree: None,
            ordering: "RCM",
            ..analysis
        };
        let f = FactorSummary::of(
            "solid",
            9,
            &Analysis {
                flops: 2.76e6,
                ..profile
            },
        );
        assert!(f.supernodes.is_none() && f.line().ends_with(", 2.8 MFLOP a factorisation"));
        let json = serde_json::to_string(&f).unwrap();
        assert!(!json.contains("supernodes") && json.contains("\"ordering\":\"RCM\""));
    }
}
