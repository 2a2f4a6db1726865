//! Light factories: an area light per emitting shape (or per emitting triangle), then the
//! scene's other emitters.

use std::sync::Arc;

use render::image_io::{self, Decode};
use render::lights::{
    AreaLight, ConstantLight, DirectionalAreaLight, DirectionalLight, EnvMap, ImagePointLight,
    ImageProfile, Light, PointLight, ProjectorLight, SpotLight, SunSkyLight,
};
use render::shapes::ShapeInfo;
use render::shapes::{MeshSampling, ShapeGeom};
use render::textures::ColorRef;
use render::world::ShapeLights;
use scene::SceneDesc;

use crate::BuildError;
use crate::materials::Declared;

/// What [`lights`] makes.
pub(crate) struct BuiltLights {
    pub lights: Vec<Light>,
    /// The light(s) of each shape.
    pub shape_lights: Vec<ShapeLights>,
    /// The medium each light emits into.
    pub media: Vec<Option<u32>>,
}

/// The images lights read from files (environment maps, goniometric and projection lights),
/// decoded as sRGB-encoded files are, kept by path so that a build after a light edit (a
/// scale, a transform) does not read them again (see [`crate::BuildCache`]).
#[derive(Default)]
pub(crate) struct LightImages(std::collections::HashMap<std::path::PathBuf, render::film::Image>);

impl LightImages {
    fn read(
        &mut self,
        path: &std::path::Path,
    ) -> Result<render::film::Image, image_io::ImageError> {
        if let Some(image) = self.0.get(path) {
            return Ok(image.clone());
        }
        let image = image_io::read_image_with(path, Decode::Srgb)?;
        self.0.insert(path.to_path_buf(), image.clone());
        Ok(image)
    }
}

