//! Mesh primitives flattened into world-space triangles: attributes and indices read and
//! checked, posed by their morph targets and skin ([`pose`]), positions and normals
//! transformed, tangents transformed or generated, zero-area triangles dropped.
//! Draco-compressed primitives are decoded by [`draco`].

mod draco;
pub(super) mod pose;

use super::context::Ctx;
use crate::accessor::{read_floats, read_indices};
use crate::error::SceneError;
use crate::geometry::{Geometry, encode_color, encode_tangent, generate_tangents, oct_encode};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::Dimensions;

/// The triangles of the primitives added so far, and what adding one needs.
pub(super) struct Meshes<'b> {
    doc: &'b gltf::Document,
    buffers: &'b [Vec<u8>],
    /// The UV sets stored (0: none; some material samples TEXCOORD_(n − 1)).
    uv_sets: usize,
    /// Some material has a normal map: tangents are stored.
    needs_tangent: bool,
    /// Some primitive has COLOR_0: vertex colours are stored.
    needs_color: bool,
    /// The UV set of each material's normal map (0 without one).
    normal_sets: Vec<usize>,
    /// The material of primitives without one (glTF's default material).
    default_material: u32,
    /// The KHR_materials_variants variant loaded and how many the file declares (`None`:
    /// every primitive's own material).
    pub(super) variant: Option<(usize, usize)>,
    pub(super) geo: Geometry,
    /// The meshes stored once, in object space (placed by instances), while `geo` holds the
    /// world-space triangles.
    pub(super) object: Geometry,
    /// Zero-area triangles dropped.
    pub(super) dropped: usize,
}

/// A primitive's attributes and indices, read and checked (object space).
struct Attributes {
    /// POSITION, 3 floats per vertex, all finite.
    positions: Vec<f32>,
    normals: Option<Vec<f32>>,
    /// TEXCOORD_k for each stored set k (`None` where the primitive lacks it).
    uvs: Vec<Option<Vec<f32>>>,
    /// COLOR_0 as RGBA (read only when colours are stored).
    colors: Option<Vec<Vec4>>,
    /// TANGENT (read only when tangents are stored).
    tangents: Option<Vec<f32>>,
    indices: Vec<u32>,
    /// JOINTS_n and WEIGHTS_n (read only for a skinned node).
    skin: Vec<pose::SkinSet>,
    /// Per vertex, whether its skinning matrix mirrors (`None`: none does, or not skinned).
    mirrored: Option<Vec<bool>>,
}

/// A primitive placed in world space by its node's transform (or one instance's); what does not
/// move is borrowed from the attributes read once for all placements.
struct Placed<'a> {
    positions: Vec<Vec3>,
    /// Shading normals; `None` if absent or any is unusable (then per-face normals).
    normals: Option<Vec<Vec3>>,
    uvs: &'a [Option<Vec<f32>>],
    colors: Option<&'a [Vec4]>,
    /// The UV set of the material's normal map (tangents follow its derivatives).
    normal_set: usize,
    /// The file's tangents, in object space.
    tangents: Option<&'a [f32]>,
    indices: &'a [u32],
    material: u32,
    world: Mat4,
    /// The transform mirrors: triangles are wound the other way round and the tangents'
    /// handedness flips.
    flip: bool,
    /// Per vertex, whether skinning mirrored it (the tangents already flipped): a triangle
    /// most of whose vertices are is wound the other way round.
    mirrored: Option<&'a [bool]>,
}

impl Placed<'_> {
    /// Vertex `i`'s UV of `set` (zero without it).
    fn uv_of(&self, set: usize, i: usize) -> Vec2 {
        let uvs = self.uvs.get(set).and_then(Option::as_ref);
        uvs.and_then(|t| t.get(2 * i..2 * i + 2)).map_or(Vec2::ZERO, |c| Vec2::new(c[0], c[1]))
    }

    /// Vertex `i`'s UV of the normal map's set (for tangents).
    fn uv(&self, i: usize) -> Vec2 {
        self.uv_of(self.normal_set, i)
    }

    /// Vertex `i`'s stored attributes besides position and normal: its UV sets and colour.
    fn push_attributes(&self, geo: &mut Geometry, sets: usize, colors: bool, i: usize) {
        geo.uvs.extend((0..sets).map(|k| self.uv_of(k, i)));
        if colors {
            let c = self.colors.and_then(|c| c.get(i)).copied().unwrap_or(Vec4::ONE);
            geo.colors.push(encode_color(c));
        }
    }
}

