//! `KHR_draco_mesh_compression`: a primitive's attributes and indices decoded from its Draco
//! bitstream (with draco-core, a port of Google's Draco decoder) instead of read from its
//! accessors. The accessors of a compressed attribute (which need no bufferView) give only its
//! type and normalisation; the values, their count and the triangles come from the bitstream.
//! An attribute of the primitive that the extension does not list is read from its accessor
//! as usual.

use super::{Attributes, Meshes};
use crate::accessor::read_floats;
use crate::error::SceneError;
use crate::load::context::Ctx;
use draco_core::{DataType, DecodeLimits, DecoderBuffer, Mesh, MeshDecoder, PointAttribute};
use gltf::accessor::Dimensions;
use gltf::json::Value;
use std::collections::HashMap;

/// The extension's name.
pub(super) const EXTENSION: &str = "KHR_draco_mesh_compression";

/// Decodes primitive `prim` (JSON path `ppath`), whose `KHR_draco_mesh_compression` object is
/// `ext`, into the attributes the loader stores: POSITION (finite), NORMAL, the UV sets stored,
/// COLOR_0 when colours are, TANGENT when tangents are, JOINTS_n and WEIGHTS_n when `skinned`,
/// and the triangles' indices.
pub(super) fn read_attributes(
    ctx: &Ctx<'_>,
    src: &Meshes<'_>,
    prim: &gltf::Primitive<'_>,
    ext: &Value,
    ppath: &str,
    skinned: bool,
) -> Result<Attributes, SceneError> {
    let epath = format!("{ppath}.extensions.{EXTENSION}");
    let (view, ids) = parse(ext, src.doc).map_err(|e| ctx.invalid(at(&epath, e)))?;
    let mesh = decode(bitstream(src.buffers, &view).map_err(|e| ctx.invalid(at(&epath, e)))?)
        .map_err(|m| ctx.invalid((epath.clone(), format!("bufferViews[{}]: {m}", view.index()))))?;
    let decoded = Decoded { ctx, src, mesh: &mesh, ids: &ids, epath: &epath, ppath };
    let positions = decoded
        .attribute(prim.get(&gltf::Semantic::Positions), Dimensions::Vec3, "POSITION")?
        .unwrap_or_default();
    if let Some(i) = positions.iter().position(|x| !x.is_finite()) {
        let v = i / 3;
        return Err(ctx.invalid((
            format!("{epath}.attributes.POSITION"),
            format!(
                "decoded vertex {v} is not finite ({:?}): positions must be finite",
                &positions[3 * v..3 * v + 3]
            ),
        )));
    }
    let normals = decoded.attribute(prim.get(&gltf::Semantic::Normals), Dimensions::Vec3, "NORMAL")?;
    let uvs = (0..src.uv_sets)
        .map(|k| {
            let name = format!("TEXCOORD_{k}");
            decoded.attribute(prim.get(&gltf::Semantic::TexCoords(k as u32)), Dimensions::Vec2, &name)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let colors = match src.needs_color {
        true => {
            let acc = prim.get(&gltf::Semantic::Colors(0));
            let width = acc.as_ref().map_or(4, |a| if a.dimensions() == Dimensions::Vec3 { 3 } else { 4 });
            let dims = if width == 3 { Dimensions::Vec3 } else { Dimensions::Vec4 };
            decoded.attribute(acc, dims, "COLOR_0")?.map(|c| super::rgba(&c, width))
        }
        false => None,
    };
    let tangents = match src.needs_tangent {
        true => decoded.attribute(prim.get(&gltf::Semantic::Tangents), Dimensions::Vec4, "TANGENT")?,
        false => None,
    };
    let skin = match skinned {
        true => super::pose::read_skin_sets(ctx, prim, ppath, |acc, name| {
            decoded.attribute(acc, Dimensions::Vec4, name)
        })?,
        false => Vec::new(),
    };
    let nverts = mesh.num_points();
    let mut indices = Vec::with_capacity(3 * mesh.num_faces());
    for face in mesh.faces() {
        for p in face {
            if p.0 as usize >= nverts {
                return Err(ctx.invalid((
                    epath.clone(),
                    format!("decoded index {} ≥ decoded vertex count {nverts}", p.0),
                )));
            }
            indices.push(p.0);
        }
    }
    Ok(Attributes { positions, normals, uvs, colors, tangents, indices, skin, mirrored: None })
}

/// A problem with a member of the extension object: the member (`bufferView`, `attributes`)
/// and the message.
type Problem = (&'static str, String);

/// A path and a message about something under it.
fn at(epath: &str, (sub, message): Problem) -> (String, String) {
    let path = if sub.is_empty() { epath.to_string() } else { format!("{epath}.{sub}") };
    (path, message)
}

/// The extension object: its bufferView and its map of attribute semantics to Draco attribute
/// ids. Errors name the member (`bufferView`, `attributes.NORMAL`) and the problem.
fn parse<'d>(
    ext: &Value,
    doc: &'d gltf::Document,
) -> Result<(gltf::buffer::View<'d>, HashMap<String, u32>), Problem> {
    let index = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .ok_or(("bufferView", "missing or not a non-negative integer".to_string()))?;
    let view = usize::try_from(index)
        .ok()
        .and_then(|i| doc.views().nth(i))
        .ok_or(("bufferView", format!("bufferViews[{index}] does not exist")))?;
    let attributes = ext
        .get("attributes")
        .and_then(Value::as_object)
        .ok_or(("attributes", "missing or not an object".to_string()))?;
    let mut ids = HashMap::new();
    for (semantic, id) in attributes {
        let Some(id) = id.as_u64().and_then(|i| u32::try_from(i).ok()) else {
            return Err((
                "attributes",
                format!("{semantic}: the Draco attribute id is not a 32-bit unsigned integer"),
            ));
        };
        ids.insert(semantic.clone(), id);
    }
    Ok((view, ids))
}

/// The bytes of `view`, the Draco bitstream.
fn bitstream<'b>(buffers: &'b [Vec<u8>], view: &gltf::buffer::View<'_>) -> Result<&'b [u8], Problem> {
    let buffer = view.buffer().index();
    let end = view.offset().checked_add(view.length());
    buffers.get(buffer).zip(end).and_then(|(b, end)| b.get(view.offset()..end)).ok_or((
        "bufferView",
        format!(
            "bufferViews[{}] (byteOffset {}, byteLength {}) exceeds buffers[{buffer}]",
            view.index(),
            view.offset(),
            view.length()
        ),
    ))
}

/// Decodes a Draco mesh. A scene holds at most [`crate::load::MAX_TRIANGLES`] triangles, so a
/// stream that declares more faces is refused before they are allocated; the decoded attribute
/// bytes keep draco-core's own ceiling (2 GiB).
fn decode(bytes: &[u8]) -> Result<Mesh, String> {
    let limits = DecodeLimits::default().with_max_faces(crate::load::MAX_TRIANGLES);
    // draco-core reports malformed streams as errors; the unwind guard is the last line of
    // defence, so that a panic inside the library on some input not yet seen is an error
    // naming the primitive instead of the end of the process.
    std::panic::catch_unwind(|| {
        let mut buffer = DecoderBuffer::new(bytes).with_limits(limits);
        let mut mesh = Mesh::new();
        MeshDecoder::new().decode(&mut buffer, &mut mesh).map(|()| mesh)
    })
    .map_err(|_| "the Draco decoder panicked on this bitstream (corrupt or unsupported)".to_string())?
    .map_err(|e| format!("the Draco bitstream does not decode: {e}"))
}

/// The decoded mesh of one primitive, and how its attributes are found.
struct Decoded<'a> {
    ctx: &'a Ctx<'a>,
    src: &'a Meshes<'a>,
    mesh: &'a Mesh,
    ids: &'a HashMap<String, u32>,
    epath: &'a str,
    ppath: &'a str,
}

impl Decoded<'_> {
    /// Attribute `name` of type `dims` (`acc` is its accessor, if the primitive has it) as
    /// floats, one element per decoded vertex: from the bitstream when the extension lists it,
    /// else from the accessor.
    fn attribute(
        &self,
        acc: Option<gltf::Accessor<'_>>,
        dims: Dimensions,
        name: &str,
    ) -> Result<Option<Vec<f32>>, SceneError> {
        let Some(acc) = acc else { return Ok(None) };
        let width = match dims {
            Dimensions::Vec2 => 2,
            Dimensions::Vec3 => 3,
            _ => 4,
        };
        let nverts = self.mesh.num_points();
        let Some(&id) = self.ids.get(name) else {
            // Not compressed: its accessor, which must have one value per decoded vertex.
            let (v, _) = read_floats(&acc, self.src.buffers, &[dims]).map_err(|e| self.ctx.invalid(e))?;
            if v.len() / width != nverts {
                return Err(self.ctx.invalid((
                    format!("{}.attributes.{name}", self.ppath),
                    format!("count {} differs from the decoded Draco vertex count {nverts}", v.len() / width),
                )));
            }
            return Ok(Some(v));
        };
        let path = format!("{}.attributes.{name}", self.epath);
        if acc.dimensions() != dims {
            return Err(self.ctx.invalid((
                format!("accessors[{}]", acc.index()),
                format!(
                    "type {:?} is not {dims:?} ({name} of a Draco-compressed primitive)",
                    acc.dimensions()
                ),
            )));
        }
        let Some(att) = self.mesh.attribute_by_unique_id(id) else {
            return Err(self.ctx.invalid((path, format!("the Draco bitstream has no attribute {id}"))));
        };
        if usize::from(att.num_components()) != width {
            return Err(self.ctx.invalid((
                path,
                format!("Draco attribute {id} has {} components, {name} needs {width}", att.num_components()),
            )));
        }
        let mut v = att.read_f32s(nverts, width);
        if acc.normalized() {
            normalise(&mut v, att).map_err(|m| self.ctx.invalid((path, m)))?;
        }
        Ok(Some(v))
    }
}

/// Maps a normalised integer attribute's values to [0, 1] or [−1, 1] as glTF's accessors do
/// (glTF 2.0 §3.11: `c / (2^b − 1)` unsigned, `max(c / (2^(b−1) − 1), −1)` signed); floats are
/// left as they are.
fn normalise(values: &mut [f32], att: &PointAttribute) -> Result<(), String> {
    let (scale, signed) = match att.data_type() {
        DataType::Float32 | DataType::Float64 => return Ok(()),
        DataType::Uint8 => (255.0, false),
        DataType::Int8 => (127.0, true),
        DataType::Uint16 => (65_535.0, false),
        DataType::Int16 => (32_767.0, true),
        other => return Err(format!("a normalised attribute cannot be stored as Draco {other:?}")),
    };
    for x in values {
        *x /= scale;
        if signed {
            *x = x.max(-1.0);
        }
    }
    Ok(())
}
