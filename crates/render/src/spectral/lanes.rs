//! The colour type made generic, Mitsuba-style (issue 21, steps 1–2 of its plan: the BSDFs are
//! generic; lights, media and the integrators are still RGB, so spectral mode runs only in
//! tests yet).
//!
//! [`Color`] is what a path carries per lane: `Vec3` (RGB, 3 lanes) or [`SampledSpectrum`]
//! (4 wavelengths). Code generic over it is monomorphised once per mode, so RGB mode runs the
//! same machine code as before. Parameters declared as RGB (constants and textures) become a
//! `Color` through a [`ColorMode`]: the identity in RGB mode, Jakob–Hanika upsampling evaluated
//! at the path's wavelengths in spectral mode.
//!
//! Every BSDF model is generic; where a model does fixed 3-channel or channel-mean
//! arithmetic (lobe-selection weights), it is done on the RGB parameters in every mode.

use super::declared::DeclaredSpectrum;
use super::rgb::{RgbAlbedoSpectrum, RgbToSpectrumTable, RgbUnboundedSpectrum};
use super::sampled::{N_SPECTRUM_SAMPLES, SampledSpectrum, SampledWavelengths, Spectrum};
use crate::math::{Mat4, Vec3, Vec4};
use crate::sampling::Samples;
use crate::textures::{ColorRef, Params, TexCoord};
use std::cell::Cell;
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// The per-lane colour a path carries. Left multiplication by a scalar (`f32 * C`) cannot be
/// a supertrait bound (a `where f32: Mul<Self>` on the trait is not implied at use sites), so
/// generic code writes `c * s`.
pub trait Color:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Mul<f32, Output = Self>
    + Div<f32, Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + MulAssign<f32>
    + DivAssign<f32>
{
    /// Number of lanes (3 for RGB, 4 for spectra).
    const LANES: usize;
    const ZERO: Self;
    const ONE: Self;

    fn splat(v: f32) -> Self;
    /// The colour whose lane `i` is `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self;
    fn lane(self, i: usize) -> f32;
    /// Largest lane (Russian roulette, the hero-channel choice).
    fn max_lane(self) -> f32;
    /// Mean over the lanes. For spectra this is NOT luminance: the lanes are values at random
    /// wavelengths, not a colour; the integrators' luminance-like uses (roulette, lobe
    /// selection weights) keep working as heuristics but change their noise, not their mean.
    fn mean(self) -> f32;
    fn is_black(self) -> bool;
    /// Whether every lane is finite.
    fn is_finite(self) -> bool;
    /// e^x per lane.
    fn exp(self) -> Self;
}

impl Color for Vec3 {
    const LANES: usize = 3;
    const ZERO: Self = Vec3::ZERO;
    const ONE: Self = Vec3::ONE;

    #[inline(always)]
    fn splat(v: f32) -> Self {
        Vec3::splat(v)
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        Vec3::new(f(0), f(1), f(2))
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self[i]
    }
    #[inline(always)]
    fn max_lane(self) -> f32 {
        self.max_element()
    }
    #[inline(always)]
    fn mean(self) -> f32 {
        (self.x + self.y + self.z) * (1.0 / 3.0)
    }
    #[inline(always)]
    fn is_black(self) -> bool {
        self == Vec3::ZERO
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        Vec3::is_finite(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        Vec3::exp(self)
    }
}

impl Color for SampledSpectrum {
    const LANES: usize = N_SPECTRUM_SAMPLES;
    const ZERO: Self = SampledSpectrum::ZERO;
    const ONE: Self = SampledSpectrum::ONE;

