//! Denoising with Intel Open Image Denoise 2 (OIDN), the denoiser of Cycles, Blender, Arnold
//! and RenderMan, loaded at run time so that the default build and the tests need nothing new.
//!
//! The library is looked for in `$PENUMBRA_OIDN` (the library file or its folder) when it is
//! set, and only there; otherwise, in order: the system's loader path (`libOpenImageDenoise.so.2`, e.g. an OIDN release unpacked on
//! `LD_LIBRARY_PATH`); the official OIDN build inside the `pyoidn` wheel (`pip install
//! pyoidn`), in the Python `site-packages` folders of `$VIRTUAL_ENV`, `~/.local` and
//! `/usr/local` and, failing those, wherever `python3` finds `pyoidn`. OIDN's core loads its
//! CPU device from its own folder.
//!
//! One call runs the `RT` filter in OIDN's recommended setting for final frames: `hdr` on,
//! quality `high`; with auxiliary images, albedo and normal are first denoised by their own
//! `RT` filters (OIDN's "prefiltering") and the beauty filter is told `cleanAux`. Images go
//! in and out as our [`Image`]s, read in place (`Vec3A` pixels: 3 floats in a 16-byte stride).

use std::borrow::Cow;
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};

use crate::film::Image;
use crate::integrators::{Aov, Integrator};
use crate::render::render;
use crate::session::{RenderOptions, Silent};
use crate::world::Scene;

/// Why denoising is not available or failed.
#[derive(Debug, thiserror::Error)]
pub enum DenoiseError {
    #[error(
        "Open Image Denoise was not found (tried {tried}); install it with `pip install pyoidn` \
         or set PENUMBRA_OIDN to libOpenImageDenoise.so"
    )]
    NotFound { tried: String },
    #[error("Open Image Denoise at {path}: {message}")]
    Load { path: String, message: String },
    #[error("Open Image Denoise: {0}")]
    Oidn(String),
    #[error("denoise: {0}")]
    Input(String),
}

type Device = *mut c_void;
type Filter = *mut c_void;

const DEVICE_TYPE_DEFAULT: c_int = 0;
const FORMAT_FLOAT3: c_int = 3;
const QUALITY_HIGH: c_int = 6;
const ERROR_NONE: c_int = 0;

/// The C functions we call, resolved once.
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> Device,
    commit_device: unsafe extern "C" fn(Device),
    release_device: unsafe extern "C" fn(Device),
    device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> c_int,
    new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    set_image: unsafe extern "C" fn(
        Filter,
        *const c_char,
        *mut c_void,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    set_int: unsafe extern "C" fn(Filter, *const c_char, c_int),
    commit_filter: unsafe extern "C" fn(Filter),
    execute_filter: unsafe extern "C" fn(Filter),
    release_filter: unsafe extern "C" fn(Filter),
}

/// A loaded OIDN library.
pub struct Oidn {
    api: Api,
    path: PathBuf,
    // Keeps the code behind `api`'s pointers mapped; dropped last.
    _lib: libloading::Library,
}

/// What [`Oidn::denoise`] is given besides the beauty image.
#[derive(Clone, Copy, Default)]
pub struct Aux<'a> {
    /// Albedo of the first non-delta hit, in [0, 1].
    pub albedo: Option<&'a Image>,
    /// Shading normal of the first non-delta hit, in [-1, 1] (needs `albedo`, as in OIDN).
    pub normal: Option<&'a Image>,
    /// Denoise the auxiliary images first (OIDN's recommendation for final frames).
    pub prefilter: bool,
}

impl Oidn {
    /// Finds and loads the library (see the module docs for where it looks).
    pub fn load() -> Result<Oidn, DenoiseError> {
        let mut tried = Vec::new();
        for candidate in candidates() {
            tried.push(candidate.display().to_string());
            let exists = candidate.is_absolute() && candidate.exists();
            if candidate.is_absolute() && !exists {
                continue;
            }
            // SAFETY: loading a shared library runs its initialisers; OIDN's are the C++
            // runtime's and its device registry, which have no preconditions on us.
            match unsafe { libloading::Library::new(&candidate) } {
                Ok(lib) => return Self::bind(lib, candidate),
                Err(e) if exists => {
                    return Err(DenoiseError::Load {
                        path: candidate.display().to_string(),
                        message: e.to_string(),
                    });
                }
                Err(_) => {}
            }
        }
        Err(DenoiseError::NotFound {
            tried: tried.join(", "),
        })
    }

