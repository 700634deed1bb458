//! Flat world-space triangle storage and octahedral normal encoding.

use glam::{Vec2, Vec3, Vec4};

/// Encodes a unit vector as two 16-bit snorm octahedral coordinates (Cigolle et al. 2014,
/// "A Survey of Efficient Representations for Independent Unit Vectors", JCGT 3(2)):
/// `x` in the low 16 bits, `y` in the high. Worst-case angular error ≈ 3e-5 rad. A zero or
/// non-finite input encodes +Z.
pub fn oct_encode(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !(l1 > 0.0) || !n.is_finite() {
        return oct_encode(Vec3::Z);
    }
    let mut p = Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        let s = Vec2::new(if p.x >= 0.0 { 1.0 } else { -1.0 }, if p.y >= 0.0 { 1.0 } else { -1.0 });
        p = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * s;
    }
    let q = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    q(p.x) | (q(p.y) << 16)
}

/// Decodes [`oct_encode`]'s output to a unit vector.
pub fn oct_decode(e: u32) -> Vec3 {
    let x = f32::from((e & 0xffff) as u16 as i16) / 32767.0;
    let y = f32::from((e >> 16) as u16 as i16) / 32767.0;
    let z = 1.0 - x.abs() - y.abs();
    let t = (-z).max(0.0);
    let x = x + if x >= 0.0 { -t } else { t };
    let y = y + if y >= 0.0 { -t } else { t };
    Vec3::new(x, y, z).normalize()
}

/// Packs a unit tangent with handedness into four snorm16 values.
pub fn encode_tangent(t: Vec4) -> [i16; 4] {
    let q = |x: f32| if x.is_finite() { (x.clamp(-1.0, 1.0) * 32767.0).round() as i16 } else { 0 };
    [q(t.x), q(t.y), q(t.z), if t.w < 0.0 { -32767 } else { 32767 }]
}

/// Unpacks [`encode_tangent`].
pub fn decode_tangent(e: [i16; 4]) -> Vec4 {
    Vec4::new(e[0] as f32, e[1] as f32, e[2] as f32, e[3] as f32) / 32767.0
}

/// The most UV sets a material may sample: `TEXCOORD_0` to `TEXCOORD_3`.
pub const MAX_UV_SETS: usize = 4;

/// What a shading point interpolates from its triangle's vertices besides its normal: the UV
/// sets (those the scene does not store are `(0, 0)`) and `COLOR_0`, which multiplies the base
/// colour and its alpha (opaque white without it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexAttributes {
    /// `TEXCOORD_k` at index k.
    pub uv: [Vec2; MAX_UV_SETS],
    /// `COLOR_0`, linear RGBA.
    pub color: Vec4,
}

impl Default for VertexAttributes {
    fn default() -> Self {
        Self { uv: [Vec2::ZERO; MAX_UV_SETS], color: Vec4::ONE }
    }
}

impl VertexAttributes {
    /// Attributes of UV0 alone (white vertex colour).
    pub fn from_uv(uv: Vec2) -> Self {
        let mut a = Self::default();
        a.uv[0] = uv;
        a
    }
}

/// Packs a linear RGBA vertex colour as unorm16 (glTF's `COLOR_0` lies in [0, 1]; values
/// outside are clamped, NaN reads 0).
pub fn encode_color(c: Vec4) -> [u16; 4] {
    c.to_array().map(|x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16)
}

/// Unpacks [`encode_color`] (also WGSL's `unpack2x16unorm`).
pub fn decode_color(e: [u16; 4]) -> Vec4 {
    Vec4::from_array(e.map(|x| f32::from(x) / 65535.0))
}

/// Per-vertex tangents from UV derivatives (Lengyel, "Computing Tangent Space Basis Vectors
/// for an Arbitrary Mesh", 2001): each triangle's `∂p/∂u` and `∂p/∂v` are accumulated on its
/// vertices, then the tangent is Gram–Schmidt-orthogonalised against the normal and the
/// handedness is the sign of `dot(cross(n, t), −∂p/∂v)`: glTF's texture coordinates have `v`
/// growing *down* the image while a normal map's green channel points *up* it, so the
/// bitangent `w·cross(n, t)` must follow −v (what MikkTSpace gives when fed `1 − v`, and what
/// exporters write into `TANGENT`; KhronosGroup/glTF-Sample-Models#174). Triangles with
/// degenerate UVs add nothing; a vertex left without a tangent gets an arbitrary one
/// orthogonal to its normal.
/// (MikkTSpace, which glTF recommends, differs in how it splits and weights; the results agree
/// on smooth, consistently mapped meshes.)
pub fn generate_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
) -> Vec<Vec4> {
    let mut t = vec![Vec3::ZERO; positions.len()];
    let mut b = vec![Vec3::ZERO; positions.len()];
    for tri in triangles {
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let (Some(&p0), Some(&p1), Some(&p2)) = (positions.get(i0), positions.get(i1), positions.get(i2))
        else {
            continue;
        };
        let uv = |i: usize| uvs.get(i).copied().unwrap_or(Vec2::ZERO);
        let (e1, e2) = (p1 - p0, p2 - p0);
        let (d1, d2) = (uv(i1) - uv(i0), uv(i2) - uv(i0));
        let det = d1.x * d2.y - d2.x * d1.y;
        if !(det.abs() > 1e-20) || !det.is_finite() {
            continue;
        }
        let r = 1.0 / det;
        let (du, dv) = ((e1 * d2.y - e2 * d1.y) * r, (e2 * d1.x - e1 * d2.x) * r);
        if !(du.is_finite() && dv.is_finite()) {
            continue;
        }
        for i in [i0, i1, i2] {
            t[i] += du;
            b[i] += dv;
        }
    }
    (0..positions.len())
        .map(|i| {
            let n = normals.get(i).copied().unwrap_or(Vec3::Z).normalize_or(Vec3::Z);
            let ortho = (t[i] - n * n.dot(t[i])).normalize_or_zero();
            if ortho == Vec3::ZERO {
                return n.any_orthonormal_vector().extend(1.0);
            }
            let w = if n.cross(ortho).dot(b[i]) > 0.0 { -1.0 } else { 1.0 };
            ortho.extend(w)
        })
        .collect()
}

