//! Medium factories: scene media to runtime ones, reading their grids.

use render::math::{Mat4, Vec3};
use render::media::grid::VoxelGrid;
use render::media::heterogeneous::Albedo;
use render::media::{Heterogeneous, Homogeneous, Medium, MediumKind, Phase};
use scene::{MediumDesc, PhaseDesc, SceneDesc, VolumeDesc, VolumeFormat, VolumeParam};

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
    Ok(Medium { kind, phase })
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
