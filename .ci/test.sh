#!/usr/bin/env bash
# glint's test command (README, "On a fresh machine"; each pass in docs/testing.md).
#
# 1. On a machine with no Vulkan driver it installs Mesa's lavapipe (a CPU Vulkan) first.
# 2. fmt, clippy -D warnings, then the whole suite on the system's lavapipe (with Xvfb and
#    xdotool installed first for `glint view`'s window tests).
# 3. Pass 4: the Python package, `pip install ./python[test]` into a fresh venv, and pytest.
#    Pass 5: the browser page: `bash web/build.sh` (wasm), Debian's Chromium installed, and
#    tests/browser.rs's ignored tests run in headless Chromium with WebGPU (SwiftShader).
# 4. Every test binary with GPU tests again on Mesa 25.0's lavapipe and on Mesa 26.1's,
#    which `.ci/lavapipe.sh` provides without touching the system (Debian 12: from
#    bookworm-backports and from Debian 13's trixie-backports, unpacked privately; 26.1's
#    test binaries run through the unpacked tree's own dynamic loader, as cargo's runner).
#    Each pass asserts the driver it runs on and, as every GPU test does on lavapipe, that
#    the GPU image equals the CPU mirror's in every bit.
#
# Each pass prints the adapter's name, driver and version. A pass that cannot get its
# driver fails with the reason; nothing is skipped in silence. GLINT_SKIP_GPU=1 skips the
# GPU checks (each test binary's `gpu_tests_ran` shows as "ignored", and the summary below
# says so) and the second pass. GLINT_ADAPTER picks the adapter (default: lavapipe, so the
# bit-exact promise is asserted even on a machine with a real GPU).
set -euo pipefail
cd "$(dirname "$0")/.."

have_vulkan() {
    ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' &&
        ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1
}
skip_gpu=0
[ "${GLINT_SKIP_GPU:-0}" = 1 ] && skip_gpu=1
if [ "$skip_gpu" = 0 ] && ! have_vulkan; then
    echo "glint: no Vulkan driver found; installing mesa-vulkan-drivers and libvulkan1 (lavapipe)"
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
fi
# `glint view`'s tests (tests/view.rs) open a real window under Xvfb and drive it with
# xdotool, and read the screen back with xwd (x11-apps); the window needs X11's client
# libraries.
view_pkgs=(xvfb xauth xdotool x11-apps libx11-xcb1 libxcursor1 libxi6 libxkbcommon-x11-0)
missing=()
for p in "${view_pkgs[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
    echo "glint: installing ${missing[*]} for the viewer's tests"
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi
export GLINT_ADAPTER="${GLINT_ADAPTER:-llvmpipe}"
# A fresh clone gains nothing from incremental builds but their disk (1.6 GB). The whole
# run needs about 6 GB under target/; say what the disk has, so a full disk reads as such.
export CARGO_INCREMENTAL=0
disk_free() { df -Pm . | awk 'NR == 2 { printf "%.1f GB free", $4 / 1024 }'; }
echo "glint: disk before the build: $(disk_free)"
# The tests start a Vulkan device in many processes: Mesa prints a conformance warning for
# lavapipe at each start, and its window-system code complains where XDG_RUNTIME_DIR is
# unset (the library sets no environment variable; `glint` itself quiets both at start).
export MESA_VK_IGNORE_CONFORMANCE_WARNING=1
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    XDG_RUNTIME_DIR="$(mktemp -d)"
    export XDG_RUNTIME_DIR
fi

cargo fmt --all --check
cargo clippy --workspace --all-targets --locked --features glint/view -- -D warnings
cargo build --locked --features view --examples
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked --features view --quiet

summary=()
adapter_line() {
    # The adapter the GPU tests will use, as the adapter reports it.
    cargo run --locked --quiet --features view -- adapters | grep -i -m1 -- "$GLINT_ADAPTER" || {
        echo "glint: no adapter matching GLINT_ADAPTER=$GLINT_ADAPTER:" >&2
        cargo run --locked --quiet --features view -- adapters >&2 || true
        return 1
    }
}

# ---- pass 1: the whole suite on the system's driver -------------------------------------
start=$SECONDS
if [ "$skip_gpu" = 1 ]; then
    echo "=== pass 1: the whole suite, GPU tests SKIPPED (GLINT_SKIP_GPU=1) ==="
else
    line1="$(adapter_line)" || {
        echo "glint: pass 1 has no lavapipe adapter; the GPU tests cannot run" >&2
        exit 1
    }
    echo "=== pass 1: the whole suite on $line1 ==="
fi
cargo test --locked --features view --no-fail-fast 2>&1 | tee /tmp/glint-pass1.log
[ "${PIPESTATUS[0]}" = 0 ] || exit 1
summary+=("pass 1 ($([ "$skip_gpu" = 1 ] && echo 'GPU SKIPPED' || echo "$line1")): $(grep -c '^test .* ok$' /tmp/glint-pass1.log) tests ok in $((SECONDS - start)) s")

# ---- pass 4: the Python package, built into a fresh venv as a user installs it ----------
# `pip install ./python` (maturin, fetched by pip) and pytest's tests under python/tests:
# bit-equality with the command line's EXR (GLINT_BIN: pass 1's debug build), errors,
# pickling, threads, Ctrl-C, and the Dask turntable on a LocalCluster of 2 workers.
start=$SECONDS
if ! python3 -m venv --help >/dev/null 2>&1 || ! python3 -c 'import ensurepip' 2>/dev/null; then
    echo "glint: python3 has no venv module; installing python3-venv"
    $([ "$(id -u)" -eq 0 ] || echo sudo) apt-get install -y -qq python3-venv >/dev/null
