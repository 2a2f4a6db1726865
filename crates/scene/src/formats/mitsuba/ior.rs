//! Named indices of refraction: Mitsuba's dielectric table and RGB complex IORs of conductors.
//!
//! Dielectrics (`int_ior="bk7"`...): Mitsuba 3's `ior_data` table (values from Hecht, *Optics*,
//! 4th ed., at ~589 nm). Defaults used by Mitsuba and Nori: `int_ior` = bk7 (1.5046) for
//! `dielectric`, `thindielectric`, `roughdielectric`; `int_ior` = polypropylene (1.49) for
//! `plastic`, `roughplastic`; `ext_ior` = air (1.000277) everywhere.
//!
//! Conductors (`material="Au"`...): Mitsuba 3 reads tabulated spectral η and k
//! (`data/ior/<name>.{eta,k}.spd`, from the luxpop.com database, identical in Mitsuba 0.6's
//! `data/ior/`) and, in RGB variants, converts each curve with
//! `spectrum_list_to_srgb(wavelengths, values, bounded = false, d65 = false)`. The table
//! below holds the result of running our own implementation of that conversion
//! ([`crate::spectra::sampled_to_rgb`] with [`crate::spectra::SpectrumUse::IorData`]) on
//! those files; silver agrees with an independent implementation of the same method to 1e-7.
//!
//! The measured spectra themselves are in [`super::ior_data`] (generated from Mitsuba's files
//! by `penumbra-tools ior-spectra`); a test checks that they reproduce the RGB table, and the
//! RGB of every other material Mitsuba ships is computed from them by the same conversion.
//! Spectral renders sample the spectra ([`measured`]).

use super::ior_data::{CONDUCTORS as MEASURED, MeasuredConductor};
use crate::spectra::{SpectrumUse, sampled_to_rgb};
use glam::Vec3;

/// Mitsuba's named dielectric IORs (lower-case names).
const DIELECTRICS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000_036),
    ("hydrogen", 1.000_132),
    ("air", 1.000_277),
    ("carbon dioxide", 1.000_45),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.520_45),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.47),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

/// Default interior IOR of dielectrics (Mitsuba and Nori): BK7 glass.
pub const BK7: f32 = 1.5046;
/// Default exterior IOR (Mitsuba and Nori): air.
pub const AIR: f32 = 1.000_277;
/// Default interior IOR of Mitsuba's plastics: polypropylene.
pub const POLYPROPYLENE: f32 = 1.49;

/// Look up a named dielectric IOR (case-insensitive).
pub fn dielectric(name: &str) -> Option<f32> {
    let lower = name.trim().to_ascii_lowercase();
    DIELECTRICS
        .iter()
        .find(|(n, _)| *n == lower)
        .map(|&(_, v)| v)
}

/// Names accepted by [`dielectric`], for error messages.
pub fn dielectric_names() -> String {
    DIELECTRICS
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// (name, η RGB, k RGB), as Mitsuba 3 computes them in RGB variants (see the module docs).
#[rustfmt::skip]
const CONDUCTORS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("Ag", [0.155_276_2, 0.116_727_96, 0.138_387_64], [4.828_355, 3.122_222_2, 2.146_901_1]),
    ("Al", [1.657_500_9, 0.880_404_7, 0.521_244_47], [9.223_811, 6.269_502, 4.837_003_7]),
    ("Au", [0.143_036, 0.375_307_08, 1.442_045_2], [3.982_997, 2.385_556_5, 1.603_359_1]),
    ("Cr", [4.369_667_5, 2.916_505_3, 1.654_904_5], [5.206_547, 4.231_306, 3.754_698_5]),
    ("Cu", [0.201_005_5, 0.923_749_5, 1.102_215_4], [3.913_262_1, 2.453_045_1, 2.142_089_8]),
];

/// RGB (η, k) of a named conductor (case-sensitive, as in Mitsuba: `Au`, `Cu`, ...): the
/// table above, else the measured spectra converted as Mitsuba's RGB variants convert them.
pub fn conductor(name: &str) -> Option<(Vec3, Vec3)> {
    if let Some((_, e, k)) = CONDUCTORS.iter().find(|(n, _, _)| *n == name) {
        return Some((Vec3::from_array(*e), Vec3::from_array(*k)));
    }
    measured(name).map(measured_rgb)
}

/// The measured η and k spectra of a named conductor (case-sensitive).
pub fn measured(name: &str) -> Option<&'static MeasuredConductor> {
    MEASURED.iter().find(|m| m.name == name)
}

/// RGB (η, k) of measured spectra, as Mitsuba 3's RGB variants compute them.
fn measured_rgb(m: &MeasuredConductor) -> (Vec3, Vec3) {
    let rgb = |v: &[f64]| {
        sampled_to_rgb(m.wavelengths, v, SpectrumUse::IorData)
            .expect("the generated table is well formed")
    };
    (rgb(m.eta), rgb(m.k))
}

/// Names accepted by [`conductor`], for error messages.
pub fn conductor_names() -> String {
    let mut v: Vec<&str> = MEASURED.iter().map(|m| m.name).collect();
    v.push("none");
    v.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookups() {
        assert_eq!(dielectric("BK7"), Some(1.5046));
        assert_eq!(dielectric("acrylic glass"), Some(1.49));
        assert_eq!(dielectric("unobtainium"), None);
        let (eta, k) = conductor("Au").unwrap();
        // Gold reflects red more than blue: small η and large k in red.
        assert!(eta.x < eta.z && k.x > k.z);
        assert!(conductor("au").is_none());
    }

    /// The RGB table is what Mitsuba's RGB variants make of the measured spectra (the
    /// conversion of `crate::spectra`): bit for bit, except silver's η, one f32 ulp away in
    /// its red channel (that row came from another implementation of the same method).
    #[test]
    fn rgb_table_is_reproduced_by_the_measured_spectra() {
        for (name, eta, k) in CONDUCTORS {
            let m = measured(name).unwrap_or_else(|| panic!("{name} has measured spectra"));
            let (e, kk) = measured_rgb(m);
            for (got, want) in [(e, eta), (kk, k)] {
                let want = Vec3::from_array(*want);
                let rel = ((got - want).abs() / want).max_element();
                assert!(
                    rel < 2e-7,
                    "{name}: {got} from the spectra, {want} in the table"
                );
            }
        }
        // Every name Mitsuba ships has both spectra on one wavelength grid.
        assert_eq!(MEASURED.len(), 71);
        for m in MEASURED {
            assert!(m.wavelengths.len() >= 2 && m.eta.len() == m.wavelengths.len());
            assert_eq!(m.k.len(), m.wavelengths.len());
            assert!(m.wavelengths.windows(2).all(|w| w[0] < w[1]), "{}", m.name);
        }
        // Names outside the RGB table convert too (tungsten: grey-ish, η > 1).
        let (eta, k) = conductor("W").unwrap();
        assert!(
            eta.min_element() > 1.0 && k.min_element() > 1.0,
            "{eta} {k}"
        );
    }
}
