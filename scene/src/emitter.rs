//! [`Emitters`]: the scene's emissive triangles as lights, chosen for next-event estimation in
//! proportion to their power by an alias table.
//!
//! A triangle is an emitter when its material's emitted radiance (`emissiveFactor` ×
//! `KHR_materials_emissive_strength`, times the mean of `emissiveTexture`) has a positive
//! luminance. Each is chosen with probability `wₘ · area / Σ`, where `wₘ` is its material's
//! *selection weight* (the luminance of that radiance: power π·area·L up to the constant π).
//! The same `f32` formula gives the selection pdf of the triangle a BSDF-sampled ray hits
//! ([`Emitters::selection_pdf`]), which is what the MIS weight of that hit needs; no
//! per-triangle table is kept, only one weight per material.
//!
//! A textured emitter is weighted by its texture's mean, not per triangle: the estimator stays
//! unbiased (any positive weight is), only less efficient where the texture varies a lot.

use crate::{LightBounds, LightBvh, Material, Scene};
use furnace_sampling::{AliasBin, AliasTable};
use glam::{Vec2, Vec3};

/// Luminance of linear Rec. 709 RGB.
pub fn luminance(c: Vec3) -> f32 {
    let [r, g, b] = furnace_sampling::LUMINANCE;
    r * c.x + g * c.y + b * c.z
}

/// Area of the triangle `v0 v1 v2`, as every emitter computation forms it.
pub fn triangle_area(v0: Vec3, v1: Vec3, v2: Vec3) -> f32 {
    0.5 * (v1 - v0).cross(v2 - v0).length()
}

/// Texture lookups per axis when a textured emitter's mean radiance is estimated.
const TEXTURE_MEAN_GRID: u32 = 32;

/// The emissive triangles of a scene and the power-proportional distribution over them.
#[derive(Debug, Clone)]
pub struct Emitters {
    triangles: Vec<u32>,
    table: AliasTable,
    material_weights: Vec<f32>,
    total: f32,
}

impl Emitters {
    /// The emitters of `scene` (its world-space triangles whose material emits), or `None` when
    /// it has none (no triangle of positive weight).
    pub fn new(scene: &Scene) -> Option<Self> {
        let material_weights: Vec<f32> = scene.materials.iter().map(|m| material_weight(scene, m)).collect();
        if !material_weights.iter().any(|&w| w > 0.0) {
            return None;
        }
        let g = &scene.geometry;
        let mut triangles = Vec::new();
        let mut weights = Vec::new();
        // World-space triangles only: the loader keeps emissive meshes there (a shared mesh's
        // triangles are in its object space, and are not lights).
        let world = if scene.instancing.is_empty() {
            g.triangle_count()
        } else {
            scene.instancing.world_triangles as usize
        };
        for t in 0..world {
            let w = material_weights[scene.triangle_material(t)];
            if w > 0.0
                && let Some([v0, v1, v2]) = g.triangle(t)
            {
                let weight = w * triangle_area(v0, v1, v2);
                if weight > 0.0 && weight.is_finite() {
                    triangles.push(t as u32);
                    weights.push(f64::from(weight));
                }
            }
        }
        let table = AliasTable::new(&weights)?;
        // The f32 sum the pdfs divide by, formed in f64 first (10⁵ emitters: no drift).
        let total = weights.iter().sum::<f64>() as f32;
        Some(Self { triangles, table, material_weights, total })
    }

    /// Number of emissive triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Always false (a scene without emitters has no `Emitters`).
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The emissive triangles, in triangle order; the alias table's item `i` is `triangles()[i]`.
    pub fn triangles(&self) -> &[u32] {
        &self.triangles
    }

    /// The alias table's bins (bin `i` belongs to `triangles()[i]`).
    pub fn bins(&self) -> &[AliasBin] {
        self.table.bins()
    }

    /// Per material, its selection weight per unit area (0: not an emitter).
    pub fn material_weights(&self) -> &[f32] {
        &self.material_weights
    }

    /// `Σ weight · area` over the emitters, the selection pdfs' denominator.
    pub fn total_weight(&self) -> f32 {
        self.total
    }

    /// The triangle chosen by the 32 bin-choosing `bits` and the `coin ∈ [0, 1)`.
    pub fn select(&self, bits: u32, coin: f32) -> u32 {
        self.triangles[self.table.sample(bits, coin)]
    }

    /// The probability with which [`Emitters::select`] picks a triangle of `material` and of
    /// `area` (0 for a non-emitting material).
    pub fn selection_pdf(&self, material: usize, area: f32) -> f32 {
        self.material_weights.get(material).map_or(0.0, |w| w * area / self.total)
    }

    /// The [`LightBvh`] over these emitters (item `i` is `triangles()[i]`), each triangle's
    /// power its selection weight (`wₘ · area`, as the alias table's).
    pub fn light_bvh(&self, scene: &Scene) -> LightBvh {
        let bounds: Vec<LightBounds> = self
            .triangles
            .iter()
            .map(|&t| {
                let t = t as usize;
                let [v0, v1, v2] = scene.geometry.triangle(t).expect("an emitter is a triangle of the scene");
                let phi = self.material_weights[scene.triangle_material(t)] * triangle_area(v0, v1, v2);
                // A triangle with no normal has no area, so it is no emitter: the fallback is never used.
                LightBounds::triangle(v0, v1, v2, phi).unwrap_or(LightBounds {
                    lo: v0,
                    hi: v0,
                    phi: 0.0,
                    axis: Vec3::Z,
                    cos_theta_o: 1.0,
                })
            })
            .collect();
        LightBvh::new(&bounds).expect("emitters are never empty")
    }

    /// The emitter index (into [`Emitters::triangles`]) of scene triangle `t`, if it is one
    /// (a binary search: the triangles are in order).
    pub fn index_of(&self, t: u32) -> Option<usize> {
        self.triangles.binary_search(&t).ok()
    }

    /// Bytes these emitters take on a GPU: 12 per emitter (triangle, alias bin) and 4 per
    /// material.
    pub fn gpu_bytes(&self) -> usize {
        12 * self.triangles.len() + 4 * self.material_weights.len()
    }
}

/// A material's selection weight per unit area: the luminance of its emitted radiance, with an
/// emission texture's mean over the unit UV square (a grid of lookups) multiplied in.
fn material_weight(scene: &Scene, m: &Material) -> f32 {
    let factor = luminance(m.emissive);
    if !(factor > 0.0 && factor.is_finite()) {
        return 0.0;
    }
    let Some(texture) = &m.emissive_texture else { return factor };
    let n = TEXTURE_MEAN_GRID;
    let mut sum = Vec3::ZERO;
    for j in 0..n {
        for i in 0..n {
            let uv = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            sum += texture.sample_bilinear(uv, &scene.textures, &scene.images).truncate();
        }
    }
    let w = luminance(m.emissive * sum / (n * n) as f32);
    if w > 0.0 && w.is_finite() { w } else { 0.0 }
}
