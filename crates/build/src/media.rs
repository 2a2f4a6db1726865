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
            };
            MediumKind::Heterogeneous(Box::new(Heterogeneous::new(
                density, albedo, *scale, to_world,
            )))
        }
    };
    let phase = match m.phase {
        PhaseDesc::Isotropic => Phase::Isotropic,
        PhaseDesc::HenyeyGreenstein { g } => Phase::HenyeyGreenstein { g },
    };
    Ok(Medium { kind, phase })
}

fn max_abs(m: &Mat4) -> f32 {
    m.to_cols_array().iter().fold(0.0f32, |a, v| a.max(v.abs()))
}

/// A grid and the map from its `[0,1]³` to the world: the scene's `to_world` for a `.vol`
/// (the grid fills the unit cube of its space); for a `.vdb`, the scene's `to_world` after
/// the map from the densified grid's `[0,1]³` to the VDB grid's own local space.
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
        VolumeFormat::Vdb { grid_name } => {
            let (grid, local_from_unit) = VoxelGrid::read_vdb(&v.path, grid_name, v.trilinear)
                .map_err(|e| fail(e.to_string()))?;
            (grid, v.to_world * local_from_unit)
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
