//! `penumbra._penumbra`, the native half of the `penumbra` Python package (the other half,
//! `python/penumbra/__init__.py`, turns its flat buffers into NumPy arrays and holds the
//! documented signatures).
//!
//! Every function goes through the library code the `penumbra` command uses (`scene::load`,
//! `build::build`, `render::render::render`, `Film::develop`, `render::image_io`,
//! `render::compare`, `render::denoise`), so that a render here is the CLI's EXR bit for bit
//! at the same seed and samples per pixel. Images cross the boundary as float32 buffers of
//! `height × width × 3` values, row by row.
//!
//! Nothing Rust panics on reaches Python as a panic: every entry point runs under
//! `catch_unwind` and a panic becomes `penumbra.InternalError`.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

use pyo3::create_exception;
use pyo3::exceptions::{PyKeyError, PyOSError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyByteArray, PyBytes, PyDict, PyString};

use build::BuildOptions;
use build::params::Value;
use render::compare::{CompareOptions, Comparison, Reference, TestImages};
use render::film::Image;
use render::math::Vec3;
use render::render::{Progress, RenderObserver, RenderOptions};
use scene::{Document, LoadError, LoadOptions, SceneDesc};

create_exception!(
    penumbra,
    SceneError,
    PyValueError,
    "A scene file (or string) could not be loaded or built. The message starts with \
     `file:line:col`; the attributes `file`, `line` and `col` hold them (line and col are 0 \
     when the problem has no place in the file)."
);
create_exception!(
    penumbra,
    InternalError,
    PyRuntimeError,
    "A bug in penumbra: a Rust panic, caught before it reached Python. Please report it with \
     the message."
);

/// Runs `f`, turning a panic into `InternalError`.
fn guard<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| Err(panic_error(payload)))
}

fn panic_error(payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into());
    InternalError::new_err(format!("penumbra panicked: {what}"))
}

/// A `SceneError` from a message and its place (`file` as the user should read it).
fn scene_error(py: Python<'_>, message: String, file: &str, line: u32, col: u32) -> PyErr {
    let err = SceneError::new_err(message);
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail but for memory.
    let _ = value.setattr("file", file);
    let _ = value.setattr("line", line);
    let _ = value.setattr("col", col);
    err
}

/// A load error as `SceneError`; `rename` replaces a temporary file's path (load_string) by
/// the name the user knows.
fn load_error(py: Python<'_>, e: &LoadError, rename: Option<(&Path, &str)>) -> PyErr {
    let mut message = e.to_string();
    let mut file = e.loc.file.display().to_string();
    if let Some((tmp, name)) = rename {
        let tmp = tmp.display().to_string();
        message = message.replace(&tmp, name);
        file = file.replace(&tmp, name);
    }
    scene_error(py, message, &file, e.loc.line, e.loc.col)
}

/// A loaded scene: the format-independent scene description (see `docs/architecture.md`),
/// and what its builds read from files or derived from its geometry (`build::BuildCache`),
/// kept for the next render. Made by `load_file` / `load_string` / `load_dict`; rendered by
/// `render`; its editable values are listed by `parameters()` and changed by `update()`
/// without a reload. Rendering it from several threads at once is safe.
#[pyclass(frozen, module = "penumbra._penumbra")]
struct Scene {
    /// The description and the build cache, changed together: a build (under the lock)
    /// always sees a cache that matches the description it builds.
    state: Mutex<SceneState>,
    /// What it was loaded from (a path, or `<string>`).
    source: String,
    /// How to load it again (pickling: Dask sends scenes to its workers this way).
    origin: Origin,
}

/// A scene's file or text and its parameters, from which a copy is loaded elsewhere.
#[derive(Clone)]
enum Origin {
    File(PathBuf, Vec<(String, String)>),
    Text(String, String, Vec<(String, String)>),
}

struct SceneState {
    desc: SceneDesc,
    cache: build::BuildCache,
    /// The `update` edits made since loading, in order (replayed on a copy).
    edits: Vec<(String, Value)>,
}

impl Scene {
    fn new(desc: SceneDesc, source: String, origin: Origin) -> Scene {
        Scene {
            state: Mutex::new(SceneState {
                desc,
                cache: build::BuildCache::default(),
                edits: Vec::new(),
            }),
            source,
            origin,
        }
    }

