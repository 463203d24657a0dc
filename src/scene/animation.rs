//! glTF animations evaluated at one time (`--time`): each channel's sampler read at that time and
//! written over its node's default translation, rotation, scale or morph weights, before the node
//! tree is walked; skins then follow their animated joints. The interpolations are the
//! specification's (Appendix C): `STEP` holds a key's value, `LINEAR` interpolates (rotations by
//! spherical linear interpolation along the shorter arc), `CUBICSPLINE` is the cubic Hermite
//! spline of each key's value and in- and out-tangents, the tangents scaled by the keys' interval
//! (rotations normalized after). Before the first key a channel holds the first value, after the
//! last the last.

use super::accessor::Reader;
use super::source::Origin;
use crate::error::Result;
use glam::{Quat, Vec3};
use gltf::animation::{Interpolation, Property};

/// Which animations play.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AnimationSelect {
    /// Every animation of the file (the default).
    All,
    /// The animation of this index.
    Index(usize),
    /// The animation of this name.
    Name(String),
}

/// The time a scene is posed at and the animations that pose it ([`super::LoadOptions::pose`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PoseAt {
    /// Seconds.
    pub time: f32,
    /// The animations played.
    pub animations: AnimationSelect,
}

/// Every node's animated properties at one time (`None`: the node's default).
#[derive(Clone, Debug, Default)]
pub(super) struct Pose {
    pub translation: Vec<Option<Vec3>>,
    pub rotation: Vec<Option<Quat>>,
    pub scale: Vec<Option<Vec3>>,
    pub weights: Vec<Option<Vec<f32>>>,
}

impl Pose {
    /// Node `node`'s local transform under this pose: its default translation, rotation and
    /// scale (a matrix decomposed) with the animated ones written over them.
    pub fn local(&self, node: &gltf::Node) -> glam::Mat4 {
        let i = node.index();
        let animated = self.translation[i].is_some() || self.rotation[i].is_some() || self.scale[i].is_some();
        if !animated {
            return super::load::local_transform(node);
        }
        let (t, r, s) = node.transform().decomposed();
        glam::Mat4::from_scale_rotation_translation(
            self.scale[i].unwrap_or(Vec3::from(s)),
            self.rotation[i].unwrap_or(Quat::from_array(r)).normalize(),
            self.translation[i].unwrap_or(Vec3::from(t)),
        )
    }
}

