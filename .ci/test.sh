#!/usr/bin/env bash
# glint's test command (README: "Run the tests"). On a machine with no Vulkan driver it
# installs Mesa's lavapipe (a CPU Vulkan) first, so the GPU tests run everywhere; they fail,
# not skip, when no adapter is found (GLINT_SKIP_GPU=1 skips them, loudly).
set -euo pipefail
cd "$(dirname "$0")/.."

have_vulkan() {
    ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' &&
        ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1
}
if [ "${GLINT_SKIP_GPU:-0}" != 1 ] && ! have_vulkan; then
    echo "glint: no Vulkan driver found; installing mesa-vulkan-drivers and libvulkan1 (lavapipe)"
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
fi

cargo fmt --check
cargo clippy --all-targets --locked -- -D warnings
cargo test --locked
