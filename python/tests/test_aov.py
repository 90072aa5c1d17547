"""AOVs from Python: the dict's arrays, their shapes and dtypes, the colour untouched, t
equal to the colour's own hit distance, the GPU's equal to the CPU's, and bad names."""

from __future__ import annotations

import os

import numpy as np
import pytest

import glint
from conftest import SCENES, bits, same_bits

ALL = ["t", "depth", "position", "geo_normal", "normal", "albedo", "prim_id",
       "object_id", "material_id", "mask"]


def test_aovs_come_as_a_dict_of_documented_arrays():
    out = glint.render(SCENES / "bb8.toml", backend="cpu", size=(64, 48), aovs=ALL)
    assert sorted(out) == sorted(["color", *ALL])
    assert out["color"].shape == (48, 64, 4) and out["color"].dtype == np.float32
    for name in ["t", "depth", "mask"]:
        assert out[name].shape == (48, 64) and out[name].dtype == np.float32, name
    for name in ["position", "geo_normal", "normal", "albedo"]:
        assert out[name].shape == (48, 64, 3) and out[name].dtype == np.float32, name
    for name in ["prim_id", "object_id", "material_id"]:
        assert out[name].shape == (48, 64) and out[name].dtype == np.uint32, name
    hit = out["mask"] == 1
    assert hit.any() and (~hit).any()
    assert (out["prim_id"][~hit] == 0xFFFFFFFF).all()
    assert (out["depth"][hit] > 0).all() and (out["depth"][hit] <= out["t"][hit]).all()
    n = np.linalg.norm(out["normal"][hit], axis=-1)
    assert np.abs(n - 1).max() < 1e-6


def test_the_colour_is_unchanged_and_t_is_its_hit_distance():
    plain = glint.render(SCENES / "bb8-shadows.toml", backend="cpu", size=(64, 48))
    out = glint.render(SCENES / "bb8-shadows.toml", backend="cpu", size=(64, 48),
                       aovs=["t"])
    assert same_bits(out["color"], plain)
    # Without antialiasing the colour's alpha is the centre ray's t: the same bits.
    assert np.array_equal(bits(out["t"]), bits(plain[..., 3]))
    # The twin: with 2x2 samples alpha is the nearest sample's t, not the centre's.
    aa = glint.render(SCENES / "bb8-shadows.toml", backend="cpu", size=(64, 48),
                      samples=2, aovs=["t"])
    assert not np.array_equal(bits(aa["t"]), bits(aa["color"][..., 3]))


def test_gpu_aovs_equal_the_cpus(lavapipe_expected):
    names = [a["name"] for a in glint.adapters()]
    if lavapipe_expected:
        assert any("llvmpipe" in n for n in names), names
    elif not names:
        pytest.fail("no Vulkan adapter: run the tests through .ci/test.sh, which installs lavapipe")
    r = glint.Renderer("gpu", adapter=os.environ.get("GLINT_ADAPTER"))
    kw = dict(size=(64, 48), aovs=["depth", "normal", "albedo", "prim_id"])
    g = r.render(SCENES / "textured.toml", **kw)
    c = glint.render(SCENES / "textured.toml", backend="cpu", **kw)
    for name in kw["aovs"]:
        assert np.array_equal(g[name].view(np.uint32), c[name].view(np.uint32)), name
    # The twin: one bit changed is seen.
    twin = c["depth"].copy()
    twin.view(np.uint32)[24, 32] ^= 1
    assert not np.array_equal(g["depth"].view(np.uint32), twin.view(np.uint32))


def test_an_unknown_aov_is_a_value_error_naming_them_all():
    with pytest.raises(ValueError, match=r'unknown AOV "speed".*geo_normal'):
        glint.render(SCENES / "bb8.toml", backend="cpu", size=(8, 8), aovs=["depth", "speed"])
