//! Rust side of the WGSL samplers ([`crate::wgsl::SAMPLING`]): the parameters a shader receives.
