//! WGSL struct layouts by naga reflection, compared with their Rust twins.

/// A WGSL struct's layout: its size and each member's (name, offset), as naga computes them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// `size_of` the struct in a storage buffer.
    pub size: u32,
    /// Members in declaration order.
    pub members: Vec<(String, u32)>,
}

/// Parses `source` (WGSL) and returns the layout of struct `name`.
///
/// # Panics
/// If the source does not parse (with naga's message) or has no such struct.
pub fn wgsl_struct(source: &str, name: &str) -> Layout {
    let module =
        naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name)
            && let naga::TypeInner::Struct { members, span } = &ty.inner
        {
            return Layout {
                size: *span,
                members: members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect(),
            };
        }
    }
    panic!("no struct {name} in the WGSL source");
}

/// Asserts that WGSL struct `name` has `size` bytes and the members at the given offsets
/// (names and offsets taken from the Rust `#[repr(C)]` struct, e.g. with `core::mem::offset_of!`).
pub fn assert_layout(source: &str, name: &str, size: usize, members: &[(&str, usize)]) {
    let got = wgsl_struct(source, name);
    let want = Layout {
        size: size as u32,
        members: members.iter().map(|(n, o)| (n.to_string(), *o as u32)).collect(),
    };
    assert_eq!(got, want, "WGSL struct {name} differs from its Rust twin (left: WGSL, right: Rust)");
}

/// Asserts that the WGSL struct `T::NAME` in `source` has `T`'s size and, for every member that
/// the Rust declares for WGSL, the Rust offset (from [`furnace_gpu::shared::GpuStruct::members`]: no list kept by
/// hand). Generated `_pad` members are left out of the comparison; the size covers them.
pub fn assert_gpu_struct<T: furnace_gpu::shared::GpuStruct>(source: &str) {
    let got = wgsl_struct(source, T::NAME);
    let got = Layout {
        size: got.size,
        members: got.members.into_iter().filter(|(n, _)| !n.starts_with("_pad")).collect(),
    };
    let want = Layout {
        size: size_of::<T>() as u32,
        members: T::members()
            .iter()
            .filter(|m| m.ty != furnace_gpu::shared::WgslType::PAD)
            .map(|m| (m.name.to_string(), m.offset))
            .collect(),
    };
    assert_eq!(
        got,
        want,
        "WGSL struct {} differs from its Rust description (left: WGSL, right: Rust)",
        T::NAME
    );
}
