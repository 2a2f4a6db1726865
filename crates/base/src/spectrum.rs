//! A spectrum as a scene declared it, in the form spectral rendering samples it: data only
//! (the renderer evaluates it, `render::spectral::declared`, which states the units). Here,
//! beside the loaders' vocabulary, so that the renderer's parameters (`render::textures`) can
//! hold one without naming the spectral toolkit.

/// A declared spectrum (values per nm of wavelength where they are radiometric).
#[derive(Clone, Debug, PartialEq)]
pub enum DeclaredSpectrum {
    /// Linear through the nodes (`wavelengths` in nm, strictly increasing, at least two),
    /// zero outside the first and last.
    Tabulated {
        wavelengths: Box<[f32]>,
        values: Box<[f32]>,
    },
    /// The same value at every wavelength.
    Constant(f32),
    /// `scale` × Planck's law at `temperature` K, in W·m⁻²·sr⁻¹·nm⁻¹.
    Blackbody { temperature: f64, scale: f64 },
}

impl DeclaredSpectrum {
    /// A tabulated spectrum; `None` unless there are at least two nodes, as many values as
    /// wavelengths, all finite, and the wavelengths strictly increase.
    pub fn tabulated(wavelengths: &[f32], values: &[f32]) -> Option<DeclaredSpectrum> {
        let ok = wavelengths.len() >= 2
            && wavelengths.len() == values.len()
            && wavelengths.iter().chain(values).all(|v| v.is_finite())
            && wavelengths.windows(2).all(|w| w[0] < w[1]);
        ok.then(|| DeclaredSpectrum::Tabulated {
            wavelengths: wavelengths.into(),
            values: values.into(),
        })
    }
}
