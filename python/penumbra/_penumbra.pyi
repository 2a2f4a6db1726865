"""Type hints of the native module (crates/python/src/lib.rs); use the `penumbra` package's
functions, which take and return NumPy arrays."""

from typing import Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

__version__: str

class SceneError(ValueError):
    """A scene could not be loaded or built: ``file:line:col: message``."""

    file: str
    line: int
    col: int

class InternalError(RuntimeError):
    """A Rust panic inside penumbra, caught before it reached Python (a bug)."""

class Scene:
    """A loaded scene, editable with ``update`` (safe to render from several threads at
    once). It keeps what its renders built (textures, the acceleration structure) for the
    next render, as far as ``update`` leaves it valid. It pickles (its file path or text,
    parameters and edits), so Dask can send it to workers."""

    def __reduce__(self) -> Tuple[object, tuple]: ...

    @property
    def source(self) -> str:
        """The file the scene was loaded from, or ``<string>``."""
    @property
    def warnings(self) -> List[str]:
        """The loader's warnings."""
    @property
    def sensor_count(self) -> int:
        """The number of sensors (cameras)."""
    def resolution(self, sensor: int = 0) -> Tuple[int, int]:
        """The film size ``(width, height)`` of a sensor."""
    def parameters(self) -> Dict[str, Union[float, Tuple[float, float, float], List[List[float]]]]:
        """The editable values by key ``"<object>.<parameter>"`` (material colours and
        roughness, light intensities, sensor and shape ``to_world``): floats, 3-tuples, and
        4x4 matrices as lists of rows."""
    def update(self, values: Mapping[str, object]) -> List[str]:
        """Set parameters by key without reloading; the next render rebuilds only what they
        made stale (the acceleration structure only for a shape's ``to_world``). Raises
        ``KeyError`` (unknown key), ``TypeError`` (wrong kind of value), ``ValueError`` (out
        of range). Returns the kinds of change: ``material``, ``light``, ``camera``,
        ``geometry``."""
    def cache_info(self) -> Dict[str, bool]:
        """Whether the next render reuses an acceleration structure (``geometry``) and
        decoded textures (``textures``)."""

def load_file(path: str, defines: Sequence[Tuple[str, str]] = ...) -> Scene: ...
def load_string(text: str, format: str = "xml", defines: Sequence[Tuple[str, str]] = ...) -> Scene: ...
def render(
    scene: Scene,
    spp: Optional[int] = None,
    seed: Optional[int] = None,
    resolution: Optional[Tuple[int, int]] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    sensor: int = 0,
    mode: Optional[str] = None,
    progress: Optional[Callable[[float], object]] = None,
    shard: Optional[Tuple[int, int]] = None,
) -> Tuple[bytearray, int, int, int, List[str], Optional[bytes]]: ...
def merge_states(parts: Sequence[bytes]) -> Tuple[bytearray, int, int, int]: ...
def _rebuild_scene(
    kind: str, payload: str, format: str, defines: List[Tuple[str, str]], edits: dict
) -> Scene: ...
def write(path: str, data: bytes, width: int, height: int) -> None: ...
def read(path: str, srgb: bool = True) -> Tuple[bytearray, int, int]: ...
def compare(
    reference: Union[str, Tuple[bytes, bytes]],
    batches: Sequence[bytes],
    width: int,
    height: int,
    test_stderr: Optional[bytes] = None,
    block: int = 8,
    alpha: float = 0.01,
) -> dict: ...
def denoise(
    color: bytes,
    width: int,
    height: int,
    albedo: Optional[bytes] = None,
    normal: Optional[bytes] = None,
    prefilter: bool = True,
    filter: Optional[str] = None,
) -> bytearray: ...
def denoiser_available() -> bool: ...
