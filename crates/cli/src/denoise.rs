//! `render --denoise`, `penumbra denoise` and `render --display-server`: what happens to the
//! image between the film and the files (Open Image Denoise, `render::denoise`) and while it
//! converges (tev, `render::display`).

use std::path::{Path, PathBuf};

use render::denoise::{Aux, Oidn, aux_spp, render_aux};
use render::display::{Display, Frame};
use render::film::{Film, Filter, Image};
use render::image_io::{read_image, write_image};
use render::render::{Progress, RenderObserver};
use render::world::Scene;

use crate::{Failure, check_outputs};

/// Which auxiliary images the denoiser gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum AuxImages {
    /// Albedo and normal of the first non-delta hit (best quality).
    All,
    /// Albedo only.
    Albedo,
    /// The beauty alone.
    None,
}

#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct DenoiseArgs {
    /// Denoise the image with Intel Open Image Denoise before writing it (every -o gets the
    /// denoised image). Needs the OIDN library: `pip install pyoidn` (or PENUMBRA_OIDN=path
    /// to libOpenImageDenoise.so).
    #[arg(long)]
    pub denoise: bool,
    /// Auxiliary images given to the denoiser, rendered after the beauty with the same film
    /// and filter (16 to 64 spp).
    #[arg(
        long,
        value_name = "all|albedo|none",
        default_value = "all",
        requires = "denoise"
    )]
    pub denoise_aux: Option<AuxImages>,
    /// Denoise the auxiliary images first and tell OIDN they are clean (OIDN's advice for
    /// final frames): on (default) or off.
    #[arg(long, value_name = "on|off", value_parser = crate::parse_on_off, requires = "denoise")]
    pub denoise_prefilter: Option<bool>,
    /// Also write the noisy image here (and, beside it, FILE_albedo.exr and FILE_normal.exr,
    /// the auxiliary images: `penumbra denoise FILE --albedo … --normal … [--filter F]`
    /// gives the same pixels as --denoise). Like the auxiliary images it is box-filtered (see
    /// `penumbra denoise --filter`).
    #[arg(long, value_name = "FILE", requires = "denoise")]
    pub keep_noisy: Option<PathBuf>,
}

/// What [`crate::render_scene_with`] does to the developed image, resolved before rendering.
pub(crate) struct Denoising {
    oidn: Oidn,
    aux: AuxImages,
    prefilter: bool,
    keep_noisy: Option<PathBuf>,
}

impl DenoiseArgs {
    /// The denoiser if asked for: loaded now, so a missing library fails before the render
    /// (exit 2, saying how to get it).
    pub(crate) fn resolve(&self) -> Result<Option<Denoising>, Failure> {
        if !self.denoise {
            return Ok(None);
        }
        let oidn = Oidn::load().map_err(Failure::input)?;
        if let Some(k) = &self.keep_noisy {
            check_outputs(&[k.clone(), aux_path(k, "albedo"), aux_path(k, "normal")])?;
        }
        Ok(Some(Denoising {
            oidn,
            aux: self.denoise_aux.unwrap_or(AuxImages::All),
            prefilter: self.denoise_prefilter.unwrap_or(true),
            keep_noisy: self.keep_noisy.clone(),
        }))
    }
}

/// `FILE_what.exr` beside `file`.
fn aux_path(file: &Path, what: &str) -> PathBuf {
    let stem = file.file_stem().and_then(|s| s.to_str()).unwrap_or("noisy");
    file.with_file_name(format!("{stem}_{what}.exr"))
}

/// The outcome of denoising: the image to write and what the live view shows beside it.
pub(crate) struct Denoised {
    pub image: Image,
    pub layers: Vec<(&'static str, Image)>,
}

impl Denoising {
    /// Sets the scene's film to the one-pixel box filter and returns its own filter: a
    /// denoiser needs noise that is independent from pixel to pixel (OIDN leaves the noise of
    /// a gaussian-splatted render, correlated over its 2-pixel radius, nearly untouched), so
    /// the render and the auxiliary images are box-filtered and the scene's filter is applied
    /// to the denoised image ([`Filter::apply_to_box_image`]).
    pub(crate) fn prepare(scene: &mut Scene) -> Filter {
        std::mem::replace(&mut scene.film.filter, Filter::Box { radius: 0.5 })
    }

