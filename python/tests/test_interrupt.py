"""Ctrl-C stops a long render with KeyboardInterrupt, and the interpreter lives on."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from conftest import SCENES

SCRIPT = textwrap.dedent(
    """
    import os, signal, sys, threading, time
    import glint
    # Python leaves SIGINT ignored where its parent ignored it (a shell's background job).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    s = glint.Scene.load(sys.argv[1])
    r = glint.Renderer("cpu-f64")
    interrupt = sys.argv[2] == "1"
    if interrupt:
        threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
    start = time.perf_counter()
    try:
        a = r.render(s, size=(int(sys.argv[3]), int(sys.argv[3])), samples=4)
        print("finished", round(time.perf_counter() - start, 2))
    except KeyboardInterrupt:
        print("interrupted", round(time.perf_counter() - start, 2))
    # The interpreter and the renderer live on.
    print("alive", r.render(s, size=(8, 8)).shape)
    """
)


def run(interrupt: bool, side: int) -> list:
    r = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(SCENES / "whitted.toml"), "1" if interrupt else "0",
         str(side)],
        capture_output=True, text=True, timeout=300,
    )
    assert r.returncode == 0, r.stderr
    return r.stdout.split("\n")


def test_ctrl_c_interrupts_a_long_render():
    # 4096² pixels, 16 rays each, in f64: minutes on two cores.
    out = run(True, 4096)
    word, seconds = out[0].split()
    assert word == "interrupted", out
    assert float(seconds) < 3.0, out
    assert out[1] == "alive (8, 8, 4)", out


def test_without_ctrl_c_the_render_finishes():
    # The twin: the same script, no signal, a frame small enough to finish.
    out = run(False, 64)
    assert out[0].split()[0] == "finished", out
    assert out[1] == "alive (8, 8, 4)", out