/// Indexed world-space triangles. Vertices are not shared between primitives or instances, so
/// every vertex has one world position, one shading normal and (optionally) one UV.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Geometry {
    /// World-space vertex positions.
    pub positions: Vec<Vec3>,
    /// World-space unit shading normals, octahedral-encoded ([`oct_decode`]), one per vertex.
    pub normals: Vec<u32>,
    /// The UV sets materials sample (`TEXCOORD_0` … `TEXCOORD_n`, n < [`MAX_UV_SETS`]), vertex
    /// by vertex: vertex i's set k at `i × sets + k` ([`Geometry::uv_sets`]); **empty** when no
    /// material uses a texture; `(0, 0)` for vertices of primitives without that set.
    pub uvs: Vec<Vec2>,
    /// `COLOR_0` per vertex as RGBA unorm16 ([`encode_color`]), **empty** unless some primitive
    /// has one; opaque white for vertices of primitives without it.
    pub colors: Vec<[u16; 4]>,
    /// World-space unit tangents with handedness `w = ±1` (glTF `TANGENT`: bitangent =
    /// `w·cross(normal, tangent)`), as snorm16 ([`encode_tangent`]); **empty** unless some
    /// material has a normal map. From the file's `TANGENT` attribute when present, otherwise
    /// generated from UV derivatives ([`generate_tangents`]).
    pub tangents: Vec<[i16; 4]>,
    /// Vertex indices of each triangle, counter-clockwise seen from the front (winding is flipped
    /// for instances with a mirroring transform, so that this stays true in world space).
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle, into [`crate::Scene::materials`].
    pub triangle_materials: Vec<u32>,
}

impl Geometry {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// World positions of triangle `t`'s vertices (`None` if out of range).
    pub fn triangle(&self, t: usize) -> Option<[Vec3; 3]> {
        let [a, b, c] = *self.triangles.get(t)?;
        let p = |i: u32| self.positions.get(i as usize).copied();
        Some([p(a)?, p(b)?, p(c)?])
    }

    /// The interpolated shading normal of triangle `t` at barycentrics `(b1, b2)`
    /// (`p = (1−b1−b2)·v0 + b1·v1 + b2·v2`), normalised; `None` if out of range.
    pub fn shading_normal(&self, t: usize, b1: f32, b2: f32) -> Option<Vec3> {
        let [a, b, c] = *self.triangles.get(t)?;
        let n = |i: u32| self.normals.get(i as usize).map(|&e| oct_decode(e));
        Some(((1.0 - b1 - b2) * n(a)? + b1 * n(b)? + b2 * n(c)?).normalize_or_zero())
    }

    /// The UV sets stored per vertex (0 without UVs).
    pub fn uv_sets(&self) -> usize {
        if self.positions.is_empty() { 0 } else { self.uvs.len() / self.positions.len() }
    }

    /// The interpolated UV0 of triangle `t` at barycentrics `(b1, b2)`; `(0, 0)` without UVs.
    pub fn uv(&self, t: usize, b1: f32, b2: f32) -> Vec2 {
        self.attributes(t, b1, b2).uv[0]
    }

    /// The interpolated UV sets and vertex colour of triangle `t` at barycentrics `(b1, b2)`:
    /// sets not stored are `(0, 0)`, the colour without `COLOR_0` opaque white.
    pub fn attributes(&self, t: usize, b1: f32, b2: f32) -> VertexAttributes {
        let mut out = VertexAttributes::default();
        let Some(&[a, b, c]) = self.triangles.get(t) else {
            return out;
        };
        let sets = self.uv_sets().min(MAX_UV_SETS);
        for (k, uv) in out.uv.iter_mut().enumerate().take(sets) {
            let at = |i: u32| self.uvs.get(i as usize * sets + k).copied().unwrap_or(Vec2::ZERO);
            *uv = (1.0 - b1 - b2) * at(a) + b1 * at(b) + b2 * at(c);
        }
        if !self.colors.is_empty() {
            let at = |i: u32| self.colors.get(i as usize).map_or(Vec4::ONE, |&e| decode_color(e));
            out.color = (1.0 - b1 - b2) * at(a) + b1 * at(b) + b2 * at(c);
        }
        out
    }

