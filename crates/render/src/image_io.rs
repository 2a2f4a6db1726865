//! Reading and writing images: OpenEXR, Radiance HDR, PFM, PNG (and, for reading, JPEG, TGA,
//! BMP).
//!
//! All images in memory are linear RGB ([`Image`]). The file format decides the encoding:
//! - `.exr`: 32-bit float RGB, written scan-line based with ZIP (16 lines) compression, so a
//!   round trip is bit-exact. Reading takes the first layer holding R, G and B channels (any
//!   sample type), with A when present.
//! - `.pfm`: the Portable Float Map: a text header `PF` (`Pf` for grey), `width height`, and a
//!   scale whose sign gives the byte order (negative = little endian), then the rows **from
//!   bottom to top** as raw f32. We write little-endian RGB; we read both byte orders and grey.
//!   Round trips are bit-exact.
//! - `.hdr`: Radiance RGBE (8-bit shared exponent, ~1 % precision). Negative and NaN values are
//!   written as 0, values are clamped to 1e38.
//! - `.png` (write and read), `.jpg`/`.jpeg`, `.tga`, `.bmp` (read): 8- or 16-bit integers,
//!   by default sRGB-encoded. Writing clamps to [0, 1], applies the exact sRGB OETF (IEC
//!   61966-2-1, linear segment below 0.0031308) and rounds to the nearest 8-bit code; reading
//!   applies the inverse, or another curve chosen with [`Decode`].
//!
//! Writes are atomic: the encoded bytes go to a uniquely named temporary file in the target's
//! directory (`.NAME.tmp-PID-N`), which is flushed to disk and then renamed over the target.
//! On any error the temporary file is removed, so a crash or a full disk never leaves a
//! half-written image under the target name.

use std::ffi::OsString;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Cursor, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::film::Image;
use crate::math::Vec3;

/// Errors of reading or writing an image. Every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The file name's extension is not a format we can write (or read).
    #[error("{path}: unsupported image format {ext:?} (expected {expected})", path = .path.display())]
    Unsupported {
        path: PathBuf,
        ext: String,
        expected: &'static str,
    },
    /// The file could not be opened, read, written or renamed.
    #[error("{path}: {source}", path = .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// The file's contents are not a valid image of its format.
    #[error("{path}: cannot decode image: {message}", path = .path.display())]
    Decode { path: PathBuf, message: String },
    /// The image cannot be stored in the requested format (e.g. it is empty or its pixel
    /// vector does not match its size).
    #[error("{path}: cannot encode image: {message}", path = .path.display())]
    Encode { path: PathBuf, message: String },
}

impl ImageError {
    fn io(path: &Path, source: io::Error) -> ImageError {
        ImageError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    fn decode(path: &Path, message: impl ToString) -> ImageError {
        ImageError::Decode {
            path: path.to_path_buf(),
            message: message.to_string(),
        }
    }
    fn encode(path: &Path, message: impl ToString) -> ImageError {
        ImageError::Encode {
            path: path.to_path_buf(),
            message: message.to_string(),
        }
    }
}

/// How integer (8/16-bit) images are turned into linear values. Float formats (EXR, HDR, PFM)
/// are always read as stored.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Decode {
    /// The sRGB EOTF (the default: PNG/JPEG files without other information are sRGB).
    #[default]
    Srgb,
    /// A pure power law: linear = code^g (e.g. `Gamma(2.2)`).
    Gamma(f32),
    /// No conversion: linear = code / max code (for normal maps, roughness maps, masks).
    Raw,
}

impl Decode {
    /// Decodes a normalized code value in [0, 1].
    #[inline]
    pub fn apply(self, v: f32) -> f32 {
        match self {
            Decode::Srgb => srgb_to_linear(v),
            Decode::Gamma(g) => v.max(0.0).powf(g),
            Decode::Raw => v,
        }
    }
}

/// The sRGB OETF (linear → encoded), IEC 61966-2-1. Not clamped.
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The sRGB EOTF (encoded → linear), IEC 61966-2-1. Not clamped.
#[inline]
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value → 8-bit sRGB code: clamp to [0, 1] (NaN → 0), OETF, round to nearest.
#[inline]
pub fn linear_to_srgb8(v: f32) -> u8 {
    let v = if v > 0.0 { v.min(1.0) } else { 0.0 };
    (linear_to_srgb(v) * 255.0 + 0.5) as u8
}

/// Reads an image as linear RGB; integer formats are decoded from sRGB.
pub fn read_image(path: &Path) -> Result<Image, ImageError> {
    read_image_with(path, Decode::Srgb)
}