/// The pose of `document`'s `pose.animations` at `pose.time`.
pub(super) fn pose(origin: &Origin, reader: &Reader, document: &gltf::Document, at: &PoseAt) -> Result<Pose> {
    let animations: Vec<gltf::Animation> = document.animations().collect();
    let chosen: Vec<&gltf::Animation> = match &at.animations {
        AnimationSelect::All => animations.iter().collect(),
        AnimationSelect::Index(i) => vec![animations.get(*i).ok_or_else(|| {
            origin.error(format!("there is no animation {i}: the file has {}", animations.len()))
        })?],
        AnimationSelect::Name(name) => {
            vec![animations.iter().find(|a| a.name() == Some(name.as_str())).ok_or_else(|| {
                let names: Vec<String> = animations
                    .iter()
                    .enumerate()
                    .map(|(i, a)| a.name().map_or(format!("#{i} (no name)"), |n| format!("'{n}'")))
                    .collect();
                origin.error(match names.len() {
                    0 => format!("there is no animation '{name}': the file has no animations"),
                    _ => format!(
                        "there is no animation '{name}': the file's animations are {}",
                        names.join(", ")
                    ),
                })
            })?]
        }
    };
    if !at.time.is_finite() {
        return Err(origin.error(format!("the pose's time {} is not finite", at.time)));
    }
    let nodes = document.nodes().len();
    let mut pose = Pose {
        translation: vec![None; nodes],
        rotation: vec![None; nodes],
        scale: vec![None; nodes],
        weights: vec![None; nodes],
    };
    for animation in chosen {
        for (c, channel) in animation.channels().enumerate() {
            let what = format!(
                "animation {}{} channel {c}",
                animation.index(),
                animation.name().map_or(String::new(), |n| format!(" ('{n}')"))
            );
            let sampler = channel.sampler();
            let times = reader.vectors::<1>(&sampler.input(), &format!("{what}: input"))?;
            let times: Vec<f32> = times.into_iter().map(|[t]| t).collect();
            if times.is_empty()
                || !times.iter().all(|t| t.is_finite())
                || times.windows(2).any(|w| w[0] >= w[1])
            {
                return Err(
                    origin.error(format!("{what}: its key times must be finite and strictly increasing"))
                );
            }
            let cubic = sampler.interpolation() == Interpolation::CubicSpline;
            let per_key = if cubic { 3 } else { 1 };
            let node = channel.target().node().index();
            let output = sampler.output();
            let out_what = format!("{what}: output");
            let key = Key::at(&times, at.time);
            let interpolation = sampler.interpolation();
            match channel.target().property() {
                Property::Translation | Property::Scale => {
                    let values = reader.vectors::<3>(&output, &out_what)?;
                    check_count(origin, &what, values.len(), times.len() * per_key)?;
                    let v: Vec<Vec3> = values.into_iter().map(Vec3::from).collect();
                    let value = sample(&v, &key, interpolation, |a, b, t| a.lerp(b, t), |v| v);
                    match channel.target().property() {
                        Property::Translation => pose.translation[node] = Some(value),
                        _ => pose.scale[node] = Some(value),
                    }
                }
                Property::Rotation => {
                    let values = reader.vectors::<4>(&output, &out_what)?;
                    check_count(origin, &what, values.len(), times.len() * per_key)?;
                    let v: Vec<Quat> = values.into_iter().map(Quat::from_array).collect();
                    // glam's slerp takes the shorter arc (it negates `end` when the dot is negative).
                    let value = sample(&v, &key, interpolation, Quat::slerp, Quat::normalize);
                    pose.rotation[node] = Some(value.normalize());
                }
                Property::MorphTargetWeights => {
                    let values: Vec<f32> =
                        reader.vectors::<1>(&output, &out_what)?.into_iter().map(|[w]| w).collect();
                    let targets = values.len() / (times.len() * per_key).max(1);
                    check_count(origin, &what, values.len(), times.len() * per_key * targets)?;
                    let weights = (0..targets)
                        .map(|k| {
                            let v: Vec<f32> = values.iter().skip(k).step_by(targets).copied().collect();
                            sample(&v, &key, interpolation, |a, b, t| a + (b - a) * t, |v| v)
                        })
                        .collect();
                    pose.weights[node] = Some(weights);
                }
            }
        }
    }
    Ok(pose)
}

fn check_count(origin: &Origin, what: &str, got: usize, want: usize) -> Result<()> {
    if got != want {
        return Err(origin.error(format!("{what}: its output has {got} values where its keys need {want}")));
    }
    Ok(())
}

/// Where a time falls among the keys: the key at or before it, the next, the interval's length
/// and the fraction of it passed (0 before the first key, 1 after the last).
struct Key {
    k: usize,
    next: usize,
    interval: f32,
    t: f32,
}

impl Key {
    fn at(times: &[f32], time: f32) -> Key {
        let last = times.len() - 1;
        if time <= times[0] {
            return Key { k: 0, next: 0, interval: 0.0, t: 0.0 };
        }
        if time >= times[last] {
            return Key { k: last, next: last, interval: 0.0, t: 0.0 };
        }
        // The last key at or before `time`.
        let k = times.partition_point(|&t| t <= time) - 1;
        let interval = times[k + 1] - times[k];
        Key { k, next: k + 1, interval, t: (time - times[k]) / interval }
    }
}

/// A channel's value at `key`: `values` one per key (`STEP`, `LINEAR`) or three (`CUBICSPLINE`:
/// in-tangent, value, out-tangent).
fn sample<T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>>(
    values: &[T],
    key: &Key,
    interpolation: Interpolation,
    linear: impl Fn(T, T, f32) -> T,
    finish: impl Fn(T) -> T,
) -> T {
    match interpolation {
        Interpolation::Step => values[key.k],
        Interpolation::Linear if key.next == key.k => values[key.k],
        Interpolation::Linear => linear(values[key.k], values[key.next], key.t),
        Interpolation::CubicSpline => {
            let value = |k: usize| values[3 * k + 1];
            if key.next == key.k {
                return value(key.k);
            }
            let (t, td) = (key.t, key.interval);
            let (t2, t3) = (t * t, t * t * t);
            let out_tangent = values[3 * key.k + 2];
            let in_tangent = values[3 * key.next];
            finish(
                value(key.k) * (2.0 * t3 - 3.0 * t2 + 1.0)
                    + out_tangent * (td * (t3 - 2.0 * t2 + t))
                    + value(key.next) * (-2.0 * t3 + 3.0 * t2)
                    + in_tangent * (td * (t3 - t2)),
            )
        }
    }
}
