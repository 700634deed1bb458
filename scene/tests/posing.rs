//! Skins, morph targets and animation, posed when loaded: Khronos samples whose posed vertices
//! are worked out by hand from the files' own numbers (SimpleSkin, SimpleMorph, BoxAnimated,
//! InterpolationTest's STEP, LINEAR and CUBICSPLINE channels, RiggedSimple), in-memory files for
//! sparse morph targets, several JOINTS/WEIGHTS sets, weight normalisation and the errors, and
//! the animation's selection (`LoadOptions::animation`, `time`).

use furnace_scene::{LoadOptions, Scene, SceneError};
use glam::{Mat4, Quat, Vec3};

fn sample(path: &str) -> std::path::PathBuf {
    furnace_tests::data::scene(path)
}

fn posed(path: &str, animation: Option<&str>, time: Option<f32>) -> Scene {
    let options = LoadOptions { animation: animation.map(str::to_string), time, ..LoadOptions::default() };
    Scene::load_with(sample(path), &options).unwrap()
}

/// Positions after a handful of f32 operations on coordinates of order 1–10: a few ulps of 10.
const EPS: f32 = 1e-5;

fn near(a: Vec3, b: Vec3, eps: f32) -> bool {
    (a - b).abs().max_element() <= eps
}

/// Asserts that some vertex of `scene` is at `want`.
fn has_vertex(scene: &Scene, want: Vec3) {
    assert!(
        scene.geometry.positions.iter().any(|&p| near(p, want, EPS)),
        "no vertex at {want} in {:?}",
        scene.geometry.positions
    );
}

/// The pairs (rest, posed) of the vertices that moved between two loads of one file (the same
/// vertices in the same order, as posing changes no count).
fn moved(rest: &Scene, posed: &Scene) -> Vec<(Vec3, Vec3)> {
    assert_eq!(rest.geometry.positions.len(), posed.geometry.positions.len());
    rest.geometry
        .positions
        .iter()
        .zip(&posed.geometry.positions)
        .filter(|(a, b)| a != b)
        .map(|(&a, &b)| (a, b))
        .collect()
}

const SIMPLE_SKIN: &str = "SimpleSkin/glTF-Embedded/SimpleSkin.gltf";

/// SimpleSkin: a 10-vertex strip on two joints, joint 1 at (0, 1, 0) with inverse bind
/// translate(0, −1, 0). At t = 1 s the animation has turned joint 1 by (0, 0, 0.707, 0.707):
/// 90° about z, so joint 1's matrix is T(0,1,0)·Rz(90°)·T(0,−1,0). By hand:
/// * vertex 9 (0.5, 2, 0), weight 1 on joint 1: (0.5, 1) → (−1, 0.5) → (−1, 1.5);
/// * vertex 4 (−0.5, 1, 0), weights ½ ½: ½ (−0.5, 1) + ½ (0, 0.5) = (−0.25, 0.75);
/// * vertex 7 (0.5, 1.5, 0), weights ¼ ¾: ¼ (0.5, 1.5) + ¾ (−0.5, 1.5) = (−0.25, 1.5);
/// * vertex 0 (−0.5, 0, 0), weight 1 on joint 0 (identity): unmoved.
///
/// At rest every joint matrix is the identity: the file's own positions.
#[test]
fn simple_skin_by_hand() {
    let rest = posed(SIMPLE_SKIN, None, None);
    assert_eq!(rest.posed_by, None);
    assert!(rest.warnings.is_empty(), "{:?}", rest.warnings);
    let (lo, hi) = rest.geometry.bounds();
    assert!(near(lo, Vec3::new(-0.5, 0.0, 0.0), EPS) && near(hi, Vec3::new(0.5, 2.0, 0.0), EPS));

    let at_1 = posed(SIMPLE_SKIN, None, Some(1.0));
    assert_eq!(at_1.posed_by, Some((0, 1.0)), "--time alone takes animation 0");
    for v in [Vec3::new(-1.0, 1.5, 0.0), Vec3::new(-0.25, 0.75, 0.0), Vec3::new(-0.25, 1.5, 0.0)] {
        has_vertex(&at_1, v);
    }
    has_vertex(&at_1, Vec3::new(-0.5, 0.0, 0.0));
    // Vertex 8 (−0.5, 2, 0) → (−0.5, 1) → (−1, −0.5) → (−1, 0.5); the highest is vertex 7's 1.5.
    let (lo, hi) = at_1.geometry.bounds();
    assert!(near(lo, Vec3::new(-1.0, 0.0, 0.0), EPS), "{lo}");
    assert!(near(hi, Vec3::new(0.5, 1.5, 0.0), EPS), "{hi}");
    assert_ne!(rest.content_hash(), at_1.content_hash(), "the pose is part of the scene's content");
    // Linear: at 0.5 s the rotation is the file's second keyframe, (0, 0, 0.383, 0.924): 45°.
    let at_half = posed(SIMPLE_SKIN, Some("0"), Some(0.5));
    let r = Quat::from_xyzw(0.0, 0.0, 0.383, 0.924).normalize();
    let j1 = Mat4::from_translation(Vec3::Y) * Mat4::from_quat(r) * Mat4::from_translation(-Vec3::Y);
    has_vertex(&at_half, j1.transform_point3(Vec3::new(0.5, 2.0, 0.0)));
}