    /// The state; a panic while it was held (a bug, reported as `InternalError`) leaves it
    /// consistent: the cache keeps only what was built completely.
    fn lock(&self) -> MutexGuard<'_, SceneState> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// A parameter's value as Python sees it: a float, an (r, g, b) / (x, y, z) tuple, or a
/// 4×4 matrix as a list of rows.
fn value_to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Float(f) => f64::from(*f).into_pyobject(py)?.into_any(),
        Value::Vec3([a, b, c]) => (f64::from(*a), f64::from(*b), f64::from(*c))
            .into_pyobject(py)?
            .into_any(),
        Value::Matrix(m) => {
            let rows: Vec<Vec<f64>> = (0..4)
                .map(|r| (0..4).map(|c| f64::from(m.col(c)[r])).collect())
                .collect();
            rows.into_pyobject(py)?.into_any()
        }
    })
}

/// A Python value as a parameter's value (its kind is checked against the key by
/// `build::params::set`).
fn value_from_py(key: &str, v: &Bound<'_, PyAny>) -> PyResult<Value> {
    let wrong = || {
        PyTypeError::new_err(format!(
            "parameter '{key}': expected a float, a sequence of 3 floats or a 4x4 matrix, \
             found {}",
            v.get_type()
                .name()
                .map_or_else(|_| "?".to_string(), |n| n.to_string())
        ))
    };
    if v.is_instance_of::<PyBool>() || v.is_instance_of::<PyString>() {
        return Err(wrong());
    }
    if let Ok(f) = v.extract::<f64>() {
        return Ok(Value::Float(f as f32));
    }
    if let Ok(xs) = v.extract::<Vec<f64>>() {
        return match xs.as_slice() {
            [a, b, c] => Ok(Value::Vec3([*a as f32, *b as f32, *c as f32])),
            _ => Err(wrong()),
        };
    }
    if let Ok(rows) = v.extract::<Vec<Vec<f64>>>()
        && rows.len() == 4
        && rows.iter().all(|r| r.len() == 4)
    {
        let cols: [f32; 16] = std::array::from_fn(|i| rows[i % 4][i / 4] as f32);
        return Ok(Value::Matrix(render::math::Mat4::from_cols_array(&cols)));
    }
    Err(wrong())
}

