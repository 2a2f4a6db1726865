//! What a render is asked and what it reports, shared by every driver (`drive/`) and the
//! integrators: [`RenderOptions`], [`Progress`],
//! [`RenderObserver`], [`RenderOutcome`], and how a camera sample starts
//! ([`camera_sample`]). Here rather than in `render.rs` so that integrators that drive a
//! render themselves do not import the driver that imports them.

use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::camera::CameraRay;
use crate::film::Film;
use crate::math::{UVec2, Vec2};
use crate::sampling::Sampler;
use crate::world::Scene;

/// Sample indices per chunk by default ([`RenderOptions::chunk_spp`]): a tile loop's work
/// item sums this many samples of each of its tile's pixels in f64 before they are rounded
/// into the film (rounding more often costs more; longer chunks make coarser passes and
/// shards).
pub const CHUNK_SPP: u32 = 4;

#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Samples per pixel to reach (upper bound when a time budget is set).
    pub spp: u32,
    /// Stop after the pass during which this much time has elapsed (passes are planned to fit).
    pub time_budget: Option<Duration>,
    pub tile_size: u32,
    /// Set it (e.g. from a Ctrl-C handler) to stop after the current pass.
    pub cancel: Arc<AtomicBool>,
    /// Target duration of one pass.
    pub pass_duration: Duration,
    /// The work items to render (`None`: all): a shard's range (see `drive/work.rs` and
    /// `Integrator::work_items`).
    pub items: Option<Range<u64>>,
    /// Sample indices per chunk of the tile loop's work items (`drive/tiles.rs`; default
    /// [`CHUNK_SPP`]): also the smallest pass. Part of what makes the image, as the tile
    /// size is.
    pub chunk_spp: u32,
    /// A checkpoint to continue from (its items' range must start where this render's
    /// does); ignored by integrators whose work has no items.
    pub resume: Option<Arc<Resume>>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            spp: 16,
            time_budget: None,
            tile_size: 16,
            cancel: Arc::new(AtomicBool::new(false)),
            pass_duration: Duration::from_secs(1),
            items: None,
            chunk_spp: CHUNK_SPP,
            resume: None,
        }
    }
}

/// A render to continue: the film after the items `items` (a checkpoint's).
#[derive(Clone)]
pub struct Resume {
    pub film: Film,
    /// The items already in `film`: `items.start` is where the render's range starts,
    /// `items.end` the next item to render.
    pub items: Range<u64>,
}

impl std::fmt::Debug for Resume {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Resume {{ items: {:?} }}", self.items)
    }
}

/// What the progress callback is told.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Pixel samples finished so far.
    pub samples_done: u64,
    /// Pixel samples planned in all (spp × pixels); with a time budget, an estimate.
    pub samples_total: u64,
    pub elapsed: Duration,
    /// Samples per pixel completed in whole passes.
    pub spp_done: u32,
}

pub struct RenderOutcome {
    pub film: Film,
    pub spp: u32,
    pub passes: u32,
    pub elapsed: Duration,
    pub cancelled: bool,
    /// Images besides the film, by name (BDPT's per-strategy images), written beside it.
    pub extra: Vec<(String, Film)>,
    /// The work items in the film (for integrators with items; else empty).
    pub items: Range<u64>,
}

/// A render as the integrators and the loops receive it: the scene, what is asked, and who
/// is told.
#[derive(Clone, Copy)]
pub struct Job<'a> {
    pub scene: &'a Scene,
    pub opts: &'a RenderOptions,
    pub observer: &'a dyn RenderObserver,
}

impl Job<'_> {
    /// A blank film of the scene's, and the sampler every pixel sample of the render starts
    /// from (the scene's kind and seed, the render's samples per pixel).
    pub fn film_and_sampler(&self) -> (Film, Sampler) {
        let s = self.scene;
        let template = Sampler::new(s.sampler.kind, self.opts.spp.max(1), s.sampler.seed);
        (s.film.film(), template)
    }
}

impl RenderOutcome {
    /// The outcome of `passes` whole passes (iterations) into `film`, begun at `start`.
    pub fn of_passes(film: Film, passes: u32, start: std::time::Instant, cancelled: bool) -> Self {
        RenderOutcome {
            film,
            spp: passes,
            passes,
            elapsed: start.elapsed(),
            cancelled,
            extra: Vec::new(),
            items: 0..0,
        }
    }
}

/// Events reported while rendering.
pub trait RenderObserver: Sync {
    /// Called often (after every tile) from worker threads.
    fn progress(&self, _p: &Progress) {}
    /// Called after every pass with the film so far (e.g. progressive output).
    fn pass_done(&self, _film: &Film, _spp: u32) {}
    /// Called after every pass of a render split into work items with the film and the
    /// items in it (what a checkpoint saves).
    fn checkpoint(&self, _film: &Film, _items: Range<u64>) {}
    /// A line for the user (path guiding's memory report), shown unless quiet.
    fn note(&self, _line: &str) {}
}

/// An observer that ignores everything.
pub struct Silent;
impl RenderObserver for Silent {}

/// Sets `sampler` up for sample `index` of `pixel` and draws its film position (uniform in
/// the pixel) and camera ray.
#[inline]
pub fn camera_sample(
    scene: &Scene,
    sampler: &mut Sampler,
    pixel: UVec2,
    index: u32,
) -> (Vec2, CameraRay) {
    sampler.start_pixel_sample(pixel, index);
    let p_film = pixel.as_vec2() + sampler.next_2d();
    let u_lens = sampler.next_2d();
    let mut cray = scene.camera.generate_ray(p_film, u_lens);
    if scene.has_motion {
        // Motion blur: one time per camera sample, uniform over the shutter. Only scenes
        // with moving shapes draw it, so static ones keep their random number streams.
        cray.ray.time = shutter_time(sampler);
    }
    (p_film, cray)
}

/// The time of a camera sample (motion blur), out of line: static scenes never call it.
#[inline(never)]
fn shutter_time(sampler: &mut Sampler) -> f32 {
    sampler.next_1d()
}
