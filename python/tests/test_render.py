"""Rendering from Python: shapes, dtypes, every backend, and bit-equality with the EXR
that ``glint render`` writes."""

from __future__ import annotations

import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import glint
from conftest import ROOT, SCENES, bits, run_cli, same_bits


def test_render_gives_float32_rgb_and_t():
    a = glint.render(SCENES / "bb8.toml", backend="cpu", size=(64, 48))
    assert a.shape == (48, 64, 4)
    assert a.dtype == np.float32
    assert a.flags["C_CONTIGUOUS"]
    t = a[..., 3]
    assert (t == -1).any() and (t > 0).any(), "misses are -1, hits positive"
    assert ((t == -1) | (t > 0)).all()


@pytest.mark.parametrize("backend", ["cpu", "cpu-f64"])
@pytest.mark.parametrize("scene", ["bb8.toml", "whitted.toml", "bb8-shadows.toml"])
def test_render_equals_the_clis_exr_in_every_bit(tmp_path, scene, backend):
    exr = tmp_path / "cli.exr"
    run_cli("render", str(SCENES / scene), "-o", str(exr), "--backend", backend,
            "--size", "160x120")
    cli = glint.load(exr)
    py = glint.render(SCENES / scene, backend=backend, size=(160, 120))
    assert same_bits(py, cli)
    # The twin: one bit of one pixel changed is seen.
    twin = py.copy()
    twin.view(np.uint32)[60, 80, 1] ^= 1
    assert not same_bits(twin, cli)


def test_a_gpu_render_equals_the_cpu_mirror_on_lavapipe(lavapipe_expected):
    names = [a["name"] for a in glint.adapters()]
    if lavapipe_expected:
        assert any("llvmpipe" in n for n in names), names
    elif not names:
        pytest.fail("no Vulkan adapter: run the tests through .ci/test.sh, which installs lavapipe")
    r = glint.Renderer("gpu", adapter=os.environ.get("GLINT_ADAPTER"))
    for scene in ["bb8-shadows.toml", "whitted.toml"]:
        g = r.render(SCENES / scene, size=(96, 72))
        c = glint.render(SCENES / scene, backend="cpu", size=(96, 72))
        assert same_bits(g, c), scene
    # The twin: another scene's image differs.
    assert not same_bits(r.render(SCENES / "bb8.toml", size=(96, 72)), c)


def test_options_override_the_scene():
    s = glint.Scene.load(SCENES / "bb8-mirror.toml")
    one = glint.render(s, backend="cpu", size=(80, 60), max_depth=0)
    deep = glint.render(s, backend="cpu", size=(80, 60))
    assert not same_bits(one, deep), "max_depth=0 drops the reflections"
    aa = glint.render(s, backend="cpu", size=(80, 60), samples=2)
    assert not same_bits(aa, deep)
    w = glint.render(s, backend="cpu", size=(80, 60), triangle="watertight")
    assert w.shape == deep.shape


def test_the_module_keeps_one_renderer_per_backend():
    glint.render(SCENES / "sphere.toml", backend="cpu", size=(8, 8))
    before = glint.renderers_made()
    for _ in range(3):
        glint.render(SCENES / "sphere.toml", backend="cpu", size=(8, 8))
    assert glint.renderers_made() == before
    assert glint.renderer("cpu") is glint.renderer("cpu")
    # The twin: a Renderer made by hand is counted.
    glint.Renderer("cpu")
    assert glint.renderers_made() == before + 1


def test_threads_render_in_parallel_and_agree():
    s = glint.Scene.load(SCENES / "whitted.toml")
    r = glint.Renderer("cpu")
    serial = [r.render(s, size=(120, 90), samples=k) for k in (1, 2, 3, 1)]
    with ThreadPoolExecutor(4) as ex:
        parallel = list(ex.map(lambda k: r.render(s, size=(120, 90), samples=k), (1, 2, 3, 1)))
    assert all(same_bits(a, b) for a, b in zip(serial, parallel))


