//! The step from scene description to renderable scene: `SceneDesc` → [`Built`] (the runtime
//! [`Scene`]: world-space geometry and its BVH, decoded textures, resolved materials, lights,
//! the chosen sensor's camera, film and sampler settings; and the runtime [`Integrator`]).
//!
//! This crate is the boundary: the only code that reads both the scene model
//! (`penumbra-scene`) and the renderer (`penumbra-render`). The renderer does not depend on
//! the scene model at all, so the compiler keeps it that way. A factory per kind of object:
//! [`shapes`], [`materials`], [`textures`], [`lights`], [`camera`], [`integrator`].

pub mod camera;
pub mod integrator;
mod lights;
mod materials;
mod media;
pub mod nori_tests;
pub mod params;
mod shapes;
pub mod spec;
mod textures;

pub use materials::material_kind;
pub use shapes::{cube_mesh, rectangle_mesh};

use std::collections::HashMap;
use std::sync::Arc;

use render::accel::Accel;
use render::film::{FilmSettings, Filter};
use render::integrators::Integrator;
use render::integrators::path::{Combine, PathConfig};
use render::integrators::volpath::VolPathConfig;
use render::lights::select::LightSampler;
use render::math::Vec3;
use render::render::{RenderOptions, RenderOutcome, Silent, render};
use render::shapes::ShapeGeom;
use render::textures::Textures;
use render::world::{SamplerSettings, Scene};
use scene::{
    IntegratorDesc, LightSelection, Loc, Material, MaterialId, RussianRoulette, SceneDesc, SppmDesc,
};

/// A problem found while building (unreadable texture, unsupported feature).
#[derive(Clone, Debug, thiserror::Error)]
#[error("{loc}: {message}")]
pub struct BuildError {
    pub loc: Loc,
    pub message: String,
}

/// Command-line overrides applied on top of the scene's own settings.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Which sensor to render (index into `SceneDesc::sensors`).
    pub sensor: usize,
    pub spp: Option<u32>,
    pub resolution: Option<(u32, u32)>,
    pub seed: Option<u64>,
    pub integrator: Option<IntegratorDesc>,
    /// Overrides `SceneDesc::light_selection`.
    pub light_selection: Option<LightSelection>,
    /// Copy shared meshes into world space instead of instancing them (see [`build`]): the
    /// reference the instanced build is tested against.
    pub flatten_instances: bool,
    /// RGB or spectral rendering: the scene is built for one of them.
    pub mode: base::RenderMode,
}

/// What [`build`] makes: the scene and the integrator to render it with.
pub struct Built {
    pub scene: Scene,
    pub integrator: Integrator,
    /// Samples per pixel (iterations, passes or mutations per pixel for the integrators that
    /// count them so): the scene's, or `BuildOptions::spp`, or Mitsuba 0.6's `maxPasses`.
    /// The one value a render's `RenderOptions::spp` is made from.
    pub spp: u32,
}

/// Turn a loaded scene into a renderable one.
pub fn build(desc: &SceneDesc, opts: &BuildOptions) -> Result<Built, BuildError> {
    build_cached(desc, opts, &mut BuildCache::default())
}

/// What a build read from files or derived from the geometry alone, kept for the next build
/// of the same scene after an edit of its description (Python's `scene.update`): the
/// world-space geometry and its acceleration structure, the scene's decoded textures (and
/// the alpha channels read for cut-outs), the media (and the grids they read), the images
/// lights read, rough plastic's tables (by α and η). Materials, lights, the camera, the film
/// and the integrator are cheap and are made anew by every build, from the description as it
/// is then.
///
/// The cache is only valid for the description it was filled from, up to the edits that
/// [`BuildCache::invalidate`] was told about: after an edit of anything else (a texture, a
/// medium, the shape list) use a fresh cache. A build with another `mode` or
/// `flatten_instances` than the cached one empties it first.
#[derive(Default)]
pub struct BuildCache {
    key: Option<(base::RenderMode, bool)>,
    geometry: Option<Arc<CachedGeometry>>,
    textures: Option<Vec<render::textures::Texture>>,
    alphas: HashMap<u32, Option<render::textures::Texture>>,
    media: Option<Vec<render::media::Medium>>,
    light_images: lights::LightImages,
    plastic_tables: materials::PlasticTables,
}

