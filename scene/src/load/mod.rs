//! The glTF 2.0 / GLB loader: parse, check required extensions, validate, load buffers
//! ourselves (so that a missing file is named), flatten the default scene into world space.
//!
//! The steps, in order: [`document`] (parse and check), [`resources`] (buffers, with
//! [`meshopt`]'s compressed views decoded into them, then the images the materials use),
//! [`material`] (textures and materials; [`spec_gloss`] bakes specular-glossiness textures once
//! the images are loaded), [`variants`] (the material variant chosen), [`animation`] (the
//! animation chosen, sampled into a pose), [`nodes`] (the node hierarchy at that pose: cameras,
//! lights, and each mesh primitive through [`primitive`], posed by its morph weights and
//! [`skin`], once per instance of [`instancing`]); then the geometry's checks here.
//! [`context::Ctx`] carries the file and the warnings through them.

mod animation;
mod context;
mod document;
mod instancing;
mod ktx2;
mod material;
mod meshopt;
mod nodes;
mod primitive;
mod resources;
mod skin;
mod spec_gloss;
mod texture_source;
mod variants;

pub use document::{ExtensionUse, SUPPORTED_EXTENSIONS};

use crate::error::SceneError;
use crate::geometry::Geometry;
use crate::material::Material;
use crate::{Instancing, Light, Scene, Sky};
use context::Ctx;
use glam::Vec3;
use primitive::Meshes;
use std::collections::HashSet;
use std::path::Path;

/// Loads a glTF (JSON or GLB) from bytes. `base` resolves relative URIs.
pub(crate) fn load(
    bytes: &[u8],
    file: &str,
    base: Option<&Path>,
    options: &crate::LoadOptions,
) -> Result<Scene, SceneError> {
    let mut ctx = Ctx::new(file, base, options.strict);
    let (doc, blob) = document::parse(bytes, file)?;
    document::check(&mut ctx, doc.as_json())?;
    let variant_names = variants::names(&mut ctx, &doc);
    let variant = match &options.variant {
        Some(wanted) => Some(variants::select(&ctx, &variant_names, wanted)?),
        None => None,
    };
    let buffers = resources::load_buffers(&mut ctx, &doc, blob.as_deref())?;
    let animations = animation::list(&doc, &buffers);
    let posed_by = animation::select(&ctx, &animations, options.animation.as_deref(), options.time)?;
    let pose = match posed_by {
        Some((index, time)) => animation::sample(&mut ctx, &doc, &buffers, index, time)?,
        None => animation::Pose::rest(doc.nodes().len()),
    };
    let mut textures = material::read_textures(&mut ctx, &doc);
    let (mut materials, bakes) = material::read_materials(&mut ctx, &doc);
    let default_material = (materials.len() - 1) as u32;
    // The UV sets stored: up to the highest any texture samples.
    let uv_sets = materials
        .iter()
        .flat_map(Material::texture_refs)
        .map(|t| t.tex_coord as usize + 1)
        .max()
        .unwrap_or(0);
    // Normal maps and anisotropy directions are given in tangent space.
    let needs_tangent = materials.iter().any(|m| m.normal_texture.is_some() || m.anisotropy.is_some());
    let needs_color =
        doc.meshes().flat_map(|m| m.primitives()).any(|p| p.get(&gltf::Semantic::Colors(0)).is_some());
    let mut images = resources::load_images(&mut ctx, &doc, &buffers, &mut materials, &textures)?;
    spec_gloss::bake_all(&mut ctx, &bakes, &mut materials, &mut textures, &mut images);

    let scene = nodes::scene_to_render(&ctx, &doc)?;
    let sky = nodes::read_sky(&mut ctx, &scene);
    let environment = nodes::read_environment(&mut ctx, &scene)?;
    let emissive: Vec<bool> = materials.iter().map(|m| m.emissive != Vec3::ZERO).collect();
    let shared = instancing::shared_meshes(&doc, &scene, &emissive);
    let declared = nodes::declared(&doc, &scene, &shared);
    if declared.triangles > MAX_TRIANGLES {
        let triangles = declared.triangles;
        return Err(ctx.invalid((
            format!("scenes[{}]", scene.index()),
            format!(
                "its meshes, placed by its nodes, make {triangles} triangles to store: more than the \
                 {MAX_TRIANGLES} (2²⁸) a scene may have"
            ),
        )));
    }
    if declared.instances > MAX_INSTANCES {
        let instances = declared.instances;
        return Err(ctx.invalid((
            format!("scenes[{}]", scene.index()),
            format!(
                "its nodes and EXT_mesh_gpu_instancing place shared meshes {instances} times: more than \
                 the {MAX_INSTANCES} (2²⁴) instances a scene may have"
            ),
        )));
    }
    let normal_sets = materials
        .iter()
        .map(|m| {
            let anisotropy = m.anisotropy.as_ref().and_then(|a| a.texture.as_ref());
            m.normal_texture.as_ref().or(anisotropy).map_or(0, |t| t.tex_coord as usize)
        })
        .collect();
    let mut meshes =
        Meshes::new(&doc, &buffers, uv_sets, needs_tangent, needs_color, normal_sets, default_material);
    meshes.variant = variant.map(|v| (v, variant_names.len()));
    let flat = nodes::flatten(&mut ctx, &doc, &scene, meshes, &pose, shared)?;
    let (mut geo, dropped) = (flat.meshes.geo, flat.meshes.dropped);
    let mut instancing = flat.instancing;
    if instancing.is_empty() {
        instancing = Instancing::default();
    } else {
        // The shared meshes after the world-space triangles.
        let world = geo.triangle_count() as u32;
        geo.append(flat.meshes.object);
        instancing.world_triangles = world;
        for r in &mut instancing.meshes {
            *r = r.start + world..r.end + world;
        }
    }
    check_geometry(&mut ctx, &geo, dropped)?;
    if !needs_tangent {
        geo.tangents = Vec::new();
    }
    Ok(Scene {
        name: file.to_string(),
        geometry: geo,
        instancing,
        materials,
        textures,
        images,
        cameras: flat.cameras,
        lights: flat
            .sun
            .map(Light::Sun)
            .into_iter()
            .chain((sky != Vec3::ZERO).then_some(Light::Sky(Sky { radiance: sky })))
            .chain(flat.lights)
            .chain(environment.map(Light::Environment))
            .collect(),
        warnings: ctx.warnings,
        dropped_triangles: dropped,
        extensions: document::extensions(doc.as_json()),
        variants: variant_names,
        animations,
        posed_by,
    })
}

