//! Rust side of the WGSL CWBVH traversal ([`crate::wgsl::TRAVERSE`]): the buffers it binds.
