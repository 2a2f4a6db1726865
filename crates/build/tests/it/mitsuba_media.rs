//! Mitsuba 3 phase functions of issue 38 (`rayleigh`, `tabphase`, `blendphase`, `sggx`) against
//! Mitsuba 3.9.1's render of the same file (`scenes/mitsuba/refs/`, the rule of
//! `repo_references.rs`). Their sampling is χ²-tested in the render crate (`chi2_media.rs`).

use crate::repo_references::check_repo_reference;

/// Three media behind null boundaries, lit from above and from behind: a forward-peaked
/// table, Rayleigh, and a blend of a backward Henyey–Greenstein lobe with the table. Read
/// the wrong way round, the table changes its sphere's brightness by ~25 % (measured with
/// Mitsuba).
#[test]
fn phase_functions() {
    check_repo_reference("phases");
}

/// Mitsuba 3's `sggx` (specular SGGX microflakes, constant S read from a 6-channel
/// gridvolume): flakes, a general S and fibres in three spheres (`scenes/mitsuba/sggx.xml`)
/// against Mitsuba 3.9.1.
///
/// Ignored: it does not pass yet. With Mitsuba's direction-dependent extinction σt·σ(ω)
/// the image is within 2 % of Mitsuba's (mean ratio RGB 1.020, 1.024, 1.024; without it,
/// 0.877, 0.865, 0.838) but the block t-test rejects (worst |t| 44.6, relMSE 2.8·10⁻² vs
/// Mitsuba's own 3.8·10⁻³). The phase function's values agree with Mitsuba's to 1e-6
/// (`media::phase` tests) and its sampling passes χ² (`chi2_media.rs`); the remaining
/// difference is not found.
#[test]
#[ignore = "2 % brighter than Mitsuba 3.9.1; cause not found (see the doc comment)"]
fn sggx_phase_function() {
    check_repo_reference("sggx");
}
