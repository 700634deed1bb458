//! Structs and constants that Rust and WGSL share, declared once in Rust and emitted as WGSL.
//!
//! [`gpu_struct!`](crate::gpu_struct) declares a `#[repr(C)]`, [`Pod`](bytemuck::Pod) struct with
//! each field's WGSL type, and implements [`GpuStruct`]: its members with their Rust offsets
//! (`offset_of!`). [`wgsl_struct`] writes the WGSL declaration from them, inserting `u32` padding
//! members wherever the Rust offsets leave a gap that WGSL's alignment rules would not (so no pad
//! is mirrored by hand: a Rust-only `pad` field is declared with [`WgslType::PAD`]), and panics
//! if a Rust offset is one WGSL cannot express. [`wgsl_consts!`](crate::wgsl_consts) declares
//! `u32` constants and their WGSL `const` lines together. The tests compare every emitted struct
//! with naga's reflection of the composed shader, member by member, from [`GpuStruct::members`].

/// A WGSL type as a struct member: its spelling, size and alignment (storage and uniform rules;
/// a uniform buffer further needs struct-typed members on 16-byte boundaries, which
/// [`wgsl_struct`] checks when asked to).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WgslType {
    /// The WGSL spelling (`vec4<f32>`, a struct's name); empty for [`WgslType::PAD`].
    pub name: &'static str,
    /// Size in bytes.
    pub size: u32,
    /// Alignment in bytes.
    pub align: u32,
}

impl WgslType {
    /// `u32`.
    pub const U32: Self = Self { name: "u32", size: 4, align: 4 };
    /// `i32`.
    pub const I32: Self = Self { name: "i32", size: 4, align: 4 };
    /// `f32`.
    pub const F32: Self = Self { name: "f32", size: 4, align: 4 };
    /// `vec2<u32>`.
    pub const VEC2_U32: Self = Self { name: "vec2<u32>", size: 8, align: 8 };
    /// `vec2<f32>`.
    pub const VEC2_F32: Self = Self { name: "vec2<f32>", size: 8, align: 8 };
    /// `vec3<f32>` (12 bytes, 16-byte aligned: a following scalar packs into its fourth word).
    pub const VEC3_F32: Self = Self { name: "vec3<f32>", size: 12, align: 16 };
    /// `array<f32, 3>` (12 bytes, 4-byte aligned: unlike `vec3<f32>`, packs like `[f32; 3]`).
    pub const ARRAY_F32_3: Self = Self { name: "array<f32, 3>", size: 12, align: 4 };
    /// `array<f32, 6>`.
    pub const ARRAY_F32_6: Self = Self { name: "array<f32, 6>", size: 24, align: 4 };
    /// `vec4<u32>`.
    pub const VEC4_U32: Self = Self { name: "vec4<u32>", size: 16, align: 16 };
    /// `vec4<f32>`.
    pub const VEC4_F32: Self = Self { name: "vec4<f32>", size: 16, align: 16 };
    /// A Rust-only padding field: not declared in WGSL (the generator pads where needed).
    pub const PAD: Self = Self { name: "", size: 0, align: 1 };
}

/// One member of a [`GpuStruct`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Member {
    /// The field's name (the WGSL member's too).
    pub name: &'static str,
    /// Its WGSL type.
    pub ty: WgslType,
    /// Its byte offset in the Rust struct.
    pub offset: u32,
}

impl Member {
    /// Member `name` of WGSL type `ty` at byte `offset` (e.g. from `offset_of!`).
    pub fn new(name: &'static str, ty: WgslType, offset: usize) -> Self {
        Self { name, ty, offset: offset as u32 }
    }
}

/// A `#[repr(C)]` struct that a shader reads, described member by member (see
/// [`gpu_struct!`](crate::gpu_struct)).
pub trait GpuStruct: bytemuck::Pod {
    /// The struct's name in Rust and WGSL.
    const NAME: &'static str;
    /// Its fields in declaration order, with WGSL types and Rust offsets.
    fn members() -> Vec<Member>;
    /// The struct as a member of another: its name, size and alignment (the largest of its
    /// members').
    fn wgsl_type() -> WgslType {
        let align = Self::members().iter().map(|m| m.ty.align).max().unwrap_or(4);
        WgslType { name: Self::NAME, size: size_of::<Self>() as u32, align }
    }
}