const SIMPLE_MORPH: &str = "SimpleMorph/glTF-Embedded/SimpleMorph.gltf";

/// SimpleMorph: a triangle whose vertex 2 (0.5, 0.5, 0) moves by (−1, 1, 0) in target 0 and by
/// (1, 1, 0) in target 1. The mesh's default weights (½, ½) give (0.5, 1.5); the animation's
/// LINEAR weights are (0, 1) at 1 s, so (1.5, 1.5), and (½, 1) at 1.5 s, so (1, 2). The other
/// vertices do not move.
#[test]
fn simple_morph_by_hand() {
    let rest = posed(SIMPLE_MORPH, None, None);
    has_vertex(&rest, Vec3::new(0.5, 1.5, 0.0));
    has_vertex(&rest, Vec3::new(1.0, 0.0, 0.0));
    has_vertex(&posed(SIMPLE_MORPH, None, Some(1.0)), Vec3::new(1.5, 1.5, 0.0));
    has_vertex(&posed(SIMPLE_MORPH, None, Some(1.5)), Vec3::new(1.0, 2.0, 0.0));
    // Clamped: before the first keyframe (0 s: weights 0) and after the last (4 s: weights 0).
    has_vertex(&posed(SIMPLE_MORPH, None, Some(100.0)), Vec3::new(0.5, 0.5, 0.0));
}

/// BoxAnimated at 1.875 s: node 0 is translated by its keyframes' constant (0, 2.52, 0) and the
/// inner box (node 2) is halfway along its LINEAR rotation from the identity (written as −1) to
/// a half turn about x (written (1, 0, 0, 0)): a quarter turn about x, (x, y, z) → (x, −z, y),
/// taken the shorter way. The other box does not move.
#[test]
fn box_animated_translation_and_slerp() {
    let path = "BoxAnimated/glTF-Binary/BoxAnimated.glb";
    let rest = posed(path, None, None);
    assert_eq!(rest.animations.len(), 1);
    assert!((rest.animations[0].duration - 3.708_33).abs() < 1e-5, "{:?}", rest.animations);
    let at = posed(path, None, Some(1.875));
    let pairs = moved(&rest, &at);
    assert!(!pairs.is_empty());
    let want = |p: Vec3| Vec3::new(p.x, -p.z, p.y) + Vec3::new(0.0, 2.52, 0.0);
    for (r, p) in &pairs {
        assert!(near(*p, want(*r), EPS), "{r} → {p}, want {}", want(*r));
    }
    // A quarter turn keeps normals unit and turns them with the box.
    let normals_moved =
        rest.geometry.normals.iter().zip(&at.geometry.normals).filter(|(a, b)| a != b).count();
    assert!(normals_moved > 0);
}

/// AnimatedMorphCube: a cube of side 0.02 scaled by 100 and turned by (0, 0.707, −0.707, 0)
/// (a half turn that takes the mesh's +y to the world's −z); target 0 lifts its bottom face
/// (y −0.01) by 0.018933, flattening the cube ("Square"; its normal and tangent displacements
/// are all zero). At 1.6 s (keyframe 48) the LINEAR weights are (0.99999994, 0): that face is at
/// y 0.0089325, world z −0.89325, and the cube spans z −1 … −0.89325 instead of −1 … 1.
#[test]
fn animated_morph_cube_positions_and_normals() {
    let path = "AnimatedMorphCube/glTF-Binary/AnimatedMorphCube.glb";
    let rest = posed(path, None, None);
    let at = posed(path, Some("Square"), Some(1.599_999_8));
    let (lo, hi) = at.geometry.bounds();
    // Coordinates of order 1 through a scale of 100: within 1e-4.
    assert!((rest.geometry.bounds().1.z - 1.0).abs() < 1e-4);
    assert!((lo.z + 1.0).abs() < 1e-4 && (hi.z + 0.893_25).abs() < 1e-4, "{lo} {hi}");
}

