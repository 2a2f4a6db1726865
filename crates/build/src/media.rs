//! Medium factories: scene media to runtime ones, reading their grids; and the media that
//! Beer–Lambert absorption inside dielectrics becomes ([`beer_media`]).

use render::math::{Mat4, Vec3};
use render::media::grid::VoxelGrid;
use render::media::heterogeneous::Albedo;
use std::sync::Arc;

use render::media::phase::{BlendPhase, SggxPhase, TabulatedPhase};
use render::media::{
    Blackbody, Emission, EmissionSampler, Heterogeneous, Homogeneous, Medium, MediumKind, Phase,
};
use scene::spectra::{SpectrumUse, planck, sampled_to_rgb};
use scene::{
    MaterialDesc, MaterialId, MediumDesc, MediumEmission, PhaseDesc, SceneDesc, SubsurfaceMedium,
    VolumeDesc, VolumeFormat, VolumeParam,
};

use crate::BuildError;
use crate::materials::{Interior, interior_of};

/// The runtime media of `desc`, in order.
pub(crate) fn media(desc: &SceneDesc) -> Result<Vec<Medium>, BuildError> {
    desc.media.iter().map(medium).collect()
}

/// The media that materials put inside their shapes, appended to `media`: for Beer–Lambert
/// absorption of dielectrics one purely absorbing homogeneous medium ([`Medium::absorbing`],
/// σt = σ exactly) per material that declares a coefficient; for a `subsurface` material its
/// homogeneous scattering medium (σt = σa + σs, albedo σs/σt, Henyey–Greenstein g). Returns,
/// per material, the medium inside the shapes that use it: the one of the material it is or
/// wraps (see [`interior_of`]), shared by every wrapper around that material.
pub(crate) fn interior_media(
    materials: &[MaterialDesc],
    media: &mut Vec<Medium>,
) -> Vec<Option<u32>> {
    let mut own: Vec<Option<u32>> = vec![None; materials.len()];
    (0..materials.len() as u32)
        .map(|id| {
            let (leaf, interior) = interior_of(materials, MaterialId(id))?;
            Some(*own[leaf.0 as usize].get_or_insert_with(|| {
                media.push(match interior {
                    Interior::Beer(sigma) => Medium::absorbing(sigma.into()),
                    Interior::Subsurface(m) => subsurface_medium(m),
                });
                media.len() as u32 - 1
            }))
        })
        .collect()
}

/// The homogeneous medium of a subsurface material.
pub(crate) fn subsurface_medium(m: &SubsurfaceMedium) -> Medium {
    let (a, s) = m.sigma();
    let t = a + s;
    let ratio = |s: f32, t: f32| if t > 0.0 { (s / t).min(1.0) } else { 0.0 };
    let albedo = scene::Rgb::new(ratio(s.x, t.x), ratio(s.y, t.y), ratio(s.z, t.z));
    Medium {
        kind: MediumKind::Homogeneous(Homogeneous::new(t.into(), albedo.into())),
        phase: if m.g == 0.0 {
            Phase::Isotropic
        } else {
            Phase::HenyeyGreenstein { g: m.g }
        },
        emission: None,
        emission_sampler: None,
    }
}