/// The WGSL declaration of `T`, with `_padN: u32` members where the Rust layout has gaps that
/// WGSL's rules would not leave, and at the end up to `size_of::<T>()`. With `uniform`, checks
/// the uniform address space's extra rule too (struct-typed members 16-byte aligned).
///
/// # Panics
/// If a Rust offset is below the WGSL offset of its member (the Rust struct packs tighter than
/// WGSL can), a gap is not a multiple of 4 bytes, or `uniform` is violated: a layout bug, caught
/// when the shader is composed (every shader is composed by a test).
pub fn wgsl_struct<T: GpuStruct>(uniform: bool) -> String {
    let mut out = format!("struct {} {{\n", T::NAME);
    let (mut cursor, mut align, mut pads) = (0u32, 4u32, 0u32);
    let mut pad_to = |out: &mut String, cursor: &mut u32, target: u32, what: &str| {
        assert!(
            (target - *cursor).is_multiple_of(4),
            "{}: a gap of {} bytes before {what} is not whole u32s",
            T::NAME,
            target - *cursor
        );
        while *cursor < target {
            out.push_str(&format!("    _pad{pads}: u32,\n"));
            pads += 1;
            *cursor += 4;
        }
    };
    for m in T::members().iter().filter(|m| m.ty != WgslType::PAD) {
        let is_struct = !m.ty.name.contains('<') && !["u32", "i32", "f32"].contains(&m.ty.name);
        let member_align = if uniform && is_struct { m.ty.align.max(16) } else { m.ty.align };
        let natural = cursor.next_multiple_of(member_align);
        assert!(
            m.offset >= natural,
            "{}.{} is at Rust offset {} but WGSL places it at {natural} or later",
            T::NAME,
            m.name,
            m.offset
        );
        if m.offset > natural {
            pad_to(&mut out, &mut cursor, m.offset, m.name);
        }
        assert!(
            m.offset.is_multiple_of(member_align),
            "{}.{} at offset {} is not {member_align}-byte aligned as WGSL requires",
            T::NAME,
            m.name,
            m.offset
        );
        out.push_str(&format!("    {}: {},\n", m.name, m.ty.name));
        cursor = m.offset + m.ty.size;
        align = align.max(member_align);
    }
    let size = size_of::<T>() as u32;
    let wgsl_size = cursor.next_multiple_of(align);
    if size > wgsl_size {
        pad_to(&mut out, &mut cursor, size, "the end");
    }
    assert_eq!(cursor.next_multiple_of(align), size, "{}: WGSL size differs from the Rust size", T::NAME);
    out.push_str("}\n");
    out
}

