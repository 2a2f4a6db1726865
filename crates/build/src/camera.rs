//! Camera factory.

use render::camera::{Camera, MeterShape};
use render::shapes::{ShapeGeom, ShapeInfo};
use scene::{Projection, SceneDesc, Shape};

/// The runtime camera of `cam` for a film of `width` × `height` pixels; `shapes` are the
/// runtime shapes of `desc` (one per scene shape, in order), where an irradiance meter finds
/// the shape it sits on. An error for a meter on a shape it cannot sample (an infinite
/// plane, an empty mesh).
pub fn camera(
    desc: &SceneDesc,
    cam: &scene::Camera,
    shapes: &[ShapeInfo],
    width: u32,
    height: u32,
) -> Result<Camera, String> {
    let camera = Camera::new(
        &cam.projection,
        cam.to_world,
        cam.near_clip,
        cam.far_clip,
        width,
        height,
    );
    let Projection::IrradianceMeter { shape } = cam.projection else {
        return Ok(camera);
    };
    let (Some(info), Some(sd)) = (shapes.get(shape), desc.shapes.get(shape)) else {
        return Err(format!("irradiancemeter: no shape {shape}"));
    };
    // A mesh shared with other shapes is an instance of a prototype in object space: the
    // meter samples its own world-space copy.
    let geom = match (&info.geom, &sd.shape) {
        (ShapeGeom::Instance(_), Shape::Mesh(m)) => crate::shapes::mesh_geom(m, &sd.to_world),
        (g, _) => g.clone(),
    };
    let meter = MeterShape::new(geom, info.flip_normals).ok_or_else(|| {
        "irradiancemeter: its shape has no finite, non-zero area to sample".to_string()
    })?;
    Ok(camera.with_irradiance_meter(meter))
}