fn medium(m: &MediumDesc) -> Result<Medium, BuildError> {
    let kind = match &m.medium {
        scene::Medium::Homogeneous {
            sigma_t,
            albedo,
            scale,
        } => MediumKind::Homogeneous(Homogeneous::new(
            Vec3::from(*sigma_t) * *scale,
            (*albedo).into(),
        )),
        scene::Medium::Heterogeneous {
            sigma_t,
            albedo,
            scale,
        } => {
            let (density, to_world) = grid(sigma_t)?;
            if density.channels != 1 {
                return Err(BuildError {
                    loc: sigma_t.loc.clone(),
                    message: format!(
                        "{}: a sigma_t grid must have one channel (it has {})",
                        sigma_t.path.display(),
                        density.channels
                    ),
                });
            }
            let albedo = match albedo {
                VolumeParam::Const(a) => Albedo::Const((*a).into()),
                VolumeParam::Grid(g) => {
                    // The medium looks both grids up at the same grid-space point.
                    let (albedo, albedo_to_world) = grid(g)?;
                    if !albedo_to_world.abs_diff_eq(to_world, 1e-5 * max_abs(&to_world)) {
                        return Err(BuildError {
                            loc: g.loc.clone(),
                            message: format!(
                                "{}: an albedo grid must cover the same box of the world as the sigma_t grid ({})",
                                g.path.display(),
                                sigma_t.path.display()
                            ),
                        });
                    }
                    Albedo::Grid(albedo)
                }
                VolumeParam::SigmaSGrid(g) => {
                    // Interpolated at the same grid-space point as σt, then divided by it.
                    let (sigma_s, s_to_world) = grid(g)?;
                    if sigma_s.res != density.res
                        || sigma_s.zero_outside != density.zero_outside
                        || !s_to_world.abs_diff_eq(to_world, 1e-5 * max_abs(&to_world))
                    {
                        return Err(BuildError {
                            loc: g.loc.clone(),
                            message: format!(
                                "{}: a sigma_s grid must have the lattice and box of the sigma_t grid",
                                g.path.display()
                            ),
                        });
                    }
                    Albedo::Ratio(sigma_s)
                }
            };
            MediumKind::Heterogeneous(Box::new(Heterogeneous::new(
                density, albedo, *scale, to_world,
            )))
        }
    };
    let phase = phase(&m.phase).map_err(|message| BuildError {
        loc: m.loc.clone(),
        message,
    })?;
    if phase.is_microflake() && !matches!(kind, MediumKind::Homogeneous(_)) {
        // Its extinction σt·σ(ω) along a ray through a grid is not a scaled distance.
        return Err(BuildError {
            loc: m.loc.clone(),
            message: "phase 'sggx' is supported in homogeneous media only".into(),
        });
    }
    let emission = match &m.emission {
        None => None,
        Some(MediumEmission::Radiance(VolumeParam::Const(le))) => {
            Some(Emission::Const((*le).into()))
        }
        Some(MediumEmission::Radiance(VolumeParam::SigmaSGrid(g))) => {
            return Err(BuildError {
                loc: g.loc.clone(),
                message: "a sigma_s grid is not a radiance".into(),
            });
        }
        Some(MediumEmission::Radiance(VolumeParam::Grid(g))) => {
            let (grid, to_world) = grid(g)?;
            Some(Emission::Grid {
                grid,
                to_grid: to_world.inverse(),
                blackbody: None,
            })
        }
        Some(MediumEmission::Temperature { grid: g, scale }) => {
            let (grid, to_world) = grid(g)?;
            Some(Emission::Grid {
                grid,
                to_grid: to_world.inverse(),
                blackbody: Some(blackbody(*scale)),
            })
        }
    };
    let emission_sampler = match &emission {
        Some(Emission::Grid {
            grid,
            to_grid,
            blackbody,
        }) => {
            let lum = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
            EmissionSampler::new(grid, to_grid.inverse(), |i| {
                let v = i * grid.channels;
                match blackbody {
                    Some(b) => lum(b.rgb(grid.data[v])),
                    None if grid.channels == 3 => {
                        lum(Vec3::new(grid.data[v], grid.data[v + 1], grid.data[v + 2]))
                    }
                    None => grid.data[v],
                }
            })
        }
        _ => None,
    };
    Ok(Medium {
        kind,
        phase,
        emission,
        emission_sampler,
    })
}

/// Black-body radiance (Planck, Mitsuba's `blackbody` units) projected to linear sRGB as
/// Mitsuba projects emission spectra, every 25 K up to 20,000 K, times `scale`.
fn blackbody(scale: f32) -> Blackbody {
    const STEP: f32 = 25.0;
    let lambdas: Vec<f64> = (0..=94).map(|i| 360.0 + 5.0 * i as f64).collect();
    let table = (0..=800)
        .map(|i| {
            let kelvin = i as f64 * STEP as f64;
            if kelvin <= 0.0 {
                return Vec3::ZERO;
            }
            let values: Vec<f64> = lambdas.iter().map(|&l| planck(l, kelvin)).collect();
            sampled_to_rgb(&lambdas, &values, SpectrumUse::Emission).map_or(Vec3::ZERO, Vec3::from)
                * scale
        })
        .collect();
    Blackbody {
        table,
        step: STEP,
        scale,
    }
}

