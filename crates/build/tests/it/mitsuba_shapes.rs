//! Mitsuba 3 shapes of issue 38 against Mitsuba 3.9.1's renders of the same files
//! (`scenes/mitsuba/refs/`, the rule of `repo_references.rs`).

use crate::repo_references::check_repo_reference;

/// `cylinder`: open ends, Mitsuba's uv under a checkerboard, p0/p1/radius, a two-sided tube
/// seen inside, an anisotropic conductor (tangent along φ), emitting cylinders facing in
/// (`flip_normals`) and out.
#[test]
fn cylinder() {
    check_repo_reference("cylinder");
}