/// The geometry part of a [`BuildCache`].
struct CachedGeometry {
    geoms: Vec<ShapeGeom>,
    accel: Arc<Accel>,
    warning: Option<String>,
    has_motion: bool,
    triangle_count: usize,
}

/// What an edit of a scene description changed, for [`BuildCache::invalidate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Changed {
    /// A material's parameter (a colour, a roughness): materials are rebuilt by every build.
    Material,
    /// A light's parameter (intensity, radiance, scale, its placement): lights are rebuilt
    /// by every build; an area light's radiance leaves its shape's geometry alone.
    Light,
    /// A sensor's parameter (its placement): the camera is made by every build.
    Camera,
    /// A shape's geometry (its transform): the world-space geometry and the acceleration
    /// structure are rebuilt.
    Geometry,
}

impl BuildCache {
    /// Forget what an edit of kind `what` made stale (only [`Changed::Geometry`] does).
    pub fn invalidate(&mut self, what: Changed) {
        match what {
            Changed::Geometry => self.geometry = None,
            Changed::Material | Changed::Light | Changed::Camera => {}
        }
    }

    /// Whether the next build will reuse an acceleration structure (for tests).
    pub fn has_geometry(&self) -> bool {
        self.geometry.is_some()
    }

    /// Whether the next build will reuse decoded textures (for tests).
    pub fn has_textures(&self) -> bool {
        self.textures.is_some()
    }
}