fn max_abs(m: &Mat4) -> f32 {
    m.to_cols_array().iter().fold(0.0f32, |a, v| a.max(v.abs()))
}

/// A grid and the map from its `[0,1]³` to the world: the scene's `to_world` for a `.vol`
/// or an inline grid (the grid fills the unit cube of its space; an inline grid reads 0
/// beyond its voxels, as pbrt-v4's `SampledGrid` does); for a `.vdb`, the scene's `to_world` after
/// the map from the densified grid's `[0,1]³` to the VDB grid's own local space, or (Nori's
/// bounding box, `own_map` false) directly.
fn grid(v: &VolumeDesc) -> Result<(VoxelGrid, Mat4), BuildError> {
    let fail = |message: String| BuildError {
        loc: v.loc.clone(),
        message,
    };
    let (grid, to_world) = match &v.format {
        VolumeFormat::MitsubaVol => (
            VoxelGrid::read_vol(&v.path, v.trilinear).map_err(|e| fail(e.to_string()))?,
            v.to_world,
        ),
        VolumeFormat::Vdb { grid_name, own_map } => {
            let (grid, local_from_unit) = VoxelGrid::read_vdb(&v.path, grid_name, v.trilinear)
                .map_err(|e| fail(e.to_string()))?;
            if *own_map {
                (grid, v.to_world * local_from_unit)
            } else {
                (grid, v.to_world)
            }
        }
        VolumeFormat::Inline {
            res,
            channels,
            data,
        } => {
            let count = res.iter().try_fold(*channels, |a, &r| a.checked_mul(r));
            if !matches!(channels, 1 | 3) || count != Some(data.len()) || data.is_empty() {
                return Err(fail(format!(
                    "an inline grid of {res:?} voxels × {channels} channels cannot hold {} values",
                    data.len()
                )));
            }
            if let Some(bad) = data.iter().find(|x| !x.is_finite() || **x < 0.0) {
                return Err(fail(format!(
                    "inline grid value {bad}: values must be finite and ≥ 0"
                )));
            }
            let grid = VoxelGrid {
                res: *res,
                channels: *channels,
                data: data.to_vec(),
                trilinear: true,
                zero_outside: true,
            };
            (grid, v.to_world)
        }
    };
    let det = to_world.determinant();
    if det == 0.0 || !det.is_finite() {
        return Err(fail(
            "the grid's to_world transform is singular or not finite".into(),
        ));
    }
    Ok((grid, to_world))
}

/// The renderer's phase function for `p`; an error for a table that is not a density, and
/// for an SGGX S grid that cannot be read, varies over space or is not positive definite.
fn phase(p: &PhaseDesc) -> Result<Phase, String> {
    Ok(match p {
        PhaseDesc::Isotropic => Phase::Isotropic,
        &PhaseDesc::HenyeyGreenstein { g } => Phase::HenyeyGreenstein { g },
        PhaseDesc::Rayleigh => Phase::Rayleigh,
        PhaseDesc::Tabulated { values } => {
            Phase::Tabulated(Arc::new(TabulatedPhase::new(values).ok_or_else(|| {
                "a tabulated phase function needs at least two non-negative values, not all \
                 zero"
                    .to_string()
            })?))
        }
        PhaseDesc::Sggx { s_grid } => {
            let g = VoxelGrid::read_vol_of(s_grid, false, &[6]).map_err(|e| e.to_string())?;
            let first: [f32; 6] = std::array::from_fn(|c| g.data[c]);
            if g.data.chunks_exact(6).any(|v| v != first) {
                // Phase functions are evaluated without the point (Mitsuba reads S there).
                return Err(format!(
                    "{}: phase 'sggx' with an S that varies over space is not supported (only \
                     a constant S: every voxel equal)",
                    s_grid.display()
                ));
            }
            Phase::Sggx(Arc::new(SggxPhase::new(first).ok_or_else(|| {
                format!(
                    "phase 'sggx': S = {first:?} (S_xx, S_yy, S_zz, S_xy, S_xz, S_yz) is not \
                     positive definite"
                )
            })?))
        }
        PhaseDesc::Blend { weight, phases } => Phase::Blend(Arc::new(BlendPhase {
            weight: weight.clamp(0.0, 1.0),
            first: phase(&phases[0])?,
            second: phase(&phases[1])?,
        })),
    })
}
