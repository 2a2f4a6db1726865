//! The vocabulary both the scene description and the renderer speak: kinds and modes that
//! are plain values (a wrap mode, a sampler kind, a tone-mapping operator, a camera
//! projection, a transmittance estimator), and `read_file`. Loaders write these into the scene model; the renderer's
//! runtime objects keep them as they are. Anything that refers to other scene elements (ids,
//! textures, files to load) is scene model, in `penumbra-scene`, and only `penumbra-build`
//! turns it into runtime objects.

pub mod cie_data;
pub mod dispersion;
pub mod spectrum;
pub mod subsurface;

use std::path::Path;

/// Read a whole file, refusing anything but a regular file first: a device such as
/// `/dev/zero` or a FIFO named as a mesh or texture would otherwise be read until memory runs
/// out, or block for ever.
pub fn read_file(path: &Path) -> std::io::Result<Vec<u8>> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        ));
    }
    std::fs::read(path)
}

/// The profile of a spot light between its full-intensity cone and its cutoff.
/// What a path carries: three RGB channels, or four sampled wavelengths (pbrt-v4's
/// `SampledWavelengths`) whose estimate becomes RGB at the film. Chosen at run time
/// (`render --mode`, Mitsuba variant names such as `scalar_spectral`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RenderMode {
    #[default]
    Rgb,
    Spectral,
}