/// Every emitter of the scene: area lights (one per emitting shape, or with `split` one per
/// triangle of an emitting mesh) first, then the others; with the light of each shape and
/// the medium each light emits into (an emitting shape's exterior, a point-like emitter's
/// declared medium).
pub(crate) fn lights(
    desc: &SceneDesc,
    shapes: &[ShapeInfo],
    split: bool,
    declared: &Declared,
    projectors: &[Option<(ColorRef, f32)>],
    images: &mut LightImages,
) -> Result<BuiltLights, BuildError> {
    // In spectral mode, the spectrum a light's constant was declared as.
    let spectrum = |v: &scene::ColorValue| declared.value(v).map(Arc::new);
    let mut lights = Vec::new();
    let mut shape_light = vec![ShapeLights::None; shapes.len()];
    for (i, (s, d)) in shapes.iter().zip(&desc.shapes).enumerate() {
        let Some(radiance) = &s.emission else {
            continue;
        };
        let two_sided = d.emission.as_ref().is_some_and(|e| e.two_sided);
        // Mitsuba's `directionalarea` emits along its normal only: the whole shape, sampled
        // by area (meshes by triangle area), never split per triangle.
        let directional = d.emission.as_ref().is_some_and(|e| e.directional);
        let triangles = match &s.geom {
            ShapeGeom::Mesh {
                positions, indices, ..
            } => {
                let areas = triangle_areas(positions, indices);
                if split && !directional {
                    // Degenerate triangles stay (so that triangle t is light first + t):
                    // they have no power and are never chosen.
                    shape_light[i] = ShapeLights::PerTriangle {
                        first: lights.len() as u32,
                        count: areas.len() as u32,
                    };
                    for (t, area) in areas.into_iter().enumerate() {
                        lights.push(Light::Area(AreaLight {
                            shape: i as u32,
                            radiance: *radiance,
                            two_sided,
                            triangles: None,
                            prim: Some(t as u32),
                            area: if area.is_finite() { area } else { 0.0 },
                        }));
                    }
                    continue;
                }
                Some(MeshSampling::new(positions, indices, &areas))
            }
            ShapeGeom::Plane { .. } => {
                return Err(BuildError {
                    loc: d.loc.clone(),
                    message: "an infinite plane cannot be an area light".into(),
                });
            }
            _ => None,
        };
        let area = s.geom.area();
        if !(area > 0.0 && area.is_finite()) {
            continue;
        }
        shape_light[i] = ShapeLights::Whole(lights.len() as u32);
        let light = AreaLight {
            shape: i as u32,
            radiance: *radiance,
            two_sided: two_sided && !directional,
            triangles,
            prim: None,
            area,
        };
        lights.push(if directional {
            Light::DirectionalArea(Box::new(DirectionalAreaLight { area: light }))
        } else {
            Light::Area(light)
        });
    }
    // Area lights emit into their shape's exterior.
    let mut media: Vec<Option<u32>> = lights
        .iter()
        .map(|l| match l {
            Light::Area(a) => shapes[a.shape as usize].exterior,
            Light::DirectionalArea(d) => shapes[d.area.shape as usize].exterior,
            _ => None,
        })
        .collect();
    for (k, e) in desc.emitters.iter().enumerate() {
        if !matches!(e.emitter, scene::Emitter::Ambient { .. }) {
            media.push(e.medium.map(|m| m.0));
        }
        lights.push(match &e.emitter {
            // Not a light: the Whitted integrator's ambient term (`Scene::ambient`).
            scene::Emitter::Ambient { .. } => continue,
            scene::Emitter::Point {
                position,
                intensity,
            } => Light::Point(PointLight {
                position: (*position).into(),
                intensity: intensity.rgb().into(),
                spectrum: spectrum(intensity),
            }),
            scene::Emitter::Spot {
                to_world,
                intensity,
                cutoff_angle,
                beam_width,
                falloff,
            } => Light::Spot(SpotLight {
                spectrum: spectrum(intensity),
                ..SpotLight::new(
                    to_world,
                    intensity.rgb().into(),
                    *cutoff_angle,
                    *beam_width,
                    *falloff,
                )
            }),
            scene::Emitter::Directional {
                direction,
                irradiance,
            } => Light::Directional(DirectionalLight {
                direction: direction.normalize_or_zero().into(),
                irradiance: irradiance.rgb().into(),
                spectrum: spectrum(irradiance),
            }),
            scene::Emitter::Constant { radiance } => Light::Constant(ConstantLight {
                radiance: radiance.rgb().into(),
                spectrum: spectrum(radiance),
            }),
            scene::Emitter::ImagePoint {
                to_world,
                path,
                intensity,
                profile,
                power,
            } => Light::ImagePoint(Arc::new(image_point(
                to_world, path, *intensity, *profile, *power, &e.loc, images,
            )?)),
            scene::Emitter::SunSky(d) => Light::SunSky(Arc::new(sunsky(d))),
            scene::Emitter::Projector {
                to_world,
                scale,
                fov,
                fov_axis,
                ..
            } => {
                let Some((irradiance, aspect)) = projectors.get(k).copied().flatten() else {
                    unreachable!("every projector's texture is resolved by `build`")
                };
                let fov_x = render::camera::fov_x_degrees(*fov, *fov_axis, aspect);
                Light::Projector(Box::new(ProjectorLight::new(
                    *to_world, irradiance, *scale, fov_x, aspect,
                )))
            }
            scene::Emitter::EnvMap {
                path,
                scale,
                to_world,
                mapping,
            } => {
                let image = images.read(path).map_err(|err| BuildError {
                    loc: e.loc.clone(),
                    message: format!("cannot read environment map: {err}"),
                })?;
                Light::EnvMap(Arc::new(EnvMap::new(image, *scale, to_world, *mapping)))
            }
        });
    }
    Ok(BuiltLights {
        lights,
        shape_lights: shape_light,
        media,
    })
}