/// Reads an image as linear RGB, decoding integer formats with `decode`.
pub fn read_image_with(path: &Path, decode: Decode) -> Result<Image, ImageError> {
    read_image_alpha(path, decode).map(|(image, _)| image)
}

/// Reads an image and its alpha channel (1 where the file has none). Alpha is never decoded
/// (it is linear coverage in every format).
pub fn read_image_alpha(path: &Path, decode: Decode) -> Result<(Image, Vec<f32>), ImageError> {
    let bytes = base::read_file(path).map_err(|e| ImageError::io(path, e))?;
    if bytes.starts_with(&EXR_MAGIC) {
        return read_exr(path, bytes);
    }
    if bytes.starts_with(b"PF") || bytes.starts_with(b"Pf") {
        return read_pfm(path, &bytes);
    }
    match extension(path).as_str() {
        "exr" | "pfm" => Err(ImageError::decode(
            path,
            "not an EXR/PFM file (bad magic number)",
        )),
        _ => read_with_image_crate(path, bytes, decode),
    }
}

/// Like [`write_image`], but 8-bit outputs (PNG) go through `tonemap` when one is given;
/// linear outputs (EXR, PFM, HDR) are written unchanged.
pub fn write_image_tonemapped(
    path: &Path,
    img: &Image,
    tonemap: Option<&base::Tonemap>,
) -> Result<(), ImageError> {
    match tonemap {
        Some(base::Tonemap::DisplayUnits) if extension(path) == "png" && !img.pixels.is_empty() => {
            // The radiance already is the 8-bit value: round and clamp it, nothing else.
            let quantize = |v: f32| (v.clamp(0.0, 255.0) + 0.5) as u8;
            let bytes = encode_png_with(img, quantize).map_err(|e| ImageError::encode(path, e))?;
            write_atomically(path, &bytes)
        }
        Some(tm) if extension(path) == "png" && !img.pixels.is_empty() => {
            let display = crate::film::tonemap::apply(img, tm);
            let quantize = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            let bytes =
                encode_png_with(&display, quantize).map_err(|e| ImageError::encode(path, e))?;
            write_atomically(path, &bytes)
        }
        _ => write_image(path, img),
    }
}

/// Writes `img` in the format given by the file extension (`.exr`, `.png`, `.pfm`, `.hdr`),
/// atomically (see the module documentation).
pub fn write_image(path: &Path, img: &Image) -> Result<(), ImageError> {
    let n = img.width as usize * img.height as usize;
    if img.width == 0 || img.height == 0 {
        return Err(ImageError::encode(path, "the image is empty"));
    }
    if img.pixels.len() != n {
        return Err(ImageError::encode(
            path,
            format!(
                "{} pixels for a {}x{} image",
                img.pixels.len(),
                img.width,
                img.height
            ),
        ));
    }
    let bytes = match extension(path).as_str() {
        "exr" => encode_exr(img, true).map_err(|e| ImageError::encode(path, e))?,
        "png" => encode_png(img).map_err(|e| ImageError::encode(path, e))?,
        "pfm" => encode_pfm(img),
        "hdr" => encode_hdr(img).map_err(|e| ImageError::encode(path, e))?,
        ext => {
            return Err(ImageError::Unsupported {
                path: path.to_path_buf(),
                ext: ext.to_string(),
                expected: ".exr, .png, .pfm or .hdr",
            });
        }
    };
    write_atomically(path, &bytes)
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        ImageError::io(
            path,
            io::Error::new(io::ErrorKind::InvalidInput, "not a file name"),
        )
    })?;
    let mut tmp_name = OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(
        ".tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut file = OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)
    })();
    match result {
        Ok(()) => {
            remove_stale_temporaries(path, name);
            // Make the rename itself durable; failure here loses nothing already written.
            #[cfg(unix)]
            if let Some(dir) = path.parent() {
                let dir = if dir.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    dir
                };
                if let Ok(d) = File::open(dir) {
                    let _ = d.sync_all();
                }
            }
            Ok(())
        }
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(ImageError::io(path, e))
        }
    }
}