#[pymethods]
impl Scene {
    /// The file the scene was loaded from, or `<string>`.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// The loader's warnings (ignored parameters, substituted defaults), as the CLI prints them.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.lock()
            .desc
            .warnings
            .iter()
            .map(|w| w.to_string())
            .collect()
    }

    /// The number of sensors (cameras) in the scene; `render(sensor=i)` picks one.
    #[getter]
    fn sensor_count(&self) -> usize {
        self.lock().desc.sensors.len()
    }

    /// The film size `(width, height)` of sensor `sensor`, as the scene declares it.
    #[pyo3(signature = (sensor = 0))]
    fn resolution(&self, sensor: usize) -> PyResult<(u32, u32)> {
        let state = self.lock();
        let s =
            state.desc.sensors.get(sensor).ok_or_else(|| {
                PyValueError::new_err(format!("the scene has no sensor {sensor}"))
            })?;
        Ok((s.film.width, s.film.height))
    }

    /// parameters() -> dict: the scene's editable values by key, with their current values.
    ///
    /// Keys are `"<object>.<parameter>"`, Mitsuba 3's `traverse()` names without `.value`:
    /// `<object>` is the object's `id` in the scene file; an object without one is named by
    /// what holds it (a shape's inline material `"<shape>.bsdf"`, the material a `twosided`
    /// wraps `"<twosided>.brdf_0"` / `".brdf_1"`, the one a `normalmap`, `bumpmap` or `mask`
    /// wraps `"<outer>.nested_bsdf"`, a `blendbsdf`'s `"<outer>.bsdf_0"` / `".bsdf_1"`), else by
    /// kind and index in file order (`shape_3`, `bsdf_2`, `emitter_0`, `sensor_0`); a shape's
    /// area light is `"<shape>.emitter"`. `<parameter>` is the scene file's name:
    /// `reflectance`, `diffuse_reflectance`, `specular_reflectance`, `alpha` (sets `alpha_u`
    /// and `alpha_v` together; listed when they are equal), `base_color`, `roughness`,
    /// `metallic`, `intensity`, `radiance`, `irradiance`, `scale`, `position`, `direction`,
    /// `fov`, `to_world`...
    ///
    /// Values are floats, `(r, g, b)` or `(x, y, z)` tuples, and 4x4 matrices as lists of
    /// rows (`to_world` of shapes, sensors and lights). Only constants are listed: a parameter
    /// given by a texture or a declared spectrum (a named conductor's `eta`) is not.
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        guard(|| {
            let params = build::params::parameters(&self.lock().desc);
            let d = PyDict::new(py);
            for p in params {
                d.set_item(p.key, value_to_py(py, &p.value)?)?;
            }
            Ok(d)
        })
    }

    /// update(values) -> list: set parameters (keys as `parameters()` lists them) without
    /// reloading the scene.
    ///
    /// Values: a float, a sequence of 3 floats (a float for a colour is a grey), a 4x4
    /// matrix (nested sequences or a NumPy array, rows first). All the edits are made or
    /// none: an unknown key raises `KeyError`, a value of the wrong kind `TypeError`, a
    /// value out of range (not finite, a negative roughness) `ValueError`.
    ///
    /// The next `render` rebuilds only what the edits made stale: material, light and camera
    /// edits keep the acceleration structure, the meshes and the decoded textures; a shape's
    /// `to_world` rebuilds the acceleration structure. The image is the one a reload of the
    /// scene file edited the same way gives, bit for bit. Returns the kinds of change made
    /// (`"material"`, `"light"`, `"camera"`, `"geometry"`).
    fn update(&self, py: Python<'_>, values: &Bound<'_, PyDict>) -> PyResult<Vec<String>> {
        guard(|| {
            let mut edits = Vec::with_capacity(values.len());
            for (k, v) in values.iter() {
                let key: String = k.extract().map_err(|_| {
                    PyTypeError::new_err(format!(
                        "parameter keys are strings, found {}",
                        k.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
                    ))
                })?;
                let value = value_from_py(&key, &v)?;
                edits.push((key, value));
            }
            // All or nothing: the edits go to a copy, which replaces the description only
            // when every one of them is valid.
            let result = py.detach(|| {
                let mut state = self.lock();
                let mut desc = state.desc.clone();
                let mut changed = Vec::new();
                for (key, value) in &edits {
                    let c = build::params::set(&mut desc, key, *value)?;
                    if !changed.contains(&c) {
                        changed.push(c);
                    }
                }
                state.desc = desc;
                state.edits.extend(edits.iter().cloned());
                for c in &changed {
                    state.cache.invalidate(*c);
                }
                Ok::<_, build::params::ParamError>(changed)
            });
            let changed = result.map_err(|e| match e {
                build::params::ParamError::Unknown { .. } => PyKeyError::new_err(e.to_string()),
                build::params::ParamError::WrongType { .. } => PyTypeError::new_err(e.to_string()),
                build::params::ParamError::Invalid { .. } => PyValueError::new_err(e.to_string()),
            })?;
            Ok(changed
                .into_iter()
                .map(|c| {
                    match c {
                        build::Changed::Material => "material",
                        build::Changed::Light => "light",
                        build::Changed::Camera => "camera",
                        build::Changed::Geometry => "geometry",
                    }
                    .to_string()
                })
                .collect())
        })
    }

    /// Whether the next render reuses a built acceleration structure (and decoded textures):
    /// `{"geometry": bool, "textures": bool}`.
    fn cache_info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let state = self.lock();
        let d = PyDict::new(py);
        d.set_item("geometry", state.cache.has_geometry())?;
        d.set_item("textures", state.cache.has_textures())?;
        Ok(d)
    }

    /// Pickling (Dask, multiprocessing): the scene is loaded again from its file or text
    /// with its parameters, and its `update` edits are replayed. A file must be at the same
    /// path where the copy is loaded.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let rebuild = py.import("penumbra._penumbra")?.getattr("_rebuild_scene")?;
        let edits = PyDict::new(py);
        for (k, v) in &self.lock().edits {
            edits.set_item(k, value_to_py(py, v)?)?;
        }
        let args = match &self.origin {
            Origin::File(path, defines) => (
                "file",
                path.display().to_string(),
                "",
                defines.clone(),
                edits,
            ),
            Origin::Text(text, format, defines) => (
                "text",
                text.clone(),
                format.as_str(),
                defines.clone(),
                edits,
            ),
        };
        Ok((rebuild, args.into_pyobject(py)?.into_any()))
    }

    fn __repr__(&self) -> String {
        let state = self.lock();
        format!(
            "<penumbra.Scene from {} ({} shapes, {} emitters, {} sensors)>",
            self.source,
            state.desc.shapes.len(),
            state.desc.emitters.len(),
            state.desc.sensors.len()
        )
    }
}

