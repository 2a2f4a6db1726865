"""Penumbra, a physically based renderer, from Python.

Load a scene in any format Penumbra reads (Mitsuba 3 / Nori XML, pbrt-v4 and v3, the
CENG795, COMP30019, CS-E5520 and CS184 course formats), render it into a float32 NumPy
array, write, compare and denoise images::

    import penumbra
    scene = penumbra.load_file("scenes/cornell-box.xml", res=128)
    image = penumbra.render(scene, spp=64, seed=1)      # H x W x 3, linear RGB
    penumbra.write("/tmp/cornell.exr", image)

Scenes can be edited without reloading them, as Mitsuba 3's ``traverse``/``update``::

    scene.parameters()                       # {"white.reflectance": (0.73, 0.73, 0.73), ...}
    scene.update({"white.reflectance": (0.5, 0.5, 0.5)})
    image = penumbra.render(scene, spp=64, seed=1)      # rebuilds the materials only

and made from Mitsuba 3's dictionary form with :func:`load_dict`.

Every call goes through the same library code as the ``penumbra`` command: ``render`` at a
given seed and spp equals ``penumbra render --seed S --spp N -o out.exr`` bit for bit.
Rendering releases the GIL (other Python threads run, and several renders can run at once);
Ctrl-C stops a render within a fraction of a second and raises ``KeyboardInterrupt``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _penumbra
from ._penumbra import InternalError, Scene, SceneError

__version__: str = _penumbra.__version__

__all__ = [
    "Scene",
    "SceneError",
    "InternalError",
    "Comparison",
    "load_file",
    "load_string",
    "load_dict",
    "render",
    "write",
    "read",
    "compare",
    "denoise",
    "denoiser_available",
]

PathLike = Union[str, "os.PathLike[str]"]


def _defines(params: dict) -> List[Tuple[str, str]]:
    """``name=value`` pairs as the CLI's ``-D`` takes them (booleans as true/false)."""
    out = []
    for k, v in params.items():
        if isinstance(v, bool):
            v = "true" if v else "false"
        out.append((str(k), str(v)))
    return out


def load_file(path: PathLike, **params: object) -> Scene:
    """Load a scene file of any supported format.

    ``params`` override the scene's Mitsuba ``<default>`` parameters, as the CLI's
    ``-D name=value`` does (``load_file("cbox.xml", spp=64, res=128)``); other formats have
    none, and giving any is an error.

    Raises ``SceneError`` (a ``ValueError``) with a ``file:line:col: message`` when the file
    cannot be read or is malformed; its ``file``, ``line`` and ``col`` attributes hold the place.
    """
    return _penumbra.load_file(os.fspath(path), _defines(params))


def load_string(text: str, format: str = "xml", **params: object) -> Scene:
    """Load a scene from a string.

    ``format`` is the file extension the text would have: ``xml`` (Mitsuba 3, Nori, CENG795),
    ``pbrt``, ``json`` (CENG795), ``txt`` (COMP30019), ``obj``, ``dae``. Files the scene
    refers to must be given by absolute paths. ``params`` as for :func:`load_file`. Errors
    name the text ``<string>``: ``<string>:3:5: ...``.
    """
    return _penumbra.load_string(text, format, _defines(params))


# Mitsuba 3's plugin types (the ones Penumbra reads) and the XML tag of each: the
# dictionary form names the type only.
_TAGS = {
    "bsdf": "diffuse conductor roughconductor dielectric thindielectric roughdielectric "
    "plastic roughplastic twosided null principled principledthin blendbsdf bumpmap "
    "normalmap mask pplastic mirror microfacet subsurface",
    "shape": "obj ply serialized sphere rectangle disk cube cylinder shapegroup instance",
    "emitter": "area point spot directional constant envmap sunsky projector directionalarea",
    "sensor": "perspective thinlens orthographic radiancemeter irradiancemeter",
    "film": "hdrfilm ldrfilm specfilm",
    "sampler": "independent stratified multijitter orthogonal ldsampler halton hammersley sobol",
    "rfilter": "box tent gaussian mitchell catmullrom lanczos",
    "integrator": "path volpath volpathmis direct photonmapper sppm ppm ptracer bdpt pssmlt mlt "
    "normals albedo depth aov ao whitted simple prb",
    "texture": "bitmap checkerboard",
    "medium": "homogeneous heterogeneous",
    "phase": "isotropic hg rayleigh tabphase blendphase sggx",
    "volume": "constvolume gridvolume",
    "spectrum": "blackbody d65 regular irregular uniform",
}
_TAG_OF = {t: tag for tag, types in _TAGS.items() for t in types.split()}