/// Declares a `#[repr(C)]`, `Pod` struct whose fields carry their WGSL types, and implements
/// [`GpuStruct`] for it. The WGSL struct has the Rust name, or the one given after `as`
/// (`pub struct GpuVertex as "SceneVertex" { … }`):
///
/// ```
/// use furnace_gpu::shared::{WgslType, wgsl_struct};
/// furnace_gpu::gpu_struct! {
///     /// A count and a colour.
///     pub struct Tinted {
///         /// The count.
///         pub count: u32 => WgslType::U32,
///         /// Rust-only: `Pod` allows no implicit padding; WGSL aligns `color` by itself.
///         pub pad: [u32; 3] => WgslType::PAD,
///         /// The colour.
///         pub color: [f32; 4] => WgslType::VEC4_F32,
///     }
/// }
/// furnace_gpu::gpu_struct! {
///     /// Three words in 16 bytes.
///     pub struct Words {
///         /// Word 0.
///         pub a: u32 => WgslType::U32,
///         /// Word 1.
///         pub b: u32 => WgslType::U32,
///         /// Word 2.
///         pub c: u32 => WgslType::U32,
///         /// Rust-only; WGSL would end the struct at 12 bytes, so it gets a `_pad0`.
///         pub pad: u32 => WgslType::PAD,
///     }
/// }
/// assert_eq!(wgsl_struct::<Tinted>(false), "struct Tinted {\n    count: u32,\n    color: vec4<f32>,\n}\n");
/// assert_eq!(wgsl_struct::<Words>(false), "struct Words {\n    a: u32,\n    b: u32,\n    c: u32,\n    _pad0: u32,\n}\n");
/// ```
#[macro_export]
macro_rules! gpu_struct {
    (
        $(#[$meta:meta])*
        pub struct $name:ident as $wgsl_name:literal {
            $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty => $wgsl:expr ),* $(,)?
        }
    ) => {
        $crate::gpu_struct! {
            @named $wgsl_name;
            $(#[$meta])*
            pub struct $name { $( $(#[$fmeta])* pub $field : $ty => $wgsl ),* }
        }
    };
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty => $wgsl:expr ),* $(,)?
        }
    ) => {
        $crate::gpu_struct! {
            @named stringify!($name);
            $(#[$meta])*
            pub struct $name { $( $(#[$fmeta])* pub $field : $ty => $wgsl ),* }
        }
    };
    (
        @named $wgsl_name:expr;
        $(#[$meta:meta])*
        pub struct $name:ident {
            $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty => $wgsl:expr ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        #[repr(C)]
        pub struct $name {
            $( $(#[$fmeta])* pub $field: $ty, )*
        }

        impl $crate::shared::GpuStruct for $name {
            const NAME: &'static str = $wgsl_name;
            fn members() -> Vec<$crate::shared::Member> {
                vec![$($crate::shared::Member {
                    name: stringify!($field),
                    ty: $wgsl,
                    offset: std::mem::offset_of!($name, $field) as u32,
                }),*]
            }
        }
    };
}

/// Declares `u32` constants and a function returning their WGSL `const` declarations, so that a
/// shader and the Rust share one list (`fn name prefix "SCENE_";` prefixes the WGSL names):
///
/// ```
/// furnace_gpu::wgsl_consts! {
///     /// Flags of the example.
///     fn example_flags_wgsl;
///     /// Bit 0.
///     pub const EXAMPLE_A: u32 = 1;
///     /// Bit 1.
///     pub const EXAMPLE_B: u32 = 2;
/// }
/// assert_eq!(EXAMPLE_B, 2);
/// assert_eq!(example_flags_wgsl(), "const EXAMPLE_A: u32 = 1u;\nconst EXAMPLE_B: u32 = 2u;\n");
/// ```
#[macro_export]
macro_rules! wgsl_consts {
    (
        $(#[$fnmeta:meta])*
        fn $fn_name:ident;
        $( $(#[$meta:meta])* pub const $name:ident : u32 = $value:expr; )*
    ) => {
        $crate::wgsl_consts! {
            $(#[$fnmeta])*
            fn $fn_name prefix "";
            $( $(#[$meta])* pub const $name : u32 = $value; )*
        }
    };
    (
        $(#[$fnmeta:meta])*
        fn $fn_name:ident prefix $prefix:literal;
        $( $(#[$meta:meta])* pub const $name:ident : u32 = $value:expr; )*
    ) => {
        $( $(#[$meta])* pub const $name: u32 = $value; )*

        $(#[$fnmeta])*
        pub fn $fn_name() -> String {
            [$((concat!($prefix, stringify!($name)), $name)),*]
                .iter()
                .map(|(n, v)| format!("const {n}: u32 = {v}u;\n"))
                .collect()
        }
    };
}

/// How a shader binds a buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindingKind {
    /// `var<uniform>`, with a dynamic offset or not, of at least `min_size` bytes (0: any).
    Uniform {
        /// Whether the bind group takes a dynamic offset for it.
        dynamic: bool,
        /// The minimum binding size in bytes (0: unchecked).
        min_size: u64,
    },
    /// `var<storage, read>` or `var<storage, read_write>`.
    Storage {
        /// `read` rather than `read_write`.
        read_only: bool,
    },
}

/// One buffer binding of a shader: its WGSL variable, type and kind.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Binding {
    /// The WGSL variable's name.
    pub name: &'static str,
    /// Its WGSL type (`array<u32>`, `FrameParams`).
    pub ty: String,
    /// How it is bound.
    pub kind: BindingKind,
}

impl Binding {
    /// A `var<storage, read>` binding.
    pub fn read(name: &'static str, ty: &str) -> Self {
        Self { name, ty: ty.to_string(), kind: BindingKind::Storage { read_only: true } }
    }

    /// A `var<storage, read_write>` binding.
    pub fn read_write(name: &'static str, ty: &str) -> Self {
        Self { name, ty: ty.to_string(), kind: BindingKind::Storage { read_only: false } }
    }
}

/// One table of a shader's bindings, numbered from `first` in `group`: it writes the WGSL
/// declarations, the bind group layout entries and (given the buffers in the same order) the
/// bind group entries, so the three cannot disagree.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BindingTable {
    /// The bind group.
    pub group: u32,
    /// The binding number of the first entry.
    pub first: u32,
    /// The bindings, numbered `first`, `first + 1`, … in order.
    pub bindings: Vec<Binding>,
}

impl BindingTable {
    /// The table of `bindings` from binding `first` of `group`.
    pub fn new(group: u32, first: u32, bindings: Vec<Binding>) -> Self {
        Self { group, first, bindings }
    }

    /// The WGSL declarations, one line per binding.
    pub fn wgsl(&self) -> String {
        self.bindings
            .iter()
            .enumerate()
            .map(|(k, b)| {
                let space = match b.kind {
                    BindingKind::Uniform { .. } => "uniform",
                    BindingKind::Storage { read_only: true } => "storage, read",
                    BindingKind::Storage { read_only: false } => "storage, read_write",
                };
                format!(
                    "@group({}) @binding({}) var<{space}> {}: {};\n",
                    self.group,
                    self.first + k as u32,
                    b.name,
                    b.ty
                )
            })
            .collect()
    }

    /// The bind group layout entries (compute stage).
    pub fn layout_entries(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        self.bindings
            .iter()
            .enumerate()
            .map(|(k, b)| wgpu::BindGroupLayoutEntry {
                binding: self.first + k as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: match b.kind {
                    BindingKind::Uniform { dynamic, min_size } => wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: dynamic,
                        min_binding_size: wgpu::BufferSize::new(min_size),
                    },
                    BindingKind::Storage { read_only } => wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                },
                count: None,
            })
            .collect()
    }

    /// The bind group entries of `resources`, one per binding in order.
    ///
    /// # Panics
    /// If `resources` does not have one entry per binding (a programming error).
    pub fn bind_entries<'a>(
        &self,
        resources: Vec<wgpu::BindingResource<'a>>,
    ) -> Vec<wgpu::BindGroupEntry<'a>> {
        assert_eq!(resources.len(), self.bindings.len(), "one resource per binding of the table");
        resources
            .into_iter()
            .enumerate()
            .map(|(k, resource)| wgpu::BindGroupEntry { binding: self.first + k as u32, resource })
            .collect()
    }
}