    #[inline(always)]
    fn splat(v: f32) -> Self {
        SampledSpectrum::splat(v)
    }
    #[inline(always)]
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self {
        SampledSpectrum::from_fn(f)
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self[i]
    }
    #[inline(always)]
    fn max_lane(self) -> f32 {
        self.max_component()
    }
    #[inline(always)]
    fn mean(self) -> f32 {
        self.average()
    }
    #[inline(always)]
    fn is_black(self) -> bool {
        SampledSpectrum::is_black(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        self.as_vec4().is_finite()
    }
    #[inline(always)]
    fn exp(self) -> Self {
        SampledSpectrum::exp(self)
    }
}

/// How RGB-declared parameters become the path's colour, and how wavelength-dependent
/// quantities are resolved: one object per path in spectral mode (it holds the wavelengths),
/// a zero-sized one in RGB mode.
pub trait ColorMode {
    type C: Color;
    /// A reflectance/transmittance in [0, 1]³.
    fn albedo(&self, rgb: Vec3) -> Self::C;
    /// An unbounded non-negative quantity (conductor η and k, scattering coefficients).
    fn unbounded(&self, rgb: Vec3) -> Self::C;
    /// An emitted radiance (or intensity, irradiance) given as linear sRGB: in spectral mode
    /// the unbounded spectrum times D65 of unit luminance, so that the colour comes back
    /// under the CIE observer (Mitsuba's and pbrt-v4's RGB illuminant spectrum).
    fn illuminant(&self, rgb: Vec3) -> Self::C;
    /// A quantity known as a function of wavelength (nm) — a black body, a tabulated
    /// spectrum — whose RGB-mode value is `rgb`: RGB mode uses `rgb`, spectral mode
    /// evaluates `f` at the path's wavelengths (exact, no upsampling).
    fn spectrum(&self, f: impl Fn(f32) -> f32, rgb: Vec3) -> Self::C;
    /// A colour parameter read as a reflectance at `at`. Parameters declared as spectra
    /// (see [`Params`]) are sampled as declared in spectral mode.
    #[inline(always)]
    fn albedo_at<P: Params + ?Sized>(&self, p: &P, r: &ColorRef, at: TexCoord) -> Self::C {
        self.albedo(p.color(r, at))
    }
    /// A colour parameter read as an emitted radiance at `at` (see [`Self::illuminant`]).
    #[inline(always)]
    fn illuminant_at<P: Params + ?Sized>(&self, p: &P, r: &ColorRef, at: TexCoord) -> Self::C {
        self.illuminant(p.color(r, at))
    }
    /// [`Self::albedo_at`] when the caller has read the parameter's RGB value already
    /// (`rgb = p.color(r, at)`, needed in RGB for lobe-selection weights): RGB mode reads
    /// nothing twice.
    #[inline(always)]
    fn albedo_read<P: Params + ?Sized>(&self, _p: &P, _r: &ColorRef, rgb: Vec3) -> Self::C {
        self.albedo(rgb)
    }
    /// An unbounded constant (conductor η and k) with the spectrum it was declared as, if
    /// any: RGB mode uses `rgb`, spectral mode samples `declared` when there is one.
    #[inline(always)]
    fn unbounded_declared(&self, rgb: Vec3, _declared: Option<&DeclaredSpectrum>) -> Self::C {
        self.unbounded(rgb)
    }
    /// An emitted constant (a light's radiance, intensity or irradiance) with the spectrum
    /// it was declared as, if any (see [`Self::unbounded_declared`]).
    #[inline(always)]
    fn illuminant_declared(&self, rgb: Vec3, _declared: Option<&DeclaredSpectrum>) -> Self::C {
        self.illuminant(rgb)
    }
    /// A scalar index of refraction for a *smooth* interface, given as a function of
    /// wavelength (nm) and its RGB-mode value. A dispersive index in spectral mode is taken
    /// at the hero wavelength and terminates the secondary wavelengths (pbrt-v4's scheme);
    /// RGB mode uses `rgb_value` unchanged.
    fn smooth_eta(&self, dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> f32;
    /// An index of refraction per lane, for interfaces that keep every wavelength through a
    /// dispersive index (the rough dielectric by MIS over the lanes, the thin sheet whose
    /// directions do not depend on it): RGB mode and non-dispersive indices give `rgb_value`
    /// in every lane; a dispersive one in spectral mode gives its value at each lane's
    /// wavelength, or the hero's in every lane once the secondary wavelengths are terminated
    /// (only the hero still counts). Nothing is terminated here.
    fn lane_ior(&self, dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> Self::C;
}

/// RGB mode: every conversion is the identity.
#[derive(Clone, Copy, Debug, Default)]
pub struct RgbMode;

impl ColorMode for RgbMode {
    type C = Vec3;
    #[inline(always)]
    fn albedo(&self, rgb: Vec3) -> Vec3 {
        rgb
    }
    #[inline(always)]
    fn unbounded(&self, rgb: Vec3) -> Vec3 {
        rgb
    }
    #[inline(always)]
    fn illuminant(&self, rgb: Vec3) -> Vec3 {
        rgb
    }
    #[inline(always)]
    fn spectrum(&self, _f: impl Fn(f32) -> f32, rgb: Vec3) -> Vec3 {
        rgb
    }
    #[inline(always)]
    fn smooth_eta(&self, _dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> f32 {
        rgb_value
    }
    #[inline(always)]
    fn lane_ior(&self, _dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> Vec3 {
        Vec3::splat(rgb_value)
    }
}

/// Spectral mode for one path: its wavelengths (terminated in place through a `Cell`, since
/// parameter evaluation takes `&self`) and the RGB → spectrum table.
#[derive(Clone)]
pub struct SpectralMode<'a> {
    wavelengths: Cell<SampledWavelengths>,
    table: &'a RgbToSpectrumTable,
    /// Unit-luminance D65 at the wavelengths: every RGB illuminant is an unbounded spectrum
    /// times it, several times per path.
    d65: SampledSpectrum,
    /// The observer in linear sRGB at the wavelengths (r̄, ḡ, b̄ over the lanes, divided by
    /// ∫ȳ): the path's estimate becomes the film's colour by three dot products.
    srgb_bar: [Vec4; 3],
}

impl<'a> SpectralMode<'a> {
    pub fn new(wavelengths: SampledWavelengths, table: &'a RgbToSpectrumTable) -> Self {
        // One interleaved (r̄, ḡ, b̄, D65) lookup per wavelength, transposed to lanes.
        let l = wavelengths.lambdas().map(super::cie::srgb_bar_d65_at);
        let lanes = Mat4::from_cols(l[0], l[1], l[2], l[3]).transpose();
        SpectralMode {
            d65: SampledSpectrum::from_vec4(lanes.w_axis),
            srgb_bar: [lanes.x_axis, lanes.y_axis, lanes.z_axis],
            wavelengths: Cell::new(wavelengths),
            table,
        }
    }

    pub fn wavelengths(&self) -> SampledWavelengths {
        self.wavelengths.get()
    }
}

impl ColorMode for SpectralMode<'_> {
    type C = SampledSpectrum;
    fn albedo(&self, rgb: Vec3) -> SampledSpectrum {
        RgbAlbedoSpectrum::new(self.table, rgb).sample(&self.wavelengths.get())
    }
    fn unbounded(&self, rgb: Vec3) -> SampledSpectrum {
        RgbUnboundedSpectrum::new(self.table, rgb).sample(&self.wavelengths.get())
    }
    fn illuminant(&self, rgb: Vec3) -> SampledSpectrum {
        // = RgbIlluminantSpectrum::new(self.table, rgb).sample(..), D65 looked up once.
        RgbUnboundedSpectrum::new(self.table, rgb).sample(&self.wavelengths.get()) * self.d65
    }
    // Declared spectra are sampled as declared (not clamped, no D65 factor: Mitsuba's
    // spectral variants' semantics, `super::declared`).
    #[inline]
    fn albedo_at<P: Params + ?Sized>(&self, p: &P, r: &ColorRef, at: TexCoord) -> SampledSpectrum {
        match p.spectrum(r) {
            Some(s) => s.sample(&self.wavelengths.get()),
            None => self.albedo(p.color(r, at)),
        }
    }
    #[inline]
    fn illuminant_at<P: Params + ?Sized>(
        &self,
        p: &P,
        r: &ColorRef,
        at: TexCoord,
    ) -> SampledSpectrum {
        match p.spectrum(r) {
            Some(s) => s.sample(&self.wavelengths.get()),
            None => self.illuminant(p.color(r, at)),
        }
    }
    #[inline]
    fn albedo_read<P: Params + ?Sized>(&self, p: &P, r: &ColorRef, rgb: Vec3) -> SampledSpectrum {
        match p.spectrum(r) {
            Some(s) => s.sample(&self.wavelengths.get()),
            None => self.albedo(rgb),
        }
    }
    #[inline]
    fn unbounded_declared(
        &self,
        rgb: Vec3,
        declared: Option<&DeclaredSpectrum>,
    ) -> SampledSpectrum {
        match declared {
            Some(s) => s.sample(&self.wavelengths.get()),
            None => self.unbounded(rgb),
        }
    }
    #[inline]
    fn illuminant_declared(
        &self,
        rgb: Vec3,
        declared: Option<&DeclaredSpectrum>,
    ) -> SampledSpectrum {
        match declared {
            Some(s) => s.sample(&self.wavelengths.get()),
            None => self.illuminant(rgb),
        }
    }
    fn spectrum(&self, f: impl Fn(f32) -> f32, _rgb: Vec3) -> SampledSpectrum {
        let wl = self.wavelengths.get();
        SampledSpectrum::from_fn(|i| f(wl.lambda(i)))
    }
    fn smooth_eta(&self, dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> f32 {
        match dispersive {
            None => rgb_value,
            Some(ior) => {
                let mut wl = self.wavelengths.get();
                wl.terminate_secondary();
                self.wavelengths.set(wl);
                ior(wl.lambda(0))
            }
        }
    }
    fn lane_ior(&self, dispersive: Option<&dyn Fn(f32) -> f32>, rgb_value: f32) -> SampledSpectrum {
        match dispersive {
            None => SampledSpectrum::splat(rgb_value),
            Some(ior) => {
                let wl = self.wavelengths.get();
                if wl.secondary_terminated() {
                    SampledSpectrum::splat(ior(wl.lambda(0)))
                } else {
                    SampledSpectrum::from_fn(|i| ior(wl.lambda(i)))
                }
            }
        }
    }
}

/// A [`ColorMode`] an integrator runs a whole path in: it is set up per camera sample (the
/// spectral mode draws the path's wavelengths from the sampler, after the camera's
/// dimensions; RGB mode draws nothing, so its sample streams are unchanged) and turns the
/// path's estimate into linear sRGB for the film. A clone is the same wavelengths with its
/// own termination (BDPT's two subpaths each terminate their own).
pub trait PathMode: ColorMode + Clone + Sized {
    /// Whether paths carry sampled wavelengths (spectral mode) rather than RGB.
    const SPECTRAL: bool;

    fn start(sampler: &mut impl Samples) -> Self;
    /// The mode `start` makes when the sampler's next number is `u` (the photon-mapping
    /// family shares one set of wavelengths across an iteration's paths).
    fn from_u(u: f32) -> Self;
    /// Whether the secondary wavelengths are terminated (only the hero still counts).
    fn terminated(&self) -> bool;
    /// This mode with the secondary wavelengths terminated.
    fn terminate(&self) -> Self;
    /// The estimate `c` of this path as linear sRGB.
    fn to_rgb(&self, c: Self::C) -> Vec3;
    /// The largest lane of a throughput that still counts (Russian roulette): terminated
    /// secondary wavelengths no longer contribute and must not keep a path alive.
    fn live_max(&self, c: Self::C) -> f32;
    /// The lane whose density samples free flights in media (the hero), from a uniform `u`
    /// drawn in both modes: a channel chosen uniformly in RGB mode; in spectral mode the
    /// hero wavelength, lane 0 (the four wavelengths are already a uniformly rotated set).
    fn hero(&self, u: f32) -> usize;
    /// The spectral-MIS weight of a path whose lane densities relative to the hero's are
    /// `ratio` (balance heuristic over the choice of hero: 1 / mean ratio). Once the
    /// secondary wavelengths are terminated only the hero's own strategy is left: 1.
    fn hero_weight(&self, ratio: Self::C) -> f32;
}

impl PathMode for RgbMode {
    const SPECTRAL: bool = false;

    #[inline(always)]
    fn start(_sampler: &mut impl Samples) -> Self {
        RgbMode
    }
    #[inline(always)]
    fn from_u(_u: f32) -> Self {
        RgbMode
    }
    #[inline(always)]
    fn terminated(&self) -> bool {
        false
    }
    #[inline(always)]
    fn terminate(&self) -> Self {
        RgbMode
    }
    #[inline(always)]
    fn to_rgb(&self, c: Vec3) -> Vec3 {
        c
    }
    #[inline(always)]
    fn live_max(&self, c: Vec3) -> f32 {
        c.max_element()
    }
    #[inline(always)]
    fn hero(&self, u: f32) -> usize {
        ((u * 3.0) as usize).min(2)
    }
    #[inline(always)]
    fn hero_weight(&self, ratio: Vec3) -> f32 {
        3.0 / ratio.element_sum()
    }
}

impl PathMode for SpectralMode<'static> {
    const SPECTRAL: bool = true;

    #[inline]
    fn start(sampler: &mut impl Samples) -> Self {
        Self::from_u(sampler.next_1d())
    }
    #[inline]
    fn from_u(u: f32) -> Self {
        SpectralMode::new(
            SampledWavelengths::sample_visible(u),
            RgbToSpectrumTable::srgb(),
        )
    }
    #[inline]
    fn terminated(&self) -> bool {
        self.wavelengths.get().secondary_terminated()
    }
    fn terminate(&self) -> Self {
        let mut wl = self.wavelengths.get();
        wl.terminate_secondary();
        SpectralMode {
            wavelengths: Cell::new(wl),
            table: self.table,
            d65: self.d65,
            srgb_bar: self.srgb_bar,
        }
    }
    #[inline]
    fn to_rgb(&self, c: SampledSpectrum) -> Vec3 {
        // = c.to_srgb(&wavelengths), with the observer looked up once per path.
        let w =
            c.safe_div(self.wavelengths.get().pdf()).as_vec4() * (1.0 / N_SPECTRUM_SAMPLES as f32);
        let [r, g, b] = self.srgb_bar;
        Vec3::new(w.dot(r), w.dot(g), w.dot(b))
    }
    #[inline]
    fn live_max(&self, c: SampledSpectrum) -> f32 {
        if self.wavelengths.get().secondary_terminated() {
            c[0]
        } else {
            c.max_component()
        }
    }
    #[inline]
    fn hero(&self, _u: f32) -> usize {
        0
    }
    #[inline]
    fn hero_weight(&self, ratio: SampledSpectrum) -> f32 {
        if self.wavelengths.get().secondary_terminated() {
            1.0 / ratio[0]
        } else {
            N_SPECTRUM_SAMPLES as f32 / (ratio[0] + ratio[1] + ratio[2] + ratio[3])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Bsdf, Conductor, Dielectric, Diffuse, TransportMode};
    use crate::math::Vec2;

    fn spectral(u: f32) -> SpectralMode<'static> {
        SpectralMode::new(
            SampledWavelengths::sample_visible(u),
            RgbToSpectrumTable::srgb(),
        )
    }

    /// The same generic model code runs in both modes; the spectral weights, lit by the
    /// upsampled RGB white (D65-shaped: an albedo round-trips only under the colour space's
    /// illuminant) and integrated over the wavelengths, return the RGB weights.
    #[test]
    fn generic_models_agree_across_modes() {
        let rgb = Vec3::new(0.8, 0.3, 0.1);
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let n = 4096;
        let mut diffuse = Vec3::ZERO;
        let mut mirror = Vec3::ZERO;
        for k in 0..n {
            let m = spectral((k as f32 + 0.5) / n as f32);
            let white = super::super::rgb::RgbIlluminantSpectrum::new(
                RgbToSpectrumTable::srgb(),
                Vec3::ONE,
            )
            .sample(&m.wavelengths());
            let d: Bsdf<SampledSpectrum> = Diffuse::new(m.albedo(rgb)).into();
            let s = d
                .sample(wo, 0.5, Vec2::new(0.3, 0.6), TransportMode::Radiance)
                .unwrap();
            diffuse += (s.weight * white).to_srgb(&m.wavelengths());
            let c: Bsdf<SampledSpectrum> = Conductor::mirror(m.albedo(rgb)).into();
            let s = c
                .sample(wo, 0.5, Vec2::ZERO, TransportMode::Radiance)
                .unwrap();
            mirror += (s.weight * white).to_srgb(&m.wavelengths());
        }
        for est in [diffuse / n as f32, mirror / n as f32] {
            assert!((est - rgb).abs().max_element() < 5e-3, "{est} vs {rgb}");
        }
        // RGB mode: the identity, bit for bit.
        let d: Bsdf = Diffuse::new(RgbMode.albedo(rgb)).into();
        let s = d
            .sample(wo, 0.5, Vec2::new(0.3, 0.6), TransportMode::Radiance)
            .unwrap();
        assert_eq!(s.weight, rgb);
    }

    /// The per-path observer gives the film the estimate's `to_srgb`, with all four
    /// wavelengths and after the secondaries are terminated.
    #[test]
    fn to_rgb_is_to_srgb() {
        let bk7 = base::dispersion::Dispersion::named("glass-bk7").unwrap();
        let ior = |l: f32| bk7.ior(l as f64) as f32;
        for k in 0..200 {
            let m = spectral((k as f32 + 0.5) / 200.0);
            let c = SampledSpectrum::new([0.3, 1.7, 0.02, 4.0]) * (1.0 + k as f32);
            for _ in 0..2 {
                let (got, want) = (m.to_rgb(c), c.to_srgb(&m.wavelengths()));
                let tol = 1e-5 * want.abs().max_element().max(1e-3);
                assert!((got - want).abs().max_element() <= tol, "{got} vs {want}");
                m.smooth_eta(Some(&ior), 1.5);
            }
            let d65 = SampledSpectrum::from_fn(|i| {
                super::super::cie::d65_unit_y(m.wavelengths().lambda(i))
            });
            assert!((m.d65 - d65).as_vec4().abs().max_element() < 1e-6);
        }
    }

    /// The illuminant conversion is pbrt-v4's `RGBIlluminantSpectrum` at the wavelengths.
    #[test]
    fn illuminant_is_the_rgb_illuminant_spectrum() {
        for (k, rgb) in [
            Vec3::ONE,
            Vec3::new(17.0, 12.0, 4.0),
            Vec3::new(0.0, 0.2, 0.9),
        ]
        .into_iter()
        .enumerate()
        {
            let m = spectral(0.13 + 0.3 * k as f32);
            let want =
                super::super::rgb::RgbIlluminantSpectrum::new(RgbToSpectrumTable::srgb(), rgb)
                    .sample(&m.wavelengths());
            let got = m.illuminant(rgb);
            for i in 0..N_SPECTRUM_SAMPLES {
                assert!(
                    (got[i] - want[i]).abs() <= 1e-6 * want[i].abs(),
                    "{got:?} vs {want:?}"
                );
            }
        }
    }

    /// Per-lane conductor Fresnel: each lane is the scalar formula at that lane's η, k.
    #[test]
    fn conductor_fresnel_is_per_lane() {
        let m = spectral(0.3);
        let eta = m.unbounded(Vec3::new(0.2, 0.9, 1.1));
        let k = m.unbounded(Vec3::new(3.9, 2.4, 2.2));
        let c = Conductor::new(eta, k, SampledSpectrum::ONE);
        let f = c.reflectance(0.7);
        for i in 0..N_SPECTRUM_SAMPLES {
            let e = crate::bsdf::fresnel::fresnel_conductor_1(0.7, eta[i], k[i]);
            assert_eq!(f[i], e);
        }
    }

    /// A dispersive smooth dielectric: the index is the hero wavelength's and the secondary
    /// wavelengths are terminated; a non-dispersive one keeps all four.
    #[test]
    fn dispersive_dielectric_terminates_secondaries() {
        let bk7 = base::dispersion::Dispersion::named("glass-bk7").unwrap();
        let ior = |l: f32| bk7.ior(l as f64) as f32;
        let m = spectral(0.1);
        let eta = m.smooth_eta(None, 1.5);
        assert!(eta == 1.5 && !m.wavelengths().secondary_terminated());
        let eta = m.smooth_eta(Some(&ior), bk7.ior_rgb() as f32);
        let wl = m.wavelengths();
        assert!(wl.secondary_terminated());
        assert_eq!(eta, ior(wl.lambda(0)));
        let mut d = Dielectric::<SampledSpectrum>::with_lanes(eta, 1.0);
        d.specular_transmittance = m.albedo(Vec3::splat(1.0));
        let s = Bsdf::from(d)
            .sample(Vec3::Z, 0.99, Vec2::ZERO, TransportMode::Radiance)
            .unwrap();
        assert!(s.transmission && (s.eta - eta).abs() < 1e-6);
        // RGB mode ignores the dispersion.
        assert_eq!(RgbMode.smooth_eta(Some(&ior), 1.5168), 1.5168);
        assert_eq!(RgbMode.lane_ior(Some(&ior), 1.5168), Vec3::splat(1.5168));
    }

    /// An index per lane: each wavelength's own, nothing terminated; the hero's everywhere
    /// once the secondaries are terminated; the constant for a non-dispersive index.
    #[test]
    fn lane_ior_keeps_every_wavelength() {
        let bk7 = base::dispersion::Dispersion::named("glass-bk7").unwrap();
        let ior = |l: f32| bk7.ior(l as f64) as f32;
        let m = spectral(0.6);
        assert_eq!(m.lane_ior(None, 1.5), SampledSpectrum::splat(1.5));
        let wl = m.wavelengths();
        let lanes = m.lane_ior(Some(&ior), 1.5168);
        assert!(!m.wavelengths().secondary_terminated());
        for i in 0..N_SPECTRUM_SAMPLES {
            assert_eq!(lanes[i], ior(wl.lambda(i)));
        }
        m.smooth_eta(Some(&ior), 1.5168);
        assert_eq!(
            m.lane_ior(Some(&ior), 1.5168),
            SampledSpectrum::splat(ior(wl.lambda(0)))
        );
    }

    /// Every BSDF model runs in spectral mode (no RGB bridge is left to panic): the weights
    /// and values are finite and non-negative at every lane.
    #[test]
    fn every_model_runs_in_spectral_mode() {
        use crate::bsdf::{
            CourseMaterial, IdealLobe, Microfacet, MicrofacetType, NoriMicrofacet, PhongFamily,
            Plastic, RoughConductor, RoughDielectric, RoughPlastic, RoughPlasticTables,
            ThinDielectric, rgb_sampling_weight,
        };
        let m = spectral(0.4);
        let (d, s) = (Vec3::new(0.7, 0.2, 0.1), Vec3::splat(0.9));
        let a = |c: Vec3| m.albedo(c);
        let beckmann = MicrofacetType::Beckmann;
        let mf = Microfacet::isotropic(beckmann, 0.2);
        let phong = PhongFamily::new(
            base::PhongModel::TorranceSparrow,
            false,
            true,
            30.0,
            d,
            s,
            1.5,
        );
        let models: Vec<Bsdf<SampledSpectrum>> = vec![
            ThinDielectric::with_lanes(1.5, 1.0).into(),
            RoughConductor::new(
                beckmann,
                0.2,
                0.3,
                m.unbounded(Vec3::new(0.2, 0.9, 1.1)),
                m.unbounded(Vec3::new(3.9, 2.4, 2.2)),
                a(s),
            )
            .into(),
            Plastic::with_weight(a(d), a(s), 1.5, 1.0, false, rgb_sampling_weight(d, s)).into(),
            RoughPlastic::with_tables_weighted(
                mf,
                1.5,
                std::sync::Arc::new(RoughPlasticTables::new(mf, 1.5)),
                a(d),
                a(s),
                true,
                rgb_sampling_weight(d, s),
            )
            .into(),
            NoriMicrofacet::new(0.2, 1.5, 1.0, d).map_lanes(a).into(),
            RoughDielectric::with_lanes(beckmann, 0.2, 0.2, 1.5, 1.0).into(),
            phong.map_lanes(a).into(),
            CourseMaterial::new(phong, IdealLobe::Conductor { eta: 0.37, k: 2.82 }, s, 0.1)
                .map_lanes(a)
                .into(),
        ];
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let ok =
            |c: SampledSpectrum| (0..N_SPECTRUM_SAMPLES).all(|i| c[i].is_finite() && c[i] >= 0.0);
        for b in &models {
            let mut sampled = 0;
            for k in 0..64 {
                let u = Vec2::new(
                    (k as f32 + 0.5) / 64.0,
                    ((k * 37) % 64) as f32 / 64.0 + 0.005,
                );
                if let Some(smp) = b.sample(wo, u.x, u, TransportMode::Radiance) {
                    assert!(ok(smp.weight), "{b:?}: {:?}", smp.weight);
                    sampled += 1;
                    let (f, _) = b.eval_pdf(wo, smp.wi, TransportMode::Radiance);
                    assert!(ok(f));
                }
            }
            assert!(sampled > 0, "{b:?}");
            assert!(ok(b.albedo()));
        }
    }
}