def _path(path: Tuple[str, ...]) -> str:
    return "dict" + "".join(f"[{k!r}]" for k in path)


def _num(x: object) -> str:
    # repr of a Python float is exact (shortest round-trip), so the loader reads the very
    # number given.
    return repr(float(x))  # type: ignore[arg-type]


def _matrix(value: object, path: Tuple[str, ...]) -> Optional[np.ndarray]:
    """A 4x4 transform from a nested list, a NumPy array or an object with a ``matrix``
    (Mitsuba's ``ScalarTransform4f``); None when ``value`` is none of these."""
    if hasattr(value, "matrix") and not isinstance(value, np.ndarray):
        value = np.asarray(value.matrix)  # type: ignore[attr-defined]
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    if a.shape != (4, 4):
        return None
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{_path(path)}: a transform must be finite")
    return a


class _Xml:
    """Mitsuba XML written one element per line, remembering the dictionary path of each
    line so that a loader error can name the key it comes from."""

    def __init__(self) -> None:
        self.lines: List[str] = []
        self.paths: List[Tuple[str, ...]] = []

    def add(self, depth: int, text: str, path: Tuple[str, ...]) -> None:
        self.lines.append("  " * depth + text)
        self.paths.append(path)


def _attrs(**attrs: object) -> str:
    from xml.sax.saxutils import quoteattr

    return "".join(f" {k}={quoteattr(str(v))}" for k, v in attrs.items() if v is not None)


def _object(xml: _Xml, d: dict, name: Optional[str], oid: Optional[str], depth: int,
            path: Tuple[str, ...]) -> None:
    ty = d.get("type")
    if not isinstance(ty, str):
        raise ValueError(f"{_path(path)}: an object needs a 'type' string, found {ty!r}")
    if ty == "scene":
        raise ValueError(f"{_path(path)}: a scene cannot be nested in another object")
    tag = _TAG_OF.get(ty)
    if tag is None:
        raise ValueError(
            f"{_path(path)}: unknown plugin type {ty!r} (Penumbra reads: "
            f"{', '.join(sorted(_TAG_OF))})"
        )
    if "id" in d and not isinstance(d["id"], str):
        raise TypeError(f"{_path(path + ('id',))}: an id is a string, found {d['id']!r}")
    oid = d.get("id", oid)
    xml.add(depth, f"<{tag}{_attrs(type=ty, id=oid, name=name)}>", path)
    for key, value in d.items():
        if key in ("type", "id"):
            continue
        _entry(xml, key, value, depth + 1, path + (key,))
    xml.add(depth, f"</{tag}>", path)


def _entry(xml: _Xml, key: object, value: object, depth: int, path: Tuple[str, ...]) -> None:
    """One ``key: value`` of an object: a property, a child object or a reference."""
    if not isinstance(key, str):
        raise TypeError(f"{_path(path[:-1])}: keys are strings, found {key!r}")
    if isinstance(value, dict):
        ty = value.get("type")
        if ty == "ref":
            rid = value.get("id")
            if not isinstance(rid, str):
                raise ValueError(f"{_path(path)}: a reference needs an 'id' string")
            xml.add(depth, f"<ref{_attrs(name=key, id=rid)}/>", path)
        elif ty == "rgb":
            v = value.get("value")
            vals = [v] if isinstance(v, (int, float)) else list(np.ravel(np.asarray(v, dtype=np.float64)))
            if len(vals) not in (1, 3):
                raise ValueError(f"{_path(path)}: an rgb value is a float or 3 floats, found {v!r}")
            xml.add(depth, f"<rgb{_attrs(name=key, value=', '.join(_num(x) for x in vals))}/>", path)
        elif ty == "spectrum" and "filename" in value:
            fn = os.path.abspath(os.fspath(value["filename"]))
            xml.add(depth, f"<spectrum{_attrs(name=key, filename=fn)}/>", path)
        elif ty == "spectrum":
            v = value.get("value")
            if isinstance(v, (int, float)):
                text = _num(v)
            else:
                try:
                    text = ", ".join(f"{_num(w)}:{_num(x)}" for w, x in v)  # type: ignore[union-attr]
                except (TypeError, ValueError):
                    raise ValueError(
                        f"{_path(path)}: a spectrum value is a float or (wavelength, value) "
                        f"pairs, found {v!r}"
                    ) from None
            xml.add(depth, f"<spectrum{_attrs(name=key, value=text)}/>", path)
        else:
            _object(xml, value, key, None, depth, path)
        return
    if isinstance(value, (bool, np.bool_)):
        xml.add(depth, f"<boolean{_attrs(name=key, value='true' if value else 'false')}/>", path)
    elif isinstance(value, (int, np.integer)):
        xml.add(depth, f"<integer{_attrs(name=key, value=int(value))}/>", path)
    elif isinstance(value, (float, np.floating)):
        xml.add(depth, f"<float{_attrs(name=key, value=_num(value))}/>", path)
    elif isinstance(value, (str, os.PathLike)):
        text = os.fspath(value)
        if key == "filename" and text:
            # Relative to the working directory, as Mitsuba resolves them.
            text = os.path.abspath(text)
        xml.add(depth, f"<string{_attrs(name=key, value=text)}/>", path)
    else:
        m = _matrix(value, path)
        if m is not None:
            xml.add(depth, f"<transform{_attrs(name=key)}>", path)
            xml.add(depth + 1, f"<matrix{_attrs(value=' '.join(_num(x) for x in m.ravel()))}/>", path)
            xml.add(depth, "</transform>", path)
            return
        try:
            v = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            v = None
        if v is None or v.shape != (3,):
            raise TypeError(
                f"{_path(path)}: unsupported value {value!r} (expected a bool, int, float, "
                f"str, 3-vector, 4x4 transform, or a dict with a 'type')"
            )
        xml.add(depth, f"<point{_attrs(name=key, value=', '.join(_num(x) for x in v))}/>", path)