    /// Renders the auxiliary images (on the current rayon pool), writes the noisy files if
    /// asked, denoises `noisy` and applies the scene's `filter` (from [`Self::prepare`]).
    pub(crate) fn apply(
        &self,
        scene: &Scene,
        spp: u32,
        noisy: Image,
        filter: &Filter,
        quiet: bool,
    ) -> Result<Denoised, Failure> {
        let start = std::time::Instant::now();
        let (albedo, normal) = match self.aux {
            AuxImages::None => (None, None),
            AuxImages::Albedo | AuxImages::All => {
                let (a, n) = render_aux(scene, aux_spp(spp));
                (Some(a), (self.aux == AuxImages::All).then_some(n))
            }
        };
        if let Some(k) = &self.keep_noisy {
            write_image(k, &noisy).map_err(Failure::other)?;
            for (what, img) in [("albedo", &albedo), ("normal", &normal)] {
                if let Some(i) = img {
                    write_image(&aux_path(k, what), i).map_err(Failure::other)?;
                }
            }
            if !quiet {
                eprintln!("wrote {} (noisy) and its auxiliary images", k.display());
            }
        }
        let image = self
            .oidn
            .denoise(
                &noisy,
                Aux {
                    albedo: albedo.as_ref(),
                    normal: normal.as_ref(),
                    prefilter: self.prefilter,
                },
            )
            .map_err(Failure::other)?;
        let image = filter.apply_to_box_image(&image);
        if !quiet {
            eprintln!(
                "denoised with Open Image Denoise ({}) in {:.2} s",
                self.oidn.path().display(),
                start.elapsed().as_secs_f64()
            );
        }
        let mut layers = vec![("noisy", noisy)];
        layers.extend(albedo.map(|a| ("albedo", a)));
        layers.extend(normal.map(|n| ("normal", n)));
        Ok(Denoised { image, layers })
    }
}

#[derive(clap::Args)]
pub(crate) struct DenoiseCmd {
    /// The noisy image (EXR, PFM or HDR: linear values).
    input: PathBuf,
    /// Albedo image of the same size (e.g. FILE_albedo.exr from `render --keep-noisy`).
    #[arg(long, value_name = "FILE")]
    albedo: Option<PathBuf>,
    /// Normal image of the same size (needs --albedo).
    #[arg(long, value_name = "FILE", requires = "albedo")]
    normal: Option<PathBuf>,
    /// Denoise the auxiliary images first: on (default) or off.
    #[arg(long, value_name = "on|off", value_parser = crate::parse_on_off)]
    prefilter: Option<bool>,
    /// The input was rendered with the one-pixel box filter: give the denoised image this
    /// reconstruction filter (box, tent, gaussian, mitchell, lanczos; Mitsuba's defaults), as
    /// `render --denoise` does for a scene with that filter.
    #[arg(long, value_name = "KIND", value_parser = build::spec::parse_filter)]
    filter: Option<scene::FilterDesc>,
    /// Output image(s). May be repeated.
    #[arg(short, long = "output", value_name = "FILE", required = true)]
    output: Vec<PathBuf>,
}

/// `penumbra denoise`.
pub(crate) fn run(args: DenoiseCmd) -> Result<(), Failure> {
    check_outputs(&args.output)?;
    let oidn = Oidn::load().map_err(Failure::input)?;
    let read =
        |p: &Path| read_image(p).map_err(|e| Failure::input(format!("{}: {e}", p.display())));
    let color = read(&args.input)?;
    let albedo = args.albedo.as_deref().map(read).transpose()?;
    let normal = args.normal.as_deref().map(read).transpose()?;
    let out = oidn
        .denoise(
            &color,
            Aux {
                albedo: albedo.as_ref(),
                normal: normal.as_ref(),
                prefilter: args.prefilter.unwrap_or(true),
            },
        )
        .map_err(Failure::input)?;
    let out = match &args.filter {
        Some(f) => Filter::new(f).apply_to_box_image(&out),
        None => out,
    };
    for o in &args.output {
        write_image(o, &out).map_err(Failure::other)?;
        eprintln!("wrote {}", o.display());
    }
    Ok(())
}

/// An observer that also shows every finished pass in tev.
pub(crate) struct Live<'a> {
    pub inner: &'a dyn RenderObserver,
    pub display: &'a Display,
}

impl RenderObserver for Live<'_> {
    fn progress(&self, p: &Progress) {
        self.inner.progress(p);
    }
    fn note(&self, line: &str) {
        self.inner.note(line);
    }
    fn pass_done(&self, film: &Film, spp: u32) {
        self.inner.pass_done(film, spp);
        self.display.update(Frame::rgb(&film.develop()));
    }
}

/// The live view's final frame: the written image and the layers beside it.
pub(crate) fn final_frame(image: &Image, layers: &[(&str, Image)]) -> Frame {
    layers
        .iter()
        .fold(Frame::rgb(image), |f, (name, img)| f.with_layer(name, img))
}