/// The most triangles a scene may store: 2²⁸. A mesh placed once, skinned, morphed or emissive
/// is copied once per node that places it (a shared one is stored once), so a file of a few
/// megabytes can name billions of triangles; the count is taken from the
/// accessors' counts before any is read, and a scene above it is refused instead of filling
/// memory (at about 64 bytes a triangle with its vertices, 2²⁸ is some 16 GiB, past what the
/// GPU integrator can bind).
pub const MAX_TRIANGLES: u64 = 1 << 28;

/// The most instances of shared meshes a scene may have: 2²⁴ (each takes some 150 bytes on the
/// host; the count is taken from the accessors before any is read).
pub const MAX_INSTANCES: u64 = 1 << 24;

/// Refuses a scene without triangles; warns about dropped triangles and about coordinates
/// outside the range the renderer handles.
fn check_geometry(ctx: &mut Ctx<'_>, geo: &Geometry, dropped: usize) -> Result<(), SceneError> {
    if geo.triangles.is_empty() {
        let reason = if dropped > 0 {
            format!("all {dropped} triangles have zero area")
        } else {
            "the scene has no triangles".to_string()
        };
        return Err(SceneError::NothingToRender { file: ctx.file.to_string(), reason });
    }
    if dropped > 0 {
        ctx.warn("", format!("{dropped} zero-area triangles dropped (they cannot be hit)"));
    }
    check_scale(ctx, geo);
    Ok(())
}

/// Largest world coordinate magnitude of a scene that f32 ray tracing handles: above it the
/// Möller–Trumbore products (edge² × distance) overflow and hits are lost. The Cornell box
/// renders its s = 1 image when scaled by 1e12 (|coordinates| ≤ 2e12) and breaks at 1e13
/// (`furnace-tests`' `tests/stability.rs`); 2⁴² ≈ 4.4e12.
pub const MAX_COORDINATE: f32 = 4_398_046_511_104.0;

/// Smallest largest-coordinate magnitude of a scene that f32 ray tracing handles: below it the
/// Möller–Trumbore triple products (three lengths multiplied, (2e-13)³ < 1.2e-38) become
/// subnormal and hits lose their precision. Ray offsets scale with the scene
/// (`furnace_accel::offset_scale`), so they are not the limit: the Cornell box renders its
/// s = 1 image scaled by 1e-12 (|coordinates| ≤ 2e-12) and breaks at 1e-13
/// (`furnace-tests`' `tests/stability.rs`); 2⁻³⁹ ≈ 1.8e-12.
pub const MIN_COORDINATE: f32 = 1.818_989_4e-12;

/// Warns when the scene's coordinates lie outside what the renderer measured to be scale
/// invariant ([`MIN_COORDINATE`] … [`MAX_COORDINATE`]).
fn check_scale(ctx: &mut Ctx<'_>, geo: &Geometry) {
    let used: HashSet<u32> = geo.triangles.iter().flatten().copied().collect();
    let max = used.iter().map(|&i| geo.positions[i as usize].abs().max_element()).fold(0.0f32, f32::max);
    if max > MAX_COORDINATE {
        ctx.warn(
            "",
            format!(
                "coordinates up to {max:e}: beyond ~{MAX_COORDINATE:.1e} f32 ray–triangle tests overflow and \
                 hits are lost; scale the scene down"
            ),
        );
    } else if max < MIN_COORDINATE {
        ctx.warn(
            "",
            format!(
                "all coordinates within ±{max:e}: below ~{MIN_COORDINATE:.1e} f32 ray–triangle tests lose \
                 precision (subnormal products) and hits are lost; scale the scene up"
            ),
        );
    }
}