def _dict_to_xml(d: object) -> _Xml:
    if not isinstance(d, dict):
        raise TypeError(f"load_dict takes a dict, found {type(d).__name__}")
    if d.get("type") != "scene":
        raise ValueError(
            f"dict['type']: load_dict loads scenes ({{'type': 'scene', ...}}), found "
            f"{d.get('type')!r}"
        )
    xml = _Xml()
    xml.add(0, '<scene version="3.0.0">', ())
    for key, value in d.items():
        if key == "type":
            continue
        path = (key,)
        if key == "id":
            continue
        if not isinstance(value, dict):
            raise TypeError(
                f"{_path(path)}: a scene holds objects (dicts with a 'type'), found {value!r}"
            )
        if value.get("type") == "ref":
            raise ValueError(f"{_path(path)}: a reference cannot stand at the top of a scene")
        # As Mitsuba 3: a top-level object's key is its id unless it gives one.
        _object(xml, value, None, str(key), 1, path)
    xml.add(0, "</scene>", ())
    return xml


def load_dict(d: dict, **params: object) -> Scene:
    """Load a scene from Mitsuba 3's dictionary form (``mi.load_dict``)::

        penumbra.load_dict({
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 8},
            "sensor": {"type": "perspective", "fov": 40.0, "to_world": matrix_4x4,
                       "film": {"type": "hdrfilm", "width": 64, "height": 64}},
            "white": {"type": "diffuse",
                      "reflectance": {"type": "rgb", "value": [0.7, 0.7, 0.7]}},
            "ball": {"type": "sphere", "radius": 0.5, "bsdf": {"type": "ref", "id": "white"}},
            "light": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        })

    Every plugin Penumbra reads from Mitsuba XML works: the dictionary is written as that
    XML and loaded by the same loader. Nested dicts with a ``"type"`` are child objects;
    ``"id"`` names an object (a top-level object's key is its id unless it gives one, as in
    Mitsuba 3, so ``parameters()`` keys start with it); ``{"type": "ref", "id": ...}``
    refers to an object; ``{"type": "rgb", "value": ...}`` and ``{"type": "spectrum",
    "value": ...}`` are colours. Values: bool, int, float, str (relative ``filename`` values
    resolve against the working directory), 3-vectors (lists, tuples, arrays) as points, and
    transforms (``to_world``...) as 4x4 matrices: nested lists, NumPy arrays, or objects with
    a ``matrix`` (Mitsuba's ``ScalarTransform4f``). ``params`` as for :func:`load_file`.

    Errors name the key path: a malformed dictionary raises ``TypeError`` or ``ValueError``
    (``dict['ball']['radius']: ...``); what the loader refuses raises ``SceneError`` whose
    message starts with the key path of the object at fault.
    """
    xml = _dict_to_xml(d)
    text = "\n".join(xml.lines) + "\n"
    try:
        return _penumbra.load_string(text, "xml", _defines(params))
    except SceneError as e:
        line = getattr(e, "line", 0)
        if 1 <= line <= len(xml.paths):
            where = _path(xml.paths[line - 1])
            err = SceneError(f"{where}: {e}")
            err.file, err.line, err.col = "<dict>", 0, 0  # type: ignore[attr-defined]
            raise err from None
        raise


