#!/usr/bin/env bash
# glint's test command (README: "Run the tests").
#
# 1. On a machine with no Vulkan driver it installs Mesa's lavapipe (a CPU Vulkan) first.
# 2. fmt, clippy -D warnings, then the whole suite on the system's lavapipe.
# 3. Every test binary with GPU tests again on Mesa >= 25's lavapipe, which
#    `.ci/lavapipe.sh` provides without touching the system (Debian 12: from backports,
#    unpacked privately; where the system's Mesa is already >= 25 that pass uses it).
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
export GLINT_ADAPTER="${GLINT_ADAPTER:-llvmpipe}"

cargo fmt --check
cargo clippy --all-targets --locked -- -D warnings
cargo build --locked --examples
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked --quiet

summary=()
adapter_line() {
    # The adapter the GPU tests will use, as the adapter reports it.
    cargo run --locked --quiet -- adapters | grep -i -m1 -- "$GLINT_ADAPTER" || {
        echo "glint: no adapter matching GLINT_ADAPTER=$GLINT_ADAPTER:" >&2
        cargo run --locked --quiet -- adapters >&2 || true
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
cargo test --locked --no-fail-fast 2>&1 | tee /tmp/glint-pass1.log
[ "${PIPESTATUS[0]}" = 0 ] || exit 1
summary+=("pass 1 ($([ "$skip_gpu" = 1 ] && echo 'GPU SKIPPED' || echo "$line1")): $(grep -c '^test .* ok$' /tmp/glint-pass1.log) tests ok in $((SECONDS - start)) s")

# ---- pass 2: the GPU test binaries on Mesa >= 25 ----------------------------------------
if [ "$skip_gpu" = 1 ]; then
    summary+=("pass 2 (Mesa >= 25): SKIPPED, GLINT_SKIP_GPU=1")
else
    start=$SECONDS
    settings="$(bash .ci/lavapipe.sh)" || {
        echo "glint: pass 2 cannot get Mesa >= 25's lavapipe (.ci/lavapipe.sh failed, above)" >&2
        exit 1
    }
    eval "$settings"
    line2="$(adapter_line)" || {
        echo "glint: pass 2 has no adapter with the Mesa >= 25 ICD" >&2
        exit 1
    }
    grep -Eq 'Mesa (2[5-9]|[3-9][0-9])\.' <<<"$line2" || {
        echo "glint: pass 2 wanted Mesa >= 25 but the adapter says: $line2" >&2
        exit 1
    }
    echo "=== pass 2: the GPU test binaries on $line2 ==="
    bins=()
    for f in $(grep -l '^gpu_sentinel!();' tests/*.rs); do
        bins+=(--test "$(basename "$f" .rs)")
    done
    # Mesa >= 24.1's lavapipe has ray queries: the ray-query tracer's tests must run here.
    GLINT_EXPECT_RAY_QUERY=1 GLINT_EXPECT_DRIVER="Mesa ${GLINT_MESA25_VERSION%%-*}" \
        cargo test --locked --no-fail-fast "${bins[@]}" 2>&1 |
        tee /tmp/glint-pass2.log
    [ "${PIPESTATUS[0]}" = 0 ] || exit 1
    summary+=("pass 2 ($line2): $(grep -c '^test .* ok$' /tmp/glint-pass2.log) tests ok in $((SECONDS - start)) s")
fi

echo
echo "=== glint test summary ==="
for s in "${summary[@]}"; do echo "$s"; done
if [ "$skip_gpu" = 1 ]; then
    echo "*** GLINT_SKIP_GPU=1: the GPU tests did NOT run; nothing here shows GPU = CPU. ***"
fi
