"""Shared fixtures: the repository's root and scenes, and glint's command line (for the
tests that compare the package with what the command writes)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def glint_bin() -> Path:
    """glint's command line: ``GLINT_BIN``, else the repository's debug or release build.
    A missing binary fails the test that needs it (with how to build it), never skips it."""
    env = os.environ.get("GLINT_BIN")
    if env:
        return Path(env)
    for kind in ("debug", "release"):
        p = ROOT / "target" / kind / "glint"
        if p.is_file():
            return p
    pytest.fail("no glint binary: run `cargo build` or set GLINT_BIN")


def run_cli(*args: str) -> subprocess.CompletedProcess:
    """Runs ``glint ARGS`` from the repository root; fails the test if it fails."""
    r = subprocess.run([str(glint_bin()), *args], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, f"glint {' '.join(args)} failed:\n{r.stderr}"
    return r


def bits(a: np.ndarray) -> np.ndarray:
    """The array's float32 bits, to compare images bit for bit (NaN == NaN, -0 != +0)."""
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two float32 images are equal in every bit."""
    return a.shape == b.shape and bool(np.array_equal(bits(a), bits(b)))


@pytest.fixture
def lavapipe_expected() -> bool:
    """Whether this run's GPU tests must find lavapipe (the README's test command sets
    GLINT_ADAPTER=llvmpipe, and .ci/test.sh installs it)."""
    return os.environ.get("GLINT_ADAPTER", "") == "llvmpipe"
