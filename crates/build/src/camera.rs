//! Camera factory.

use render::camera::Camera;

/// The runtime camera of `desc` for a film of `width` × `height` pixels.
pub fn camera(desc: &scene::Camera, width: u32, height: u32) -> Camera {
    Camera::new(
        &desc.projection,
        desc.to_world,
        desc.near_clip,
        desc.far_clip,
        width,
        height,
    )
}