def test_the_gil_is_released_while_rendering():
    # A Python thread keeps counting while a long render runs in another: with the GIL
    # held for the whole render it could not run at all.
    s = glint.Scene.load(SCENES / "whitted.toml")
    r = glint.Renderer("cpu-f64")
    done = threading.Event()
    def work():
        r.render(s, size=(640, 480), samples=2)
        done.set()
    t = threading.Thread(target=work)
    t.start()
    time.sleep(0.02)
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0)
    t.join()
    assert ticks > 1000, ticks


def test_save_writes_what_the_cli_writes(tmp_path):
    png = tmp_path / "cli.png"
    run_cli("render", str(SCENES / "bb8.toml"), "-o", str(png), "--backend", "cpu",
            "--size", "96x72")
    a = glint.render(SCENES / "bb8.toml", backend="cpu", size=(96, 72))
    glint.save(a, tmp_path / "py.png")
    assert same_bits(glint.load(tmp_path / "py.png"), glint.load(png))
    glint.save(a, tmp_path / "py.exr")
    assert same_bits(glint.load(tmp_path / "py.exr"), a)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cli.png", "py.exr", "py.png"]


def test_save_refuses_bad_input(tmp_path):
    a = np.zeros((4, 4, 4), np.float32)
    with pytest.raises(ValueError, match="unknown image extension"):
        glint.save(a, tmp_path / "x.jpg")
    with pytest.raises(ValueError, match="shape"):
        glint.save(np.zeros((4, 4, 3), np.float32), tmp_path / "x.png")
    with pytest.raises(FileNotFoundError):
        glint.save(a, tmp_path / "no" / "such" / "x.png")
    with pytest.raises(FileNotFoundError):
        glint.load(tmp_path / "missing.exr")


def test_compare_reports_the_clis_metrics(lavapipe_expected):
    c = glint.compare(SCENES / "bb8.toml", adapter=os.environ.get("GLINT_ADAPTER"),
                      size=(64, 48))
    assert {"gpu_vs_cpu", "cpu_vs_f64", "gpu_vs_f64", "adapter", "exactness"} <= set(c)
    assert c["width"] == 64 and c["height"] == 48
    if lavapipe_expected:
        assert c["gpu_vs_cpu"]["bit_exact"] is True
        assert c["gpu_vs_cpu"]["differing_bits"] == 0
    # The twin: f32 against f64 is not exact, and says so.
    assert c["cpu_vs_f64"]["bit_exact"] is False
    assert c["cpu_vs_f64"]["differing_bits"] > 0


def test_compare_with_the_corrections_is_bit_exact(lavapipe_expected):
    c = glint.compare(SCENES / "whitted.toml", adapter=os.environ.get("GLINT_ADAPTER"),
                      size=(48, 36), math="corrected")
    if lavapipe_expected:
        assert c["gpu_vs_cpu"]["bit_exact"] is True
    with pytest.raises(ValueError, match="unknown math"):
        glint.render(SCENES / "bb8.toml", backend="cpu", math="approximate")


def test_compare_needs_a_gpu_renderer():
    with pytest.raises(ValueError, match="GPU renderer"):
        glint.compare_on(glint.Renderer("cpu"), SCENES / "bb8.toml")


def test_unknown_names_are_value_errors():
    with pytest.raises(ValueError, match="unknown backend"):
        glint.Renderer("vulkan")
    assert glint.backends() == ["auto", "gpu", "gpu-rq", "cpu", "cpu-f64"]
    with pytest.raises(ValueError):
        glint.render(SCENES / "bb8.toml", backend="cpu", triangle="pluecker")
    with pytest.raises(ValueError, match="size 0x4"):
        glint.render(SCENES / "bb8.toml", backend="cpu", size=(0, 4))
    with pytest.raises(TypeError):
        glint.render(42, backend="cpu")