impl<'b> Meshes<'b> {
    pub(super) fn new(
        doc: &'b gltf::Document,
        buffers: &'b [Vec<u8>],
        uv_sets: usize,
        needs_tangent: bool,
        needs_color: bool,
        normal_sets: Vec<usize>,
        default_material: u32,
    ) -> Self {
        Self {
            doc,
            buffers,
            uv_sets,
            needs_tangent,
            needs_color,
            normal_sets,
            default_material,
            variant: None,
            geo: Geometry::default(),
            object: Geometry::default(),
            dropped: 0,
        }
    }
}

impl<'b> Meshes<'b> {
    /// The file's buffers, as the accessors read them.
    pub(super) fn buffers(&self) -> &'b [Vec<u8>] {
        self.buffers
    }

    /// Adds primitive `prim` (JSON path `ppath`) of node `npath`, posed by `posing`, once per
    /// transform of `worlds` (the node's, or one per instance; a skinned primitive, placed by
    /// its joints, once), reading its accessors once: triangle lists, strips and fans; points,
    /// lines and primitives without positions are skipped with a warning.
    pub(super) fn add_primitive(
        &mut self,
        ctx: &mut Ctx<'_>,
        prim: &gltf::Primitive<'_>,
        (ppath, npath): (&str, &str),
        worlds: &[Mat4],
        posing: &pose::Posing<'_>,
    ) -> Result<(), SceneError> {
        use gltf::mesh::Mode;
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            ctx.warn(
                ppath,
                format!("mode {mode:?}: points and lines have no area to render; primitive skipped"),
            );
            return Ok(());
        }
        let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
            ctx.warn(ppath, "no POSITION attribute: primitive skipped");
            return Ok(());
        };
        let skinned = posing.skin.is_some();
        let mut attributes = match prim.extension_value(draco::EXTENSION) {
            Some(ext) => draco::read_attributes(ctx, self, prim, ext, ppath, skinned)?,
            None => self.read_attributes(ctx, prim, &pos_acc, ppath, skinned)?,
        };
        pose::morph(
            ctx,
            self.doc,
            self.buffers,
            (posing.mesh, prim),
            ppath,
            posing.weights,
            &mut attributes,
        )?;
        let worlds = match posing.skin {
            Some(skin) if pose::skin(ctx, skin, &mut attributes, ppath, posing.node_world)? => {
                &[Mat4::IDENTITY][..]
            }
            _ => worlds,
        };
        let own = prim.material().index().map_or(self.default_material, |i| i as u32);
        let mapped = match self.variant {
            Some((v, count)) => {
                super::variants::mapped_material(ctx, prim, ppath, v, (count, self.doc.materials().len()))?
            }
            None => None,
        };
        let material = mapped.unwrap_or(own);
        let normal_set = self.normal_sets.get(material as usize).copied().unwrap_or(0);
        for &world in worlds {
            let placed = place(ctx, &attributes, material, normal_set, world, ppath, npath)?;
            let base = self.geo.positions.len();
            if let Some(normals) = &placed.normals {
                self.add_vertices(ctx, &placed, normals, ppath)?;
            }
            self.add_triangles(ctx, &placed, base, ppath)?;
        }
        Ok(())
    }

    /// Reads the attributes the scene stores (and, for a `skinned` node, the joints and
    /// weights) and the indices, checking counts and ranges.
    fn read_attributes(
        &self,
        ctx: &mut Ctx<'_>,
        prim: &gltf::Primitive<'_>,
        pos_acc: &gltf::Accessor<'_>,
        ppath: &str,
        skinned: bool,
    ) -> Result<Attributes, SceneError> {
        let positions = read_positions(ctx, pos_acc, self.buffers, ppath)?;
        let reader = Reader { ctx, buffers: self.buffers, ppath, nverts: positions.len() / 3 };
        let normals =
            reader.attribute(prim.get(&gltf::Semantic::Normals), &[Dimensions::Vec3], "NORMAL")?.map(|a| a.0);
        let uvs = (0..self.uv_sets)
            .map(|k| {
                let name = format!("TEXCOORD_{k}");
                let uv = reader.attribute(
                    prim.get(&gltf::Semantic::TexCoords(k as u32)),
                    &[Dimensions::Vec2],
                    &name,
                );
                uv.map(|uv| uv.map(|a| a.0))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let colors = if self.needs_color {
            let color = prim.get(&gltf::Semantic::Colors(0));
            reader
                .attribute(color, &[Dimensions::Vec3, Dimensions::Vec4], "COLOR_0")?
                .map(|(c, width)| rgba(&c, width))
        } else {
            None
        };
        let tangents = if self.needs_tangent {
            reader
                .attribute(prim.get(&gltf::Semantic::Tangents), &[Dimensions::Vec4], "TANGENT")?
                .map(|a| a.0)
        } else {
            None
        };
        let skin = match skinned {
            true => pose::read_skin_sets(reader.ctx, prim, ppath, |acc, name| {
                reader.attribute(acc, &[Dimensions::Vec4], name).map(|a| a.map(|a| a.0))
            })?,
            false => Vec::new(),
        };
        let indices = reader.indices(prim.indices())?;
        let indices = match prim.mode() {
            gltf::mesh::Mode::TriangleStrip => strip_triangles(&indices),
            gltf::mesh::Mode::TriangleFan => fan_triangles(&indices),
            _ => {
                if !indices.len().is_multiple_of(3) {
                    ctx.warn(
                        ppath,
                        format!("{} indices is not a multiple of 3: the rest ignored", indices.len()),
                    );
                }
                indices
            }
        };
        Ok(Attributes { positions, normals, uvs, colors, tangents, indices, skin, mirrored: None })
    }

    /// Copies the vertices of a primitive with shading normals once (its triangles index
    /// them), with their normals, tangents and UVs as the scene stores them.
    fn add_vertices(
        &mut self,
        ctx: &Ctx<'_>,
        p: &Placed<'_>,
        normals: &[Vec3],
        ppath: &str,
    ) -> Result<(), SceneError> {
        let nverts = p.positions.len();
        if self.geo.positions.len() + nverts > u32::MAX as usize {
            return Err(ctx.invalid((ppath.to_string(), "more than 2^32 vertices".into())));
        }
        self.geo.positions.extend_from_slice(&p.positions);
        self.geo.normals.extend(normals.iter().map(|&n| oct_encode(n)));
        if self.needs_tangent {
            self.geo.tangents.extend(vertex_tangents(p, normals).into_iter().map(encode_tangent));
        }
        for i in 0..nverts {
            p.push_attributes(&mut self.geo, self.uv_sets, self.needs_color, i);
        }
        Ok(())
    }

    /// Adds the primitive's triangles (its vertices start at `base` when it has shading
    /// normals), dropping and counting the zero-area ones.
    fn add_triangles(
        &mut self,
        ctx: &Ctx<'_>,
        p: &Placed<'_>,
        base: usize,
        ppath: &str,
    ) -> Result<(), SceneError> {
        for t in p.indices.chunks_exact(3) {
            let (mut a, b, mut c) = (t[0] as usize, t[1] as usize, t[2] as usize);
            let mirrored =
                p.mirrored.is_some_and(|m| usize::from(m[a]) + usize::from(m[b]) + usize::from(m[c]) >= 2);
            if p.flip != mirrored {
                std::mem::swap(&mut a, &mut c);
            }
            let Some(face_normal) = face_normal(p.positions[a], p.positions[b], p.positions[c]) else {
                self.dropped += 1;
                continue;
            };
            if p.normals.is_some() {
                self.geo.triangles.push([(base + a) as u32, (base + b) as u32, (base + c) as u32]);
            } else {
                self.add_flat_triangle(ctx, p, [a, b, c], face_normal, ppath)?;
            }
            self.geo.triangle_materials.push(p.material);
        }
        Ok(())
    }

    /// A triangle of a primitive without shading normals: three vertices of its own with the
    /// face normal (and a tangent from its UVs).
    fn add_flat_triangle(
        &mut self,
        ctx: &Ctx<'_>,
        p: &Placed<'_>,
        [a, b, c]: [usize; 3],
        face_normal: Vec3,
        ppath: &str,
    ) -> Result<(), SceneError> {
        let geo = &mut self.geo;
        let v0 = geo.positions.len();
        if v0 + 3 > u32::MAX as usize {
            return Err(ctx.invalid((ppath.to_string(), "more than 2^32 vertices".into())));
        }
        let n = oct_encode(face_normal);
        let face_tangent = self.needs_tangent.then(|| {
            let uv = [p.uv(a), p.uv(b), p.uv(c)];
            let (pa, pb, pc) = (p.positions[a], p.positions[b], p.positions[c]);
            generate_tangents(&[pa, pb, pc], &[face_normal; 3], &uv, &[[0, 1, 2]])[0]
        });
        for &i in &[a, b, c] {
            geo.positions.push(p.positions[i]);
            geo.normals.push(n);
            p.push_attributes(geo, self.uv_sets, self.needs_color, i);
            if let Some(t) = face_tangent {
                geo.tangents.push(encode_tangent(t));
            }
        }
        geo.triangles.push([v0 as u32, v0 as u32 + 1, v0 as u32 + 2]);
        Ok(())
    }
}

/// Reads a primitive's other accessors against its vertex count; errors name the primitive.
struct Reader<'a> {
    ctx: &'a Ctx<'a>,
    buffers: &'a [Vec<u8>],
    ppath: &'a str,
    nverts: usize,
}

