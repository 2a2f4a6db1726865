//! Mitsuba 3 phase functions of issue 38 (`rayleigh`, `tabphase`, `blendphase`) against
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
