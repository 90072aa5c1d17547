"""glint from Python: render scenes into numpy arrays.

glint is a ray tracer whose main path is a WGSL compute shader, with a CPU tracer that
mirrors it bit for bit on Mesa lavapipe and an f64 tracer that is the ground truth for
error. This package is its library, reached from Python::

    import glint
    image = glint.render("scenes/bb8.toml")   # float32 (height, width, 4): RGB and t
    glint.save("bb8.png", image)

A ``Renderer`` keeps its device and compiled pipelines across calls; the module-level
``render`` keeps one per backend and adapter, so it never starts a device per call.
"""

from __future__ import annotations

import os
import threading
from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from ._glint import (
    RenderError,
    Renderer,
    Scene,
    SceneError,
    _compare_on,
    _renderers_made,
    _save,
    adapters,
    aovs,
    backends,
    load,
)

__all__ = [
    "Renderer",
    "RenderError",
    "Scene",
    "SceneError",
    "adapters",
    "aovs",
    "backends",
    "compare",
    "load",
    "render",
    "renderer",
    "save",
]

SceneLike = Union[Scene, str, "os.PathLike[str]", Dict[str, Any]]

Progress = Callable[[int, int], Any]

_renderers: Dict[Tuple[str, Optional[str], Optional[int]], Renderer] = {}
_lock = threading.Lock()


def renderer(
    backend: str = "auto", adapter: Optional[str] = None, threads: Optional[int] = None
) -> Renderer:
    """The process's shared ``Renderer`` for ``backend``, ``adapter`` and ``threads``, made
    on first use (and made again if it was closed).

    The module-level ``render`` and ``compare`` use it, so a device starts once per
    process, not once per call.
    """
    key = (backend, adapter, threads)
    with _lock:
        r = _renderers.get(key)
        if r is None or r.closed:
            r = Renderer(backend, adapter, threads)
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
    threads: Optional[int] = None,
    progress: Optional[Progress] = None,
    aovs: Optional[Sequence[str]] = None,
) -> Union[np.ndarray, Dict[str, np.ndarray]]:
    """Renders ``scene`` and returns float32 of shape (height, width, 4).

    The channels are linear RGB and the primary ray's hit distance t (-1 for a miss):
    exactly what ``glint render -o x.exr`` writes, in every bit.

    ``scene`` is a path (str or os.PathLike), a ``glint.Scene`` or a dict with the scene
    file's keys. ``backend`` is one of ``glint.backends()``; ``size=(width, height)``,
    ``samples``, ``triangle`` and ``max_depth`` override the scene's; ``adapter`` picks a
    Vulkan adapter by name; ``math`` is the GPU kernel's division and square root
    (``"exact"``: correctly rounded on every driver, the default; ``"corrected"``;
    ``"fast"``: the driver's own); ``threads`` the CPU threads (default one per core);
    ``progress(rows_done, rows_total)`` is called as rows are traced. Note the shapes:
    ``size`` is (width, height), as the command line's ``--size WxH``; the array is
    (height, width, 4), numpy's rows first. Raises ``glint.SceneError`` for a bad scene,
    ``OSError`` for a file that cannot be read, ``glint.RenderError`` when the render
    fails, ``KeyboardInterrupt`` on Ctrl-C.

    With ``aovs``, a list of AOV names (``t``, ``depth``, ``position``, ``geo_normal``,
    ``normal``, ``albedo``, ``prim_id``, ``object_id``, ``material_id``, ``mask``), it
    returns a dict: ``"color"``, the array above, and one array per AOV, of the ray
    through each pixel's centre: (height, width) for ``t``, ``depth``, ``mask`` and the
    ids, (height, width, 3) for ``position``, the normals and ``albedo``; float32, except
    the ids (uint32, 4294967295 on a miss). docs/aov.md defines each. An unknown name
    raises ``ValueError``; a single string, ``TypeError``.
    """
    if isinstance(aovs, str):
        raise TypeError(f"aovs: a list of AOV names, such as [{aovs!r}], not a string")
    return renderer(backend, adapter, threads).render(
        scene,
        size=size,
        samples=samples,
        triangle=triangle,
        max_depth=max_depth,
        math=math,
        progress=progress,
        aovs=None if aovs is None else list(aovs),
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
    return _compare_on(
        renderer("gpu", adapter),
        scene,
        size=size,
        samples=samples,
        triangle=triangle,
        max_depth=max_depth,
        math=math,
    )


def save(path: Any, array: Any, encoding: str = "linear") -> None:
    """Writes an image to ``path`` as its extension says: ``.png`` (8-bit RGB, as
    ``glint render`` writes it) or ``.exr`` (float32, exactly). The file appears whole or
    not at all (a temporary file beside it, then a rename).

    ``array`` has shape (height, width, 3) or (height, width, 4) and dtype float32 (linear
    colour, as ``render`` returns it; the 4th channel, t, goes to the EXR's alpha, and an
    RGB array gets alpha 1) or uint8 (bytes, written to a PNG as they are, and to an EXR as
    byte / 255). ``encoding`` is a PNG's transfer for float arrays: ``"linear"`` (the
    default, as the command line) or ``"srgb"`` (the sRGB curve; the PNG says so); an EXR
    is always linear. The older order, ``save(array, path)``, is still taken.
    """
    if isinstance(path, np.ndarray) and not isinstance(array, np.ndarray):
        path, array = array, path
    a = np.asarray(array)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(f"save: expected shape (height, width, 3 or 4), got {a.shape}")
    if a.dtype == np.uint8:
        a = a.astype(np.float32) / np.float32(255.0)
        encoding = "linear"
    elif a.dtype != np.float32:
        raise TypeError(f"save: expected float32 or uint8, got {a.dtype}")
    if a.shape[2] == 3:
        a = np.concatenate([a, np.ones(a.shape[:2] + (1,), np.float32)], axis=2)
    _save(np.ascontiguousarray(a), path, encoding)