    fn bind(lib: libloading::Library, path: PathBuf) -> Result<Oidn, DenoiseError> {
        let load_err = |e: libloading::Error| DenoiseError::Load {
            path: path.display().to_string(),
            message: e.to_string(),
        };
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the symbol is OIDN 2's C API function of this name, whose signature
                // (from OpenImageDenoise/oidn.h) is the type the field declares; the pointer
                // stays valid while `_lib` is loaded, which outlives `api` in `Oidn`.
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }.map_err(load_err)?
            };
        }
        let api = Api {
            new_device: sym!("oidnNewDevice"),
            commit_device: sym!("oidnCommitDevice"),
            release_device: sym!("oidnReleaseDevice"),
            device_error: sym!("oidnGetDeviceError"),
            new_filter: sym!("oidnNewFilter"),
            set_image: sym!("oidnSetSharedFilterImage"),
            set_bool: sym!("oidnSetFilterBool"),
            set_int: sym!("oidnSetFilterInt"),
            commit_filter: sym!("oidnCommitFilter"),
            execute_filter: sym!("oidnExecuteFilter"),
            release_filter: sym!("oidnReleaseFilter"),
        };
        Ok(Oidn {
            api,
            path,
            _lib: lib,
        })
    }

    /// Where the library was loaded from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The denoised beauty (see the module docs for the filter settings).
    pub fn denoise(&self, color: &Image, aux: Aux) -> Result<Image, DenoiseError> {
        let size = (color.width, color.height);
        for (what, img) in [("albedo", aux.albedo), ("normal", aux.normal)] {
            if let Some(i) = img
                && (i.width, i.height) != size
            {
                return Err(DenoiseError::Input(format!(
                    "the {what} image is {}x{}, the beauty {}x{}",
                    i.width, i.height, size.0, size.1
                )));
            }
        }
        if aux.normal.is_some() && aux.albedo.is_none() {
            return Err(DenoiseError::Input(
                "a normal image needs an albedo image too (as OIDN does)".into(),
            ));
        }
        if color.pixels.is_empty() {
            return Ok(color.clone());
        }
        let device = DeviceGuard::new(self)?;
        let (mut albedo, mut normal) =
            (aux.albedo.map(Cow::Borrowed), aux.normal.map(Cow::Borrowed));
        if aux.prefilter {
            for (name, img) in [("albedo", &mut albedo), ("normal", &mut normal)] {
                if let Some(i) = img {
                    // An auxiliary image alone through its own RT filter (LDR: albedo is in
                    // [0, 1], normals in [-1, 1]).
                    let mut out = Image::new(i.width, i.height);
                    let mut f = device.filter()?;
                    f.image(name, i)?;
                    f.output(&mut out)?;
                    f.set_int("quality", QUALITY_HIGH);
                    f.run()?;
                    *img = Some(Cow::Owned(out));
                }
            }
        }
        let mut out = Image::new(color.width, color.height);
        let mut f = device.filter()?;
        f.image("color", color)?;
        if let Some(a) = &albedo {
            f.image("albedo", a)?;
        }
        if let Some(n) = &normal {
            f.image("normal", n)?;
        }
        f.output(&mut out)?;
        f.set_bool("hdr", true);
        f.set_bool("cleanAux", aux.prefilter && albedo.is_some());
        f.set_int("quality", QUALITY_HIGH);
        f.run()?;
        Ok(out)
    }
}

