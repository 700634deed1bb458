//! KHR_materials_variants: the file's variant names (the root extension's `variants`) and, for
//! the variant a load selects, each primitive's material from its `mappings`.

use super::context::Ctx;
use crate::error::SceneError;
use gltf::json::Value;

/// The extension's name, as files spell it.
pub(super) const EXTENSION: &str = "KHR_materials_variants";

/// The variants' names, in file order (empty without the extension). A variant without a
/// string `name` is listed as `""` with a warning; it can still be selected by its index.
pub(super) fn names(ctx: &mut Ctx<'_>, doc: &gltf::Document) -> Vec<String> {
    let Some(ext) = doc.extension_value(EXTENSION) else { return Vec::new() };
    let path = format!("extensions.{EXTENSION}.variants");
    let Some(list) = ext.get("variants").and_then(Value::as_array) else {
        ctx.warn(path, "missing or not an array: the file has no variants");
        return Vec::new();
    };
    let mut names = Vec::with_capacity(list.len());
    for (i, v) in list.iter().enumerate() {
        match v.get("name").and_then(Value::as_str) {
            Some(name) => names.push(name.to_string()),
            None => {
                ctx.warn(format!("{path}[{i}].name"), "missing or not a string: select it by its index");
                names.push(String::new());
            }
        }
    }
    names
}

/// The index of the variant `wanted` names: a variant's name, else its index. Any other value
/// is [`SceneError::UnknownVariant`], listing the file's variants.
pub(super) fn select(ctx: &Ctx<'_>, names: &[String], wanted: &str) -> Result<usize, SceneError> {
    names
        .iter()
        .position(|n| n == wanted)
        .or_else(|| wanted.parse::<usize>().ok().filter(|&i| i < names.len()))
        .ok_or_else(|| SceneError::UnknownVariant {
            file: ctx.file.to_string(),
            variant: wanted.to_string(),
            available: names.to_vec(),
        })
}

/// The material primitive `prim` (JSON path `ppath`) takes in variant `variant`: the material
/// of the first mapping that lists it, `None` when none does (the primitive's own material
/// then). A mapping that is malformed, names a variant the file does not declare or a material
/// it does not have is an error naming it.
pub(super) fn mapped_material(
    ctx: &Ctx<'_>,
    prim: &gltf::Primitive<'_>,
    ppath: &str,
    variant: usize,
    (variants, materials): (usize, usize),
) -> Result<Option<u32>, SceneError> {
    let Some(ext) = prim.extension_value(EXTENSION) else { return Ok(None) };
    let path = format!("{ppath}.extensions.{EXTENSION}.mappings");
    let invalid = |path: String, message: String| ctx.invalid((path, message));
    let mappings = ext
        .get("mappings")
        .and_then(Value::as_array)
        .ok_or_else(|| invalid(path.clone(), "missing or not an array".into()))?;
    for (k, m) in mappings.iter().enumerate() {
        let mpath = format!("{path}[{k}]");
        let index = |v: &Value| v.as_u64().and_then(|i| usize::try_from(i).ok());
        let material = m.get("material").and_then(index).filter(|&i| i < materials).ok_or_else(|| {
            invalid(format!("{mpath}.material"), format!("not one of the {materials} materials"))
        })?;
        let listed = m
            .get("variants")
            .and_then(Value::as_array)
            .ok_or_else(|| invalid(format!("{mpath}.variants"), "missing or not an array".into()))?;
        for (j, v) in listed.iter().enumerate() {
            let v = index(v).filter(|&v| v < variants).ok_or_else(|| {
                invalid(format!("{mpath}.variants[{j}]"), format!("not one of the {variants} variants"))
            })?;
            if v == variant {
                return Ok(Some(material as u32));
            }
        }
    }
    Ok(None)
}