impl Reader<'_> {
    /// Attribute `name` from `acc` (if present) as floats of one of the types `dims`, one
    /// element per vertex, with its width (components per element).
    fn attribute(
        &self,
        acc: Option<gltf::Accessor<'_>>,
        dims: &[Dimensions],
        name: &str,
    ) -> Result<Option<(Vec<f32>, usize)>, SceneError> {
        let Some(acc) = acc else { return Ok(None) };
        let (v, _) = read_floats(&acc, self.buffers, dims).map_err(|e| self.ctx.invalid(e))?;
        let width = match acc.dimensions() {
            Dimensions::Vec2 => 2,
            Dimensions::Vec3 => 3,
            _ => 4,
        };
        let n = v.len() / width;
        if n != self.nverts {
            return Err(self.ctx.invalid((
                format!("{}.attributes.{name}", self.ppath),
                format!("count {n} differs from POSITION's count {}", self.nverts),
            )));
        }
        Ok(Some((v, width)))
    }

    /// The indices from `acc`, each below the vertex count; without an accessor, 0, 1, 2, ….
    fn indices(&self, acc: Option<gltf::Accessor<'_>>) -> Result<Vec<u32>, SceneError> {
        let nverts = self.nverts;
        let Some(acc) = acc else { return Ok((0..nverts as u32).collect()) };
        let idx = read_indices(&acc, self.buffers).map_err(|e| self.ctx.invalid(e))?;
        if let Some(&bad) = idx.iter().find(|&&i| i as usize >= nverts) {
            return Err(self.ctx.invalid((
                format!("{}.indices", self.ppath),
                format!("index {bad} ≥ vertex count {nverts}"),
            )));
        }
        Ok(idx)
    }
}

