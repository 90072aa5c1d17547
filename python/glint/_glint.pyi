"""Type stubs of glint's extension module (re-exported by ``glint``)."""

import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

_Path = Union[str, "os.PathLike[str]"]

class SceneError(ValueError):
    """A scene is invalid: the message names the file, the line and the key."""

    file: Optional[str]
    line: Optional[int]
    key: Optional[str]

class RenderError(RuntimeError):
    """A render failed for a reason other than the scene or a file."""

class Scene:
    """A validated scene; its camera settable, picklable (by its text and paths)."""

    @staticmethod
    def load(path: _Path, *, cache: Union[None, bool, _Path] = True) -> Scene:
        """Loads and validates a scene file (meshes relative to its folder); cached as the
        command line caches unless ``cache`` is False or None."""
    @staticmethod
    def from_toml(text: str, base_dir: _Path = ".") -> Scene:
        """A scene from TOML text; mesh paths resolve against ``base_dir``."""
    @staticmethod
    def from_dict(d: Dict[str, Any], base_dir: _Path = ".") -> Scene:
        """A scene from a dict with the scene file's keys."""
    def to_dict(self) -> Dict[str, Any]:
        """The scene as a dict with the scene file's keys."""
    def to_toml(self) -> str:
        """The scene as TOML text."""
    @property
    def path(self) -> str:
        """The scene file's path (or ``<dict>`` / ``<toml>`` in the base folder)."""
    @property
    def size(self) -> Tuple[int, int]:
        """The camera's (width, height)."""
    @property
    def triangles(self) -> int:
        """How many triangles, meshes' included."""
    @property
    def spheres(self) -> int:
        """How many spheres."""
    @property
    def warnings(self) -> List[str]:
        """The warnings loading gave."""
    @property
    def camera(self) -> Dict[str, Any]:
        """The camera: eye, look_at, up, fov, size (width, height), samples."""
    @camera.setter
    def camera(self, value: Dict[str, Any]) -> None:
        """Changes the camera's given parts, as with_camera does, in this scene."""
    def camera_at(self, frame: float) -> Dict[str, Any]:
        """The camera at a frame of the camera path ([[camera.keys]]), as camera gives it."""
    def with_camera(
        self,
        *,
        eye: Optional[Tuple[float, float, float]] = None,
        look_at: Optional[Tuple[float, float, float]] = None,
        up: Optional[Tuple[float, float, float]] = None,
        fov: Optional[float] = None,
        size: Optional[Tuple[int, int]] = None,
        samples: Optional[int] = None,
    ) -> Scene:
        """A copy with the camera's given parts changed; meshes are not read again."""
    def with_instances(
        self, mesh: str, transforms: Any, material: Optional[str] = None
    ) -> Scene:
        """A copy with the named mesh placed once more for each object-to-world map of
        transforms, an (N, 3, 4) or (N, 4, 4) array (rows [m0, m1, m2, t]), with material
        replacing the mesh's own where given; meshes are not read again. A refused map
        raises ValueError naming its index, and nothing is added."""

class Renderer:
    """One backend, with its device and compiled pipelines kept across calls."""

    def __init__(
        self, backend: str = "auto", adapter: Optional[str] = None, threads: Optional[int] = None
    ) -> None: ...
    @overload
    def render(
        self,
        scene: Union[Scene, _Path, Dict[str, Any]],
        *,
        size: Optional[Tuple[int, int]] = None,
        samples: Optional[int] = None,
        triangle: Optional[str] = None,
        max_depth: Optional[int] = None,
        math: str = "exact",
        progress: Optional[Callable[[int, int], Any]] = None,
        aovs: None = None,
    ) -> npt.NDArray[np.float32]:
        """Renders a scene: float32 (height, width, 4), RGB and the hit distance t."""
    @overload
    def render(
        self,
        scene: Union[Scene, _Path, Dict[str, Any]],
        *,
        size: Optional[Tuple[int, int]] = None,
        samples: Optional[int] = None,
        triangle: Optional[str] = None,
        max_depth: Optional[int] = None,
        math: str = "exact",
        progress: Optional[Callable[[int, int], Any]] = None,
        aovs: Sequence[str],
    ) -> Dict[str, npt.NDArray[Any]]:
        """Renders a scene and its AOVs: ``color`` and one array per AOV (docs/aov.md)."""
    def close(self) -> None:
        """Lets the device go; a later render raises RenderError."""
    @property
    def closed(self) -> bool:
        """Whether close() was called."""
    def __enter__(self) -> Renderer: ...
    def __exit__(self, *args: Any) -> bool: ...
    @property
    def backend(self) -> str:
        """The backend asked for."""
    @property
    def note(self) -> Optional[str]:
        """Why ``auto`` chose what it chose, where it says."""
    def describe(self) -> str:
        """What renders, in words."""

def _compare_on(
    renderer: Renderer,
    scene: Union[Scene, _Path, Dict[str, Any]],
    *,
    size: Optional[Tuple[int, int]] = None,
    samples: Optional[int] = None,
    triangle: Optional[str] = None,
    max_depth: Optional[int] = None,
    math: str = "exact",
) -> Dict[str, Any]:
    """``glint compare`` on a GPU renderer's device."""

def aovs() -> List[str]:
    """The AOV names ``render(..., aovs=[...])`` takes, in order (docs/aov.md)."""

def adapters() -> List[Dict[str, str]]:
    """The Vulkan adapters, best first."""

def _save(array: npt.NDArray[np.float32], path: _Path, encoding: str) -> None:
    """glint.save's core: C-contiguous float32 (height, width, 4)."""

def load(path: _Path) -> npt.NDArray[np.float32]:
    """Reads a PNG or EXR as float32 (height, width, 4)."""

def _renderers_made() -> int:
    """How many Renderers this process has made."""

def backends() -> List[str]:
    """The backend names the library takes."""