fi
rm -rf .cache/pyenv
python3 -m venv .cache/pyenv
.cache/pyenv/bin/pip install --quiet --upgrade pip
echo "=== pass 4: pip install ./python[test], then pytest python/tests ==="
.cache/pyenv/bin/pip install --quiet "./python[test]"
cargo build --locked --features view --quiet # the command line the tests compare with
GLINT_BIN="$PWD/target/debug/glint" .cache/pyenv/bin/python -m pytest python/tests 2>&1 |
    tee /tmp/glint-pass4.log
[ "${PIPESTATUS[0]}" = 0 ] || exit 1
summary+=("pass 4 (Python $(.cache/pyenv/bin/python -c 'import sys; print(sys.version.split()[0])')): $(grep -Eo '[0-9]+ passed' /tmp/glint-pass4.log | tail -1) in $((SECONDS - start)) s")

# ---- pass 5: the browser page in headless Chromium with WebGPU --------------------------
# web/build.sh provides its wasm toolchain itself (rustup's target, or Debian's, privately);
# the tests drive Chromium through the DevTools protocol with Node's built-in WebSocket.
start=$SECONDS
if ! command -v chromium >/dev/null; then
    echo "glint: installing chromium for the browser page's tests"
    export DEBIAN_FRONTEND=noninteractive
    $([ "$(id -u)" -eq 0 ] || echo sudo) apt-get update -qq
    $([ "$(id -u)" -eq 0 ] || echo sudo) apt-get install -y -qq chromium >/dev/null
fi
command -v node >/dev/null || {
    echo "glint: pass 5 needs Node.js 20 or newer (node) for the DevTools driver" >&2
    exit 1
}
echo "=== pass 5: the browser page ($(chromium --version 2>/dev/null), node $(node --version)) ==="
# The page's crate is empty natively: clippy lints it (and glint as compiled for wasm32)
# while web/build.sh builds it, where the system's toolchain (rustup's) builds the page;
# with Debian's wasm toolchain there is no matching clippy, and this says so.
if compgen -G "$(rustc --print target-libdir --target wasm32-unknown-unknown 2>/dev/null)/libstd-*.rlib" >/dev/null ||
    { command -v rustup >/dev/null && rustup target add wasm32-unknown-unknown >/dev/null 2>&1; }; then
    GLINT_WEB_CLIPPY=1 bash web/build.sh
else
    echo "glint: the system's rustc has no wasm32 target: the page is built with Debian's toolchain and NOT linted by clippy for wasm32"
    bash web/build.sh
fi
cargo test --locked --features view --test browser -- --ignored 2>&1 | tee /tmp/glint-pass5.log
[ "${PIPESTATUS[0]}" = 0 ] || exit 1
summary+=("pass 5 (browser: $(chromium --version 2>/dev/null)): $(grep -c '^test .* ok$' /tmp/glint-pass5.log) tests ok in $((SECONDS - start)) s")

# ---- passes 2 and 3: the GPU test binaries on Mesa 25.0 and on Mesa 26.1 ---------------
gpu_bins=()
for f in $(grep -l '^gpu_sentinel!();' tests/*.rs); do
    gpu_bins+=(--test "$(basename "$f" .rs)")
done
driver_pass() { # pass number, Mesa major
    local n="$1" major="$2" settings line start=$SECONDS
    settings="$(bash .ci/lavapipe.sh "$major")" || {
        echo "glint: pass $n cannot get Mesa $major's lavapipe (.ci/lavapipe.sh $major failed, above)" >&2
        return 1
    }
    (
        eval "$settings"
        line="$(adapter_line)" || {
            echo "glint: pass $n has no adapter with the Mesa $major ICD" >&2
            exit 1
        }
        grep -Eq "Mesa $major\." <<<"$line" || {
            echo "glint: pass $n wanted Mesa $major but the adapter says: $line" >&2
            exit 1
        }
        echo "=== pass $n: the GPU test binaries on $line ==="
        # Mesa >= 24.1's lavapipe has ray queries: the ray-query tracer's tests must run here.
        GLINT_EXPECT_RAY_QUERY=1 GLINT_EXPECT_DRIVER="Mesa ${GLINT_MESA_VERSION%%-*}" \
            cargo test --locked --features view --no-fail-fast "${gpu_bins[@]}" 2>&1 |
            tee "/tmp/glint-pass$n.log"
        [ "${PIPESTATUS[0]}" = 0 ] || exit 1
        echo "$line" >"/tmp/glint-pass$n.adapter"
    ) || return 1
    summary+=("pass $n ($(cat "/tmp/glint-pass$n.adapter")): $(grep -c '^test .* ok$' "/tmp/glint-pass$n.log") tests ok in $((SECONDS - start)) s")
}
if [ "$skip_gpu" = 1 ]; then
    summary+=("passes 2 and 3 (Mesa 25.0, 26.1): SKIPPED, GLINT_SKIP_GPU=1")
else
    driver_pass 2 25 || exit 1
    driver_pass 3 26 || exit 1
fi

echo
echo "=== glint test summary ($(du -sm target | awk '{ printf "%.1f GB", $1 / 1024 }') under target/, $(disk_free) after) ==="
for s in "${summary[@]}"; do echo "$s"; done
if [ "$skip_gpu" = 1 ]; then
    echo "*** GLINT_SKIP_GPU=1: the GPU tests did NOT run; nothing here shows GPU = CPU. ***"
fi
