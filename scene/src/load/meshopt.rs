//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views stored compressed by
//! meshoptimizer's codecs, decoded with meshoptimizer's own decoders (the `meshopt` crate) into
//! the views' place in their buffer before any accessor reads them.
//!
//! A compressed view names a range of a source buffer, the element count and size
//! (`count`, `byteStride`), the codec (`mode`: ATTRIBUTES, TRIANGLES, INDICES) and a filter
//! applied after decoding (`filter`: NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL, and with the KHR
//! extension COLOR). The view's own buffer is often a placeholder marked `fallback: true`,
//! without data: it is not read, and holds the decoded bytes.

use super::context::Ctx;
use crate::error::SceneError;
use gltf::json::Value;

/// The two extensions' names, the ratified one first (a view carrying both is decoded by it).
pub(super) const EXTENSIONS: [&str; 2] = ["KHR_meshopt_compression", "EXT_meshopt_compression"];

/// The most bytes one file's compressed views may decode to: 4 GiB. The indices of a scene of
/// [`super::MAX_TRIANGLES`] triangles alone take 3 GiB; the bound keeps a file of a few bytes
/// that declares a huge `count` from making the loader allocate past that.
const MAX_DECODED_BYTES: u64 = 1 << 32;

/// The meshoptimizer codec versions the bundled decoders read (meshoptimizer 1.3, through
/// meshopt 0.7): vertex codec 0 and 1, index codec 0 and 1. A stream of a later version is
/// refused by name instead of as corrupt data.
const DECODER_VERSION: u8 = 1;

/// Whether buffer `b` is a meshopt fallback: its data (if any) is not needed, since the
/// compressed views that use it are decoded into it.
pub(super) fn is_fallback(b: &gltf::Buffer<'_>) -> bool {
    EXTENSIONS.iter().any(|name| {
        b.extension_value(name).and_then(|e| e.get("fallback")).and_then(Value::as_bool) == Some(true)
    })
}

/// A compressed view's extension object, checked.
struct Compressed {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    Color,
}

/// Decodes every compressed buffer view into its buffer (`buffers`, indexed as the file's).
pub(super) fn decode_views(
    ctx: &Ctx<'_>,
    doc: &gltf::Document,
    buffers: &mut [Vec<u8>],
) -> Result<(), SceneError> {
    let mut total: u64 = 0;
    for view in doc.views() {
        let Some((name, ext)) = EXTENSIONS.iter().find_map(|&n| view.extension_value(n).map(|e| (n, e)))
        else {
            continue;
        };
        let path = format!("bufferViews[{}].extensions.{name}", view.index());
        let invalid = |message: String| ctx.invalid((path.clone(), message));
        let c = parse(ext, name == EXTENSIONS[0]).map_err(invalid)?;
        // `count × byteStride` bytes fill the view: the specification asks for its byteLength;
        // fewer are accepted, the rest of the view left as it was (zeros in a fallback buffer).
        let size = c.count.checked_mul(c.stride).filter(|&s| s <= view.length()).ok_or_else(|| {
            invalid(format!(
                "count {} × byteStride {} exceeds the bufferView's byteLength {}",
                c.count,
                c.stride,
                view.length()
            ))
        })?;
        let target = view.buffer();
        if view.offset().checked_add(view.length()).is_none_or(|e| e > target.length()) {
            return Err(ctx.invalid((
                format!("bufferViews[{}]", view.index()),
                format!(
                    "byteOffset {} + byteLength {} exceeds buffers[{}] ({} bytes)",
                    view.offset(),
                    view.length(),
                    target.index(),
                    target.length()
                ),
            )));
        }
        // No overflow: `size` ≤ byteLength, and byteOffset + byteLength fits (checked above).
        let (end, view_end) = (view.offset() + size, view.offset() + view.length());
        // What this view makes the loader allocate: its decoded bytes, or what its (fallback)
        // buffer grows by to hold the view, whichever is more.
        let growth = view_end.saturating_sub(buffers.get(target.index()).map_or(0, Vec::len));
        total = total.saturating_add(size.max(growth) as u64);
        if total > MAX_DECODED_BYTES {
            return Err(invalid(format!(
                "the compressed views decode to more than the {} GiB a file may decode to",
                MAX_DECODED_BYTES >> 30
            )));
        }
        let source =
            c.offset.checked_add(c.length).and_then(|e| buffers.get(c.buffer)?.get(c.offset..e)).ok_or_else(
                || {
                    invalid(format!(
                        "byteOffset {} + byteLength {} exceeds buffers[{}] ({} bytes)",
                        c.offset,
                        c.length,
                        c.buffer,
                        buffers.get(c.buffer).map_or(0, Vec::len)
                    ))
                },
            )?;
        let decoded = decode(&c, source).map_err(invalid)?;
        let data = &mut buffers[target.index()];
        // A fallback buffer holds no data: it grows to hold the compressed views.
        if data.len() < view_end {
            data.resize(view_end, 0);
        }
        data[view.offset()..end].copy_from_slice(&decoded);
    }
    Ok(())
}