impl RenderMode {
    /// The mode of a Mitsuba 3 variant name (`scalar_rgb`, `llvm_ad_spectral`, ...): its
    /// colour part; `None` for a name that is not a colour variant we render (monochrome,
    /// polarized).
    pub fn from_mitsuba_variant(v: &str) -> Option<RenderMode> {
        let colour = v.rsplit('_').next()?;
        match colour {
            "rgb" => Some(RenderMode::Rgb),
            "spectral" => Some(RenderMode::Spectral),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpotFalloff {
    /// Mitsuba 3: linear in the angle from the beam width to the cutoff.
    #[default]
    Mitsuba,
    /// The CENG795/CENG477 course: ((cos α − cos cutoff) / (cos beam − cos cutoff))⁴.
    Cosine4,
    /// pbrt-v4: smoothstep of cos α from cos cutoff (0) to cos beam (1), t²(3 − 2t).
    SmoothStep,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MicrofacetDistribution {
    Ggx,
    Beckmann,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhongModel {
    OriginalPhong,
    ModifiedPhong,
    OriginalBlinnPhong,
    ModifiedBlinnPhong,
    TorranceSparrow,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureFilter {
    Nearest,
    Bilinear,
    /// pbrt-v4's trilinear filtering over a MIP map, the level chosen by the lookup's
    /// footprint.
    Trilinear,
    /// pbrt-v4's elliptically weighted average over a MIP map (Heckbert 1989, Gaussian
    /// weights, anisotropy clamped to 8).
    Ewa,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrapMode {
    Repeat,
    Mirror,
    Clamp,
}

/// How the course's Perlin noise n ∈ [−1, 1] becomes a value in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseConversion {
    /// (n + 1) / 2 (`linear`, the lecture's "patch").
    Linear,
    /// |n| (`absval`, the lecture's "vein").
    AbsVal,
}

/// The noise textures of pbrt-v4 and their parameters (`omega` is its `roughness`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NoiseKind {
    Fbm {
        octaves: u32,
        omega: f32,
    },
    Wrinkled {
        octaves: u32,
        omega: f32,
    },
    Windy,
    Marble {
        octaves: u32,
        omega: f32,
        scale: f32,
        variation: f32,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvMapping {
    /// Equirectangular (Mitsuba `envmap`).
    LatLong,
    /// Light probe (angular map, CENG795 `probe`).
    Probe,
    /// pbrt-v4's equal-area octahedral square map (Clarberg 2008): every pixel subtends the
    /// same solid angle.
    EqualArea,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    X,
    Y,
    Diagonal,
    Smaller,
    Larger,
}

#[derive(Clone, Debug)]
pub enum Projection {
    Perspective {
        /// Degrees, measured along `fov_axis`.
        fov: f32,
        fov_axis: FovAxis,
    },
    ThinLens {
        fov: f32,
        fov_axis: FovAxis,
        aperture_radius: f32,
        focus_distance: f32,
    },
    /// Mitsuba's orthographic camera: the image covers [-1,1]² of the camera plane (scaled
    /// by `to_world`).
    Orthographic,
    /// Mitsuba 3's `radiancemeter`: every sample is the one ray from the frame's origin along
    /// its +z (no clipping); its film is 1×1.
    RadianceMeter,
    /// Mitsuba 3's `irradiancemeter`, nested in the shape of index `shape` of the scene's
    /// shapes: rays leave the shape's surface, uniform by area, cosine-distributed about its
    /// normal, each sample weighted π; its 1×1 film measures the irradiance averaged over the
    /// shape. `to_world` is unused.
    IrradianceMeter { shape: usize },
    /// A pinhole whose image is the window [left, right] × [bottom, top] of the plane one
    /// unit in front of the eye, in the image's own right/up coordinates (CENG795
    /// `NearPlane` / `NearDistance`): off-axis when the window is not centred, non-square
    /// pixels when its aspect differs from the film's.
    Window {
        left: f32,
        right: f32,
        bottom: f32,
        top: f32,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CropWindow {
    pub offset_x: u32,
    pub offset_y: u32,
    pub width: u32,
    pub height: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterDesc {
    /// Box of the given radius (pixels); Mitsuba default 0.5.
    Box { radius: f32 },
    /// Tent (triangle) of the given radius; default 1.
    Tent { radius: f32 },
    /// Gaussian with standard deviation `stddev`, truncated at `radius` (Mitsuba: 0.5, 4σ = 2).
    Gaussian { stddev: f32, radius: f32 },
    /// Mitchell–Netravali with parameters B and C (radius 2).
    Mitchell { b: f32, c: f32, radius: f32 },
    /// Windowed sinc, `sinc(x) · sinc(x / tau)` on `|x| ≤ radius` (Mitsuba's `lanczos`:
    /// radius = tau = `lobes`, default 3; pbrt-v4's `sinc`: radius 4, tau 3).
    Lanczos { radius: f32, tau: f32 },
}

/// A tone-mapping operator for display outputs.
#[derive(Clone, Debug, PartialEq)]
pub enum Tonemap {
    /// Reinhard et al. 2002 photographic global operator: scale by `key` / log-average
    /// luminance, burn out the brightest `burn_percent` % of pixels, then colour
    /// `saturation` and display `gamma` (CENG795 `TMO Photographic`).
    Photographic {
        key: f32,
        burn_percent: f32,
        saturation: f32,
        gamma: f32,
    },
    /// The radiance is in display units 0–255 (CENG795 scenes without a `Tonemap`): an 8-bit
    /// pixel is clamp(round(L), 0, 255) per channel, with no gamma.
    DisplayUnits,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerKind {
    Independent,
    Stratified,
    Halton,
    /// Owen-scrambled Sobol.
    Sobol,
    /// Kensler's correlated multi-jittered sampling (2013; Mitsuba's `multijitter`): the
    /// samples of a pixel fill an m × n grid of cells (m·n = spp) and, within the cells, the
    /// n × m sub-grid of every row and column once, the sub-cells of one column shuffled by
    /// one permutation for all columns (and the rows alike); without `jitter` each sample sits
    /// at its sub-cell's centre.
    MultiJitter {
        jitter: bool,
    },
}

#[derive(Clone, Debug)]
pub struct SamplerDesc {
    pub kind: SamplerKind,
    pub spp: u32,
    pub seed: u64,
}

impl Default for SamplerDesc {
    fn default() -> Self {
        SamplerDesc {
            kind: SamplerKind::Independent,
            spp: 16,
            seed: 0,
        }
    }
}

/// The density estimation kernel of photon mapping radiance estimates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PhotonKernel {
    /// Uniform over the disk: 1/(πr²).
    #[default]
    Box,
    /// Jensen's cone filter (k = 1): 3(1 − d/r)/(πr²).
    Cone,
    /// Epanechnikov: 2(1 − d²/r²)/(πr²).
    Epanechnikov,
}

impl PhotonKernel {
    pub fn from_name(name: &str) -> Option<PhotonKernel> {
        Some(match name {
            "box" | "uniform" => PhotonKernel::Box,
            "cone" => PhotonKernel::Cone,
            "epanechnikov" => PhotonKernel::Epanechnikov,
            _ => return None,
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MisHeuristic {
    Balance,
    Power,
}

/// When paths are terminated at random (and survivors reweighted, so the mean is unchanged).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RussianRoulette {
    Off,
    /// Mitsuba: from `from_depth` segments on, continue with probability
    /// min(max component of throughput × η², 0.95).
    Throughput {
        from_depth: u32,
    },
    /// The courses' rule: after `after` segments, terminate with fixed probability `q`.
    Fixed {
        after: u32,
        q: f32,
    },
}

/// How a path picks its next direction at a non-delta vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectionSampling {
    /// Importance sampling of the BSDF (the default).
    Bsdf,
    /// Uniform over the hemisphere of the shading normal on the side of `wo` (CS184 `-H`,
    /// CENG795 without `ImportanceSampling`); transmission is not sampled.
    UniformHemisphere,
}

/// How one emitter is chosen for next-event estimation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSelection {
    /// Every emitter equally likely (Mitsuba).
    #[default]
    Uniform,
    /// Proportional to emitted power (alias table).
    Power,
    /// A light BVH over position and orientation bounds (Conty & Kulla 2018, as pbrt-v4).
    Bvh,
}

/// How the transmittance of a shadow-ray segment through a grid is estimated (`volpath`'s
/// `transmittance` parameter). All are unbiased; they differ in variance and cost (figures
/// in the tests' output and the issue notes). σ̄ is the majorant, σc a control extinction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TransmittanceEstimator {
    /// Track-length: tentative collisions at rate σ̄, each real with probability σ/σ̄; 0 at
    /// the first real one, 1 past the end (Woodcock tracking used as an estimator).
    DeltaTracking,
    /// Π (1 − σ(tᵢ)/σ̄) over tentative collisions at rate σ̄ (Novák et al. 2014).
    #[default]
    RatioTracking,
    /// Ratio tracking of the residual σ − σc against σ̄ − σc, times e^{−σc·d}, with σc the
    /// smallest density on the segment (Novák et al. 2014).
    ResidualRatioTracking,
    /// At every tentative collision (and at the start), the ratio-tracking weight so far
    /// times the probability e^{−σ̄·(d − tᵢ)} that the next flight leaves the segment.
    NextFlightRatioTracking,
    /// e^{−σ̄·d} Σₖ (d·(σ̄ − σ))ᵏ/k! with each power estimated from k uniform points, all
    /// terms up to the 90 % point of the expected order's cumulative mass, then Russian
    /// roulette (Georgiev et al. 2019's power-series CMF estimator).
    PowerSeriesCmf,
    /// Unbiased ray marching (Kettunen et al. 2021): a jittered ray march gives the control
    /// optical depth τc; e^{−τc} Σₖ Πᵢ (τc − τ̂ᵢ)/k! with independent jittered marches τ̂ᵢ
    /// and the same CMF-based truncation.
    UnbiasedRayMarching,
}

impl TransmittanceEstimator {
    pub const ALL: [TransmittanceEstimator; 6] = [
        TransmittanceEstimator::DeltaTracking,
        TransmittanceEstimator::RatioTracking,
        TransmittanceEstimator::ResidualRatioTracking,
        TransmittanceEstimator::NextFlightRatioTracking,
        TransmittanceEstimator::PowerSeriesCmf,
        TransmittanceEstimator::UnbiasedRayMarching,
    ];

    /// The scene-file name of the estimator.
    pub fn name(&self) -> &'static str {
        match self {
            TransmittanceEstimator::DeltaTracking => "delta",
            TransmittanceEstimator::RatioTracking => "ratio",
            TransmittanceEstimator::ResidualRatioTracking => "residual",
            TransmittanceEstimator::NextFlightRatioTracking => "next_flight",
            TransmittanceEstimator::PowerSeriesCmf => "power_series",
            TransmittanceEstimator::UnbiasedRayMarching => "ray_marching",
        }
    }

    pub fn from_name(name: &str) -> Option<TransmittanceEstimator> {
        TransmittanceEstimator::ALL
            .into_iter()
            .find(|e| e.name() == name)
    }
}

pub mod testing;