fn load_document(
    py: Python<'_>,
    path: &Path,
    defines: Vec<(String, String)>,
    rename: Option<(&Path, &str)>,
) -> PyResult<SceneDesc> {
    let xml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    // The CLI's rule (crates/cli: load_scene): `-D` sets Mitsuba/Nori <default>s only.
    if !defines.is_empty() && (!xml || scene::formats::ceng795::is_ceng795_xml(path)) {
        let shown = rename.map_or_else(|| path.display().to_string(), |(_, n)| n.to_string());
        return Err(scene_error(
            py,
            format!(
                "{shown}: parameters set Mitsuba/Nori XML <default>s; this scene format has none"
            ),
            &shown,
            0,
            0,
        ));
    }
    let opts = LoadOptions { defines };
    let doc = py
        .detach(|| catch_unwind(|| scene::load(path, &opts)))
        .map_err(panic_error)?
        .map_err(|e| load_error(py, &e, rename))?;
    match doc {
        Document::Scene(desc) => Ok(*desc),
        Document::Test(_) => Err(scene_error(
            py,
            format!(
                "{}: this is a Nori test file, not a scene (run it with `penumbra test`)",
                path.display()
            ),
            &path.display().to_string(),
            0,
            0,
        )),
    }
}

/// load_file(path, defines) -> Scene
#[pyfunction]
#[pyo3(signature = (path, defines = Vec::new()))]
fn load_file(py: Python<'_>, path: PathBuf, defines: Vec<(String, String)>) -> PyResult<Scene> {
    guard(|| {
        let defines_kept = defines.clone();
        let desc = load_document(py, &path, defines, None)?;
        let absolute = std::path::absolute(&path).unwrap_or_else(|_| path.clone());
        let origin = Origin::File(absolute, defines_kept);
        Ok(Scene::new(desc, path.display().to_string(), origin))
    })
}

/// load_string(text, format, defines) -> Scene
#[pyfunction]
#[pyo3(signature = (text, format = "xml", defines = Vec::new()))]
fn load_string(
    py: Python<'_>,
    text: &str,
    format: &str,
    defines: Vec<(String, String)>,
) -> PyResult<Scene> {
    guard(|| {
        let ext = format.trim_start_matches('.').to_ascii_lowercase();
        if !matches!(
            ext.as_str(),
            "xml" | "json" | "txt" | "obj" | "dae" | "pbrt"
        ) {
            return Err(PyValueError::new_err(format!(
                "format must be one of xml, json, txt, obj, dae, pbrt (a file extension), \
                 found '{format}'"
            )));
        }
        // The loaders read files (relative references resolve beside them): the text goes
        // to a file of its own in a fresh temporary folder, removed after loading.
        static CALLS: AtomicU64 = AtomicU64::new(0);
        let dir = std::env::temp_dir().join(format!(
            "penumbra-py-{}-{}",
            std::process::id(),
            CALLS.fetch_add(1, Ordering::Relaxed)
        ));
        let path = dir.join(format!("string.{ext}"));
        std::fs::create_dir_all(&dir)
            .and_then(|()| std::fs::write(&path, text))
            .map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))?;
        let origin = Origin::Text(text.to_string(), ext.clone(), defines.clone());
        let result = load_document(py, &path, defines, Some((&path, "<string>")));
        let _ = std::fs::remove_dir_all(&dir);
        Ok(Scene::new(result?, "<string>".into(), origin))
    })
}

/// The progress a render reports, read by the thread that holds the GIL.
#[derive(Default)]
struct Shared {
    done: AtomicU64,
    total: AtomicU64,
}

impl RenderObserver for Shared {
    fn progress(&self, p: &Progress) {
        self.done.fetch_max(p.samples_done, Ordering::Relaxed);
        self.total.store(p.samples_total, Ordering::Relaxed);
    }
}

/// What the render thread hands back.
struct Rendered {
    pixels: Vec<Vec3>,
    width: u32,
    height: u32,
    spp: u32,
    warnings: Vec<String>,
    /// A shard's film state.
    state: Option<Vec<u8>>,
}

/// Why the render thread stopped without an image.
enum RenderFailure {
    /// Bad input (build error, unsupported integrator): `SceneError` / `ValueError`.
    Scene(build::BuildError),
    Value(String),
}

/// How long one pass of the progressive loop lasts (the CLI's is 1 s). Cancellation
/// (Ctrl-C) takes effect at the end of a pass, so this bounds how long KeyboardInterrupt
/// waits; the image does not depend on it (the film's sums are exact: see
/// `render::film::accum`).
const PASS_DURATION: Duration = Duration::from_millis(250);