/// COLOR_0's values (`width` 3: RGB, alpha 1; 4: RGBA) as RGBA.
fn rgba(values: &[f32], width: usize) -> Vec<Vec4> {
    values
        .chunks_exact(width)
        .map(|c| if width == 3 { Vec4::new(c[0], c[1], c[2], 1.0) } else { Vec4::from_slice(c) })
        .collect()
}

/// The triangle list of a `TRIANGLE_STRIP`: triangle i is (pᵢ, pᵢ₊₁, pᵢ₊₂) for even i and
/// (pᵢ, pᵢ₊₂, pᵢ₊₁) for odd i (glTF 2.0, 3.7.2.1), so that all keep the first one's winding.
fn strip_triangles(strip: &[u32]) -> Vec<u32> {
    strip
        .windows(3)
        .enumerate()
        .flat_map(|(i, w)| if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[0], w[2], w[1]] })
        .collect()
}

/// The triangle list of a `TRIANGLE_FAN`: triangle i is (pᵢ₊₁, pᵢ₊₂, p₀) (glTF 2.0, 3.7.2.1).
fn fan_triangles(fan: &[u32]) -> Vec<u32> {
    match fan.split_first() {
        Some((&first, rest)) => rest.windows(2).flat_map(|w| [w[0], w[1], first]).collect(),
        None => Vec::new(),
    }
}

/// POSITION, which must be finite.
fn read_positions(
    ctx: &Ctx<'_>,
    pos_acc: &gltf::Accessor<'_>,
    buffers: &[Vec<u8>],
    ppath: &str,
) -> Result<Vec<f32>, SceneError> {
    let (pos, _) = read_floats(pos_acc, buffers, &[Dimensions::Vec3]).map_err(|e| ctx.invalid(e))?;
    // NaN and infinite positions are an error, not dropped triangles: the glTF Validator
    // reports them (ACCESSOR_INVALID_FLOAT), and a model with a broken vertex is one the user
    // wants to hear about by name rather than see rendered with a hole.
    if let Some(i) = pos.iter().position(|x| !x.is_finite()) {
        let v = i / 3;
        return Err(ctx.invalid((
            format!("{ppath}.attributes.POSITION"),
            format!(
                "accessors[{}] vertex {v} is ({}, {}, {}): positions must be finite",
                pos_acc.index(),
                pos[3 * v],
                pos[3 * v + 1],
                pos[3 * v + 2]
            ),
        )));
    }
    Ok(pos)
}

