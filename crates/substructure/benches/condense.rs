//! Condensation benchmark (filled in the next commit).
fn main() {}