const INTERPOLATION: &str = "InterpolationTest/glTF-Binary/InterpolationTest.glb";

/// InterpolationTest: one animation per channel kind, each moving one cube; every vertex of
/// that cube (24, with its normals) moves as the hand-computed transform says, nothing else.
#[test]
fn interpolation_test_step_linear_cubic() {
    let rest = posed(INTERPOLATION, None, None);
    let names: Vec<&str> = rest.animations.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names.len(), 9, "{names:?}");
    let check = |name: &str, time: f32, f: &dyn Fn(Vec3) -> Vec3, eps: f32| {
        let at = posed(INTERPOLATION, Some(name), Some(time));
        let pairs = moved(&rest, &at);
        assert_eq!(pairs.len(), 24, "{name} at {time} s moved {} vertices", pairs.len());
        for (r, p) in &pairs {
            assert!(near(*p, f(*r), eps), "{name} at {time} s: {r} → {p}, want {}", f(*r));
        }
    };
    // Translations (keyframes 0.4167 s: y 10 and 0.8333 s: y 6; zero tangents for CUBICSPLINE).
    // STEP at 0.5 s (node 8 at y 6.665 at rest): y 10 after keyframe 0.4583 s.
    check("Step Translation", 0.5, &|p| p + Vec3::Y * (10.0 - 6.665_226_5), EPS);
    // LINEAR at a quarter of the segment: 10 + ¼ (6 − 10) = 9 (node 10 at y 6.9589 at rest).
    let (t0, t1) = (0.416_666_66_f32, 0.833_333_3_f32);
    check("Linear Translation", t0 + 0.25 * (t1 - t0), &|p| p + Vec3::Y * (9.0 - 6.958_913_3), 1e-4);
    // CUBICSPLINE with zero tangents: the Hermite basis at s = ¼ is h₀₀ = 2s³ − 3s² + 1 =
    // 0.84375 and h₀₁ = 0.15625: y = 0.84375 · 10 + 0.15625 · 6 = 9.375 (node 9 at 6.7342).
    // The tolerance: s is within 1e-7 of ¼ in f32, and coordinates near 10 round to 1e-6; 1e-4
    // still tells 9.375 from LINEAR's 9.
    check("CubicSpline Translation", t0 + 0.25 * (t1 - t0), &|p| p + Vec3::Y * (9.375 - 6.734_194_3), 1e-4);

    // Rotations about z through the cube's centre (its node's translation); keyframes
    // (0, 0, −0.383, 0.924) at 0.4167 s and (0, 0, −0.707, 0.707) at 0.875 s: −45° and −90°.
    // The moved cube is R_new · R_rest⁻¹ of the rest one about the centre.
    let about = |centre: Vec3, r: Quat| move |p: Vec3| centre + r * (p - centre);
    // STEP at 0.5 s: −45° (node 5 unrotated at rest).
    let step = about(Vec3::new(0.0, 3.356_412_4, 0.0), Quat::from_rotation_z((-45f32).to_radians()));
    check("Step Rotation", 0.5, &step, EPS);
    // LINEAR halfway (0.645833 s): slerp gives −67.5° (node 7 at −4.5° at rest).
    let rest_rotation = Quat::from_xyzw(0.0, 0.0, -0.039_259_82, 0.999_229_1).normalize();
    let linear = about(
        Vec3::new(-3.311_399_2, 3.356_412_4, 0.0),
        Quat::from_rotation_z((-67.5f32).to_radians()) * rest_rotation.inverse(),
    );
    check("Linear Rotation", (0.416_666_66 + 0.875) / 2.0, &linear, 1e-4);

    // Scales: LINEAR halfway between 0.5 (0.4167 s) and 1 (0.875 s) is 0.75, about node 3's
    // origin; STEP keeps 0.5 until 0.875 s.
    let centre = Vec3::new(-3.296_329_7, 0.0, 6.461_143_5e-5);
    check("Linear Scale", (0.416_666_66 + 0.875) / 2.0, &|p| centre + 0.75 * (p - centre), 1e-4);
    check("Step Scale", 0.8, &|p| 0.5 * p, EPS);
}

