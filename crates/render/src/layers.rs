//! Render layers (COMP30019's extended `-s`): the beauty image split by where each radiance
//! contribution came from, one film per layer, so that the layers sum to the beauty image.
//!
//! Every contribution the path tracer adds is classified from its [`Contribution`] record:
//! - **emission**: an emitter seen directly by the camera ray (depth 1);
//! - **reflection** / **refraction**: the path left its first surface by a delta (mirror-like)
//!   reflection / transmission — everything seen in mirrors and through glass;
//! - **direct**: light reaching the first surface straight from an emitter — next-event
//!   estimation at the first vertex, the Whitted ambient term there, or a BSDF-sampled
//!   direction from a non-delta first vertex hitting an emitter (depth 2);
//! - **indirect**: the rest (light that bounced off further surfaces after a non-delta first
//!   vertex).
//!
//! The estimators are the path tracer's own (`li_recorded`), so the beauty film is the image
//! `render` would produce with the same sampler stream, and each layer is linear in the same
//! samples: the sum of the layer films equals the beauty film up to float rounding.

use rayon::prelude::*;

use crate::film::{Film, FilmTile};
use crate::integrators::path::{Contribution, PathConfig, PathRecorder, li_recorded};
use crate::math::{UVec2, Vec3};
use crate::sampling::Sampler;
use crate::session::camera_sample;
use crate::world::Scene;

/// The layers besides beauty; they sum to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layer {
    Emission,
    Direct,
    Indirect,
    Reflection,
    Refraction,
}

impl Layer {
    pub const ALL: [Layer; 5] = [
        Layer::Emission,
        Layer::Direct,
        Layer::Indirect,
        Layer::Reflection,
        Layer::Refraction,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Layer::Emission => "emission",
            Layer::Direct => "direct",
            Layer::Indirect => "indirect",
            Layer::Reflection => "reflection",
            Layer::Refraction => "refraction",
        }
    }

    /// The layer a contribution belongs to.
    pub fn of(c: &Contribution) -> Layer {
        match c.first {
            None if c.depth <= 1 => Layer::Emission,
            // Emitter samples and the ambient term at the first vertex.
            None => Layer::Direct,
            Some(s) if s.delta && s.transmission => Layer::Refraction,
            Some(s) if s.delta => Layer::Reflection,
            Some(_) if c.depth <= 2 => Layer::Direct,
            Some(_) => Layer::Indirect,
        }
    }
}

/// The beauty film and one film per [`Layer`] (in `Layer::ALL` order).
pub struct LayerFilms {
    pub beauty: Film,
    pub layers: [Film; 5],
}

#[derive(Default)]
struct Split {
    acc: [Vec3; 5],
}

impl PathRecorder for Split {
    fn contribution(&mut self, l: Vec3, c: Contribution) {
        self.acc[Layer::of(&c) as usize] += l;
    }
}

/// Render `spp` samples per pixel of `scene` with the path tracer configured by `cfg`, split
/// into layers. Tiles run on the current rayon pool and merge in a fixed order.
pub fn render_layers(scene: &Scene, cfg: &PathConfig, spp: u32, tile_size: u32) -> LayerFilms {
    let spp = spp.max(1);
    let new_film = || {
        Film::new(
            scene.film.width,
            scene.film.height,
            scene.film.crop,
            scene.film.filter,
        )
    };
    let mut beauty = new_film();
    let mut layers: [Film; 5] = std::array::from_fn(|_| new_film());
    let template = Sampler::new(scene.sampler.kind, spp, scene.sampler.seed);
    let tiles = beauty.tile_bounds(tile_size.max(1));
    let finished: Vec<(FilmTile, [FilmTile; 5])> = tiles
        .par_iter()
        .map(|&(lo, hi)| {
            let mut bt = beauty.tile(lo, hi);
            let mut lt: [FilmTile; 5] = std::array::from_fn(|i| layers[i].tile(lo, hi));
            let mut sampler = template.clone();
            for y in lo.y..hi.y {
                for x in lo.x..hi.x {
                    let pixel = UVec2::new(x, y);
                    for index in 0..spp {
                        let (p_film, cray) = camera_sample(scene, &mut sampler, pixel, index);
                        let mut split = Split::default();
                        let l = li_recorded(scene, &cray, &mut sampler, cfg, &mut split);
                        bt.add_sample(p_film, l);
                        for (t, v) in lt.iter_mut().zip(split.acc) {
                            t.add_sample(p_film, v);
                        }
                    }
                }
            }
            (bt, lt)
        })
        .collect();
    for (bt, lt) in finished {
        beauty.merge(&bt);
        for (f, t) in layers.iter_mut().zip(lt) {
            f.merge(&t);
        }
    }
    LayerFilms { beauty, layers }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::path::{Scatter, Via};

    #[test]
    fn classification() {
        let c = |depth, first, via| Layer::of(&Contribution { depth, first, via });
        let diffuse = Some(Scatter {
            delta: false,
            transmission: false,
        });
        let mirror = Some(Scatter {
            delta: true,
            transmission: false,
        });
        let glass = Some(Scatter {
            delta: true,
            transmission: true,
        });
        assert_eq!(c(1, None, Via::Emission), Layer::Emission);
        assert_eq!(c(2, None, Via::EmitterSample), Layer::Direct);
        assert_eq!(c(2, None, Via::Ambient), Layer::Direct);
        assert_eq!(c(2, diffuse, Via::Emission), Layer::Direct);
        assert_eq!(c(3, diffuse, Via::EmitterSample), Layer::Indirect);
        assert_eq!(c(3, mirror, Via::EmitterSample), Layer::Reflection);
        assert_eq!(c(5, glass, Via::Emission), Layer::Refraction);
    }
}
