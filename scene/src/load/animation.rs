//! Animations: the file's list (names and durations), the one a load selects, and its channels
//! sampled at one time into a [`Pose`]: the nodes' translations, rotations, scales and morph
//! weights that override the file's own (glTF 2.0 §3.11, appendix C).
//!
//! Sampling, per channel: the time is clamped to the sampler's keyframe range; between
//! keyframes k and k + 1 at t_k ≤ t < t_{k+1}, with s = (t − t_k) / (t_{k+1} − t_k),
//! * STEP: v_k;
//! * LINEAR: (1 − s) v_k + s v_{k+1}, rotations by slerp along the shorter arc;
//! * CUBICSPLINE (each keyframe stores in-tangent a, value v, out-tangent b; Δ = t_{k+1} − t_k):
//!   (2s³ − 3s² + 1) v_k + Δ (s³ − 2s² + s) b_k + (−2s³ + 3s²) v_{k+1} + Δ (s³ − s²) a_{k+1};
//!
//! rotations are normalised after interpolation.

use super::context::Ctx;
use crate::AnimationInfo;
use crate::accessor::read_floats;
use crate::error::SceneError;
use glam::{Quat, Vec3};
use gltf::accessor::Dimensions;
use gltf::animation::{Interpolation, Property};
use gltf::json::validation::Checked;

/// What an animation sets on one node; `None` keeps the node's own value.
#[derive(Debug, Clone, Default)]
pub(super) struct NodePose {
    translation: Option<Vec3>,
    rotation: Option<Quat>,
    scale: Option<Vec3>,
    weights: Option<Vec<f32>>,
}

/// The nodes' animated values (one entry per node of the file; all `None` without an
/// animation).
#[derive(Debug, Clone)]
pub(super) struct Pose {
    nodes: Vec<NodePose>,
}

impl Pose {
    /// The file's own transforms and weights for `nodes` nodes.
    pub(super) fn rest(nodes: usize) -> Self {
        Self { nodes: vec![NodePose::default(); nodes] }
    }

    /// Node `node`'s local transform: the file's, its translation, rotation or scale replaced
    /// where the animation sets them (a matrix is decomposed first, as glTF forbids animating a
    /// node that has one).
    pub(super) fn transform(&self, node: &gltf::Node<'_>) -> gltf::scene::Transform {
        let own = node.transform();
        let Some(p) = self.nodes.get(node.index()) else { return own };
        if p.translation.is_none() && p.rotation.is_none() && p.scale.is_none() {
            return own;
        }
        let (t, r, s) = own.decomposed();
        gltf::scene::Transform::Decomposed {
            translation: p.translation.map_or(t, |v| v.to_array()),
            rotation: p.rotation.map_or(r, |q| q.to_array()),
            scale: p.scale.map_or(s, |v| v.to_array()),
        }
    }

    /// The morph weights of node `node`'s mesh: the animation's, else the node's `weights`,
    /// else the mesh's (glTF 2.0 §3.7.2.2); empty when none gives any (every weight 0).
    pub(super) fn weights<'n>(&'n self, node: &gltf::Node<'n>) -> &'n [f32] {
        if let Some(w) = self.nodes.get(node.index()).and_then(|p| p.weights.as_deref()) {
            return w;
        }
        node.weights().or_else(|| node.mesh().and_then(|m| m.weights())).unwrap_or(&[])
    }
}

/// The file's animations: names (`""` without one) and durations (the largest keyframe time of
/// their samplers' inputs, from the accessor's `max` or else its values; a sampler whose input
/// cannot be read adds nothing here, and is an error only when its animation is sampled).
pub(super) fn list(doc: &gltf::Document, buffers: &[Vec<u8>]) -> Vec<AnimationInfo> {
    let json = doc.as_json();
    json.animations
        .iter()
        .map(|a| {
            let duration = a
                .samplers
                .iter()
                .filter_map(|s| {
                    let declared = json
                        .accessors
                        .get(s.input.value())
                        .and_then(|acc| acc.max.as_ref())
                        .and_then(|m| m.get(0))
                        .and_then(|m| m.as_f64())
                        .map(|m| m as f32);
                    declared.or_else(|| {
                        let acc = doc.accessors().nth(s.input.value())?;
                        let (t, _) = read_floats(&acc, buffers, &[Dimensions::Scalar]).ok()?;
                        t.into_iter().filter(|x| x.is_finite()).reduce(f32::max)
                    })
                })
                .filter(|d| d.is_finite())
                .fold(0.0f32, f32::max);
            AnimationInfo { name: a.name.clone().unwrap_or_default(), duration }
        })
        .collect()
}

