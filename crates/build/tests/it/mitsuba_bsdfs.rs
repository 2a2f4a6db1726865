//! Mitsuba 3's BSDF plugins of issue 38 (`principled`, `principledthin`, `pplastic`,
//! `blendbsdf`, `bumpmap`), each on a small scene of `scenes/mitsuba/` against Mitsuba 3.9.1's
//! render of the same file (`repo_references::check_repo_reference`: no load warnings, block
//! t-test of 16 × 32 spp, relMSE at 256 spp at most 1.5× Mitsuba's).

use crate::repo_references::check_repo_reference;

/// `principled`: metallic + anisotropic, spec_trans with `eta`, clearcoat with `specular`,
/// sheen with tint and flatness, the defaults, and textured base colour, roughness, metallic
/// and clearcoat.
#[test]
fn principled() {
    check_repo_reference("principled");
}

/// `blendbsdf`: a constant weight, a bitmap weight, and a blend of blends with a rough
/// plastic and a measured conductor.
#[test]
fn blendbsdf() {
    check_repo_reference("blendbsdf");
}

/// `bumpmap` over a bitmap height map (bilinear, raw 8-bit grey), as in Bitterli's bathroom:
/// a diffuse and a rough plastic rectangle, positive and negative `scale`, a tiled `to_uv`.
#[test]
fn bumpmap() {
    check_repo_reference("bumpmap");
}

/// `pplastic` (unpolarised): Mitsuba's example, an anisotropic GGX one with a textured
/// diffuse reflectance and a tinted specular one, a textured ground.
#[test]
fn pplastic() {
    check_repo_reference("pplastic");
}

/// `principledthin`: a rough anisotropic spec_trans sheet (spec_tint, eta), a diffuse
/// transmission sheet with sheen and flatness (textured base colour), a sphere with bitmap
/// spec_trans and roughness, a thin ground; the sheets backlit.
#[test]
fn principledthin() {
    check_repo_reference("principledthin");
}
