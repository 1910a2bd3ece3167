use glam::Vec3;

use crate::{CameraError, SceneError};

/// A pinhole camera with a square-pixel image plane; image row 0 is the top.
///
/// The fields are private because they depend on each other (an orthonormal frame, the
/// tangent of half the field of view): build one with [`Camera::look_at`] and resize it with
/// [`Camera::with_resolution`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub(crate) position: Vec3,
    /// The target `look_at` was given (in the scene's frame, as `position`): kept so that an
    /// export can hand another renderer, or bdpm's own import, the very inputs of the frame;
    /// recomputing them from `forward` would round.
    pub(crate) target: Vec3,
    /// The approximate up `look_at` was given, for the same reason.
    up_given: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    vfov_degrees: f32,
    width: u32,
    height: u32,
    tan_half: f32,
}

impl Camera {
    /// A camera at `eye` looking at `target`, with `up` as the approximate image-up direction,
    /// a vertical field of view in degrees, and an image of `width` × `height` pixels.
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        vfov_degrees: f32,
        width: u32,
        height: u32,
    ) -> Result<Camera, SceneError> {
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(SceneError::BadCamera(CameraError::NotFinite));
        }
        let forward = (target - eye).normalize_or_zero();
        if forward == Vec3::ZERO {
            return Err(SceneError::BadCamera(CameraError::TargetIsPosition));
        }
        let right = forward.cross(up).normalize_or_zero();
        if right == Vec3::ZERO {
            return Err(SceneError::BadCamera(CameraError::UpParallel));
        }
        if !(vfov_degrees > 0.0 && vfov_degrees < 179.0) {
            return Err(SceneError::BadCamera(CameraError::FieldOfView));
        }
        if width == 0 || height == 0 {
            return Err(SceneError::BadCamera(CameraError::Resolution));
        }
        let up_given = up;
        let up = right.cross(forward);
        Ok(Camera {
            position: eye,
            target,
            up_given,
            forward,
            right,
            up,
            vfov_degrees,
            width,
            height,
            tan_half: (vfov_degrees.to_radians() * 0.5).tan(),
        })
    }

    /// Pinhole position, metres (in the scene's frame once the camera is part of a
    /// [`crate::Scene`]).
    #[inline]
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// The point `look_at` was given to look at, metres (in the scene's frame, as
    /// [`Camera::position`]).
    #[inline]
    pub fn target(&self) -> Vec3 {
        self.target
    }

    /// The approximate up direction `look_at` was given (not the orthonormal [`Camera::up`]).
    #[inline]
    pub fn up_given(&self) -> Vec3 {
        self.up_given
    }

    /// Unit viewing direction.
    #[inline]
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// Unit image-right direction (`forward × up`).
    #[inline]
    pub fn right(&self) -> Vec3 {
        self.right
    }

    /// Unit image-up direction.
    #[inline]
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// Vertical field of view, degrees.
    #[inline]
    pub fn vfov_degrees(&self) -> f32 {
        self.vfov_degrees
    }

    /// Image width, pixels.
    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height, pixels.
    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The same camera with another image size (the field of view stays vertical).
    pub fn with_resolution(&self, width: u32, height: u32) -> Result<Camera, SceneError> {
        let mut camera = Camera::look_at(
            self.position,
            self.position + self.forward,
            self.up,
            self.vfov_degrees,
            width,
            height,
        )?;
        // The frame is rebuilt as it always was (image bits of earlier versions); the inputs
        // given to the first look_at stay what they were.
        camera.target = self.target;
        camera.up_given = self.up_given;
        Ok(camera)
    }

    /// Unit direction of the ray through image point (x, y) in pixels from the top-left corner
    /// (pixel (i, j) covers [i, i+1) × [j, j+1)).
    #[inline]
    pub fn ray_direction(&self, x: f32, y: f32) -> Vec3 {
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half * aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// Area of one pixel on the image plane at unit distance from the pinhole (dimensionless:
    /// m² per m²). A pixel's value is the mean radiance over this area, so a light-tracing
    /// splat divides by it.
    pub fn pixel_area(&self) -> f32 {
        let aspect = self.width as f32 / self.height as f32;
        (2.0 * self.tan_half * aspect / self.width as f32)
            * (2.0 * self.tan_half / self.height as f32)
    }

    /// The image point (x, y) in pixels where a world point projects, if it is in front of the
    /// camera and inside the image.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let aspect = self.width as f32 / self.height as f32;
        let sx = d.dot(self.right) / (z * self.tan_half * aspect);
        let sy = d.dot(self.up) / (z * self.tan_half);
        let x = (sx + 1.0) * 0.5 * self.width as f32;
        let y = (1.0 - sy) * 0.5 * self.height as f32;
        let inside =
            (0.0..self.width as f32).contains(&x) && (0.0..self.height as f32).contains(&y);
        inside.then_some((x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_view_is_not_mirrored_and_projection_inverts_rays() {
        // Looking along +z with +y up, +x is on the image's left (right-handed world).
        let c = Camera::look_at(
            Vec3::new(0.0, 0.0, -4.0),
            Vec3::ZERO,
            Vec3::Y,
            40.0,
            200,
            100,
        )
        .unwrap();
        let (x, _) = c.project(Vec3::new(0.5, 0.0, 0.0)).unwrap();
        assert!(x < 100.0);
        let (_, y) = c.project(Vec3::new(0.0, 0.5, 0.0)).unwrap();
        assert!(y < 50.0, "up is the top of the image");
        let d = c.ray_direction(37.25, 81.5);
        let (x, y) = c.project(c.position + d * 3.0).unwrap();
        assert!((x - 37.25).abs() < 1e-3 && (y - 81.5).abs() < 1e-3);
        assert!((c.ray_direction(100.0, 50.0) - c.forward).length() < 1e-6);
    }

    #[test]
    fn bad_cameras_are_rejected() {
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0, 4, 4).is_err());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0, 4, 4).is_err());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 0.0, 4, 4).is_err());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, 0, 4).is_err());
    }
}