/// The animation and time a load asked for: `animation` by name, else by index; animation 0
/// when only `time` is given; `None` when neither is. Time 0 without `time`.
pub(super) fn select(
    ctx: &Ctx<'_>,
    animations: &[AnimationInfo],
    animation: Option<&str>,
    time: Option<f32>,
) -> Result<Option<(usize, f32)>, SceneError> {
    let wanted = match (animation, time) {
        (None, None) => return Ok(None),
        (Some(a), _) => a.to_string(),
        (None, Some(_)) => "0".to_string(),
    };
    let index = animations
        .iter()
        .position(|a| a.name == wanted)
        .or_else(|| wanted.parse::<usize>().ok().filter(|&i| i < animations.len()))
        .ok_or_else(|| SceneError::UnknownAnimation {
            file: ctx.file.to_string(),
            animation: wanted,
            available: animations.to_vec(),
        })?;
    Ok(Some((index, time.unwrap_or(0.0))))
}

/// Animation `index`'s channels sampled at `time` seconds. A channel's sampler must have
/// non-decreasing finite keyframe times and as many outputs as its interpolation needs; any
/// other is an error naming the sampler. Channels without a node (another extension's
/// targets) are ignored with a warning.
pub(super) fn sample(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    index: usize,
    time: f32,
) -> Result<Pose, SceneError> {
    let json = doc.as_json();
    let mut pose = Pose::rest(json.nodes.len());
    let apath = format!("animations[{index}]");
    let Some(anim) = json.animations.get(index) else { return Ok(pose) };
    for (c, channel) in anim.channels.iter().enumerate() {
        let cpath = format!("{apath}.channels[{c}]");
        let node = channel.target.node.value();
        let (Some(slot), Checked::Valid(property)) = (pose.nodes.get_mut(node), channel.target.path) else {
            ctx.warn(
                format!("{cpath}.target"),
                "not a node's translation, rotation, scale or weights: ignored",
            );
            continue;
        };
        let s = channel.sampler.value();
        let spath = format!("{apath}.samplers[{s}]");
        let Some(sampler) = anim.samplers.get(s) else {
            return Err(ctx.invalid((format!("{cpath}.sampler"), format!("sampler {s} does not exist"))));
        };
        let interpolation = match sampler.interpolation {
            Checked::Valid(i) => i,
            Checked::Invalid => {
                return Err(
                    ctx.invalid((format!("{spath}.interpolation"), "not STEP, LINEAR or CUBICSPLINE".into()))
                );
            }
        };
        let read = |i: gltf::json::Index<gltf::json::Accessor>, dims: &[Dimensions], path: String| {
            let acc = doc.accessors().nth(i.value()).ok_or_else(|| {
                ctx.invalid((path.clone(), format!("accessor {} does not exist", i.value())))
            })?;
            read_floats(&acc, buffers, dims).map(|(v, _)| v).map_err(|e| ctx.invalid(e))
        };
        let times = read(sampler.input, &[Dimensions::Scalar], format!("{spath}.input"))?;
        check_times(&times).map_err(|m| ctx.invalid((format!("{spath}.input"), m)))?;
        let (dims, width) = match property {
            Property::Translation | Property::Scale => (Dimensions::Vec3, 3),
            Property::Rotation => (Dimensions::Vec4, 4),
            Property::MorphTargetWeights => (Dimensions::Scalar, 1),
        };
        let values = read(sampler.output, &[dims], format!("{spath}.output"))?;
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        // Elements per keyframe value: 3 or 4 components, or one weight per morph target.
        let elements = values.len() / width;
        let count = times.len() * per_key;
        let ok =
            elements.is_multiple_of(count) && (property == Property::MorphTargetWeights || elements == count);
        if !ok || values.iter().any(|v| !v.is_finite()) {
            return Err(ctx.invalid((
                format!("{spath}.output"),
                format!(
                    "{elements} finite values expected to be {count} ({} keyframes{}){}",
                    times.len(),
                    if per_key == 3 { " × in-tangent, value, out-tangent" } else { "" },
                    if property == Property::MorphTargetWeights { " × the morph targets" } else { "" }
                ),
            )));
        }
        let n = width * elements / count;
        let v = interpolate(&times, &values, n, interpolation, time, property == Property::Rotation);
        match property {
            Property::Translation => slot.translation = Some(Vec3::from_slice(&v)),
            Property::Scale => slot.scale = Some(Vec3::from_slice(&v)),
            Property::Rotation => {
                let q = Quat::from_slice(&v);
                if !(q.length() > 0.0) {
                    return Err(ctx.invalid((
                        format!("{spath}.output"),
                        format!("the rotation at {time} s is a zero quaternion"),
                    )));
                }
                slot.rotation = Some(q.normalize());
            }
            Property::MorphTargetWeights => slot.weights = Some(v),
        }
    }
    Ok(pose)
}