/// RiggedSimple: a cylinder on two bones, posed by matrices (world · inverse bind). Its
/// inverse bind matrices invert Armature · Bone (and · Bone.001): the bones' worlds without
/// the root Z_UP. At rest the bones are where they were bound, so every joint matrix is Z_UP
/// and each skinned vertex lies at Z_UP · v, not where the cylinder's node (Z_UP · Armature, a
/// quarter turn more about the cylinder's axis) would put it unskinned: the node's transform is
/// ignored, as glTF says. At 1 s the animation bends the upper bone.
#[test]
fn rigged_simple_rest_is_the_bind_pose() {
    let path = "RiggedSimple/glTF-Binary/RiggedSimple.glb";
    let rest = posed(path, None, None);
    assert!(rest.warnings.is_empty(), "{:?}", rest.warnings);
    let (doc, buffers, _) = gltf::import(sample(path)).unwrap();
    let z_up = Mat4::from_cols_array_2d(&doc.nodes().next().unwrap().transform().matrix());
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let file: Vec<Vec3> =
        prim.reader(|b| Some(&buffers[b.index()])).read_positions().unwrap().map(Vec3::from).collect();
    assert_eq!(file.len(), rest.geometry.positions.len(), "one vertex each, in order (it has normals)");
    let worst = file
        .iter()
        .zip(&rest.geometry.positions)
        .map(|(&v, &p)| (z_up.transform_point3(v) - p).length())
        .fold(0.0f32, f32::max);
    println!("RiggedSimple: rest pose vs Z_UP · v, largest distance {worst:e} (the cylinder is 9.15 long)");
    // The bind matrices and the bones' rest transforms are written separately by the exporter,
    // each rounded to f32: they agree to 5e-7 (measured, printed above); 1e-5 leaves room for
    // rounding, while a quarter turn off would be 1.4.
    assert!(worst < 1e-5, "{worst}");
    let bent = posed(path, None, Some(1.0));
    let (_, hi) = rest.geometry.bounds();
    let (_, bent_hi) = bent.geometry.bounds();
    assert!(!near(bent_hi, hi, 1e-2), "the bone bends at 1 s: {bent_hi} vs {hi}");
}

/// An unknown animation name is an error listing the file's animations; an index works; a file
/// without animations refuses `time`.
#[test]
fn animation_selection() {
    let options = LoadOptions { animation: Some("Walk".into()), ..LoadOptions::default() };
    let e = Scene::load_with(sample(INTERPOLATION), &options).unwrap_err();
    assert!(matches!(e, SceneError::UnknownAnimation { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("no animation 'Walk'") && text.contains("0 'Step Scale'"), "{text}");
    let by_index = posed(INTERPOLATION, Some("5"), Some(0.5));
    assert_eq!(by_index.posed_by, Some((5, 0.5)));
    assert_eq!(by_index.animations[5].name, "Linear Rotation");
    let options = LoadOptions { time: Some(1.0), ..LoadOptions::default() };
    let e = Scene::load_with(sample("Box/glTF/Box.gltf"), &options).unwrap_err();
    assert!(e.to_string().contains("the file has no animations"), "{e}");
    // A file without animations loads as before without the options.
    let plain = Scene::load(sample("Box/glTF/Box.gltf")).unwrap();
    assert!(plain.animations.is_empty() && plain.posed_by.is_none());
}

// ---- In-memory files ------------------------------------------------------------------------

/// A file of one triangle (0,0,0) (1,0,0) (0,1,0) (accessor 0) in mesh 0, node 0 in the
/// scene; the other members as JSON text; `extra` are accessors 1, 2, … as (JSON without
/// bufferView, bytes or none).
#[derive(Default)]
struct File<'a> {
    /// Attributes besides POSITION (`,"JOINTS_0":1`).
    attributes: &'a str,
    /// Members of the primitive besides its attributes (`,"targets":[…]`).
    primitive: &'a str,
    /// Members of the mesh besides its primitives.
    mesh: &'a str,
    nodes: &'a str,
    skins: &'a str,
    extra: Vec<(&'a str, Option<Vec<u8>>)>,
}

impl File<'_> {
    fn bytes(&self) -> Vec<u8> {
        let mut bin: Vec<u8> =
            [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|c| c.to_le_bytes()).collect();
        let mut views = vec![r#"{"buffer":0,"byteOffset":0,"byteLength":36}"#.to_string()];
        let mut accessors = vec![
            r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#
                .to_string(),
        ];
        for (json, bytes) in &self.extra {
            let view = bytes.as_ref().map(|b| {
                while !bin.len().is_multiple_of(4) {
                    bin.push(0);
                }
                views.push(format!(r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#, bin.len(), b.len()));
                bin.extend(b);
                format!(r#""bufferView":{},"#, views.len() - 1)
            });
            accessors.push(format!("{{{}{json}}}", view.unwrap_or_default()));
        }
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0{}}}{}}}]{}}}],"skins":[{}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{}],"accessors":[{}]}}"#,
            self.nodes,
            self.attributes,
            self.primitive,
            self.mesh,
            self.skins,
            bin.len(),
            base64::encode(&bin),
            views.join(","),
            accessors.join(",")
        )
        .into_bytes()
    }
}