/// [`build`], reusing what `cache` holds from an earlier build of the same description (as
/// [`BuildCache`] says) and keeping there what this build reads or derives. The result is
/// the one [`build`] gives for `desc`, bit for bit.
pub fn build_cached(
    desc: &SceneDesc,
    opts: &BuildOptions,
    cache: &mut BuildCache,
) -> Result<Built, BuildError> {
    let key = (opts.mode, opts.flatten_instances);
    if cache.key != Some(key) {
        *cache = BuildCache {
            key: Some(key),
            ..BuildCache::default()
        };
    }
    let sensor = desc.sensors.get(opts.sensor).ok_or_else(|| BuildError {
        loc: Loc::file(&desc.source),
        message: format!(
            "the scene has {} sensor(s); sensor {} does not exist",
            desc.sensors.len(),
            opts.sensor
        ),
    })?;

    let spectral = opts.mode == base::RenderMode::Spectral;
    let mut declared = materials::Declared::new(spectral, desc.textures.len());
    let (materials, default_material) =
        materials::materials(&desc.materials, &mut declared, &mut cache.plastic_tables)?;
    cache.plastic_tables.keep_used();
    let mut media = match &cache.media {
        Some(m) => m.clone(),
        None => {
            let m = media::media(desc)?;
            cache.media = Some(m.clone());
            m
        }
    };
    let beer = media::interior_media(&desc.materials, &mut media);
    let geometry = match &cache.geometry {
        Some(g) => g.clone(),
        None => {
            let shapes::Geometry {
                geoms,
                protos,
                warning,
            } = shapes::geometry(desc, opts)?;
            let has_motion = geoms
                .iter()
                .any(|g| matches!(g, ShapeGeom::Instance(i) if i.motion != Vec3::ZERO));
            let triangle_count = geoms.iter().map(ShapeGeom::triangle_count).sum();
            let accel = Accel::build_instanced(
                geoms.iter().map(ShapeGeom::accel_shape).collect(),
                protos.iter().map(ShapeGeom::accel_shape).collect(),
            );
            let g = Arc::new(CachedGeometry {
                geoms,
                accel: Arc::new(accel),
                warning,
                has_motion,
                triangle_count,
            });
            cache.geometry = Some(g.clone());
            g
        }
    };
    let mut shapes = shapes::shape_infos(
        desc,
        geometry.geoms.clone(),
        &materials,
        default_material,
        &beer,
        &mut declared,
    );
    let mut warnings: Vec<String> = geometry.warning.iter().cloned().collect();
    let has_motion = geometry.has_motion;
    let triangle_count = geometry.triangle_count;
    let accel = geometry.accel.clone();
    let bounds = accel.bounds();

    let mut textures = match &cache.textures {
        Some(t) => t.clone(),
        None => {
            let t = desc
                .textures
                .iter()
                .map(textures::load_texture)
                .collect::<Result<Vec<_>, _>>()?;
            cache.textures = Some(t.clone());
            t
        }
    };
    // Projectors' textures and their aspect ratios (Mitsuba's resolution: a bitmap's, 1×1
    // for the others).
    let projectors: Vec<Option<(render::textures::ColorRef, f32)>> = desc
        .emitters
        .iter()
        .map(|e| match &e.emitter {
            scene::Emitter::Projector { irradiance, .. } => {
                let aspect = match irradiance {
                    scene::ColorParam::Texture(t) => match &textures[t.0 as usize] {
                        render::textures::Texture::Bitmap { image, .. } => {
                            image.width as f32 / image.height as f32
                        }
                        _ => 1.0,
                    },
                    _ => 1.0,
                };
                Some((declared.color_ref(irradiance), aspect))
            }
            _ => None,
        })
        .collect();
    // Declared spectra's textures sit right after the scene's (`Declared` counts on it).
    textures.append(&mut declared.textures);
    textures::opacity_from_alpha(desc, &mut shapes, &mut textures, &mut cache.alphas)?;

    let selection = opts.light_selection.unwrap_or(desc.light_selection);
    let split = selection != LightSelection::Uniform;
    let lights::BuiltLights {
        lights,
        shape_lights,
        media: light_media,
    } = lights::lights(
        desc,
        &shapes,
        split,
        &declared,
        &projectors,
        &mut cache.light_images,
    )?;
    let infinite_lights = (0..lights.len() as u32)
        .filter(|&i| lights[i as usize].is_infinite())
        .collect();

    let has_cutouts = shapes.iter().any(|s| s.opacity.is_some());
    let is_mask = |id: &MaterialId| {
        matches!(
            desc.materials.get(id.0 as usize).map(|m| &m.material),
            Some(Material::Mask { .. })
        )
    };
    if desc
        .shapes
        .iter()
        .any(|s| s.emission.is_some() && s.material.is_some_and(|m| is_mask(&m)))
    {
        warnings.push(format!(
            "{}: warning: an emitting shape's alpha cut-out is ignored (it emits, and is hit, everywhere)",
            desc.source.display()
        ));
    }
    for m in &desc.materials {
        let below = match &m.material {
            Material::TwoSided { front, back } => {
                is_mask(front) || back.as_ref().is_some_and(is_mask)
            }
            Material::NormalMap { nested, .. } | Material::Mask { nested, .. } => is_mask(nested),
            _ => false,
        };
        if below {
            warnings.push(format!(
                "{}: warning: a mask (alpha cut-out) below another material has no effect; put it outermost",
                m.loc
            ));
        }
    }

    let mut film = FilmSettings {
        width: sensor.film.width,
        height: sensor.film.height,
        crop: sensor.film.crop,
        filter: Filter::new(&sensor.film.filter),
        tonemap: sensor.film.tonemap.clone(),
    };
    if let Some((w, h)) = opts.resolution {
        film.width = w;
        film.height = h;
        film.crop = None;
    }
    let mut spp = opts.spp.unwrap_or(sensor.sampler.spp);
    let sampler = SamplerSettings {
        kind: sensor.sampler.kind,
        seed: opts.seed.unwrap_or(sensor.sampler.seed),
    };
    let camera = camera::camera(desc, &sensor.camera, &shapes, film.width, film.height).map_err(
        |message| BuildError {
            loc: sensor.loc.clone(),
            message,
        },
    )?;
    let integrator_desc = opts
        .integrator
        .clone()
        .or_else(|| sensor.integrator.clone())
        .unwrap_or_else(|| desc.integrator.clone());
    // Mitsuba 0.6's `maxPasses`: the iterations when `--spp` does not say.
    if let (
        None,
        IntegratorDesc::Sppm(SppmDesc {
            passes: Some(n), ..
        }),
    ) = (opts.spp, &integrator_desc)
    {
        spp = *n;
    }
    let ambient: Vec3 = desc
        .emitters
        .iter()
        .filter_map(|e| match e.emitter {
            scene::Emitter::Ambient { radiance } => Some(radiance),
            _ => None,
        })
        .map(Vec3::from)
        .sum();
    let scene_radius = {
        let r = 0.5 * (bounds.1 - bounds.0).length();
        if r.is_finite() && r > 0.0 { r } else { 1.0 }
    };
    let mut integrator =
        integrator::integrator(&integrator_desc, scene_radius).map_err(|e| BuildError {
            loc: Loc::file(&desc.source),
            message: e.to_string(),
        })?;
    // An irradiance meter's samples carry a weight (π), which the tile loop applies; the
    // integrators that render their passes themselves start no camera rays from it.
    if matches!(
        sensor.camera.projection,
        scene::Projection::IrradianceMeter { .. }
    ) && !matches!(
        integrator,
        Integrator::Aov(_)
            | Integrator::Path(_)
            | Integrator::VolPath(_)
            | Integrator::Direct(_)
            | Integrator::Photon(_)
    ) {
        return Err(BuildError {
            loc: sensor.loc.clone(),
            message: format!(
                "an irradiancemeter is measured by the per-sample integrators (path, volpath, \
                 direct, aov, photon), not by {}",
                integrator.name()
            ),
        });
    }
    // Microflake media (`sggx`) scale their extinction by direction, which volpath's
    // free flights and transmittances apply; the other integrators' media densities do not.
    if media.iter().any(|m| m.phase.is_microflake())
        && !matches!(integrator, Integrator::VolPath(_) | Integrator::Path(_))
    {
        return Err(BuildError {
            loc: Loc::file(&desc.source),
            message: format!(
                "phase 'sggx' is rendered by volpath (path ignores media), not by {}",
                integrator.name()
            ),
        });
    }
    // Mitsuba's `path` ignores media, and so does ours for a scene that declares any. When
    // every medium comes from Beer absorption (purely absorbing, homogeneous), the path
    // tracer applies them, as the courses' tracers apply absorption inside their glass.
    // Subsurface materials put scattering media inside their shapes, which only the
    // integrators that walk media render: Mitsuba's `path` becomes `volpath` with its depth,
    // roulette and hidden emitters (the same estimator wherever there is no medium); the
    // course variants of the path tracer are refused.
    let scattering_interiors = media
        .iter()
        .skip(desc.media.len())
        .any(|m| !m.is_purely_absorbing());
    if let (true, Integrator::Path(cfg)) = (scattering_interiors, &integrator) {
        let rr_depth = match cfg.rr {
            RussianRoulette::Throughput { from_depth } => Some(from_depth),
            _ => None,
        };
        let plain = rr_depth.is_some_and(|from| {
            let max_depth = if cfg.max_depth == u32::MAX {
                -1
            } else {
                cfg.max_depth as i32
            };
            *cfg == PathConfig::mitsuba(max_depth, from, cfg.hide_emitters, Combine::Power)
        });
        let Some(rr_depth) = rr_depth.filter(|_| plain) else {
            return Err(BuildError {
                loc: Loc::file(&desc.source),
                message: "subsurface materials need an integrator that walks media (volpath, \
                          bdpt, photon mapping, or Mitsuba's plain path, rendered by volpath); \
                          this variant of the path tracer cannot render them"
                    .into(),
            });
        };
        warnings.push(format!(
            "{}: warning: the path integrator renders this scene's subsurface materials through \
             volpath (the same estimator where there is no medium){}",
            desc.source.display(),
            if desc.media.is_empty() {
                ""
            } else {
                "; the scene's declared media are rendered too"
            },
        ));
        integrator = Integrator::VolPath(VolPathConfig {
            max_depth: cfg.max_depth,
            rr_depth,
            hide_emitters: cfg.hide_emitters,
            equiangular: false,
            transmittance: Default::default(),
            sample_emission: false,
        });
    }
    // Guiding asked for where it does not apply (see `integrator::path_config`) is said, not
    // dropped quietly.
    if let IntegratorDesc::Path(d) = &integrator_desc
        && d.guiding
        && !matches!(&integrator, Integrator::Path(c) if c.guiding.is_some())
    {
        warnings.push(format!(
            "{}: warning: path guiding is off for this render: it guides the path tracer's \
             BSDF-sampled directions, without splitting or a depth filter, in scenes without \
             subsurface materials",
            desc.source.display()
        ));
    }
    if let Integrator::Path(cfg) = &mut integrator {
        cfg.media_absorption = desc.media.is_empty() && !media.is_empty();
        debug_assert!(!cfg.media_absorption || media.iter().all(|m| m.is_purely_absorbing()));
        if !desc.media.is_empty() {
            warnings.push(format!(
                "{}: warning: the path integrator ignores participating media, as Mitsuba's \
                 does (use volpath, bdpt or mlt to render them)",
                desc.source.display(),
            ));
        }
    }
    if ambient != Vec3::ZERO && !matches!(integrator_desc, IntegratorDesc::Whitted { .. }) {
        warnings.push(format!(
            "{}: warning: the ambient light is used only by the Whitted ray tracer; the {} integrator ignores it",
            desc.source.display(),
            integrator.name(),
        ));
    }

    let has_nulls = shapes
        .iter()
        .any(|s| s.material.is_some_and(|m| materials[m as usize].is_null()));
    let filtered = textures
        .iter()
        .any(render::textures::Texture::uses_footprint);
    let texture_footprint = filtered.then(|| (1.0 / (spp.max(1) as f32).sqrt()).max(0.125));
    let mut scene = Scene {
        texture_footprint,
        accel,
        shapes,
        has_unlit: materials.iter().any(|m| m.unlit.is_some()),
        materials,
        warnings,
        textures: Textures::new(textures),
        camera,
        film,
        sampler,
        background: desc.background.map(Vec3::from),
        background_texture: desc.background_texture.map(|t| t.0),
        ambient,
        lights,
        media,
        camera_medium: sensor.medium.map(|m| m.0),
        shape_lights,
        light_sampler: LightSampler::Uniform,
        infinite_lights,
        light_media,
        bounds,
        triangle_count,
        has_cutouts,
        has_nulls,
        has_motion,
        mode: opts.mode,
    };
    scene.light_sampler =
        LightSampler::new(selection, &scene.lights, &scene.infinite_lights, &scene);
    Ok(Built {
        scene,
        integrator,
        spp,
    })
}

