//! Cameras and `KHR_lights_punctual` lights, placed in world space by their nodes.
//!
//! glTF cameras and lights look down their node's local -Z with +Y up.

use crate::error::Result;
use glam::{Mat4, Vec3};
use gltf::json;
use gltf::json::validation::Checked;

use super::source::Origin;

/// A perspective or orthographic camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position (orthographic: the centre of the plane the rays start from).
    pub position: [f32; 3],
    /// Unit view direction.
    pub forward: [f32; 3],
    /// Unit up direction, perpendicular to `forward`.
    pub up: [f32; 3],
    /// Vertical field of view in radians (perspective cameras; unused by orthographic ones).
    pub yfov: f32,
    /// Width / height, when the file fixes it (otherwise the image's; orthographic: xmag / ymag).
    pub aspect: Option<f32>,
    /// Distance of the near plane.
    pub znear: f32,
    /// `Some` for an orthographic camera (glTF `camera.orthographic`), `None` for a perspective one.
    pub orthographic: Option<Orthographic>,
    /// The sub-pixel offset of every pixel's sample position from its centre, in pixels of the
    /// image rendered (x right, y down), each in [-0.5, 0.5): anti-aliasing's jitter
    /// ([`Camera::jittered`]). 0 for a file's cameras. The hybrid's passes sample there (rounded
    /// to 1/4096 pixel); the path tracer samples each pixel's whole area and ignores it.
    pub jitter: [f32; 2],
}

/// An orthographic camera's view: a box of parallel rays rather than a pyramid.
///
/// glTF's projection matrix puts `xmag` and `ymag` at the viewport's edges, so a viewport of
/// another aspect than xmag / ymag stretches the view. umbra keeps the image's aspect, as it does
/// for a perspective camera's `aspectRatio`: `ymag` is half the view's height and the half
/// width is |ymag| × the image's width / height (= `xmag` when the image has the file's aspect);
/// a negative magnification mirrors the image, as the matrix does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orthographic {
    /// Half the view's width (glTF `xmag`), scene units.
    pub xmag: f32,
    /// Half the view's height (glTF `ymag`), scene units.
    pub ymag: f32,
    /// Distance of the far plane (read and checked; rays are not cut off there, as for
    /// perspective cameras).
    pub zfar: f32,
}

impl Camera {
    /// Reads glTF camera `index` as placed by a node with transform `world`.
    pub(super) fn from_gltf(
        origin: &Origin,
        document: &gltf::Document,
        index: usize,
        world: Mat4,
    ) -> Result<Self> {
        let camera = &document.as_json().cameras[index];
        let positive = |x: f32| x > 0.0 && x.is_finite();
        let (position, forward, up) = frame(world);
        match (&camera.type_, &camera.perspective, &camera.orthographic) {
            (Checked::Valid(json::camera::Type::Perspective), Some(p), _) => {
                let (yfov, znear, aspect) = (p.yfov, p.znear, p.aspect_ratio);
                if !positive(yfov) || yfov >= std::f32::consts::PI {
                    return Err(
                        origin.error(format!("camera {index}: yfov {yfov} must lie between 0 and π radians"))
                    );
                }
                if !positive(znear) || aspect.is_some_and(|a| !positive(a)) {
                    return Err(origin.error(format!(
                        "camera {index}: znear ({znear}) and aspectRatio ({aspect:?}) must be positive"
                    )));
                }
                Ok(Self { position, forward, up, yfov, aspect, znear, orthographic: None, jitter: [0.0; 2] })
            }
            (Checked::Valid(json::camera::Type::Orthographic), _, Some(o)) => {
                let (xmag, ymag, znear, zfar) = (o.xmag, o.ymag, o.znear, o.zfar);
                let nonzero = |x: f32| x != 0.0 && x.is_finite();
                if !nonzero(xmag) || !nonzero(ymag) {
                    return Err(origin.error(format!(
                        "camera {index}: orthographic xmag ({xmag}) and ymag ({ymag}) must be finite and not 0"
                    )));
                }
                if !(znear >= 0.0 && zfar > znear && zfar.is_finite()) {
                    return Err(origin.error(format!(
                        "camera {index}: orthographic znear ({znear}) must be at least 0 and zfar ({zfar}) greater"
                    )));
                }
                let (yfov, aspect) = (0.0, Some((xmag / ymag).abs()));
                let orthographic = Some(Orthographic { xmag, ymag, zfar });
                Ok(Self { position, forward, up, yfov, aspect, znear, orthographic, jitter: [0.0; 2] })
            }
            (Checked::Valid(json::camera::Type::Perspective), None, _) => {
                Err(origin
                    .error(format!("camera {index} is 'perspective' but has no perspective properties")))
            }
            _ => {
                Err(origin
                    .error(format!("camera {index} is 'orthographic' but has no orthographic properties")))
            }
        }
    }

    /// This camera with every pixel sampled at `jitter` pixels from its centre ([`Camera::jitter`]).
    pub fn jittered(&self, jitter: [f32; 2]) -> Self {
        Self { jitter, ..*self }
    }

    /// Half the view's width and height at view depth `depth` for an image of aspect
    /// `image_aspect` (width / height): the pinhole's grow with depth, an orthographic camera's
    /// do not (signed: a negative magnification mirrors).
    pub fn half_extent(&self, depth: f32, image_aspect: f32) -> (f32, f32) {
        match self.orthographic {
            Some(o) => (o.ymag.abs() * image_aspect * o.xmag.signum(), o.ymag),
            None => {
                let tan = (self.yfov * 0.5).tan();
                (depth * tan * image_aspect, depth * tan)
            }
        }
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
            orthographic: None,
            jitter: [0.0; 2],
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
