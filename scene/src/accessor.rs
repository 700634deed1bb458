//! Reading accessors ourselves, with every offset, stride and count checked, instead of through
//! `gltf`'s readers: those underflow on `count = 0`, `debug_assert!` on mismatched component
//! types and `unwrap` on short sparse data, which would panic on invalid files.

use gltf::accessor::{DataType, Dimensions};

/// A located problem: the glTF JSON path and the message.
pub(crate) type Located = (String, String);

fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

fn dims_count(d: Dimensions) -> usize {
    match d {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 => 4,
        Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

/// Reads one component at `bytes[0..]` as f32, normalising integers when `normalized` (glTF 2.0
/// §3.11: `max(c / (2^(b−1) − 1), −1)` for signed, `c / (2^b − 1)` for unsigned).
fn component(bytes: &[u8], t: DataType, normalized: bool) -> f32 {
    let b = |i: usize| bytes.get(i).copied().unwrap_or(0);
    match t {
        DataType::F32 => f32::from_le_bytes([b(0), b(1), b(2), b(3)]),
        DataType::U8 => {
            let v = f32::from(b(0));
            if normalized { v / 255.0 } else { v }
        }
        DataType::I8 => {
            let v = f32::from(b(0) as i8);
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        DataType::U16 => {
            let v = f32::from(u16::from_le_bytes([b(0), b(1)]));
            if normalized { v / 65535.0 } else { v }
        }
        DataType::I16 => {
            let v = f32::from(i16::from_le_bytes([b(0), b(1)]));
            if normalized { (v / 32767.0).max(-1.0) } else { v }
        }
        DataType::U32 => u32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f32,
    }
}

fn uint(bytes: &[u8], t: DataType) -> Option<u32> {
    let b = |i: usize| bytes.get(i).copied().unwrap_or(0);
    match t {
        DataType::U8 => Some(u32::from(b(0))),
        DataType::U16 => Some(u32::from(u16::from_le_bytes([b(0), b(1)]))),
        DataType::U32 => Some(u32::from_le_bytes([b(0), b(1), b(2), b(3)])),
        _ => None,
    }
}

/// The largest number of components furnace reads from one accessor without a buffer view
/// (all zeros, or sparse): bounds the memory an invalid `count` could make us allocate.
const MAX_VIEWLESS_COMPONENTS: usize = 1 << 28;

/// The checked byte range of `count` elements of `elem` bytes at `offset` in `view` with
/// `stride`: returns the view's bytes and the stride.
fn view_slice<'b>(
    view: &gltf::buffer::View<'_>,
    buffers: &'b [Vec<u8>],
    offset: usize,
    count: usize,
    elem: usize,
    path: &str,
) -> Result<(&'b [u8], usize), Located> {
    let vpath = format!("bufferViews[{}]", view.index());
    let buf =
        buffers.get(view.buffer().index()).ok_or_else(|| (vpath.clone(), "buffer not loaded".to_string()))?;
    let vstart = view.offset();
    let vend = vstart.checked_add(view.length()).filter(|&e| e <= buf.len()).ok_or_else(|| {
        (
            vpath.clone(),
            format!(
                "byteOffset {} + byteLength {} exceeds buffers[{}] ({} bytes)",
                vstart,
                view.length(),
                view.buffer().index(),
                buf.len()
            ),
        )
    })?;
    let data = &buf[vstart..vend];
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err((
            format!("{vpath}.byteStride"),
            format!("byteStride {stride} is smaller than the element size {elem}"),
        ));
    }
    if count == 0 {
        return Ok((&data[0..0], stride));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(elem))
        .and_then(|x| x.checked_add(offset))
        .filter(|&e| e <= data.len())
        .ok_or_else(|| {
            (
                path.to_string(),
                format!(
                    "{count} elements of {elem} bytes (stride {stride}) at byteOffset {offset} \
                     do not fit in {vpath} ({} bytes)",
                    data.len()
                ),
            )
        })?;
    Ok((&data[offset..end], stride))
}

/// Reads accessor `acc` as `count × n` floats, requiring its type to be one of `allowed` and
/// `n` components per element. Applies sparse substitution.
pub(crate) fn read_floats(
    acc: &gltf::Accessor<'_>,
    buffers: &[Vec<u8>],
    allowed: &[Dimensions],
) -> Result<(Vec<f32>, usize), Located> {
    let path = format!("accessors[{}]", acc.index());
    let dims = acc.dimensions();
    if !allowed.contains(&dims) {
        return Err((path, format!("type {dims:?} is not one of {allowed:?}")));
    }
    let n = dims_count(dims);
    let t = acc.data_type();
    let csize = component_size(t);
    let elem = n * csize;
    let count = acc.count();
    let normalized = acc.normalized();
    let total = count.checked_mul(n).ok_or_else(|| (path.clone(), format!("count {count} is too large")))?;
    let mut out = match acc.view() {
        Some(view) => {
            let (data, stride) = view_slice(&view, buffers, acc.offset(), count, elem, &path)?;
            let mut out = Vec::with_capacity(total);
            for i in 0..count {
                let e = &data[i * stride..i * stride + elem];
                for c in 0..n {
                    out.push(component(&e[c * csize..], t, normalized));
                }
            }
            out
        }
        None => {
            if total > MAX_VIEWLESS_COMPONENTS {
                return Err((path, format!("count {count} without a bufferView is too large")));
            }
            vec![0.0; total]
        }
    };
    if let Some(sparse) = acc.sparse() {
        let spath = format!("{path}.sparse");
        let scount = sparse.count();
        let ind = sparse.indices();
        let it = match ind.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let isz = component_size(it);
        let (idata, istride) =
            view_slice(&ind.view(), buffers, ind.offset(), scount, isz, &format!("{spath}.indices"))?;
        let vals = sparse.values();
        let (vdata, vstride) =
            view_slice(&vals.view(), buffers, vals.offset(), scount, elem, &format!("{spath}.values"))?;
        // Sparse views are tightly packed (byteStride is not allowed on them).
        let _ = (istride, vstride);
        for k in 0..scount {
            let idx = uint(&idata[k * isz..], it).unwrap_or(0) as usize;
            if idx >= count {
                return Err((
                    format!("{spath}.indices"),
                    format!("sparse index {idx} ≥ accessor count {count}"),
                ));
            }
            let e = &vdata[k * elem..k * elem + elem];
            for c in 0..n {
                out[idx * n + c] = component(&e[c * csize..], t, normalized);
            }
        }
    }
    Ok((out, n))
}

/// Reads an index accessor (scalar `UNSIGNED_BYTE/SHORT/INT`, no normalisation).
pub(crate) fn read_indices(acc: &gltf::Accessor<'_>, buffers: &[Vec<u8>]) -> Result<Vec<u32>, Located> {
    let path = format!("accessors[{}]", acc.index());
    let t = acc.data_type();
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(t, DataType::U8 | DataType::U16 | DataType::U32)
        || acc.normalized()
    {
        return Err((
            path,
            format!(
                "indices must be unnormalised scalar unsigned integers, not {:?} {:?}",
                acc.dimensions(),
                t
            ),
        ));
    }
    if acc.sparse().is_some() {
        // Rare for indices; read through the float path (exact below 2^24).
        let (f, _) = read_floats(acc, buffers, &[Dimensions::Scalar])?;
        return Ok(f.into_iter().map(|x| x as u32).collect());
    }
    let count = acc.count();
    let csize = component_size(t);
    match acc.view() {
        Some(view) => {
            let (data, stride) = view_slice(&view, buffers, acc.offset(), count, csize, &path)?;
            Ok((0..count).map(|i| uint(&data[i * stride..], t).unwrap_or(0)).collect())
        }
        None => {
            if count > MAX_VIEWLESS_COMPONENTS {
                return Err((path, format!("count {count} without a bufferView is too large")));
            }
            Ok(vec![0; count])
        }
    }
}
