//! Placeholder: the BRDF benchmark is being written.
fn main() {}
