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
    before = glint._renderers_made()
    for _ in range(3):
        glint.render(SCENES / "sphere.toml", backend="cpu", size=(8, 8))
    assert glint._renderers_made() == before
    assert glint.renderer("cpu") is glint.renderer("cpu")
    # The twin: a Renderer made by hand is counted.
    glint.Renderer("cpu")
    assert glint._renderers_made() == before + 1


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
    glint.save(tmp_path / "py.png", a)
    assert same_bits(glint.load(tmp_path / "py.png"), glint.load(png))
    glint.save(tmp_path / "py.exr", a)
    assert same_bits(glint.load(tmp_path / "py.exr"), a)
    # The older order is still taken.
    glint.save(a, tmp_path / "old.png")
    assert same_bits(glint.load(tmp_path / "old.png"), glint.load(png))
    # sRGB: the command line's --encoding srgb, bit for bit; and not the linear PNG.
    srgb = tmp_path / "cli-srgb.png"
    run_cli("render", str(SCENES / "bb8.toml"), "-o", str(srgb), "--backend", "cpu",
            "--size", "96x72", "--encoding", "srgb")
    glint.save(tmp_path / "py-srgb.png", a, encoding="srgb")
    assert same_bits(glint.load(tmp_path / "py-srgb.png"), glint.load(srgb))
    assert not same_bits(glint.load(srgb), glint.load(png))
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "cli-srgb.png", "cli.png", "old.png", "py-srgb.png", "py.exr", "py.png"]


def test_save_takes_rgb_and_bytes(tmp_path):
    a = glint.render(SCENES / "bb8.toml", backend="cpu", size=(32, 24))
    glint.save(tmp_path / "rgba.png", a)
    glint.save(tmp_path / "rgb.png", a[..., :3].copy())
    assert same_bits(glint.load(tmp_path / "rgb.png"), glint.load(tmp_path / "rgba.png"))
    # uint8 bytes go to the PNG as they are.
    b = (np.arange(32 * 24 * 3) % 256).astype(np.uint8).reshape(24, 32, 3)
    glint.save(tmp_path / "bytes.png", b)
    back = glint.load(tmp_path / "bytes.png")[..., :3]
    assert np.array_equal(np.rint(back * 255).astype(np.uint8), b)
    # An RGB EXR gets alpha 1.
    glint.save(tmp_path / "rgb.exr", a[..., :3].copy())
    e = glint.load(tmp_path / "rgb.exr")
    assert same_bits(e[..., :3], a[..., :3]) and (e[..., 3] == 1).all()


def test_save_refuses_bad_input(tmp_path):
    a = np.zeros((4, 4, 4), np.float32)
    with pytest.raises(ValueError, match="unknown image extension"):
        glint.save(a, tmp_path / "x.jpg")
    with pytest.raises(ValueError, match="shape"):
        glint.save(tmp_path / "x.png", np.zeros((4, 4, 2), np.float32))
    with pytest.raises(TypeError, match="float64"):
        glint.save(tmp_path / "x.png", np.zeros((4, 4, 4), np.float64))
    with pytest.raises(ValueError, match="encoding"):
        glint.save(tmp_path / "x.png", a, encoding="gamma")
    with pytest.raises(FileNotFoundError):
        glint.save(tmp_path / "no" / "such" / "x.png", a)
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
        glint._compare_on(glint.Renderer("cpu"), SCENES / "bb8.toml")


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


def test_threads_progress_and_close():
    s = glint.Scene.load(SCENES / "whitted.toml")
    seen = []
    one = glint.Renderer("cpu", threads=1)
    a = one.render(s, size=(64, 48), progress=lambda done, total: seen.append((done, total)))
    b = glint.Renderer("cpu").render(s, size=(64, 48))
    assert same_bits(a, b), "the thread count changes no bit"
    assert seen and seen[-1] == (48, 48) and all(t == 48 for _, t in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    # A progress callback that raises stops the render with its exception.
    def stop(done, total):
        raise RuntimeError("stop here")
    with pytest.raises(RuntimeError, match="stop here"):
        one.render(s, size=(64, 48), progress=stop)
    with pytest.raises(ValueError, match="threads"):
        glint.Renderer("cpu", threads=0)
    # close(), and the context manager.
    with glint.Renderer("cpu") as r:
        r.render(s, size=(8, 8))
        assert not r.closed
    assert r.closed and r.describe() == "closed"
    with pytest.raises(glint.RenderError, match="closed"):
        r.render(s, size=(8, 8))
    r.close()  # twice is allowed
    # The module's shared renderer is made again once closed.
    glint.renderer("cpu").close()
    assert not glint.renderer("cpu").closed
