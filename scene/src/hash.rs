//! [`Scene::content_hash`]: one hash of everything that changes a scene's image.

use crate::Scene;

impl Scene {
    /// A 64-bit hash of everything a renderer reads from the scene (geometry, materials,
    /// textures, images, cameras, lights), as 16 hex digits: two loads of the same content give
    /// the same hash, any change to what is rendered changes it (with probability 1 − 2⁻⁶⁴). Not
    /// cryptographic: it guards against resuming a render with an edited scene, not against
    /// forgery. The name, the loader's warnings and the extensions the file lists are not part
    /// of it.
    ///
    /// Stable across platforms and Rust versions (a fixed multiply–xorshift over 32-bit words,
    /// the small parts by their `Debug` text); a new field of the scene must be added here.
    pub fn content_hash(&self) -> String {
        let mut h = WordHash::default();
        let g = &self.geometry;
        h.len(g.positions.len());
        for p in &g.positions {
            p.to_array().iter().for_each(|c| h.word(c.to_bits()));
        }
        h.len(g.normals.len());
        g.normals.iter().for_each(|&n| h.word(n));
        h.len(g.uvs.len());
        for uv in &g.uvs {
            uv.to_array().iter().for_each(|c| h.word(c.to_bits()));
        }
        // Vertex colours only where stored, so that the hashes of scenes without them stay
        // those recorded in earlier renders.
        if !g.colors.is_empty() {
            h.len(g.colors.len());
            g.colors.iter().for_each(|c| h.word(u32::from(c[0]) | (u32::from(c[1]) << 16)));
            g.colors.iter().for_each(|c| h.word(u32::from(c[2]) | (u32::from(c[3]) << 16)));
        }
        h.len(g.tangents.len());
        for t in &g.tangents {
            t.iter().for_each(|&c| h.word(u32::from(c as u16)));
        }
        h.len(g.triangles.len());
        g.triangles.iter().flatten().for_each(|&i| h.word(i));
        h.len(g.triangle_materials.len());
        g.triangle_materials.iter().for_each(|&m| h.word(m));
        // Instancing only where there is some, so that flat scenes keep their recorded hashes.
        let inst = &self.instancing;
        if !inst.is_empty() {
            h.word(inst.world_triangles);
            h.len(inst.meshes.len());
            inst.meshes.iter().for_each(|r| [r.start, r.end].into_iter().for_each(|w| h.word(w)));
            h.len(inst.instances.len());
            for i in &inst.instances {
                h.word(i.mesh);
                i.world_from_object.to_cols_array().iter().for_each(|c| h.word(c.to_bits()));
            }
        }
        for image in &self.images {
            h.word(image.width);
            h.word(image.height);
            h.len(image.texels.len());
            image.texels.iter().for_each(|&t| h.word(u32::from_le_bytes(t)));
        }
        // Environment maps by their texels (their Debug text gives only source and size).
        for env in self.lights.iter().filter_map(|l| match l {
            crate::Light::Environment(e) => Some(e),
            _ => None,
        }) {
            h.word(env.map.width());
            h.word(env.map.height());
            env.map.texels().iter().flat_map(|t| t.to_array()).for_each(|c| h.word(c.to_bits()));
        }
        // The small parts by their Debug text: every field, floats in round-trip precision.
        // A lit material's `unlit: false` (its last field), a material's empty layers, absent
        // specular textures, absent iridescence, diffuse transmission and anisotropy and a dispersion of 0 are left out:
        // files without them hash as they did before the fields existed.
        let no_layers = format!(", layers: {:?}", crate::MaterialLayers::default());
        let no_specular_textures = format!(", specular_textures: {:?}", crate::SpecularTextures::default());
        let materials = format!("{:?}", self.materials)
            .replace(&no_layers, "")
            .replace(&no_specular_textures, "")
            .replace(", iridescence: None", "")
            .replace(", diffuse_transmission: None", "")
            .replace(", anisotropy: None", "")
            .replace(", dispersion: 0.0", "")
            .replace(", unlit: false }", " }");
        let small = format!("{materials}|{:?}|{:?}|{}", self.textures, self.cameras, self.lights_debug());
        h.len(small.len());
        small.bytes().for_each(|b| h.word(u32::from(b)));
        format!("{:016x}", h.finish())
    }
}

/// A multiply–xorshift hash over 32-bit words (stable across platforms and Rust versions,
/// unlike `std`'s `DefaultHasher`).
struct WordHash(u64);

impl Default for WordHash {
    fn default() -> Self {
        Self(0x243f_6a88_85a3_08d3)
    }
}

impl WordHash {
    fn word(&mut self, w: u32) {
        self.0 = (self.0 ^ u64::from(w)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        self.0 ^= self.0 >> 29;
    }

    fn len(&mut self, n: usize) {
        self.word(n as u32);
        self.word((n as u64 >> 32) as u32);
    }

    fn finish(&self) -> u64 {
        let mut x = self.0;
        x ^= x >> 33;
        x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
        x ^= x >> 33;
        x
    }
}

#[cfg(test)]
mod tests {
    use crate::builtin;

    #[test]
    fn content_hash_is_stable_and_sees_changes() {
        let a = builtin::cornell_box().unwrap();
        let h = a.content_hash();
        assert_eq!(h.len(), 16);
        assert_eq!(builtin::cornell_box().unwrap().content_hash(), h);
        let mut b = a.clone();
        b.geometry.positions[7].x = f32::from_bits(b.geometry.positions[7].x.to_bits() ^ 1);
        assert_ne!(b.content_hash(), h, "one ulp of one vertex");
        let mut c = a.clone();
        c.set_sky(c.sky() + glam::Vec3::new(0.0, 0.0, 0.5));
        assert_ne!(c.content_hash(), h, "the sky");
        let mut d = a.clone();
        d.materials[0].roughness_factor *= 0.5;
        assert_ne!(d.content_hash(), h, "a material");
        let mut e = a;
        e.name = "elsewhere.glb".into();
        assert_eq!(e.content_hash(), h, "the name is not content");
        e.extensions.push(crate::ExtensionUse { name: "EXT_mesh_gpu_instancing".into(), required: true });
        assert_eq!(e.content_hash(), h, "the extensions the file lists are not content");
    }
}
