"""Type stubs of the ``glint`` package."""

import os
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

from ._glint import RenderError as RenderError
from ._glint import Renderer as Renderer
from ._glint import Scene as Scene
from ._glint import SceneError as SceneError
from ._glint import adapters as adapters
from ._glint import aovs as aovs
from ._glint import backends as backends
from ._glint import load as load

SceneLike = Union[Scene, str, "os.PathLike[str]", Dict[str, Any]]
Progress = Callable[[int, int], Any]

def renderer(
    backend: str = "auto", adapter: Optional[str] = None, threads: Optional[int] = None
) -> Renderer:
    """The process's shared Renderer for a backend, adapter and thread count."""

@overload
def render(
    scene: SceneLike,
    backend: str = "auto",
    size: Optional[Tuple[int, int]] = None,
    samples: Optional[int] = None,
    triangle: Optional[str] = None,
    max_depth: Optional[int] = None,
    adapter: Optional[str] = None,
    math: str = "exact",
    threads: Optional[int] = None,
    progress: Optional[Progress] = None,
    aovs: None = None,
) -> npt.NDArray[np.float32]:
    """Renders a scene: float32 (height, width, 4), RGB and the hit distance t."""
@overload
def render(
    scene: SceneLike,
    backend: str = "auto",
    size: Optional[Tuple[int, int]] = None,
    samples: Optional[int] = None,
    triangle: Optional[str] = None,
    max_depth: Optional[int] = None,
    adapter: Optional[str] = None,
    math: str = "exact",
    threads: Optional[int] = None,
    progress: Optional[Progress] = None,
    *,
    aovs: Sequence[str],
) -> Dict[str, npt.NDArray[Any]]:
    """Renders a scene and its AOVs: ``color`` and one array per AOV (docs/aov.md)."""

def compare(
    scene: SceneLike,
    adapter: Optional[str] = None,
    size: Optional[Tuple[int, int]] = None,
    samples: Optional[int] = None,
    triangle: Optional[str] = None,
    max_depth: Optional[int] = None,
    math: str = "exact",
) -> Dict[str, Any]:
    """glint compare's metrics as a dict."""

def save(
    path: Union[str, "os.PathLike[str]"],
    array: Union[npt.NDArray[np.float32], npt.NDArray[np.uint8]],
    encoding: str = "linear",
) -> None:
    """Writes (height, width, 3|4) float32 or uint8 as PNG or EXR, whole or not at all."""