/// How often the waiting thread takes the GIL to check for signals and report progress.
const POLL: Duration = Duration::from_millis(20);

/// What `render` returns: the pixels, width, height, samples per pixel done, warnings and a
/// shard's film state.
type Rendering<'py> = (
    Bound<'py, PyByteArray>,
    u32,
    u32,
    u32,
    Vec<String>,
    Option<Bound<'py, PyBytes>>,
);

/// render(scene, spp, seed, resolution, integrator, threads, sensor, mode, progress, shard)
///   -> (bytearray, width, height, spp, warnings, state)
/// With `shard=(i, k)`, renders the i-th of k parts of the work and `state` is its film
/// state (bytes, for `merge_states`); else `state` is None.
#[pyfunction(name = "render")]
#[pyo3(signature = (scene, spp = None, seed = None, resolution = None, integrator = None,
                    threads = None, sensor = 0, mode = None, progress = None, shard = None))]
#[allow(clippy::too_many_arguments)]
fn py_render<'py>(
    py: Python<'py>,
    scene: &Scene,
    spp: Option<u32>,
    seed: Option<u64>,
    resolution: Option<(u32, u32)>,
    integrator: Option<&str>,
    threads: Option<usize>,
    sensor: usize,
    mode: Option<&str>,
    progress: Option<Bound<'py, PyAny>>,
    shard: Option<(u32, u32)>,
) -> PyResult<Rendering<'py>> {
    guard(|| {
        if let Some((i, k)) = shard
            && i >= k
        {
            return Err(PyValueError::new_err(format!(
                "shard ({i}, {k}): the index must be below the count"
            )));
        }
        if spp == Some(0) {
            return Err(PyValueError::new_err("spp must be at least 1"));
        }
        if let Some((w, h)) = resolution
            && (w == 0 || h == 0 || w > 1 << 16 || h > 1 << 16)
        {
            return Err(PyValueError::new_err(format!(
                "resolution must be between 1 and 65536 per axis, found ({w}, {h})"
            )));
        }
        let (sensors, scene_integrator) = {
            let state = scene.lock();
            (state.desc.sensors.len(), state.desc.integrator.clone())
        };
        if sensor >= sensors {
            return Err(PyValueError::new_err(format!(
                "the scene has no sensor {sensor} ({sensors} sensors)"
            )));
        }
        let integrator = match integrator {
            Some(s) => {
                let mut i = build::spec::parse_integrator(s).map_err(PyValueError::new_err)?;
                build::spec::keep_scene_max_depth(&scene_integrator, &mut i);
                Some(i)
            }
            None => None,
        };
        let opts = BuildOptions {
            sensor,
            spp,
            resolution,
            seed,
            integrator,
            light_selection: None,
            flatten_instances: false,
            mode: mode
                .map(|m| {
                    build::spec::parse_mode(m)
                        .map_err(|e| PyValueError::new_err(format!("mode: {e}")))
                })
                .transpose()?
                .unwrap_or_default(),
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .build()
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let cancel = Arc::new(AtomicBool::new(false));
        let finished = AtomicBool::new(false);
        let shared = Shared::default();
        let source = scene.source.clone();

        let work = || -> Result<Rendered, RenderFailure> {
            let defaults = RenderOptions::default();
            let (
                build::Built {
                    scene,
                    integrator,
                    spp,
                },
                identity,
            ) = {
                // The build reuses what earlier renders read and built (textures, the
                // acceleration structure), as far as `update` left it valid.
                let mut state = scene.lock();
                let state = &mut *state;
                let built = build::build_cached(&state.desc, &opts, &mut state.cache)
                    .map_err(RenderFailure::Scene)?;
                // A shard's render is named by what makes its image (see the CLI's).
                let what = (&opts, built.spp, defaults.tile_size, defaults.chunk_spp);
                let identity = shard.map(|_| build::spec::identity(&state.desc, &what));
                (built, identity)
            };
            if let Some(why) = integrator.unsupported(&scene) {
                return Err(RenderFailure::Value(why.to_string()));
            }
            let mut ropts = RenderOptions {
                spp,
                cancel: cancel.clone(),
                pass_duration: PASS_DURATION,
                ..RenderOptions::default()
            };
            // A shard: its items, and the state that names the render.
            let info = match shard {
                None => None,
                Some((i, k)) => {
                    let n = integrator
                        .work_items(&scene, &ropts)
                        .map_err(RenderFailure::Value)?;
                    let items = build::spec::shard_items(i, k, n);
                    ropts.items = Some(items.clone());
                    Some(render::film::state::StateInfo {
                        identity: identity.unwrap_or_default(),
                        description: format!("{source} ({} spp)", ropts.spp),
                        items_total: n,
                        items,
                        spp: ropts.spp,
                        tonemap: scene.film.tonemap.clone(),
                    })
                }
            };
            let outcome =
                pool.install(|| render::render::render(&scene, &integrator, &ropts, &shared));
            let state = info.map(|mut info| {
                info.items = outcome.items.clone();
                render::film::state::to_bytes(&info, &outcome.film)
            });
            let image: Image = outcome.film.develop();
            let mut warnings: Vec<String> = scene.warnings.iter().map(|w| w.to_string()).collect();
            let bad = outcome.film.nonfinite_count();
            if bad > 0 {
                warnings.push(format!(
                    "{bad} sample(s) were NaN or infinite and were discarded"
                ));
            }
            Ok(Rendered {
                width: image.width,
                height: image.height,
                pixels: image.pixels,
                spp: outcome.spp,
                warnings,
                state,
            })
        };

        let mut interrupt: Option<PyErr> = None;
        let result = std::thread::scope(|s| {
            let worker = s.spawn(|| {
                let r = catch_unwind(AssertUnwindSafe(work));
                finished.store(true, Ordering::Release);
                r
            });
            let mut reported = u64::MAX;
            while !finished.load(Ordering::Acquire) {
                py.detach(|| {
                    let until = std::time::Instant::now() + POLL;
                    while !finished.load(Ordering::Acquire) && std::time::Instant::now() < until {
                        std::thread::sleep(Duration::from_millis(2));
                    }
                });
                if interrupt.is_some() {
                    continue;
                }
                // Ctrl-C (or any signal handler that raises) stops the render at the end of
                // its pass; the exception is raised once the render thread has stopped.
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    interrupt = Some(e);
                    continue;
                }
                if let Some(cb) = &progress {
                    let (done, total) = (
                        shared.done.load(Ordering::Relaxed),
                        shared.total.load(Ordering::Relaxed),
                    );
                    if done != reported && total > 0 {
                        reported = done;
                        let fraction = (done as f64 / total as f64).min(1.0);
                        if let Err(e) = cb.call1((fraction,)) {
                            cancel.store(true, Ordering::Relaxed);
                            interrupt = Some(e);
                        }
                    }
                }
            }
            worker.join()
        });
        if let Some(e) = interrupt {
            return Err(e);
        }
        let rendered = match result {
            Ok(Ok(Ok(r))) => r,
            Ok(Ok(Err(RenderFailure::Scene(e)))) => {
                let file = e.loc.file.display().to_string();
                return Err(scene_error(py, e.to_string(), &file, e.loc.line, e.loc.col));
            }
            Ok(Ok(Err(RenderFailure::Value(m)))) => return Err(PyValueError::new_err(m)),
            Ok(Err(payload)) | Err(payload) => return Err(panic_error(payload)),
        };
        if let Some(cb) = &progress {
            cb.call1((1.0f64,))?;
        }
        let bytes = PyByteArray::new(py, &pixel_bytes(&rendered.pixels));
        Ok((
            bytes,
            rendered.width,
            rendered.height,
            rendered.spp,
            rendered.warnings,
            rendered.state.map(|s| PyBytes::new(py, &s)),
        ))
    })
}