/// Build `desc` once and render it once per seed of `seeds`, each render the image
/// [`render_desc`] gives with that seed in `opts` (the seed is read only at render time):
/// the batches of the statistical tests, without building the scene for every batch (for
/// scenes with environment maps, grids or rough plastic, building is most of a batch's time).
pub fn render_seeds(
    desc: &SceneDesc,
    opts: &BuildOptions,
    seeds: impl IntoIterator<Item = u64>,
) -> Result<Vec<RenderOutcome>, String> {
    let Built {
        mut scene,
        integrator,
        spp,
    } = build(desc, opts).map_err(|e| e.to_string())?;
    Ok(seeds
        .into_iter()
        .map(|seed| {
            scene.sampler.seed = seed;
            render(
                &scene,
                &integrator,
                &RenderOptions {
                    spp,
                    ..Default::default()
                },
                &Silent,
            )
        })
        .collect())
}

/// Build `desc` with `opts` and render it to the end with no observer: the convenience of
/// tests and tools that need one image (at [`Built::spp`]).
pub fn render_desc(desc: &SceneDesc, opts: &BuildOptions) -> Result<RenderOutcome, String> {
    let Built {
        scene,
        integrator,
        spp,
    } = build(desc, opts).map_err(|e| e.to_string())?;
    Ok(render(
        &scene,
        &integrator,
        &RenderOptions {
            spp,
            ..Default::default()
        },
        &Silent,
    ))
}