/// Mitsuba 3's `sunsky`: the model's coefficients for this turbidity, albedo and sun, in the
/// emitter's frame (the rotation of `to_world`). The spectral datasets read the albedo at the
/// model's 11 wavelengths: a grey albedo as it is, a coloured one upsampled from its RGB.
fn sunsky(d: &scene::SunSkyDesc) -> SunSkyLight {
    use render::lights::sunsky_model::{self, SunSkyModel, SunSkyParams, WAVELENGTH_COUNT};
    use render::spectral::Spectrum;
    use render::spectral::rgb::{RgbAlbedoSpectrum, RgbToSpectrumTable};
    let a = d.albedo;
    let albedo_spectral = if a.x == a.y && a.y == a.z {
        [a.x; WAVELENGTH_COUNT]
    } else {
        let s = RgbAlbedoSpectrum::new(RgbToSpectrumTable::srgb(), a.into());
        std::array::from_fn(|i| s.eval(sunsky_model::wavelength(i)))
    };
    let rot = render::math::Mat3::from_mat4(d.to_world);
    let sun_dir = (rot.inverse() * render::math::Vec3::from(d.sun_direction)).normalize();
    let model = SunSkyModel::new(&SunSkyParams {
        turbidity: d.turbidity,
        albedo_rgb: a.to_array(),
        albedo_spectral,
        sun_dir,
        sun_scale: d.sun_scale,
        sky_scale: d.sky_scale,
        sun_half_aperture: (0.5 * d.sun_aperture).to_radians(),
        complex_sun: d.complex_sun,
    });
    SunSkyLight::new(model, rot)
}

/// An image-modulated point light: the frame's rotation (a uniform scale divided out), the
/// image in linear RGB, and pbrt-v4's `power` normalisation — the goniometric light's by the
/// mean of its grey image over the sphere, the projection light's by the luminance it emits.
fn image_point(
    to_world: &render::math::Mat4,
    path: &std::path::Path,
    intensity: scene::Rgb,
    profile: scene::ImageProfile,
    power: Option<f32>,
    loc: &scene::Loc,
    images: &mut LightImages,
) -> Result<ImagePointLight, BuildError> {
    let fail = |message: String| BuildError {
        loc: loc.clone(),
        message,
    };
    let lin = render::math::Mat3::from_mat4(*to_world);
    let s = lin.x_axis.length();
    let rot = lin * (1.0 / s);
    let orthogonal = (rot.transpose() * rot).abs_diff_eq(render::math::Mat3::IDENTITY, 1e-4);
    if !(s > 0.0 && s.is_finite() && orthogonal) {
        return Err(fail(
            "a goniometric or projection light's transform must be a rotation and uniform scale"
                .into(),
        ));
    }
    let image = images
        .read(path)
        .map_err(|err| fail(format!("cannot read the light's image: {err}")))?;
    if image.pixels.iter().any(|p| !p.is_finite()) {
        return Err(fail(format!(
            "{}: pixels that are not finite cannot be a light",
            path.display()
        )));
    }
    let profile = match profile {
        scene::ImageProfile::Goniometric => {
            if image.width != image.height {
                return Err(fail(format!(
                    "{}: a goniometric light takes a square (equal-area) image, not {}×{}",
                    path.display(),
                    image.width,
                    image.height
                )));
            }
            ImageProfile::Goniometric
        }
        scene::ImageProfile::Projection { fov } => {
            let aspect = image.width as f32 / image.height as f32;
            ImageProfile::Projection {
                tan_half: (fov.to_radians() / 2.0).tan(),
                half: if aspect > 1.0 {
                    render::math::Vec2::new(aspect, 1.0)
                } else {
                    render::math::Vec2::new(1.0, 1.0 / aspect)
                },
            }
        }
    };
    let position = to_world.w_axis.truncate().into();
    let mut light = ImagePointLight::new(position, rot, image, intensity.into(), profile);
    if let Some(phi) = power.filter(|&p| p > 0.0) {
        // pbrt-v4 normalises the image alone (the goniometric light's grey, the projection
        // light's luminance), the colour of `intensity` staying as it is.
        let unit = ImagePointLight::new(
            position,
            rot,
            light.image.clone(),
            render::math::Vec3::ONE,
            profile,
        )
        .power_rgb();
        let k = match profile {
            ImageProfile::Goniometric => unit.x,
            ImageProfile::Projection { .. } => render::math::luminance(unit),
        };
        if k > 0.0 {
            light.scale *= phi / k;
        }
    }
    Ok(light)
}

/// The area of each triangle of a world-space mesh.
fn triangle_areas(positions: &[render::math::Vec3], indices: &[[u32; 3]]) -> Vec<f32> {
    indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .collect()
}
