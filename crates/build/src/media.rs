//! Medium factories: scene media to runtime ones, reading their grids.

use render::math::{Mat4, Vec3};
use render::media::grid::VoxelGrid;
use render::media::heterogeneous::Albedo;
use render::media::{
    Blackbody, Emission, EmissionSampler, Heterogeneous, Homogeneous, Medium, MediumKind, Phase,
};
use scene::spectra::{SpectrumUse, planck, sampled_to_rgb};
use scene::{
    MediumDesc, MediumEmission, PhaseDesc, SceneDesc, VolumeDesc, VolumeFormat, VolumeParam,
};

use crate::BuildError;

/// The runtime media of `desc`, in order.
pub(crate) fn media(desc: &SceneDesc) -> Result<Vec<Medium>, BuildError> {
    desc.media.iter().map(medium).collect()
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
            let density = grid(sigma_t)?;
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
                VolumeParam::Grid(g) => Albedo::Grid(grid(g)?),
            };
            MediumKind::Heterogeneous(Box::new(Heterogeneous::new(
                density,
                albedo,
                *scale,
                to_world(sigma_t)?,
            )))
        }
    };
    let phase = match m.phase {
        PhaseDesc::Isotropic => Phase::Isotropic,
        PhaseDesc::HenyeyGreenstein { g } => Phase::HenyeyGreenstein { g },
    };
    let emission = match &m.emission {
        None => None,
        Some(MediumEmission::Radiance(VolumeParam::Const(le))) => {
            Some(Emission::Const((*le).into()))
        }
        Some(MediumEmission::Radiance(VolumeParam::Grid(g))) => Some(Emission::Grid {
            grid: grid(g)?,
            to_grid: to_world(g)?.inverse(),
            blackbody: None,
        }),
        Some(MediumEmission::Temperature { grid: g, scale }) => Some(Emission::Grid {
            grid: grid(g)?,
            to_grid: to_world(g)?.inverse(),
            blackbody: Some(blackbody(*scale)),
        }),
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
    Blackbody { table, step: STEP }
}

fn to_world(v: &VolumeDesc) -> Result<Mat4, BuildError> {
    let det = v.to_world.determinant();
    if det == 0.0 || !det.is_finite() {
        return Err(BuildError {
            loc: v.loc.clone(),
            message: "the grid's to_world transform is singular or not finite".into(),
        });
    }
    Ok(v.to_world)
}

fn grid(v: &VolumeDesc) -> Result<VoxelGrid, BuildError> {
    let fail = |message: String| BuildError {
        loc: v.loc.clone(),
        message,
    };
    match &v.format {
        VolumeFormat::MitsubaVol => {
            VoxelGrid::read_vol(&v.path, v.trilinear).map_err(|e| fail(e.to_string()))
        }
        VolumeFormat::Vdb { grid_name } => Err(fail(format!(
            "{}: OpenVDB grids ('{grid_name}') are not readable yet; convert the grid to a Mitsuba .vol file",
            v.path.display()
        ))),
    }
}
