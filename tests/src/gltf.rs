//! Minimal glTF 2.0 scenes written in memory for tests: quads with Lambert or emissive
//! materials, textures made procedurally (PNG in data URIs), orthographic cameras, a sun
//! (`KHR_lights_punctual`) and a sky (`scenes[0].extras.background_radiance_rgb`, as in the
//! references' README). Loaded with `Scene::from_slice`, so the tests go through the loader as
//! a user's file would.

use glam::{Quat, Vec2, Vec3, Vec4};
use std::fmt::Write as _;

/// Base64 (RFC 4648, with padding), for data URIs.
pub fn base64(bytes: &[u8]) -> String {
    base64::encode(bytes)
}

/// An RGBA8 image encoded as PNG.
///
/// # Panics
/// If the encoder fails (it does not, for an in-memory buffer of the right size).
pub fn png(width: u32, height: u32, texel: impl Fn(u32, u32) -> [u8; 4]) -> Vec<u8> {
    let image = image::RgbaImage::from_fn(width, height, |x, y| image::Rgba(texel(x, y)));
    let mut out = std::io::Cursor::new(Vec::new());
    image.write_to(&mut out, image::ImageFormat::Png).expect("encoding a PNG in memory");
    out.into_inner()
}

/// A material of the test scenes.
#[derive(Debug, Clone)]
pub struct MaterialDesc {
    /// Linear base colour (the Lambert albedo: metallic 0, `specularFactor` 0).
    pub albedo: Vec3,
    /// Emitted radiance (`emissiveFactor`).
    pub emissive: Vec3,
    /// PNG of the base-colour texture (its alpha drives MASK).
    pub base_color_png: Option<Vec<u8>>,
    /// `alphaCutoff` with `alphaMode: MASK`; `None` is OPAQUE (unless `blend_alpha`).
    pub mask_cutoff: Option<f32>,
    /// `alphaMode: BLEND` with this `baseColorFactor` alpha.
    pub blend_alpha: Option<f32>,
    /// PNG of the normal texture and its `scale`.
    pub normal_png: Option<(Vec<u8>, f32)>,
    /// glTF `doubleSided`.
    pub double_sided: bool,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        Self {
            albedo: Vec3::splat(0.5),
            emissive: Vec3::ZERO,
            base_color_png: None,
            mask_cutoff: None,
            blend_alpha: None,
            normal_png: None,
            double_sided: true,
        }
    }
}

/// A horizontal quad `[x0, x1] × [z0, z1]` at height `y`, facing +Y, with
/// `u = (x − x0)/(x1 − x0)` and `v = (z − z0)/(z1 − z0)`, optionally with a TANGENT attribute.
#[derive(Debug, Clone)]
pub struct Quad {
    /// `[x0, x1]`.
    pub x: [f32; 2],
    /// `[z0, z1]`.
    pub z: [f32; 2],
    /// Height.
    pub y: f32,
    /// A TANGENT attribute for every vertex.
    pub tangent: Option<Vec4>,
    /// Its material.
    pub material: MaterialDesc,
}

impl Quad {
    /// The `(u, v)` of the point `(x, _, z)` of the quad's plane.
    pub fn uv(&self, x: f32, z: f32) -> Vec2 {
        Vec2::new((x - self.x[0]) / (self.x[1] - self.x[0]), (z - self.z[0]) / (self.z[1] - self.z[0]))
    }
}

/// An orthographic camera at `position` looking straight down (−Y), image up = −Z, showing
/// `2·half_size` metres square.
#[derive(Debug, Clone, Copy)]
pub struct TopCamera {
    /// Where the camera is.
    pub position: Vec3,
    /// Half the side of the square it sees, in metres.
    pub half_size: f32,
}

/// A scene: quads, cameras (the first is the default), sun travelling along `direction` with
/// `irradiance`, constant sky.
#[derive(Debug, Clone)]
pub struct SceneDesc {
    /// The quads.
    pub quads: Vec<Quad>,
    /// Orthographic cameras; the first is the default.
    pub cameras: Vec<TopCamera>,
    /// A sun: `(direction of travel, irradiance)`.
    pub sun: Option<(Vec3, Vec3)>,
    /// Constant sky radiance.
    pub sky: Vec3,
}