fn le<T: Copy>(values: &[T], to: fn(T) -> Vec<u8>) -> Option<Vec<u8>> {
    Some(values.iter().flat_map(|&v| to(v)).collect())
}

fn f32s(v: &[f32]) -> Option<Vec<u8>> {
    le(v, |x| x.to_le_bytes().to_vec())
}

fn load(bytes: &[u8]) -> Result<Scene, SceneError> {
    Scene::from_slice(bytes, "pose.gltf")
}

/// A sparse morph target without a bufferView (zeros but for its sparse entries, as exporters
/// write them): vertex 2 moves by (0, 1, 0) in target 0 and vertex 1 by (2, 0, 0) in target 1;
/// node weights (0.5, 0.25) override the mesh's (1, 1).
#[test]
fn sparse_morph_targets_and_node_weights() {
    let sparse = |index: u8, d: [f32; 3]| {
        let mut bytes = vec![index, 0, 0, 0];
        bytes.extend(d.iter().flat_map(|c| c.to_le_bytes()));
        bytes
    };
    let target = |view_index: usize| {
        format!(
            r#""componentType":5126,"count":3,"type":"VEC3","sparse":{{"count":1,"indices":{{"bufferView":{view_index},"componentType":5121}},"values":{{"bufferView":{view_index},"byteOffset":4}}}}"#
        )
    };
    // Accessors 1 and 2 have no bufferView; their sparse data is in views 1 and 2, made by
    // two accessors (3 and 4) that no attribute uses.
    let (t0, t1) = (target(1), target(2));
    let bytes = File {
        primitive: r#","targets":[{"POSITION":1},{"POSITION":2}]"#,
        mesh: r#","weights":[1,1]"#,
        nodes: r#"{"mesh":0,"weights":[0.5,0.25]}"#,
        extra: vec![
            (&t0, None),
            (&t1, None),
            (r#""componentType":5121,"count":16,"type":"SCALAR""#, Some(sparse(2, [0.0, 1.0, 0.0]))),
            (r#""componentType":5121,"count":16,"type":"SCALAR""#, Some(sparse(1, [2.0, 0.0, 0.0]))),
        ],
        ..File::default()
    }
    .bytes();
    let scene = load(&bytes).unwrap_or_else(|e| panic!("{e}\n{}", String::from_utf8_lossy(&bytes)));
    has_vertex(&scene, Vec3::new(0.0, 1.5, 0.0));
    has_vertex(&scene, Vec3::new(1.5, 0.0, 0.0));
    has_vertex(&scene, Vec3::ZERO);
}

/// A NORMAL target: normals (0, 0, 1) displaced by (1, 0, 0) at weight 1 become (1, 0, 1)/√2;
/// a target without POSITION moves no vertex.
#[test]
fn normal_morph_target() {
    let normals = f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let displacement = f32s(&[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
    let bytes = File {
        attributes: r#","NORMAL":1"#,
        primitive: r#","targets":[{"NORMAL":2}]"#,
        mesh: r#","weights":[1]"#,
        nodes: r#"{"mesh":0}"#,
        extra: vec![
            (r#""componentType":5126,"count":3,"type":"VEC3""#, normals),
            (r#""componentType":5126,"count":3,"type":"VEC3""#, displacement),
        ],
        ..File::default()
    }
    .bytes();
    let scene = load(&bytes).unwrap_or_else(|e| panic!("{e}"));
    has_vertex(&scene, Vec3::new(1.0, 0.0, 0.0));
    let want = Vec3::new(1.0, 0.0, 1.0).normalize();
    for &n in &scene.geometry.normals {
        // Octahedral normals of 2 × 16 bits: within 1e-4 of the unit vector.
        assert!(near(furnace_scene::oct_decode(n), want, 1e-4), "{}", furnace_scene::oct_decode(n));
    }
}

/// A skinned triangle on joints 0 (at the origin) and 1 (node 2, translated by (0, 0, 5)),
/// identity inverse binds: JOINTS_0 (u8) and JOINTS_1 (u16) sets, float and normalised-u8
/// weights that sum to 2 (normalised to 1), and the skinned node's own transform ignored.
#[test]
fn two_sets_normalised_weights_and_ignored_node_transform() {
    let joints0 = le(&[0u8, 0, 0, 0, 1, 0, 0, 0, 0, 9, 0, 0], |x| vec![x]);
    // Vertex 0: weight 1 on joint 0 (set 0) and 1 on joint 0 (set 1): stays at the origin.
    // Vertex 1: weight 1 on joint 1 (set 0) and 1 on joint 1 (set 1): moves by (0, 0, 5).
    // Vertex 2: weight 1 on joint 0 (set 0; joint 9 has weight 0) and 1 on joint 1 (set 1):
    // halfway, (0, 1, 2.5).
    let weights0 = f32s(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    let joints1 = le(&[0u16, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0], |x| x.to_le_bytes().to_vec());
    let weights1 = le(&[255u8, 0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0], |x| vec![x]);
    let bytes = File {
        attributes: r#","JOINTS_0":1,"WEIGHTS_0":2,"JOINTS_1":3,"WEIGHTS_1":4"#,
        nodes: r#"{"mesh":0,"skin":0,"translation":[100,0,0]},{"children":[2]},{"translation":[0,0,5]}"#,
        skins: r#"{"joints":[1,2]}"#,
        extra: vec![
            (r#""componentType":5121,"count":3,"type":"VEC4""#, joints0),
            (r#""componentType":5126,"count":3,"type":"VEC4""#, weights0),
            (r#""componentType":5123,"count":3,"type":"VEC4""#, joints1),
            (r#""componentType":5121,"normalized":true,"count":3,"type":"VEC4""#, weights1),
        ],
        ..File::default()
    }
    .bytes();
    let scene = load(&bytes).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    has_vertex(&scene, Vec3::ZERO);
    has_vertex(&scene, Vec3::new(1.0, 0.0, 5.0));
    has_vertex(&scene, Vec3::new(0.0, 1.0, 2.5));
}

/// Bad skins are errors naming the attribute and the vertex: a joint index beyond the skin's
/// joints (with a non-zero weight), a negative weight, JOINTS_0 without WEIGHTS_0.
#[test]
fn bad_skins_are_errors_naming_the_path() {
    let skin_file = |joints: &[u8], weights: &[f32]| {
        File {
            attributes: r#","JOINTS_0":1,"WEIGHTS_0":2"#,
            nodes: r#"{"mesh":0,"skin":0},{}"#,
            skins: r#"{"joints":[1]}"#,
            extra: vec![
                (r#""componentType":5121,"count":3,"type":"VEC4""#, le(joints, |x| vec![x])),
                (r#""componentType":5126,"count":3,"type":"VEC4""#, f32s(weights)),
            ],
            ..File::default()
        }
        .bytes()
    };
    let one = [1.0, 0.0, 0.0, 0.0];
    let weights: Vec<f32> = one.iter().cycle().take(12).copied().collect();
    let mut joints = [0u8; 12];
    joints[8] = 3;
    let e = load(&skin_file(&joints, &weights)).unwrap_err().to_string();
    assert!(
        e.contains("meshes[0].primitives[0].attributes.JOINTS_0") && e.contains("vertex 2: joint 3"),
        "{e}"
    );
    let mut negative = weights.clone();
    negative[4] = -1.0;
    let e = load(&skin_file(&[0; 12], &negative)).unwrap_err().to_string();
    assert!(e.contains("attributes.WEIGHTS_0") && e.contains("vertex 1"), "{e}");
    let bytes = File {
        attributes: r#","JOINTS_0":1"#,
        nodes: r#"{"mesh":0,"skin":0},{}"#,
        skins: r#"{"joints":[1]}"#,
        extra: vec![(r#""componentType":5121,"count":3,"type":"VEC4""#, le(&[0u8; 12], |x| vec![x]))],
        ..File::default()
    }
    .bytes();
    let e = load(&bytes).unwrap_err().to_string();
    assert!(e.contains("attributes.JOINTS_0") && e.contains("no WEIGHTS_0"), "{e}");
}
