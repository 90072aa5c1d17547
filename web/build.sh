#!/usr/bin/env bash
# Builds the browser page into web/dist/: index.html, app.js, style.css, the wasm module
# (glint_web_bg.wasm) with its JS glue (glint_web.js), and scenes/ (the scenes whose
# files are in the repository, with scenes/index.json listing them). Any static server
# serves the folder, e.g. `python3 -m http.server -d web/dist 8000`.
#
#     bash web/build.sh
#
# - The Rust toolchain for wasm32-unknown-unknown comes from web/toolchain.sh: rustup's
#   target where rustup can add it, else Debian's, fetched privately (no system change).
# - wasm-bindgen-cli, at exactly the version of the `wasm-bindgen` crate in Cargo.lock (the
#   two must agree), is installed once with the system's cargo into .cache/wasm-bindgen.
#   Not `--locked`: one of its locked dependencies is missing from some registry mirrors.
# - The wasm is built with `--locked` into target/wasm (apart from native builds, which
#   may use another rustc).
# - It prints the module's size: raw, gzip -9 and, where `brotli` is installed, brotli.
# - GLINT_WEB_CLIPPY=1 lints the page's crate and glint, as compiled for wasm32, with
#   clippy's `-D warnings` while building them (clippy-driver as cargo's workspace wrapper):
#   the lints of `cargo clippy --target wasm32-unknown-unknown -p glint-web -- -D warnings`
#   without checking every dependency a second time (1 min 48 s of CI). It needs the
#   system's toolchain (rustup's), whose clippy-driver matches its rustc; with Debian's
#   toolchain it fails, saying so.
# Exit status: 0 with the folder built, non-zero with the reason on stderr.
set -euo pipefail
cd "$(dirname "$0")/.."
say() { echo "build.sh: $*" >&2; }

dist=web/dist
version="$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/[^0-9.]/, ""); print; exit }' Cargo.lock)"
[ -n "$version" ] || { say "no wasm-bindgen in Cargo.lock"; exit 1; }

bindgen=.cache/wasm-bindgen/bin/wasm-bindgen
if ! [ -x "$bindgen" ] || [ "$("$bindgen" --version 2>/dev/null)" != "wasm-bindgen $version" ]; then
    say "installing wasm-bindgen-cli $version into .cache/wasm-bindgen (once)"
    cargo install --quiet --force wasm-bindgen-cli --version "=$version" --root .cache/wasm-bindgen
fi

# The toolchain's settings only in this subshell's cargo.
settings="$(bash web/toolchain.sh)"
(
    eval "$settings"
    if [ "${GLINT_WEB_CLIPPY:-0}" = 1 ]; then
        driver="$(rustc --print sysroot)/bin/clippy-driver"
        [ "$GLINT_WASM_CARGO" = cargo ] && [ -x "$driver" ] || {
            say "GLINT_WEB_CLIPPY=1: no clippy-driver for the toolchain that builds the page (rustup's toolchain with clippy is needed)"
            exit 1
        }
        export RUSTC_WORKSPACE_WRAPPER="$driver" CLIPPY_ARGS="-Dwarnings"
        say "clippy -D warnings on glint-web and glint while they build"
    fi
    say "building glint-web with $GLINT_WASM_CARGO (rustc $GLINT_WASM_RUSTC_VERSION)"
    CARGO_TARGET_DIR=target/wasm "$GLINT_WASM_CARGO" build --locked --release \
        --target wasm32-unknown-unknown -p glint-web
)
wasm=target/wasm/wasm32-unknown-unknown/release/glint_web.wasm

rm -rf "$dist"
mkdir -p "$dist/scenes"
# Without the function-name and producers sections: 0.44 MB less with rustc 1.95, 1.16 MB
# with Debian's 1.98.1 (0.12-0.13 MB less gzipped). A panic's message, file and line still
# reach the console; its stack shows function indices.
"$bindgen" --target web --no-typescript --remove-name-section --remove-producers-section \
    --out-dir "$dist" "$wasm"
cp web/index.html web/app.js web/style.css "$dist/"

# The scenes that need nothing outside the repository (no meshes/ download), with the
# files they name.
names=()
for f in scenes/*.toml; do
    grep -q 'meshes/' "$f" && continue
    names+=("$(basename "$f" .toml)")
    cp "$f" "$dist/scenes/"
done
cp scenes/*.obj scenes/*.mtl scenes/*.ply "$dist/scenes/"
cp -r scenes/textures "$dist/scenes/"
{
    printf '{"scenes": ['
    sep=""
    for n in "${names[@]}"; do
        printf '%s"%s"' "$sep" "$n"
        sep=", "
    done
    printf ']}\n'
} >"$dist/scenes/index.json"

out="$dist/glint_web_bg.wasm"
raw=$(stat -c %s "$out")
gz=$(gzip -9 -c "$out" | wc -c)
line="glint_web_bg.wasm: $raw bytes, gzip -9 $gz"
if command -v brotli >/dev/null; then
    line="$line, brotli $(brotli -c -q 11 "$out" | wc -c)"
fi
say "$line"
say "built $dist (${#names[@]} scenes); serve it with: python3 -m http.server -d $dist 8000"