/// Reads the extension object of a compressed view (`khr`: the KHR extension, which adds the
/// COLOR filter) and checks what meshoptimizer's decoders require of it.
fn parse(ext: &Value, khr: bool) -> Result<Compressed, String> {
    let uint = |key: &str, default: Option<u64>| -> Result<usize, String> {
        match ext.get(key) {
            None => default.ok_or_else(|| format!("{key} is missing")),
            Some(v) => v.as_u64().ok_or_else(|| format!("{key} is not a non-negative integer")),
        }
        .and_then(|v| usize::try_from(v).map_err(|_| format!("{key} {v} is too large")))
    };
    let text = |key: &str, default: Option<&'static str>| -> Result<String, String> {
        match ext.get(key) {
            None => default.map(str::to_string).ok_or_else(|| format!("{key} is missing")),
            Some(v) => v.as_str().map(str::to_string).ok_or_else(|| format!("{key} is not a string")),
        }
    };
    let mode = match text("mode", None)?.as_str() {
        "ATTRIBUTES" => Mode::Attributes,
        "TRIANGLES" => Mode::Triangles,
        "INDICES" => Mode::Indices,
        other => return Err(format!("mode '{other}' is not ATTRIBUTES, TRIANGLES or INDICES")),
    };
    let filter = match text("filter", Some("NONE"))?.as_str() {
        "NONE" => Filter::None,
        "OCTAHEDRAL" => Filter::Octahedral,
        "QUATERNION" => Filter::Quaternion,
        "EXPONENTIAL" => Filter::Exponential,
        "COLOR" if khr => Filter::Color,
        other => return Err(format!("filter '{other}' is not one of this extension's filters")),
    };
    let c = Compressed {
        buffer: uint("buffer", None)?,
        offset: uint("byteOffset", Some(0))?,
        length: uint("byteLength", None)?,
        stride: uint("byteStride", None)?,
        count: uint("count", None)?,
        mode,
        filter,
    };
    // The decoders assert these (an assertion ends the process), so they are checked here.
    let (stride, count) = (c.stride, c.count);
    match mode {
        Mode::Attributes if !(stride.is_multiple_of(4) && (4..=256).contains(&stride)) => {
            return Err(format!("byteStride {stride} of ATTRIBUTES is not a multiple of 4 in 4–256"));
        }
        Mode::Triangles | Mode::Indices if stride != 2 && stride != 4 => {
            return Err(format!("byteStride {stride} of {mode:?} indices is not 2 or 4"));
        }
        Mode::Triangles if !count.is_multiple_of(3) => {
            return Err(format!("count {count} of TRIANGLES is not a multiple of 3"));
        }
        _ => {}
    }
    let filter_strides: &[usize] = match filter {
        Filter::None | Filter::Exponential => &[],
        Filter::Octahedral | Filter::Color => &[4, 8],
        Filter::Quaternion => &[8],
    };
    if filter != Filter::None && mode != Mode::Attributes {
        return Err(format!("filter {filter:?} applies to ATTRIBUTES only, not {mode:?}"));
    }
    if !filter_strides.is_empty() && !filter_strides.contains(&stride) {
        return Err(format!(
            "byteStride {stride} does not suit filter {filter:?} (it needs {filter_strides:?})"
        ));
    }
    Ok(c)
}