def _image(buf: bytearray, width: int, height: int) -> np.ndarray:
    # The bytearray is writable, so the array is too, without a copy.
    return np.frombuffer(buf, dtype=np.float32).reshape(height, width, 3)


def render(
    scene: Scene,
    spp: Optional[int] = None,
    seed: Optional[int] = 0,
    resolution: Optional[Tuple[int, int]] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[float], object]] = None,
    *,
    sensor: int = 0,
    mode: Optional[str] = None,
) -> np.ndarray:
    """Render ``scene`` and return the linear RGB image as a float32 array (height, width, 3).

    - ``spp``: samples per pixel (default: the scene's); for ``sppm``/``ppm`` iterations,
      for ``mlt`` mutations per pixel, as the CLI's ``--spp``.
    - ``seed``: seed of the sample streams (``--seed``); ``None`` takes the scene's (else 0).
      The image is a pure function of scene, seed and spp, whatever ``threads`` is.
    - ``resolution``: ``(width, height)``, as ``--res WxH`` (drops the film's crop window).
    - ``integrator``: as ``--integrator``: ``path``, ``volpath``, ``normals``, ``albedo``,
      ``depth``, ``ao[:N]``, ``photon[:PHOTONS[,GATHER[,K]]]``, ``sppm[:...]``, ``ppm[:...]``,
      ``ptracer``, ``bdpt``, ``mlt[:...]``; the scene's ``max_depth`` is kept.
    - ``threads``: worker threads (default: all cores).
    - ``progress``: called with the fraction done (0..1) from the calling thread, about
      every 20 ms while samples are added and once with 1.0 at the end; an exception it
      raises stops the render and is raised here.
    - ``sensor``: which sensor (camera) of the scene; ``mode``: ``rgb`` (default),
      ``spectral`` or a Mitsuba variant name (``scalar_spectral``), as ``--mode``.

    The GIL is released while rendering. Ctrl-C (SIGINT) stops the render at the end of the
    current pass (passes last about 0.25 s) and raises ``KeyboardInterrupt``.
    """
    buf, width, height, _spp, _warnings, _state = _native_render(
        scene, spp, seed, resolution, integrator, threads, sensor, mode, progress=progress
    )
    return _image(buf, width, height)


def _native_render(scene, spp, seed, resolution, integrator, threads, sensor, mode,
                   progress=None, shard=None):
    """``_penumbra.render`` with the arguments as :func:`render` takes them (shared with
    ``penumbra.distributed``)."""
    return _penumbra.render(
        scene,
        spp=spp,
        seed=seed,
        resolution=None if resolution is None else (int(resolution[0]), int(resolution[1])),
        integrator=integrator,
        threads=threads,
        sensor=sensor,
        mode=mode,
        progress=progress,
        shard=shard,
    )