/// Keyframe times: at least one, finite, non-decreasing.
fn check_times(times: &[f32]) -> Result<(), String> {
    if times.is_empty() {
        return Err("no keyframes".into());
    }
    if let Some(i) = times.iter().position(|t| !t.is_finite()) {
        return Err(format!("keyframe {i}'s time is {}", times[i]));
    }
    if let Some(i) = times.windows(2).position(|w| w[1] < w[0]) {
        return Err(format!("keyframe times decrease ({} then {})", times[i], times[i + 1]));
    }
    Ok(())
}

/// The value (`n` components) of a sampler with keyframe `times` and `values` at `time`;
/// `rotation`: quaternions, slerped by LINEAR (the caller normalises).
fn interpolate(
    times: &[f32],
    values: &[f32],
    n: usize,
    interpolation: Interpolation,
    time: f32,
    rotation: bool,
) -> Vec<f32> {
    let cubic = interpolation == Interpolation::CubicSpline;
    // Keyframe k's value: the middle of (in-tangent, value, out-tangent) for CUBICSPLINE.
    let value = |k: usize| {
        let at = if cubic { (3 * k + 1) * n } else { k * n };
        &values[at..at + n]
    };
    let last = times.len() - 1;
    // The segment [t_k, t_{k+1}) holding `time`; before the first and from the last keyframe on,
    // the end value (clamped).
    let k = times.partition_point(|&t| t <= time);
    if k == 0 {
        return value(0).to_vec();
    }
    if k > last {
        return value(last).to_vec();
    }
    let k = k - 1;
    let (t0, t1) = (times[k], times[k + 1]);
    let dt = t1 - t0;
    let s = ((time - t0) / dt).clamp(0.0, 1.0);
    match interpolation {
        Interpolation::Step => value(k).to_vec(),
        Interpolation::Linear if rotation => {
            slerp(Quat::from_slice(value(k)), Quat::from_slice(value(k + 1)), s).to_array().to_vec()
        }
        Interpolation::Linear => value(k).iter().zip(value(k + 1)).map(|(a, b)| a + s * (b - a)).collect(),
        Interpolation::CubicSpline => {
            let (s2, s3) = (s * s, s * s * s);
            let out_tangent = &values[(3 * k + 2) * n..(3 * k + 3) * n];
            let in_tangent = &values[3 * (k + 1) * n..(3 * (k + 1) + 1) * n];
            (0..n)
                .map(|i| {
                    (2.0 * s3 - 3.0 * s2 + 1.0) * value(k)[i]
                        + dt * (s3 - 2.0 * s2 + s) * out_tangent[i]
                        + (-2.0 * s3 + 3.0 * s2) * value(k + 1)[i]
                        + dt * (s3 - s2) * in_tangent[i]
                })
                .collect()
        }
    }
}

