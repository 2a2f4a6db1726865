//! Mitsuba 3 phase functions of issue 38 (`rayleigh`, `tabphase`, `blendphase`, `sggx`) against
//! Mitsuba 3.9.1's render of the same file (`scenes/mitsuba/refs/`, the rule of
//! `repo_references.rs`). Their sampling is χ²-tested in the render crate (`chi2_media.rs`).

use crate::repo_references::{check_repo_reference, check_repo_reference_with};

/// Three media behind null boundaries, lit from above and from behind: a forward-peaked
/// table, Rayleigh, and a blend of a backward Henyey–Greenstein lobe with the table. Read
/// the wrong way round, the table changes its sphere's brightness by ~25 % (measured with
/// Mitsuba).
#[test]
fn phase_functions() {
    check_repo_reference("phases");
}

/// Mitsuba 3's `sggx` (specular SGGX microflakes, constant S read from a 6-channel
/// gridvolume) against Mitsuba 3.9.1 where Mitsuba is right (`scenes/mitsuba/sggx.xml`):
/// flakes and fibres absorbing only (their extinction σt·σ(ω) depends on the direction), and
/// S = I/4 scattering. Mitsuba's sampling of an anisotropic S does not follow its phase
/// function (the scene's comment has the figures), so scattering through one is proven by
/// the white furnace (`furnace_media.rs`) and χ² (`chi2_media.rs`) instead.
///
/// Batches of 128 spp, not 32: at 32 a block's batch means are skewed by the small ceiling
/// light's rare MIS-weighted hits (in the block that failed, 14 of the 16 batch means of
/// seeds 0–15 lay below the reference, while an 8192-spp render sits at z = −0.6 there and
/// three other seed sets pass with p_min 1.4e-3 to 1.5e-2); at 128 the block means are
/// near enough to normal for the t-test (seeds 0–15: p_min 3.6e-2; 100–115: 8.7e-3).
#[test]
fn sggx_phase_function() {
    check_repo_reference_with("sggx", None, 128);
}