/// The library files to try, in order.
fn candidates() -> Vec<PathBuf> {
    const FILE: &str = "libOpenImageDenoise.so.2";
    if let Some(p) = std::env::var_os("PENUMBRA_OIDN") {
        // The user's word is final: only there.
        let p = PathBuf::from(p);
        return vec![if p.is_dir() { p.join(FILE) } else { p }];
    }
    let mut out = Vec::new();
    // The loader's own search (LD_LIBRARY_PATH, ld.so.cache): a bare file name.
    out.push(PathBuf::from(FILE));
    let mut roots: Vec<PathBuf> = Vec::new();
    if let Some(v) = std::env::var_os("VIRTUAL_ENV") {
        roots.push(PathBuf::from(v).join("lib"));
    }
    if let Some(h) = std::env::var_os("HOME") {
        roots.push(PathBuf::from(h).join(".local/lib"));
    }
    roots.push(PathBuf::from("/usr/local/lib"));
    roots.push(PathBuf::from("/usr/lib"));
    for root in roots {
        let Ok(dir) = std::fs::read_dir(&root) else {
            continue;
        };
        let mut pythons: Vec<PathBuf> = dir
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("python3"))
            })
            .collect();
        pythons.sort();
        for py in pythons.into_iter().rev() {
            for site in ["site-packages", "dist-packages"] {
                out.push(py.join(site).join("pyoidn/oidn/lib").join(FILE));
            }
        }
    }
    // Last: ask Python where pyoidn is (a conda or other interpreter).
    if let Ok(o) = std::process::Command::new("python3")
        .args([
            "-c",
            "import importlib.util as u, os; s = u.find_spec('pyoidn'); \
             print(os.path.dirname(s.origin) if s and s.origin else '')",
        ])
        .stderr(std::process::Stdio::null())
        .output()
    {
        let dir = String::from_utf8_lossy(&o.stdout).trim().to_string();
        if !dir.is_empty() {
            out.push(PathBuf::from(dir).join("oidn/lib").join(FILE));
        }
    }
    out
}

/// An OIDN device, released on drop.
struct DeviceGuard<'a> {
    oidn: &'a Oidn,
    device: Device,
}

impl<'a> DeviceGuard<'a> {
    fn new(oidn: &'a Oidn) -> Result<Self, DenoiseError> {
        // SAFETY: oidnNewDevice takes a device type and returns a new handle (or null).
        let device = unsafe { (oidn.api.new_device)(DEVICE_TYPE_DEFAULT) };
        if device.is_null() {
            return Err(DenoiseError::Oidn("no device could be created".into()));
        }
        let g = DeviceGuard { oidn, device };
        // SAFETY: `device` is the live handle made above.
        unsafe { (oidn.api.commit_device)(device) };
        g.check()?;
        Ok(g)
    }

    /// The device's pending error, if any.
    fn check(&self) -> Result<(), DenoiseError> {
        let mut msg: *const c_char = std::ptr::null();
        // SAFETY: `device` is live; OIDN writes a pointer to a NUL-terminated message it owns
        // (valid until the next call on the device), or leaves it null.
        let code = unsafe { (self.oidn.api.device_error)(self.device, &mut msg) };
        if code == ERROR_NONE {
            return Ok(());
        }
        let text = if msg.is_null() {
            format!("error code {code}")
        } else {
            // SAFETY: non-null, NUL-terminated, owned by OIDN and not yet invalidated.
            unsafe { CStr::from_ptr(msg) }
                .to_string_lossy()
                .into_owned()
        };
        Err(DenoiseError::Oidn(text))
    }

    fn filter(&self) -> Result<FilterGuard<'_, 'a>, DenoiseError> {
        // SAFETY: `device` is live; "RT" is a NUL-terminated filter type name.
        let filter = unsafe { (self.oidn.api.new_filter)(self.device, c"RT".as_ptr()) };
        self.check()?;
        if filter.is_null() {
            return Err(DenoiseError::Oidn("no RT filter".into()));
        }
        Ok(FilterGuard {
            device: self,
            filter,
        })
    }
}

impl Drop for DeviceGuard<'_> {
    fn drop(&mut self) {
        // SAFETY: the handle is live and released once; its filters were released first
        // (they borrow this guard).
        unsafe { (self.oidn.api.release_device)(self.device) };
    }
}