def _rgb(image: object, what: str = "image") -> Tuple[bytes, int, int]:
    """An image as contiguous float32 RGB bytes: (H, W, 3), (H, W, 4) without its alpha, or
    (H, W) / (H, W, 1) grey."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(f"{what}: expected an array of shape (H, W, 3), found {a.shape}")
    if a.shape[2] == 4:
        a = a[:, :, :3]
    h, w = a.shape[0], a.shape[1]
    if h == 0 or w == 0:
        raise ValueError(f"{what}: the image is empty ({h}x{w})")
    return np.ascontiguousarray(a).tobytes(), w, h


def write(path: PathLike, image: object) -> None:
    """Write ``image`` (float32-convertible, (H, W, 3)) to ``path``; the extension picks the
    format: ``.exr`` (32-bit float), ``.png`` (8-bit sRGB), ``.hdr``, ``.pfm``. The file is
    written atomically (a temporary file, then a rename), as by the CLI."""
    data, w, h = _rgb(image)
    _penumbra.write(os.fspath(path), data, w, h)


def read(path: PathLike, srgb: bool = True) -> np.ndarray:
    """Read an image (EXR, PFM, HDR as stored; PNG/JPEG decoded from sRGB unless
    ``srgb=False``) as a float32 array (H, W, 3), with the reader the renderer uses."""
    buf, w, h = _penumbra.read(os.fspath(path), srgb)
    return _image(buf, w, h)


@dataclass(frozen=True)
class Comparison:
    """The outcome of :func:`compare` (``render::compare``'s figures).

    ``passed`` is the block t-test's verdict (smallest p-value over block-channels at least
    the Šidák-corrected level); ``bool(c)`` is ``c.passed``. ``worst`` is the block with the
    smallest p-value: ``(x, y, channel, test_mean, reference_mean, t, dof, p)``.
    """

    passed: bool
    rel_mse: float
    mean_ratio: Tuple[float, float, float]
    min_p: float
    threshold: float
    block_channels: int
    test_dof: float
    worst: Tuple[int, int, int, float, float, float, float, float]
    summary: str

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        return self.summary


def compare(
    reference: Union[PathLike, Tuple[object, object]],
    batches: Union[Sequence[object], object],
    stderr: Optional[object] = None,
    block: int = 8,
    alpha: float = 0.01,
) -> Comparison:
    """The block t-test the project's tests use (``penumbra compare``,
    ``shared/references/README.md``) of a render against a reference.

    - ``reference``: a path (``NAME``, ``NAME.exr``: ``NAME.stderr.exr`` must be beside it)
      or a ``(mean, stderr)`` pair of arrays.
    - ``batches``: K >= 2 independent renders of equal spp (different seeds), a list of
      arrays; or one array with its per-pixel standard error given as ``stderr``.
    - ``block``, ``alpha``: block edge in pixels and family-wise level.
    """
    if isinstance(reference, (str, os.PathLike)):
        ref = os.fspath(reference)
        size = None
    else:
        mean, se = reference  # type: ignore[misc]
        m, w, h = _rgb(mean, "reference mean")
        s, _, _ = _rgb(se, "reference stderr")
        ref, size = (m, s), (w, h)
    if stderr is not None:
        items = [batches]
    else:
        items = list(batches)  # type: ignore[arg-type]
    data = [_rgb(b, f"batch {i}") for i, b in enumerate(items)]
    if not data:
        raise ValueError("compare needs at least 2 batch images (or one with stderr=)")
    w, h = size if size is not None else (data[0][1], data[0][2])
    for i, (_, bw, bh) in enumerate(data):
        if (bw, bh) != (w, h):
            raise ValueError(f"batch {i} is {bw}x{bh}, expected {w}x{h}")
    se_bytes = None if stderr is None else _rgb(stderr, "stderr")[0]
    d = _penumbra.compare(ref, [b for b, _, _ in data], w, h, se_bytes, block, alpha)
    return Comparison(
        passed=d["passed"],
        rel_mse=d["rel_mse"],
        mean_ratio=tuple(d["mean_ratio"]),  # type: ignore[arg-type]
        min_p=d["min_p"],
        threshold=d["threshold"],
        block_channels=d["block_channels"],
        test_dof=d["test_dof"],
        worst=tuple(d["worst"]),  # type: ignore[arg-type]
        summary=d["summary"],
    )


def denoiser_available() -> bool:
    """Whether Intel Open Image Denoise can be loaded (``pip install pyoidn``, or the
    ``PENUMBRA_OIDN`` environment variable naming the library)."""
    return _penumbra.denoiser_available()


def denoise(
    image: object,
    albedo: Optional[object] = None,
    normal: Optional[object] = None,
    prefilter: bool = True,
    filter: Optional[str] = None,
) -> np.ndarray:
    """Denoise ``image`` (H, W, 3) with Intel Open Image Denoise 2, as ``penumbra denoise``:
    HDR, quality high, optionally guided by ``albedo`` (and ``normal``, which needs
    ``albedo``), prefiltering them when ``prefilter``. ``filter`` (``box``, ``tent``,
    ``gaussian``, ``mitchell``, ``lanczos``) applies that reconstruction filter afterwards,
    for an image rendered with the one-pixel box filter. Raises ``RuntimeError`` when the
    library is not found (see :func:`denoiser_available`)."""
    c, w, h = _rgb(image)

    def aux(a: Optional[object], what: str) -> Optional[bytes]:
        if a is None:
            return None
        b, aw, ah = _rgb(a, what)
        if (aw, ah) != (w, h):
            raise ValueError(f"the {what} image is {aw}x{ah}, the image {w}x{h}")
        return b

    buf = _penumbra.denoise(c, w, h, aux(albedo, "albedo"), aux(normal, "normal"), prefilter, filter)
    return _image(buf, w, h)
