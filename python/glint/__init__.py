"""glint from Python: render scenes into numpy arrays.

glint is a ray tracer whose main path is a WGSL compute shader, with a CPU tracer that
mirrors it bit for bit on Mesa lavapipe and an f64 tracer that is the ground truth for
error. This package is its library, reached from Python::

    import glint
    image = glint.render("scenes/bb8.toml")   # float32 (height, width, 4): RGB and t
    glint.save(image, "bb8.png")

A ``Renderer`` keeps its device and compiled pipelines across calls; the module-level
``render`` keeps one per backend and adapter, so it never starts a device per call.
"""

from __future__ import annotations

import os
import threading
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

from ._glint import (
    RenderError,
    Renderer,
    Scene,
    SceneError,
    adapters,
    backends,
    compare_on,
    load,
    renderers_made,
    save,
)

__all__ = [
    "Renderer",
    "RenderError",
    "Scene",
    "SceneError",
    "adapters",
    "backends",
    "compare",
    "load",
    "render",
    "renderer",
    "save",
]

SceneLike = Union[Scene, str, "os.PathLike[str]", Dict[str, Any]]

_renderers: Dict[Tuple[str, Optional[str]], Renderer] = {}
_lock = threading.Lock()


def renderer(backend: str = "auto", adapter: Optional[str] = None) -> Renderer:
    """The process's shared ``Renderer`` for ``backend`` and ``adapter``, made on first use.

    The module-level ``render`` and ``compare`` use it, so a device starts once per
    process, not once per call.
    """
    key = (backend, adapter)
    with _lock:
        r = _renderers.get(key)
        if r is None:
            r = Renderer(backend, adapter)
            _renderers[key] = r
        return r


def render(
    scene: SceneLike,
    backend: str = "auto",
    size: Optional[Tuple[int, int]] = None,
    samples: Optional[int] = None,
    triangle: Optional[str] = None,
    max_depth: Optional[int] = None,
    adapter: Optional[str] = None,
    math: str = "exact",
) -> np.ndarray:
    """Renders ``scene`` and returns float32 of shape (height, width, 4).

    The channels are linear RGB and the primary ray's hit distance t (-1 for a miss):
    exactly what ``glint render -o x.exr`` writes, in every bit.

    ``scene`` is a path (str or os.PathLike), a ``glint.Scene`` or a dict with the scene
    file's keys. ``backend`` is one of ``glint.backends()``; ``size=(width, height)``,
    ``samples``, ``triangle`` and ``max_depth`` override the scene's; ``adapter`` picks a
    Vulkan adapter by name; ``math`` is the GPU kernel's division and square root
    (``"exact"``: correctly rounded on every driver, the default; ``"corrected"``;
    ``"fast"``: the driver's own). Raises
    ``glint.SceneError`` for a bad scene, ``OSError`` for a file that cannot be read,
    ``glint.RenderError`` when the render fails, ``KeyboardInterrupt`` on Ctrl-C.
    """
    return renderer(backend, adapter).render(
        scene,
        size=size,
        samples=samples,
        triangle=triangle,
        max_depth=max_depth,
        math=math,
    )


def compare(
    scene: SceneLike,
    adapter: Optional[str] = None,
    size: Optional[Tuple[int, int]] = None,
    samples: Optional[int] = None,
    triangle: Optional[str] = None,
    max_depth: Optional[int] = None,
    math: str = "exact",
) -> Dict[str, Any]:
    """``glint compare``: the GPU's image against its CPU mirror and both against f64.

    Returns a dict of the same metrics as the command: ``gpu_vs_cpu``, ``cpu_vs_f64`` and
    ``gpu_vs_f64`` (each with ``bit_exact``, ``differing_bits``, ``hit_miss``,
    ``differing_t``, ``max_abs``, ``rms``, ``mean_abs``, ``max_u8``), ``adapter``,
    ``exactness``, ``traversal``, ``algorithm``, ``width``, ``height``, ``warnings`` and
    ``ray_query``. ``math`` as in ``render``; with ``"exact"`` the GPU's image is the
    mirror's in every bit. Needs a Vulkan adapter (lavapipe will do).
    """
    return compare_on(
        renderer("gpu", adapter),
        scene,
        size=size,
        samples=samples,
        triangle=triangle,
        max_depth=max_depth,
        math=math,
    )