/// Pixels as float32 RGB triples, native byte order (NumPy's `float32`).
fn pixel_bytes(pixels: &[Vec3]) -> Vec<u8> {
    let mut out = Vec::with_capacity(pixels.len() * 12);
    for p in pixels {
        for c in [p.x, p.y, p.z] {
            out.extend_from_slice(&c.to_ne_bytes());
        }
    }
    out
}

/// An image from float32 RGB triples (what `pixel_bytes` makes).
fn image_from_bytes(data: &[u8], width: u32, height: u32, what: &str) -> PyResult<Image> {
    let n = width as usize * height as usize;
    if data.len() != n * 12 {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes for a {width}x{height} RGB float32 image (expected {})",
            data.len(),
            n * 12
        )));
    }
    let pixels = data
        .chunks_exact(12)
        .map(|p| {
            let c = |k: usize| f32::from_ne_bytes([p[k], p[k + 1], p[k + 2], p[k + 3]]);
            Vec3::new(c(0), c(4), c(8))
        })
        .collect();
    Image::from_pixels(width, height, pixels)
        .ok_or_else(|| PyValueError::new_err(format!("{what}: bad image size {width}x{height}")))
}

/// write(path, data, width, height)
#[pyfunction(name = "write")]
fn py_write(py: Python<'_>, path: PathBuf, data: &[u8], width: u32, height: u32) -> PyResult<()> {
    guard(|| {
        let image = image_from_bytes(data, width, height, "image")?;
        py.detach(|| render::image_io::write_image(&path, &image))
            .map_err(|e| match e {
                render::image_io::ImageError::Unsupported { .. } => {
                    PyValueError::new_err(e.to_string())
                }
                _ => PyOSError::new_err(e.to_string()),
            })
    })
}