/// An OIDN filter, released on drop. The images it is given are borrowed for its life by
/// the caller's discipline: every image passed to it outlives the `run` call that reads it.
struct FilterGuard<'d, 'a> {
    device: &'d DeviceGuard<'a>,
    filter: Filter,
}

impl FilterGuard<'_, '_> {
    fn set_raw(
        &mut self,
        name: &str,
        img: *mut c_void,
        w: u32,
        h: u32,
    ) -> Result<(), DenoiseError> {
        let name = CString::new(name).expect("no NUL in image names");
        let stride = std::mem::size_of::<crate::math::Vec3>();
        // SAFETY: `filter` is live; `img` points at w·h pixels of `stride` bytes whose first
        // three f32 are x, y, z (glam's Vec3A), which OIDN reads (inputs) or writes (output)
        // as FLOAT3 during `run`, while the image is alive and not otherwise accessed.
        unsafe {
            (self.device.oidn.api.set_image)(
                self.filter,
                name.as_ptr(),
                img,
                FORMAT_FLOAT3,
                w as usize,
                h as usize,
                0,
                stride,
                stride * w as usize,
            )
        };
        self.device.check()
    }

    fn image(&mut self, name: &str, img: &Image) -> Result<(), DenoiseError> {
        // OIDN takes `void*` for inputs too; it only reads them.
        let ptr = img.pixels.as_ptr() as *mut c_void;
        self.set_raw(name, ptr, img.width, img.height)
    }

    fn output(&mut self, img: &mut Image) -> Result<(), DenoiseError> {
        let ptr = img.pixels.as_mut_ptr() as *mut c_void;
        self.set_raw("output", ptr, img.width, img.height)
    }

    fn set_bool(&mut self, name: &str, v: bool) {
        let name = CString::new(name).expect("no NUL in parameter names");
        // SAFETY: `filter` is live and the name NUL-terminated.
        unsafe { (self.device.oidn.api.set_bool)(self.filter, name.as_ptr(), v) };
    }

    fn set_int(&mut self, name: &str, v: c_int) {
        let name = CString::new(name).expect("no NUL in parameter names");
        // SAFETY: as `set_bool`.
        unsafe { (self.device.oidn.api.set_int)(self.filter, name.as_ptr(), v) };
    }

    fn run(&mut self) -> Result<(), DenoiseError> {
        // SAFETY: `filter` is live; its images were set from buffers the caller keeps alive
        // and untouched until this returns (OIDN's CPU device executes synchronously here).
        unsafe {
            (self.device.oidn.api.commit_filter)(self.filter);
        }
        self.device.check()?;
        // SAFETY: as above.
        unsafe {
            (self.device.oidn.api.execute_filter)(self.filter);
        }
        self.device.check()
    }
}

impl Drop for FilterGuard<'_, '_> {
    fn drop(&mut self) {
        // SAFETY: the handle is live and released once.
        unsafe { (self.device.oidn.api.release_filter)(self.filter) };
    }
}

/// Samples per pixel of the auxiliary images for a beauty of `spp`: four times as many, at
/// least 16 and at most 64 (they trace camera rays only, and converge long before the beauty).
pub fn aux_spp(spp: u32) -> u32 {
    spp.saturating_mul(4).clamp(16, 64)
}

/// The denoiser's albedo and normal images of `scene` ([`Aov::DenoiseAlbedo`],
/// [`Aov::DenoiseNormal`]), through the scene's own film and filter, at `spp`, on the current
/// rayon pool.
pub fn render_aux(scene: &Scene, spp: u32) -> (Image, Image) {
    let opts = RenderOptions {
        spp,
        ..Default::default()
    };
    let [albedo, normal] = [Aov::DenoiseAlbedo, Aov::DenoiseNormal].map(|aov| {
        render(scene, &Integrator::Aov(aov), &opts, &Silent)
            .film
            .develop()
    });
    (albedo, normal)
}