/// Transforms the primitive's positions and shading normals to world space.
fn place<'a>(
    ctx: &mut Ctx<'_>,
    a: &'a Attributes,
    material: u32,
    normal_set: usize,
    world: Mat4,
    ppath: &str,
    npath: &str,
) -> Result<Placed<'a>, SceneError> {
    let flip = Mat3::from_mat4(world).determinant() < 0.0;
    let pos = &a.positions;
    let wp: Vec<Vec3> =
        pos.chunks_exact(3).map(|p| world.transform_point3(Vec3::new(p[0], p[1], p[2]))).collect();
    // Finite positions that the node's (finite) transform takes past f32's range.
    if let Some(v) = wp.iter().position(|p| !p.is_finite()) {
        return Err(ctx.invalid((
            format!("{npath}: {ppath}.attributes.POSITION"),
            format!(
                "vertex {v} ({}, {}, {}) transformed to world space is {}: the node's transform takes it \
                 beyond f32's range (3.4e38)",
                pos[3 * v],
                pos[3 * v + 1],
                pos[3 * v + 2],
                wp[v]
            ),
        )));
    }
    let normals = a.normals.as_deref().and_then(|n| world_normals(ctx, n, world, ppath));
    Ok(Placed {
        positions: wp,
        normals,
        uvs: &a.uvs,
        colors: a.colors.as_deref(),
        normal_set,
        tangents: a.tangents.as_deref(),
        indices: &a.indices,
        material,
        world,
        flip,
        mirrored: a.mirrored.as_deref(),
    })
}

/// Shading normals in world space (by the inverse transpose); `None`, with a warning, if any
/// is zero or not finite.
fn world_normals(ctx: &mut Ctx<'_>, n: &[f32], world: Mat4, ppath: &str) -> Option<Vec<Vec3>> {
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let v: Vec<Vec3> = n
        .chunks_exact(3)
        .map(|c| (normal_matrix * Vec3::new(c[0], c[1], c[2])).normalize_or_zero())
        .collect();
    if v.iter().all(|x| *x != Vec3::ZERO) {
        Some(v)
    } else {
        ctx.warn(format!("{ppath}.attributes.NORMAL"), "zero or non-finite normals: per-face normals used");
        None
    }
}

/// Per-vertex world-space tangents of a primitive with shading `normals`.
fn vertex_tangents(p: &Placed<'_>, normals: &[Vec3]) -> Vec<Vec4> {
    // The file's tangents transform as directions (not by the inverse transpose);
    // a mirroring transform flips the handedness. Otherwise generate them.
    let world3 = Mat3::from_mat4(p.world);
    let from_file: Option<Vec<Vec4>> = p.tangents.map(|t| {
        t.chunks_exact(4)
            .map(|c| {
                let w = if (c[3] < 0.0) != p.flip { -1.0 } else { 1.0 };
                (world3 * Vec3::new(c[0], c[1], c[2])).normalize_or_zero().extend(w)
            })
            .collect()
    });
    let usable = from_file.filter(|v| v.iter().all(|t| t.truncate() != Vec3::ZERO));
    usable.unwrap_or_else(|| {
        let local: Vec<[u32; 3]> = p.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let uv: Vec<Vec2> = (0..p.positions.len()).map(|i| p.uv(i)).collect();
        generate_tangents(&p.positions, normals, &uv, &local)
    })
}

/// The unit normal of triangle (`pa`, `pb`, `pc`), `None` for a zero-area one.
fn face_normal(pa: Vec3, pb: Vec3, pc: Vec3) -> Option<Vec3> {
    let cross = (pb - pa).cross(pc - pa);
    let area2 = cross.length();
    // The face normal. `length` squares the cross product, which overflows f32 for edges
    // beyond ~4e9 and underflows below ~5e-12: such triangles were dropped as if
    // degenerate. Then it is formed in f64, where the positions' differences are exact and
    // nothing over- or underflows; only a zero cross product (zero area) drops a triangle.
    if area2 > 0.0 && area2.is_finite() {
        return Some(cross / area2);
    }
    let (da, db, dc) = (pa.as_dvec3(), pb.as_dvec3(), pc.as_dvec3());
    let c64 = (db - da).cross(dc - da);
    let l = c64.length();
    (l > 0.0 && l.is_finite()).then(|| (c64 / l).as_vec3())
}