/// read(path, srgb) -> (bytearray, width, height)
#[pyfunction(name = "read")]
#[pyo3(signature = (path, srgb = true))]
fn py_read<'py>(
    py: Python<'py>,
    path: PathBuf,
    srgb: bool,
) -> PyResult<(Bound<'py, PyByteArray>, u32, u32)> {
    guard(|| {
        use render::image_io::Decode;
        let decode = if srgb { Decode::Srgb } else { Decode::Raw };
        let image = py
            .detach(|| render::image_io::read_image_with(&path, decode))
            .map_err(|e| PyOSError::new_err(e.to_string()))?;
        Ok((
            PyByteArray::new(py, &pixel_bytes(&image.pixels)),
            image.width,
            image.height,
        ))
    })
}

/// compare(reference, batches, width, height, block, alpha) -> dict
///
/// `reference`: a path prefix (str) or a (mean, stderr) pair of buffers; `batches`: a list
/// of K ≥ 2 buffers, or one (mean, stderr) pair in a one-element list with `stderr = True`.
#[pyfunction(name = "compare")]
#[pyo3(signature = (reference, batches, width, height, test_stderr = None, block = 8, alpha = 0.01))]
#[allow(clippy::too_many_arguments)]
fn py_compare<'py>(
    py: Python<'py>,
    reference: Bound<'py, PyAny>,
    batches: Vec<Vec<u8>>,
    width: u32,
    height: u32,
    test_stderr: Option<Vec<u8>>,
    block: u32,
    alpha: f64,
) -> PyResult<Bound<'py, PyDict>> {
    guard(|| {
        let compare_err = |e: render::compare::CompareError| PyValueError::new_err(e.to_string());
        let reference = if let Ok(prefix) = reference.extract::<PathBuf>() {
            render::compare::load_reference(&prefix).map_err(compare_err)?
        } else {
            let (mean, stderr): (Vec<u8>, Vec<u8>) = reference.extract()?;
            Reference {
                mean: image_from_bytes(&mean, width, height, "reference mean")?,
                stderr: image_from_bytes(&stderr, width, height, "reference stderr")?,
            }
        };
        let test = match test_stderr {
            Some(se) => {
                let [mean] = batches.as_slice() else {
                    return Err(PyValueError::new_err(
                        "a test stderr image goes with exactly one test image",
                    ));
                };
                TestImages::MeanStderr {
                    mean: image_from_bytes(mean, width, height, "test image")?,
                    stderr: image_from_bytes(&se, width, height, "test stderr")?,
                }
            }
            None => TestImages::Batches(
                batches
                    .iter()
                    .enumerate()
                    .map(|(i, b)| image_from_bytes(b, width, height, &format!("batch {i}")))
                    .collect::<PyResult<_>>()?,
            ),
        };
        let options = CompareOptions {
            block,
            alpha,
            ..CompareOptions::default()
        };
        let c: Comparison = py
            .detach(|| render::compare::compare_with(&reference, &test, &options))
            .map_err(compare_err)?;
        let d = PyDict::new(py);
        d.set_item("passed", c.passed)?;
        d.set_item("rel_mse", c.rel_mse)?;
        d.set_item("mean_ratio", c.mean_ratio.to_vec())?;
        d.set_item("min_p", c.min_p)?;
        d.set_item("threshold", c.threshold)?;
        d.set_item("block_channels", c.block_channels)?;
        d.set_item("test_dof", c.test_dof)?;
        let w = &c.worst;
        d.set_item(
            "worst",
            (w.x, w.y, w.channel, w.test, w.reference, w.t, w.dof, w.p),
        )?;
        d.set_item("summary", c.to_string())?;
        Ok(d)
    })
}

