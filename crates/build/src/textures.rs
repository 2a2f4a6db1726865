//! Texture factories: decoded images and procedural textures, and opacity masks read from
//! an image's alpha channel.

use std::sync::Arc;

use render::image_io::{self, Decode};
use render::math::Vec3;
use render::shapes::ShapeInfo;
use render::textures::{MipMap, TexRef, Texture};

use scene::{SceneDesc, TextureFilter};

use crate::BuildError;

/// An opacity read from a bitmap whose file has an alpha channel uses that channel (an RGBA
/// `map_d`, or the diffuse map itself as exporters write it); files without one use their
/// first channel, as any scalar texture does. The alpha textures are appended to `textures`.
/// `alphas` keeps the alpha channel read for each scene texture (`None`: opaque, or not a
/// bitmap), so that a later build of the same scene does not read the file again.
pub(crate) fn opacity_from_alpha(
    desc: &SceneDesc,
    shapes: &mut [ShapeInfo],
    textures: &mut Vec<Texture>,
    alphas: &mut std::collections::HashMap<u32, Option<Texture>>,
) -> Result<(), BuildError> {
    let mut alpha_of: std::collections::HashMap<u32, Option<u32>> = Default::default();
    for shape in shapes.iter_mut() {
        let Some(TexRef::Texture(t)) = &mut shape.opacity else {
            continue;
        };
        let id = match alpha_of.get(t) {
            Some(id) => *id,
            None => {
                let alpha = match alphas.get(t) {
                    Some(a) => a.clone(),
                    None => {
                        let a = alpha_texture(&desc.textures[*t as usize])?;
                        alphas.insert(*t, a.clone());
                        a
                    }
                };
                let id = alpha.map(|tex| {
                    textures.push(tex);
                    textures.len() as u32 - 1
                });
                alpha_of.insert(*t, id);
                id
            }
        };
        if let Some(id) = id {
            *t = id;
        }
    }
    Ok(())
}

/// The alpha channel of a bitmap texture as a texture, if the file has a non-opaque one.
fn alpha_texture(desc: &scene::TextureDesc) -> Result<Option<Texture>, BuildError> {
    let scene::Texture::Bitmap {
        path,
        filter,
        wrap,
        to_uv,
        corner_texels,
        ..
    } = &desc.texture
    else {
        return Ok(None);
    };
    let (mut image, alpha) =
        image_io::read_image_alpha(path, Decode::Raw).map_err(|e| BuildError {
            loc: desc.loc.clone(),
            message: format!("cannot read texture: {e}"),
        })?;
    if alpha.iter().all(|&a| a >= 1.0) {
        return Ok(None);
    }
    for (p, a) in image.pixels.iter_mut().zip(alpha) {
        *p = Vec3::splat(a);
    }
    Ok(Some(Texture::Bitmap {
        image: Arc::new(image),
        filter: *filter,
        wrap: *wrap,
        to_uv: *to_uv,
        corner_texels: *corner_texels,
        mips: None,
    }))
}

pub(crate) fn load_texture(desc: &scene::TextureDesc) -> Result<Texture, BuildError> {
    load_texture_kind(&desc.texture, desc)
}

fn load_texture_kind(
    texture: &scene::Texture,
    desc: &scene::TextureDesc,
) -> Result<Texture, BuildError> {
    Ok(match texture {
        scene::Texture::Constant(c) => Texture::Constant((*c).into()),
        scene::Texture::Checkerboard {
            color0,
            color1,
            to_uv,
        } => Texture::Checkerboard {
            color0: (*color0).into(),
            color1: (*color1).into(),
            to_uv: *to_uv,
        },
        scene::Texture::Bitmap {
            path,
            filter,
            wrap,
            raw,
            gamma,
            to_uv,
            corner_texels,
            mipmapped,
        } => {
            // Loaders resolve file names (absolute, or relative to the working directory).
            let decode = match (raw, gamma) {
                (true, _) => Decode::Raw,
                (false, Some(g)) => Decode::Gamma(*g),
                (false, None) => Decode::Srgb,
            };
            let image = image_io::read_image_with(path, decode).map_err(|e| BuildError {
                loc: desc.loc.clone(),
                message: format!("cannot read texture: {e}"),
            })?;
            let mips = (*mipmapped
                || matches!(filter, TextureFilter::Trilinear | TextureFilter::Ewa))
            .then(|| Arc::new(MipMap::new(&image, *wrap)));
            Texture::Bitmap {
                image: Arc::new(image),
                filter: *filter,
                wrap: *wrap,
                to_uv: *to_uv,
                corner_texels: *corner_texels,
                mips,
            }
        }
        scene::Texture::Perlin { scale, conversion } => Texture::Perlin {
            scale: *scale,
            conversion: *conversion,
        },
        scene::Texture::SolidChecker {
            black,
            white,
            scale,
            offset,
        } => Texture::SolidChecker {
            black: (*black).into(),
            white: (*white).into(),
            scale: *scale,
            offset: *offset,
        },
        scene::Texture::Affine {
            texture,
            scale,
            offset,
        } => Texture::Affine {
            texture: Box::new(load_texture_kind(texture, desc)?),
            scale: *scale,
            offset: (*offset).into(),
        },
        scene::Texture::Product { a, b } => Texture::Product(Box::new([
            load_texture_kind(a, desc)?,
            load_texture_kind(b, desc)?,
        ])),
        scene::Texture::Mix { a, b, amount } => Texture::Mix(Box::new([
            load_texture_kind(a, desc)?,
            load_texture_kind(b, desc)?,
            load_texture_kind(amount, desc)?,
        ])),
        scene::Texture::Bilerp {
            v00,
            v01,
            v10,
            v11,
            to_uv,
        } => Texture::Bilerp {
            corners: [*v00, *v10, *v01, *v11].map(Into::into),
            to_uv: *to_uv,
        },
        scene::Texture::Checker3D { a, b, to_texture } => Texture::Checker3D {
            textures: Box::new([load_texture_kind(a, desc)?, load_texture_kind(b, desc)?]),
            to_texture: *to_texture,
        },
        scene::Texture::Dots {
            inside,
            outside,
            to_uv,
        } => Texture::Dots {
            textures: Box::new([
                load_texture_kind(inside, desc)?,
                load_texture_kind(outside, desc)?,
            ]),
            to_uv: *to_uv,
        },
        scene::Texture::Noise { kind, to_texture } => Texture::Noise {
            kind: *kind,
            to_texture: *to_texture,
        },
    })
}