/// Spherical linear interpolation along the shorter arc (glTF 2.0 appendix C): with
/// a = arccos |q₀·q₁| and σ the sign of q₀·q₁, q = (sin(a(1 − s)) q₀ + σ sin(a s) q₁) / sin a;
/// linear interpolation where a is too small for the division.
fn slerp(q0: Quat, q1: Quat, s: f32) -> Quat {
    let (q0, q1) = (q0.normalize(), q1.normalize());
    let d = q0.dot(q1);
    let (q1, d) = if d < 0.0 { (-q1, -d) } else { (q1, d) };
    if d > 1.0 - 1e-6 {
        return (q0 * (1.0 - s) + q1 * s).normalize();
    }
    let a = d.min(1.0).acos();
    let sin_a = a.sin();
    q0 * ((a * (1.0 - s)).sin() / sin_a) + q1 * ((a * s).sin() / sin_a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tolerance of f32 interpolation on values of order 1: a few ulps of 1.
    const EPS: f32 = 1e-6;

    #[test]
    fn step_linear_and_clamping() {
        let times = [1.0, 2.0, 4.0];
        let values = [0.0, 10.0, 30.0];
        let at = |i, t| interpolate(&times, &values, 1, i, t, false)[0];
        assert_eq!(at(Interpolation::Linear, 0.0), 0.0, "before the first keyframe: the first value");
        assert_eq!(at(Interpolation::Linear, 9.0), 30.0, "after the last: the last value");
        assert!((at(Interpolation::Linear, 1.5) - 5.0).abs() < EPS);
        assert!((at(Interpolation::Linear, 3.0) - 20.0).abs() < EPS);
        assert_eq!(at(Interpolation::Step, 1.99), 0.0);
        assert_eq!(at(Interpolation::Step, 2.0), 10.0);
        assert_eq!(at(Interpolation::Step, 3.9), 10.0);
    }

    #[test]
    fn cubic_spline_is_the_hermite_curve() {
        // Two keyframes at t = 0 and 2 (Δ = 2): values 1 and 3, out-tangent of the first 4,
        // in-tangent of the second −2. At s = 1/2 the Hermite basis is (1/2, 1/8, 1/2, −1/8):
        // 1/2 · 1 + 2 · 1/8 · 4 + 1/2 · 3 + 2 · (−1/8) · (−2) = 0.5 + 1 + 1.5 + 0.5 = 3.5.
        let times = [0.0, 2.0];
        let values = [9.0, 1.0, 4.0, -2.0, 3.0, 9.0];
        let at = |t| interpolate(&times, &values, 1, Interpolation::CubicSpline, t, false)[0];
        assert!((at(1.0) - 3.5).abs() < EPS, "{}", at(1.0));
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(2.0), 3.0);
        assert_eq!(at(5.0), 3.0, "clamped to the last value, not its tangent");
    }

    #[test]
    fn slerp_takes_the_shorter_arc_at_constant_speed() {
        // Quaternion components of order 1 after a few f32 operations: within 1e-6.
        let close = |a: Quat, b: Quat| a.abs_diff_eq(b, 1e-6);
        let q0 = Quat::IDENTITY;
        let q1 = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        assert!(close(slerp(q0, q1, 0.5), Quat::from_rotation_z(std::f32::consts::FRAC_PI_4)));
        // −q1 is the same rotation: still half of the quarter turn, not the long way round.
        assert!(close(slerp(q0, -q1, 0.5), Quat::from_rotation_z(std::f32::consts::FRAC_PI_4)));
        assert!(close(slerp(q0, q1, 1.0 / 3.0), Quat::from_rotation_z(std::f32::consts::PI / 6.0)));
    }

    #[test]
    fn times_must_not_decrease() {
        assert!(check_times(&[0.0, 1.0, 1.0, 2.0]).is_ok());
        assert!(check_times(&[0.0, 2.0, 1.0]).unwrap_err().contains("decrease"));
        assert!(check_times(&[]).is_err());
        assert!(check_times(&[0.0, f32::NAN]).is_err());
    }
}