/// The binary buffer with its views and accessors, as JSON fragments.
#[derive(Default)]
struct Buffer {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl Buffer {
    fn view(&mut self, bytes: &[u8]) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        // Keep every view 4-byte aligned.
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views.push(format!(r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#, bytes.len()));
        self.views.len() - 1
    }

    /// `f32` data as an accessor of `count` elements of `kind`; returns its index.
    fn floats(&mut self, data: &[f32], kind: &str, count: usize, bounds: Option<(Vec3, Vec3)>) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let minmax = bounds.map_or(String::new(), |(lo, hi)| {
            format!(r#","min":{},"max":{}"#, vec(lo.to_array()), vec(hi.to_array()))
        });
        self.accessors.push(format!(
            r#"{{"bufferView":{view},"componentType":5126,"count":{count},"type":"{kind}"{minmax}}}"#
        ));
        self.accessors.len() - 1
    }

    /// `u16` indices as an accessor; returns its index.
    fn indices(&mut self, indices: &[u16]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(format!(
            r#"{{"bufferView":{view},"componentType":5123,"count":{},"type":"SCALAR"}}"#,
            indices.len()
        ));
        self.accessors.len() - 1
    }
}

fn vec(v: impl IntoIterator<Item = f32>) -> String {
    let items: Vec<String> = v.into_iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", items.join(","))
}

fn quat(q: Quat) -> String {
    vec(q.to_array())
}

impl SceneDesc {
    /// The glTF JSON (one buffer and every image in data URIs).
    pub fn to_gltf(&self) -> String {
        let mut buffer = Buffer::default();
        let (mut meshes, mut materials, mut images, mut textures) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut nodes: Vec<String> = Vec::new();
        for (i, q) in self.quads.iter().enumerate() {
            let corners = [(0, 0), (1, 0), (1, 1), (0, 1)];
            let positions: Vec<f32> = corners.iter().flat_map(|&(a, b)| [q.x[a], q.y, q.z[b]]).collect();
            let normals: Vec<f32> = corners.iter().flat_map(|_| [0.0, 1.0, 0.0]).collect();
            let uvs: Vec<f32> = corners.iter().flat_map(|&(a, b)| [a as f32, b as f32]).collect();
            let lo = Vec3::new(q.x[0], q.y, q.z[0]);
            let hi = Vec3::new(q.x[1], q.y, q.z[1]);
            let p = buffer.floats(&positions, "VEC3", 4, Some((lo, hi)));
            let n = buffer.floats(&normals, "VEC3", 4, None);
            let t = buffer.floats(&uvs, "VEC2", 4, None);
            let mut attributes = format!(r#""POSITION":{p},"NORMAL":{n},"TEXCOORD_0":{t}"#);
            if let Some(tangent) = q.tangent {
                let data: Vec<f32> = corners.iter().flat_map(|_| tangent.to_array()).collect();
                let k = buffer.floats(&data, "VEC4", 4, None);
                write!(attributes, r#","TANGENT":{k}"#).unwrap();
            }
            // Indices (u16), counter-clockwise seen from +Y: (0,3,2), (0,2,1) with the corner
            // order above ((x0,z0), (x1,z0), (x1,z1), (x0,z1)).
            let indices = buffer.indices(&[0, 3, 2, 0, 2, 1]);
            meshes.push(format!(
                r#"{{"primitives":[{{"attributes":{{{attributes}}},"indices":{indices},"material":{i}}}]}}"#
            ));
            let m = &q.material;
            let mut texture = |png: &[u8]| {
                images.push(format!(r#"{{"uri":"data:image/png;base64,{}"}}"#, base64(png)));
                textures.push(format!(r#"{{"source":{}}}"#, images.len() - 1));
                textures.len() - 1
            };
            let base_texture = m
                .base_color_png
                .as_ref()
                .map_or(String::new(), |png| format!(r#","baseColorTexture":{{"index":{}}}"#, texture(png)));
            let normal = m.normal_png.as_ref().map_or(String::new(), |(png, scale)| {
                format!(r#","normalTexture":{{"index":{},"scale":{scale:?}}}"#, texture(png))
            });
            let alpha = match (m.mask_cutoff, m.blend_alpha) {
                (Some(c), _) => format!(r#","alphaMode":"MASK","alphaCutoff":{c:?}"#),
                (None, Some(_)) => r#","alphaMode":"BLEND""#.to_string(),
                (None, None) => String::new(),
            };
            materials.push(format!(
                r#"{{"pbrMetallicRoughness":{{"baseColorFactor":{},"metallicFactor":0.0,"roughnessFactor":1.0{base_texture}}},"emissiveFactor":{},"doubleSided":{}{normal}{alpha},"extensions":{{"KHR_materials_specular":{{"specularFactor":0.0}}}}}}"#,
                vec(m.albedo.extend(m.blend_alpha.unwrap_or(1.0)).to_array()),
                vec(m.emissive.to_array()),
                m.double_sided
            ));
            nodes.push(format!(r#"{{"mesh":{i}}}"#));
        }
        // A camera looking down −Y: rotate its −Z onto −Y (image up becomes −Z).
        let down = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
        let mut cameras = Vec::new();
        for (i, c) in self.cameras.iter().enumerate() {
            cameras.push(format!(
                r#"{{"type":"orthographic","orthographic":{{"xmag":{h:?},"ymag":{h:?},"znear":0.001,"zfar":100.0}}}}"#,
                h = c.half_size
            ));
            nodes.push(format!(
                r#"{{"camera":{i},"translation":{},"rotation":{}}}"#,
                vec(c.position.to_array()),
                quat(down)
            ));
        }
        let mut lights = String::new();
        if let Some((direction, irradiance)) = self.sun {
            let rotation = Quat::from_rotation_arc(Vec3::NEG_Z, direction.normalize());
            lights = format!(
                r#","extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"directional","color":{},"intensity":1.0}}]}}}}"#,
                vec(irradiance.to_array())
            );
            nodes.push(format!(
                r#"{{"rotation":{},"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}"#,
                quat(rotation)
            ));
        }
        let node_list: Vec<String> = (0..nodes.len()).map(|i| i.to_string()).collect();
        let uses_lights = if self.sun.is_some() { r#""KHR_lights_punctual","# } else { "" };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":[{uses_lights}"KHR_materials_specular"],"scene":0,"scenes":[{{"nodes":[{}],"extras":{{"background_radiance_rgb":{}}}}}],"nodes":[{}],"meshes":[{}],"materials":[{}],"accessors":[{}],"bufferViews":[{}],"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],"cameras":[{}]{}{}{}{lights}}}"#,
            node_list.join(","),
            vec(self.sky.to_array()),
            nodes.join(","),
            meshes.join(","),
            materials.join(","),
            buffer.accessors.join(","),
            buffer.views.join(","),
            buffer.bin.len(),
            base64(&buffer.bin),
            cameras.join(","),
            if images.is_empty() { String::new() } else { format!(r#","images":[{}]"#, images.join(",")) },
            if textures.is_empty() {
                String::new()
            } else {
                format!(r#","textures":[{}]"#, textures.join(","))
            },
            "",
        )
    }

    /// Loads [`SceneDesc::to_gltf`] with the scene crate's loader; panics on an error or a
    /// warning (the file is meant to be clean).
    pub fn load(&self, name: &str) -> furnace_scene::Scene {
        let json = self.to_gltf();
        let scene = furnace_scene::Scene::from_slice(json.as_bytes(), name)
            .unwrap_or_else(|e| panic!("{name}: {e}\n{json}"));
        assert!(scene.warnings.is_empty(), "{name}: warnings {:?}", scene.warnings);
        scene
    }
}