/// Remove the temporaries `.NAME.tmp-PID-N` of earlier writes to `path` whose process is
/// gone (a `kill -9` between create and rename left them for ever). Our own process's are
/// left alone (another thread may be writing), and so is everything where liveness cannot be
/// told (no `/proc`).
fn remove_stale_temporaries(path: &Path, name: &std::ffi::OsStr) {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let prefix = format!(".{}.tmp-", name.to_string_lossy());
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let me = std::process::id();
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(rest) = file_name.to_str().and_then(|f| f.strip_prefix(&prefix)) else {
            continue;
        };
        let Some((pid, counter)) = rest.split_once('-') else {
            continue;
        };
        let (Ok(pid), Ok(_)) = (pid.parse::<u32>(), counter.parse::<u64>()) else {
            continue;
        };
        if pid != me && !proc.join(pid.to_string()).exists() {
            let _ = fs::remove_file(entry.path());
        }
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

// ---------------------------------------------------------------------------------------------
// OpenEXR

const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Largest decoded image accepted (16384² pixels): a corrupt header must not make us
/// allocate what it claims.
const MAX_IMAGE_PIXELS: usize = 1 << 28;
/// Above this many decoded bytes, an image must not claim more than this many times its file
/// size (real compressed EXRs stay far below; a damaged header claiming gigapixels does not).
const MAX_EXPANSION: usize = 256;

/// Refuse a claimed `w × h` image of `bytes_per_pixel` decoded bytes before allocating it.
fn check_claimed_size(
    path: &Path,
    w: usize,
    h: usize,
    bytes_per_pixel: usize,
    file_len: usize,
) -> Result<(), ImageError> {
    let pixels = w.saturating_mul(h);
    let decoded = pixels.saturating_mul(bytes_per_pixel);
    if pixels > MAX_IMAGE_PIXELS || (decoded > 64 << 20 && decoded / MAX_EXPANSION > file_len) {
        return Err(ImageError::decode(
            path,
            format!(
                "the header claims a {w}x{h} image ({decoded} bytes decoded) in a file of \
                 {file_len} bytes: refused as corrupt or too large"
            ),
        ));
    }
    Ok(())
}

fn read_exr(path: &Path, bytes: Vec<u8>) -> Result<(Image, Vec<f32>), ImageError> {
    use exr::prelude::*;
    // The headers first: the decoder below allocates what the largest layer claims.
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes[..]), false)
        .map_err(|e| ImageError::decode(path, e))?;
    for h in &meta.headers {
        let size = h.layer_size;
        let channels = h.channels.list.len().max(4);
        check_claimed_size(path, size.width(), size.height(), channels * 4, bytes.len())?;
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size: Vec2<usize>, _: &RgbaChannels| (size, vec![[0.0f32; 4]; size.area()]),
            |(size, px): &mut (Vec2<usize>, Vec<[f32; 4]>),
             pos: Vec2<usize>,
             (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * size.width() + pos.x()] = [r, g, b, a];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| ImageError::decode(path, e))?;
    let (size, px) = image.layer_data.channel_data.pixels;
    let (width, height) = checked_size(path, size.width(), size.height())?;
    let pixels = px.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let alpha = px.iter().map(|p| p[3]).collect();
    Ok((
        crate::film::Image {
            width,
            height,
            pixels,
        },
        alpha,
    ))
}

/// The EXR bytes of `img` (ZIP, 16-line blocks), compressed on a thread pool of the exr
/// crate's with `parallel`: the blocks are written in increasing line order whichever thread
/// finishes first, so the bytes are the sequential encoder's.
fn encode_exr(img: &Image, parallel: bool) -> Result<Vec<u8>, exr::error::Error> {
    use exr::prelude::*;
    let w = img.width as usize;
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = img.pixels[pos.y() * w + pos.x()];
        (p.x, p.y, p.z)
    });
    let layer = Layer::new(
        (w, img.height as usize),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    let mut out = Cursor::new(Vec::new());
    let image = Image::from_layer(layer);
    if parallel {
        image.write().to_buffered(&mut out)?;
    } else {
        image.write().non_parallel().to_buffered(&mut out)?;
    }
    Ok(out.into_inner())
}

