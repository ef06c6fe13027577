//! The lower crack face's facets, each pair's place in the transformed face basis (module
//! `recover`) and the small vector algebra both need: what `pairs` builds and `recover` reads.

/// One facet of the lower face: its corners in cyclic order, the corners of its cell (for
/// the outward side), and its mid-edge nodes (quadratic cells) with the two corners of each.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Facet {
    pub(crate) corners: [usize; 4],
    pub(crate) cell: Vec<usize>,
    pub(crate) mids: Vec<(usize, [usize; 2])>,
}

/// A lower-face node's place in the transformed face basis N̂ (module `recover`).
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Basis {
    /// Whether the node is a mid-edge node of its facets (quadratic faces).
    pub(crate) mid: bool,
    /// Pairs whose lower node is a mid-edge node next to this corner (on an edge from it).
    pub(crate) next: Vec<usize>,
    /// Mid-edge node: the pairs whose lower node is a corner at an end of its edge (a front
    /// node at an end is no pair and is not listed: its gap is zero).
    pub(crate) ends: Vec<usize>,
    /// ∫ N̂_i dA over the reference facets around the node (m², > 0).
    pub(crate) weight: f64,
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// |a × b|.
pub(crate) fn cross_norm(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = cross(a, b);
    dot(c, c).sqrt()
}

/// n/|n|, None for a zero or non-finite vector.
pub(crate) fn unit(n: [f64; 3]) -> Option<[f64; 3]> {
    let l = dot(n, n).sqrt();
    (l > 0.0 && l.is_finite()).then(|| n.map(|c| c / l))
}