/// Decodes one view's stream (`source`) into `count × byteStride` bytes.
fn decode(c: &Compressed, source: &[u8]) -> Result<Vec<u8>, String> {
    check_version(c.mode, source)?;
    if c.count == 0 {
        return Ok(Vec::new());
    }
    let failed = |e: meshopt::Error| match e {
        meshopt::Error::Native(-1) => "the stream's header is not meshoptimizer's".to_string(),
        meshopt::Error::Native(-2) => "the stream is truncated or corrupt".to_string(),
        other => format!("the stream does not decode: {other}"),
    };
    match c.mode {
        Mode::Attributes => {
            let mut words = decode_vertices(source, c.count, c.stride).map_err(failed)?;
            apply_filter(c.filter, &mut words, c.stride);
            // The decoder and the filters wrote bytes in memory order: taken as they are.
            Ok(bytemuck::cast_slice(&words).to_vec())
        }
        Mode::Triangles if c.stride == 2 => {
            let v: Vec<u16> = meshopt::decode_index_buffer(source, c.count).map_err(failed)?;
            Ok(v.iter().flat_map(|i| i.to_le_bytes()).collect())
        }
        Mode::Triangles => {
            let v: Vec<u32> = meshopt::decode_index_buffer(source, c.count).map_err(failed)?;
            Ok(v.iter().flat_map(|i| i.to_le_bytes()).collect())
        }
        Mode::Indices if c.stride == 2 => {
            let v: Vec<u16> = meshopt::decode_index_sequence(source, c.count).map_err(failed)?;
            Ok(v.iter().flat_map(|i| i.to_le_bytes()).collect())
        }
        Mode::Indices => {
            let v: Vec<u32> = meshopt::decode_index_sequence(source, c.count).map_err(failed)?;
            Ok(v.iter().flat_map(|i| i.to_le_bytes()).collect())
        }
    }
}

/// Refuses a stream whose header names a codec version the bundled decoders do not read.
fn check_version(mode: Mode, source: &[u8]) -> Result<(), String> {
    let (header, codec) = match mode {
        Mode::Attributes => (0xa0, "vertex"),
        Mode::Triangles => (0xe0, "index"),
        Mode::Indices => (0xd0, "index sequence"),
    };
    match source.first() {
        Some(&b) if b & 0xf0 == header && b & 0x0f > DECODER_VERSION => Err(format!(
            "{codec} codec version {}: the meshoptimizer decoders furnace is built with (1.3, through \
             meshopt 0.7) read versions up to {DECODER_VERSION}",
            b & 0x0f
        )),
        _ => Ok(()),
    }
}

/// meshoptimizer's vertex decoder, with the view's `stride` (4 to 256 bytes, a multiple of 4),
/// into 32-bit words (the filters read them in place).
fn decode_vertices(source: &[u8], count: usize, stride: usize) -> Result<Vec<u32>, meshopt::Error> {
    debug_assert!(stride.is_multiple_of(4) && (4..=256).contains(&stride));
    let mut words = vec![0u32; count * stride / 4];
    // meshopt's safe `decode_vertex_buffer` takes the stride from a type's size; a glTF view's
    // stride is known only at run time, so the decoder is called directly.
    #[allow(unsafe_code)]
    // SAFETY: `words` holds `count × stride` bytes, exactly what the decoder writes for `count`
    // vertices of `stride` bytes; it reads at most `source.len()` bytes of `source`, and
    // `stride` is within what it accepts (checked by `parse`).
    let rc = unsafe {
        meshopt::ffi::meshopt_decodeVertexBuffer(
            words.as_mut_ptr().cast(),
            count,
            stride,
            source.as_ptr(),
            source.len(),
        )
    };
    if rc == 0 { Ok(words) } else { Err(meshopt::Error::Native(rc)) }
}

/// Applies a filter in place to decoded vertices of `stride` bytes (a stride that suits the
/// filter: checked by `parse`), through meshopt's safe wrappers over meshoptimizer's filters.
fn apply_filter(filter: Filter, words: &mut [u32], stride: usize) {
    match (filter, stride) {
        (Filter::None, _) => {}
        (Filter::Octahedral, 4) => meshopt::decode_filter_oct::<i8>(bytemuck::cast_slice_mut(words)),
        (Filter::Octahedral, _) => meshopt::decode_filter_oct::<i16>(bytemuck::cast_slice_mut(words)),
        (Filter::Quaternion, _) => meshopt::decode_filter_quat(bytemuck::cast_slice_mut(words)),
        // Each 32-bit value is decoded on its own, whatever the vector's width.
        (Filter::Exponential, _) => meshopt::decode_filter_exp::<1>(bytemuck::cast_slice_mut(words)),
        (Filter::Color, 4) => meshopt::decode_filter_color::<u8>(bytemuck::cast_slice_mut(words)),
        (Filter::Color, _) => meshopt::decode_filter_color::<u16>(bytemuck::cast_slice_mut(words)),
    }
}
