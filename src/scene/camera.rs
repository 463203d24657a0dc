//! Cameras and `KHR_lights_punctual` lights, placed in world space by their nodes.
//!
//! glTF cameras and lights look down their node's local -Z with +Y up.

use crate::error::Result;
use glam::{Mat4, Vec3};
use gltf::json;
use gltf::json::validation::Checked;

use super::source::Origin;

/// A perspective camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: [f32; 3],
    /// Unit view direction.
    pub forward: [f32; 3],
    /// Unit up direction, perpendicular to `forward`.
    pub up: [f32; 3],
    /// Vertical field of view in radians.
    pub yfov: f32,
    /// Width / height, when the file fixes it (otherwise the image's).
    pub aspect: Option<f32>,
    /// Distance of the near plane.
    pub znear: f32,
}

impl Camera {
    /// Reads glTF camera `index` as placed by a node with transform `world`; for an orthographic
    /// camera, which umbra does not render, the warning that says so instead (also logged).
    pub(super) fn from_gltf(
        origin: &Origin,
        document: &gltf::Document,
        index: usize,
        world: Mat4,
    ) -> Result<std::result::Result<Self, String>> {
        let camera = &document.as_json().cameras[index];
        let perspective = match (&camera.type_, &camera.perspective) {
            (Checked::Valid(json::camera::Type::Perspective), Some(p)) => p,
            (Checked::Valid(json::camera::Type::Orthographic), _) => {
                let warning = format!(
                    "{}: camera {index} is orthographic; skipping it (umbra renders perspective)",
                    origin.name()
                );
                log::warn!("{warning}");
                return Ok(Err(warning));
            }
            _ => {
                return Err(origin
                    .error(format!("camera {index} is 'perspective' but has no perspective properties")))
            }
        };
        let (yfov, znear, aspect) = (perspective.yfov, perspective.znear, perspective.aspect_ratio);
        let positive = |x: f32| x > 0.0 && x.is_finite();
        if !positive(yfov) || yfov >= std::f32::consts::PI {
            return Err(origin.error(format!("camera {index}: yfov {yfov} must lie between 0 and π radians")));
        }
        if !positive(znear) || aspect.is_some_and(|a| !positive(a)) {
            return Err(origin.error(format!(
                "camera {index}: znear ({znear}) and aspectRatio ({aspect:?}) must be positive"
            )));
        }
        let (position, forward, up) = frame(world);
        Ok(Ok(Self { position, forward, up, yfov, aspect, znear }))
    }

    /// A camera looking down -Z at the centre of the box `lo..hi`, far enough back that the box's
    /// bounding sphere fits a 45° vertical field of view.
    pub(super) fn framing(lo: Vec3, hi: Vec3) -> Self {
        let yfov = 45f32.to_radians();
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let distance = radius / (yfov * 0.5).sin();
        Self {
            position: (centre + Vec3::Z * distance).to_array(),
            forward: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            yfov,
            aspect: None,
            znear: (distance - radius) * 0.5,
        }
    }
}

/// The kind of a punctual light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    /// Emits in all directions from a point.
    Point,
    /// A point emitting in a cone.
    Spot,
    /// Parallel light from infinitely far away.
    Directional,
}

/// A `KHR_lights_punctual` light in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// The light's name (empty when it has none).
    pub name: String,
    /// Point, spot or directional.
    pub kind: LightKind,
    /// Position (unused by directional lights).
    pub position: [f32; 3],
    /// Unit direction the light shines in (the node's -Z; unused by point lights).
    pub direction: [f32; 3],
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Candela (lm/sr) for point and spot lights, lux (lm/m²) for directional ones.
    pub intensity: f32,
    /// Distance at which the light may be cut off; `None`: infinite.
    pub range: Option<f32>,
    /// Spot: angle from the axis where the falloff starts (0 for other kinds).
    pub inner_cone_angle: f32,
    /// Spot: angle from the axis where the light ends (π for other kinds).
    pub outer_cone_angle: f32,
}

impl Light {
    /// Adds everything but the name to a content hash ([`super::Scene::content_hash`]).
    pub(super) fn hash_into(&self, h: &mut super::ContentHasher) {
        let Light {
            name: _,
            kind,
            position,
            direction,
            color,
            intensity,
            range,
            inner_cone_angle,
            outer_cone_angle,
        } = self;
        h.u32(match kind {
            LightKind::Point => 0,
            LightKind::Spot => 1,
            LightKind::Directional => 2,
        });
        h.f32s(position);
        h.f32s(direction);
        h.f32s(color);
        h.f32s(&[*intensity]);
        match range {
            None => h.u32(0),
            Some(r) => {
                h.u32(1);
                h.f32s(&[*r]);
            }
        }
        h.f32s(&[*inner_cone_angle, *outer_cone_angle]);
    }

    /// A glTF light as placed by a node with transform `world`.
    pub(super) fn from_gltf(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Self {
        use gltf::khr_lights_punctual::Kind;
        let (kind, inner_cone_angle, outer_cone_angle) = match light.kind() {
            Kind::Point => (LightKind::Point, 0.0, std::f32::consts::PI),
            Kind::Directional => (LightKind::Directional, 0.0, std::f32::consts::PI),
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                (LightKind::Spot, inner_cone_angle, outer_cone_angle)
            }
        };
        let (position, direction, _) = frame(world);
        Self {
            name: light.name().unwrap_or_default().to_owned(),
            kind,
            position,
            direction,
            color: light.color(),
            intensity: light.intensity(),
            range: light.range(),
            inner_cone_angle,
            outer_cone_angle,
        }
    }
}

/// Position, unit forward (-Z) and unit up (+Y, made perpendicular to forward) of a node frame.
fn frame(world: Mat4) -> ([f32; 3], [f32; 3], [f32; 3]) {
    let forward = world.transform_vector3(-Vec3::Z).normalize_or(-Vec3::Z);
    let up = world.transform_vector3(Vec3::Y);
    let up = (up - forward * forward.dot(up)).normalize_or(forward.any_orthonormal_vector());
    (world.w_axis.truncate().to_array(), forward.to_array(), up.to_array())
}