fn checked_size(path: &Path, w: usize, h: usize) -> Result<(u32, u32), ImageError> {
    match (u32::try_from(w), u32::try_from(h)) {
        (Ok(w), Ok(h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(ImageError::decode(path, format!("bad image size {w}x{h}"))),
    }
}

// ---------------------------------------------------------------------------------------------
// PFM

fn read_pfm(path: &Path, bytes: &[u8]) -> Result<(Image, Vec<f32>), ImageError> {
    let bad = |m: &str| ImageError::decode(path, format!("PFM: {m}"));
    // Header: three whitespace-separated tokens after the magic, then exactly one whitespace
    // byte before the raster.
    let mut pos = 0;
    let mut token = || -> Option<&[u8]> {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        (pos > start).then(|| &bytes[start..pos])
    };
    let magic = token().ok_or_else(|| bad("missing header"))?;
    let channels = match magic {
        b"PF" => 3,
        b"Pf" => 1,
        _ => return Err(bad("bad magic (expected PF or Pf)")),
    };
    let mut number = |what: &str| -> Result<String, ImageError> {
        token()
            .and_then(|t| std::str::from_utf8(t).ok())
            .map(str::to_owned)
            .ok_or_else(|| bad(&format!("missing {what}")))
    };
    let width: usize = number("width")?.parse().map_err(|_| bad("bad width"))?;
    let height: usize = number("height")?.parse().map_err(|_| bad("bad height"))?;
    let scale: f32 = number("scale")?.parse().map_err(|_| bad("bad scale"))?;
    if scale == 0.0 || scale.is_nan() {
        return Err(bad("scale must be non-zero"));
    }
    let little_endian = scale < 0.0;
    let start = pos + 1; // the single whitespace byte ending the header
    let (w32, h32) = checked_size(path, width, height)?;
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels * 4))
        .ok_or_else(|| bad("image too large"))?;
    if bytes.len() < start || bytes.len() - start < expected {
        return Err(bad(&format!(
            "truncated raster ({} bytes, expected {expected})",
            bytes.len().saturating_sub(start)
        )));
    }
    let raster = &bytes[start..start + expected];
    let value = |i: usize| {
        let b = [
            raster[4 * i],
            raster[4 * i + 1],
            raster[4 * i + 2],
            raster[4 * i + 3],
        ];
        if little_endian {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut pixels = Vec::with_capacity(width * height);
    for y in 0..height {
        let row = height - 1 - y; // rows are stored bottom to top
        for x in 0..width {
            let i = (row * width + x) * channels;
            pixels.push(if channels == 3 {
                Vec3::new(value(i), value(i + 1), value(i + 2))
            } else {
                Vec3::splat(value(i))
            });
        }
    }
    Ok((
        Image {
            width: w32,
            height: h32,
            pixels,
        },
        vec![1.0; width * height],
    ))
}

fn encode_pfm(img: &Image) -> Vec<u8> {
    let (w, h) = (img.width as usize, img.height as usize);
    let header = format!("PF\n{w} {h}\n-1.0\n");
    let mut out = Vec::with_capacity(header.len() + w * h * 12);
    out.extend_from_slice(header.as_bytes());
    for y in (0..h).rev() {
        for p in &img.pixels[y * w..(y + 1) * w] {
            for c in [p.x, p.y, p.z] {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// PNG, Radiance HDR and the other formats of the `image` crate

fn encode_png(img: &Image) -> image::ImageResult<Vec<u8>> {
    encode_png_with(img, linear_to_srgb8)
}

fn encode_png_with(img: &Image, quantize: fn(f32) -> u8) -> image::ImageResult<Vec<u8>> {
    use image::ImageEncoder;
    let data: Vec<u8> = img
        .pixels
        .iter()
        .flat_map(|p| [p.x, p.y, p.z].map(quantize))
        .collect();
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(
        &data,
        img.width,
        img.height,
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(out)
}

fn encode_hdr(img: &Image) -> image::ImageResult<Vec<u8>> {
    // RGBE stores non-negative values with an exponent in [-127, 127]: flush what it cannot
    // represent (negative, NaN, below 2^-127) to 0 and clamp the top.
    let rgbe_safe = |v: f32| if v >= 1e-38 { v.min(1e38) } else { 0.0 };
    let data: Vec<image::Rgb<f32>> = img
        .pixels
        .iter()
        .map(|p| image::Rgb([rgbe_safe(p.x), rgbe_safe(p.y), rgbe_safe(p.z)]))
        .collect();
    let mut out = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut out).encode(
        &data,
        img.width as usize,
        img.height as usize,
    )?;
    Ok(out)
}

fn read_with_image_crate(
    path: &Path,
    bytes: Vec<u8>,
    decode: Decode,
) -> Result<(Image, Vec<f32>), ImageError> {
    use image::DynamicImage as D;
    const EXPECTED: &str = ".exr, .pfm, .hdr, .png, .jpg, .tga or .bmp";
    let ext = extension(path);
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| ImageError::io(path, e))?;
    if reader.format().is_none() {
        // Content sniffing failed (TGA has no magic number): fall back to the extension.
        match image::ImageFormat::from_extension(&ext) {
            Some(f) => reader.set_format(f),
            None => {
                return Err(ImageError::Unsupported {
                    path: path.to_path_buf(),
                    ext,
                    expected: EXPECTED,
                });
            }
        }
    }
    let dynamic = reader.decode().map_err(|e| match e {
        image::ImageError::Unsupported(_) => ImageError::Unsupported {
            path: path.to_path_buf(),
            ext: ext.clone(),
            expected: EXPECTED,
        },
        image::ImageError::IoError(e) => ImageError::io(path, e),
        e => ImageError::decode(path, e),
    })?;
    let (width, height) = checked_size(path, dynamic.width() as usize, dynamic.height() as usize)?;
    let n = width as usize * height as usize;
    let mut pixels = Vec::with_capacity(n);
    let mut alpha = Vec::with_capacity(n);
    match &dynamic {
        D::ImageRgb32F(_) | D::ImageRgba32F(_) => {
            // Float data (Radiance HDR) is linear already.
            for p in dynamic.to_rgba32f().pixels() {
                pixels.push(Vec3::new(p[0], p[1], p[2]));
                alpha.push(p[3]);
            }
        }
        D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageRgb8(_) | D::ImageRgba8(_) => {
            let lut: [f32; 256] = std::array::from_fn(|i| decode.apply(i as f32 / 255.0));
            for p in dynamic.to_rgba8().pixels() {
                pixels.push(Vec3::new(
                    lut[p[0] as usize],
                    lut[p[1] as usize],
                    lut[p[2] as usize],
                ));
                alpha.push(p[3] as f32 / 255.0);
            }
        }
        _ => {
            for p in dynamic.to_rgba32f().pixels() {
                pixels.push(Vec3::new(
                    decode.apply(p[0]),
                    decode.apply(p[1]),
                    decode.apply(p[2]),
                ));
                alpha.push(p[3]);
            }
        }
    }
    Ok((
        Image {
            width,
            height,
            pixels,
        },
        alpha,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parallel EXR encoder writes the sequential one's bytes (blocks in line order,
    /// whichever thread compressed them), and they read back as written.
    #[test]
    fn parallel_exr_is_the_sequential_bytes() {
        let (w, h) = (97u32, 301u32);
        let img = Image {
            width: w,
            height: h,
            pixels: (0..w * h)
                .map(|i| {
                    let x = (i as f32 * 0.618_034).fract();
                    Vec3::new(x, x * x * 40.0, (i % w) as f32 / w as f32)
                })
                .collect(),
        };
        let sequential = encode_exr(&img, false).unwrap();
        for _ in 0..3 {
            assert!(encode_exr(&img, true).unwrap() == sequential);
        }
        let (back, _) = read_exr(Path::new("test.exr"), sequential).unwrap();
        assert_eq!((back.width, back.height), (w, h));
        assert!(back.pixels == img.pixels);
    }

    #[test]
    fn srgb_pair_inverts_and_is_continuous() {
        for i in 0..=1000 {
            let v = i as f32 / 1000.0;
            assert!((srgb_to_linear(linear_to_srgb(v)) - v).abs() < 1e-6, "{v}");
        }
        // Both pieces meet at the breakpoints (continuity within f32 rounding).
        let t = 0.003_130_8f32;
        assert!((12.92 * t - (1.055 * t.powf(1.0 / 2.4) - 0.055)).abs() < 1e-6);
    }

    #[test]
    fn srgb8_rounds_and_clamps() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(7.0), 255);
        assert_eq!(linear_to_srgb8(f32::INFINITY), 255);
        // 18 % grey is sRGB code 117.5..118: 0.18 → 0.4613 → 117.63 → 118.
        assert_eq!(linear_to_srgb8(0.18), 118);
        // Every code decodes and re-encodes to itself.
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb_to_linear(c as f32 / 255.0)), c);
        }
    }

    #[test]
    fn pfm_rejects_truncated_and_bad_headers() {
        let p = Path::new("x.pfm");
        assert!(read_pfm(p, b"PF\n2 2\n-1.0\n\0\0\0\0").is_err());
        assert!(read_pfm(p, b"PF\n2\n").is_err());
        assert!(read_pfm(p, b"PF\n99999999999 99999999999\n-1.0\n").is_err());
        assert!(read_pfm(p, b"PF\n1 1\n0\n000000000000").is_err());
        assert!(read_pfm(p, b"PF\n0 1\n-1\n").is_err());
    }
}