    /// Axis-aligned bounds of all vertices (`(+∞, −∞)` when empty).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    /// The interpolated tangent `(xyz, handedness)` at barycentrics `(b1, b2)`, if the scene has
    /// tangents; xyz re-normalised.
    pub fn tangent(&self, t: usize, b1: f32, b2: f32) -> Option<Vec4> {
        let [a, b, c] = *self.triangles.get(t)?;
        let v = |i: u32| self.tangents.get(i as usize).map(|&e| decode_tangent(e));
        let (ta, tb, tc) = (v(a)?, v(b)?, v(c)?);
        let xyz =
            ((1.0 - b1 - b2) * ta.truncate() + b1 * tb.truncate() + b2 * tc.truncate()).normalize_or_zero();
        Some(xyz.extend(if ta.w < 0.0 { -1.0 } else { 1.0 }))
    }

    /// Appends `other`'s vertices and triangles after this geometry's (its vertex indices moved
    /// past this one's vertices). Both must store the same attributes: the same UV sets, and
    /// colours and tangents in both or neither (one loader's output).
    pub fn append(&mut self, other: Geometry) {
        let base = self.positions.len() as u32;
        self.positions.extend(other.positions);
        self.normals.extend(other.normals);
        self.uvs.extend(other.uvs);
        self.colors.extend(other.colors);
        self.tangents.extend(other.tangents);
        self.triangles.extend(other.triangles.into_iter().map(|t| t.map(|v| v + base)));
        self.triangle_materials.extend(other.triangle_materials);
    }

    /// Bytes held by the geometry arrays (lengths, not capacities).
    pub fn bytes(&self) -> usize {
        self.positions.len() * 12
            + self.normals.len() * 4
            + self.uvs.len() * 8
            + self.colors.len() * 8
            + self.tangents.len() * 8
            + self.triangles.len() * 12
            + self.triangle_materials.len() * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangents_follow_u_and_detect_mirrored_uvs() {
        // A unit quad in the xy-plane facing +z, u along +x, v along +y: tangent +x; "up" in
        // the image is −v = −y = −cross(z, x), so w = −1.
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let n = [Vec3::Z; 4];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let tris = [[0, 1, 2], [0, 2, 3]];
        for t in generate_tangents(&p, &n, &uv, &tris) {
            assert!((t - Vec4::new(1.0, 0.0, 0.0, -1.0)).abs().max_element() < 1e-6, "{t}");
        }
        // v mirrored (v along −y, the usual glTF layout of this quad): same tangent, w = +1.
        let uv_m = uv.map(|c| Vec2::new(c.x, 1.0 - c.y));
        for t in generate_tangents(&p, &n, &uv_m, &tris) {
            assert!((t - Vec4::new(1.0, 0.0, 0.0, 1.0)).abs().max_element() < 1e-6, "{t}");
        }
        // Degenerate UVs: a unit tangent orthogonal to the normal, no NaN.
        for t in generate_tangents(&p, &n, &[Vec2::ZERO; 4], &tris) {
            assert!(
                t.is_finite()
                    && (t.truncate().length() - 1.0).abs() < 1e-6
                    && t.truncate().dot(Vec3::Z).abs() < 1e-6
            );
        }
        // snorm16 round trip within 1/32767 per component.
        let e = decode_tangent(encode_tangent(Vec4::new(0.6, -0.8, 0.0, -1.0)));
        assert!((e - Vec4::new(0.6, -0.8, 0.0, -1.0)).abs().max_element() < 1.0 / 32767.0 + 1e-7);
    }

    #[test]
    fn octahedral_round_trip() {
        // Fixed pseudo-random directions over the sphere, including the poles and the
        // octahedron's folded edges.
        let mut worst = 0.0f32;
        let mut dirs = vec![Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        for i in 0..10_000u32 {
            let u = (i as f32 + 0.5) / 10_000.0;
            let v = (i.wrapping_mul(2_654_435_761) as f32) / 4_294_967_296.0;
            let z = 1.0 - 2.0 * u;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * v;
            dirs.push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
        }
        for d in dirs {
            let e = oct_decode(oct_encode(d));
            // atan2(|a×b|, a·b): acos(a·b) would lose ~5e-4 rad to f32 rounding near 1.
            worst = worst.max(e.cross(d).length().atan2(e.dot(d)));
        }
        // 16-bit octahedral: the quantisation step is 2/65534 in the octahedron, at most
        // ≈ 1.5 × that in angle (Cigolle et al. Table 1 gives 0.0025° ≈ 4.4e-5 rad max error).
        assert!(worst < 1e-4, "worst angular error {worst}");
    }

    #[test]
    fn degenerate_normals_encode_up() {
        assert_eq!(oct_decode(oct_encode(Vec3::ZERO)), Vec3::Z);
        assert_eq!(oct_decode(oct_encode(Vec3::NAN)), Vec3::Z);
    }
}