/// denoise(color, width, height, albedo, normal, prefilter, filter) -> bytearray
#[pyfunction(name = "denoise")]
#[pyo3(signature = (color, width, height, albedo = None, normal = None, prefilter = true, filter = None))]
#[allow(clippy::too_many_arguments)]
fn py_denoise<'py>(
    py: Python<'py>,
    color: &[u8],
    width: u32,
    height: u32,
    albedo: Option<Vec<u8>>,
    normal: Option<Vec<u8>>,
    prefilter: bool,
    filter: Option<&str>,
) -> PyResult<Bound<'py, PyByteArray>> {
    guard(|| {
        let color = image_from_bytes(color, width, height, "image")?;
        let albedo = albedo
            .map(|a| image_from_bytes(&a, width, height, "albedo"))
            .transpose()?;
        let normal = normal
            .map(|n| image_from_bytes(&n, width, height, "normal"))
            .transpose()?;
        if normal.is_some() && albedo.is_none() {
            return Err(PyValueError::new_err(
                "a normal image needs an albedo image too (as in Open Image Denoise)",
            ));
        }
        let filter = filter
            .map(|f| build::spec::parse_filter(f).map_err(PyValueError::new_err))
            .transpose()?;
        let out = py.detach(|| -> Result<Image, String> {
            let oidn = render::denoise::Oidn::load().map_err(|e| e.to_string())?;
            let out = oidn
                .denoise(
                    &color,
                    render::denoise::Aux {
                        albedo: albedo.as_ref(),
                        normal: normal.as_ref(),
                        prefilter,
                    },
                )
                .map_err(|e| e.to_string())?;
            Ok(match filter {
                Some(f) => render::film::Filter::new(&f).apply_to_box_image(&out),
                None => out,
            })
        });
        let out = out.map_err(PyRuntimeError::new_err)?;
        Ok(PyByteArray::new(py, &pixel_bytes(&out.pixels)))
    })
}

/// Whether Open Image Denoise can be loaded (`pip install pyoidn`, or PENUMBRA_OIDN).
#[pyfunction]
fn denoiser_available(py: Python<'_>) -> bool {
    py.detach(|| render::denoise::Oidn::load().is_ok())
}

/// _rebuild_scene(kind, payload, format, defines, edits) -> Scene: what unpickling a scene
/// calls (see `Scene.__reduce__`).
#[pyfunction]
fn _rebuild_scene(
    py: Python<'_>,
    kind: &str,
    payload: String,
    format: &str,
    defines: Vec<(String, String)>,
    edits: Bound<'_, PyDict>,
) -> PyResult<Scene> {
    let scene = match kind {
        "file" => load_file(py, PathBuf::from(payload), defines)?,
        "text" => load_string(py, &payload, format, defines)?,
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown scene origin '{other}'"
            )));
        }
    };
    if !edits.is_empty() {
        scene.update(py, &edits)?;
    }
    Ok(scene)
}

/// merge_states(parts) -> (bytearray, width, height, spp): the image of a render from the
/// film states of its shards (`render(..., shard=(i, k))`), bit for bit the single
/// process's; refuses states of other renders and names missing or doubled work.
#[pyfunction]
fn merge_states<'py>(
    py: Python<'py>,
    parts: Vec<Vec<u8>>,
) -> PyResult<(Bound<'py, PyByteArray>, u32, u32, u32)> {
    guard(|| {
        let named: Vec<(String, &[u8])> = parts
            .iter()
            .enumerate()
            .map(|(i, p)| (format!("part {i}"), p.as_slice()))
            .collect();
        let whole = py
            .detach(|| render::film::state::merge_bytes(&named))
            .map_err(PyValueError::new_err)?;
        let image = whole.film.develop();
        let bytes = PyByteArray::new(py, &pixel_bytes(&image.pixels));
        Ok((bytes, image.width, image.height, whole.info.spp))
    })
}

#[pymodule]
fn _penumbra(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("InternalError", m.py().get_type::<InternalError>())?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(load_string, m)?)?;
    m.add_function(wrap_pyfunction!(py_render, m)?)?;
    m.add_function(wrap_pyfunction!(merge_states, m)?)?;
    m.add_function(wrap_pyfunction!(_rebuild_scene, m)?)?;
    m.add_function(wrap_pyfunction!(py_write, m)?)?;
    m.add_function(wrap_pyfunction!(py_read, m)?)?;
    m.add_function(wrap_pyfunction!(py_compare, m)?)?;
    m.add_function(wrap_pyfunction!(py_denoise, m)?)?;
    m.add_function(wrap_pyfunction!(denoiser_available, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
