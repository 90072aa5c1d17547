"""Type stubs of the ``glint`` package."""

import os
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._glint import RenderError as RenderError
from ._glint import Renderer as Renderer
from ._glint import Scene as Scene
from ._glint import SceneError as SceneError
from ._glint import adapters as adapters
from ._glint import backends as backends
from ._glint import compare_on as compare_on
from ._glint import load as load
from ._glint import renderers_made as renderers_made
from ._glint import save as save

SceneLike = Union[Scene, str, "os.PathLike[str]", Dict[str, Any]]

def renderer(backend: str = "auto", adapter: Optional[str] = None) -> Renderer:
    """The process's shared Renderer for a backend and adapter."""

def render(
    scene: SceneLike,
    backend: str = "auto",
    size: Optional[Tuple[int, int]] = None,
    samples: Optional[int] = None,
    triangle: Optional[str] = None,
    max_depth: Optional[int] = None,
    adapter: Optional[str] = None,
    math: str = "exact",
) -> npt.NDArray[np.float32]:
    """Renders a scene: float32 (height, width, 4), RGB and the hit distance t."""

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
