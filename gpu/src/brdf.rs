//! Rust side of the WGSL BSDFs ([`crate::wgsl::BRDF`]): material records and tables a shader
//! receives.
