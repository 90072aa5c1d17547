#!/usr/bin/env bash
# Provides newer lavapipes (Mesa's CPU Vulkan) than the system's, Mesa 25.0 and Mesa 26.1,
# without touching the system's packages or apt sources, and prints the environment
# settings that select one, or runs a command under one:
#
#     eval "$(bash .ci/lavapipe.sh)"       # Mesa 25.0, the same as `bash .ci/lavapipe.sh 25`
#     eval "$(bash .ci/lavapipe.sh 26)"    # Mesa 26.1
#     bash .ci/lavapipe.sh 25 -- CMD ARGS...
#     bash .ci/lavapipe.sh 26 -- target/release/glint adapters
#
# Settings printed (bash `export` lines, for eval):
#   25: VK_ICD_FILENAMES, LD_LIBRARY_PATH and GLINT_MESA_VERSION (`.ci/test.sh` reads it).
#   26: VK_ICD_FILENAMES, GLINT_MESA_VERSION, GLINT_LAVAPIPE_LOADER (the runner below) and
#       CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_RUNNER (the same runner, so that `cargo run`,
#       `cargo test` and `cargo bench` start each binary through it). No LD_LIBRARY_PATH:
#       trixie's libraries would break every other program started from that shell.
# `VERSION -- CMD ARGS...` sets these and execs CMD (its exit status is the script's). For 26
# CMD goes through the runner, so an ELF program given by path or found on PATH runs on
# Mesa 26.1; a script, or cargo, runs as it is with the runner exported as cargo's runner.
#
# - Mesa 25: on Debian 12 it fetches `mesa-vulkan-drivers`, `libdrm2` and `libdrm-amdgpu1`
#   from `bookworm-backports`. They run on Debian 12's own libc and LLVM; LD_LIBRARY_PATH
#   only points the driver at the newer libdrm.
# - Mesa 26: Debian 12 has no Mesa >= 25.1. It fetches `mesa-vulkan-drivers` from Debian
#   13's `trixie-backports` and `libvulkan1`, with all their dependencies from `trixie` and
#   `trixie-backports` (about 38 packages, libc6 2.41, libstdc++6 and libLLVM 19 among them),
#   resolved against an EMPTY private dpkg status file, so apt takes every dependency as
#   not installed. That libvulkan_lvp.so needs a newer glibc, libstdc++ and LLVM than Debian
#   12's, and a process has one glibc: its dynamic loader and libc.so.6 must match. So the
#   program runs through the unpacked tree's own dynamic loader:
#       ROOT/usr/lib64/ld-linux-x86-64.so.2 --library-path ROOT/usr/lib/x86_64-linux-gnu:… \
#           --argv0 PROGRAM PROGRAM ARGS...
#   (the trixie libvulkan1 comes first on that path; what the tree lacks comes from the
#   system's usual directories). That works for ELF executables only, and only for that
#   process: what it starts runs on the system's glibc again, where the Mesa 26 ICD cannot
#   load (no adapter), unless it is started through the runner too. In such a process
#   /proc/self/exe (Rust's `current_exe`) names the loader, not the program.
#   The runner, `$cache/26/run PROGRAM ARGS...`, written by this script, does exactly that.
# - Both: packages come through a private apt configuration (its own sources list, lists,
#   cache and, for 26, dpkg status, all under the cache folder), are unpacked with `dpkg -x`,
#   and an ICD json naming the absolute path of the unpacked `libvulkan_lvp.so` is written
#   beside them. The archive's address is read from the machine's own bookworm apt source;
#   none is written here. Signatures are always checked: against
#   /usr/share/keyrings/debian-archive-keyring.gpg, which holds trixie's keys since
#   debian-archive-keyring 2023.3+deb12u1; where it is older, the newest
#   debian-archive-keyring from bookworm itself (verified with the bookworm keys) is fetched
#   and its keyring used for trixie.
# - Where the system's own lavapipe is already at least the version asked for, it says so
#   (on stderr) and selects the system's ICD (for 26 the runner then starts programs as they
#   are).
# - Idempotent: a second run finds the unpacked driver and answers at once.
#
# Cache folder: $GLINT_LAVAPIPE_CACHE, default `.cache/lavapipe` in the repository (ignored
# by git). Layout:
#     25/  apt/ debs/ root/ lvp_icd.json version .lock          (Mesa 25.0, bookworm-backports)
#     26/  apt/ root/ lvp_icd.json version .lock run [keyring/] (Mesa 26.1, trixie-backports)
#          (26's .debs stay in apt/archives/; keyring/ only where the system's lacks trixie)
# (A cache from before 26 existed, with 25's files at the top, is moved into 25/.)
# Exit status: 0 with the settings on stdout, non-zero with the reason on stderr; with `--`,
# the command's.
set -euo pipefail
self="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
cd "$(dirname "$0")/.."

say() { echo "lavapipe.sh: $*" >&2; }
die() {
    say "$*"
    exit 1
}
# The private apt helpers shared with web/toolchain.sh.
# shellcheck source=.ci/debian-apt.sh
. .ci/debian-apt.sh
usage="usage: bash .ci/lavapipe.sh [25|26] [-- CMD ARGS...]"

want=25
case "${1:-}" in
-h | --help)
    sed -n '2,/^set -euo/p' "$self" | sed -e '$d' -e 's/^# \{0,1\}//'
    exit 0
    ;;
25 | 26)
    want="$1"
    shift
    ;;
"" | --) ;;
*) die "unknown version '$1' (25 or 26); $usage" ;;
esac
run=0
if [ $# -gt 0 ]; then
    [ "$1" = -- ] || die "unexpected '$1'; $usage"
    shift
    [ $# -gt 0 ] || die "no command after --; $usage"
    run=1
fi

cache="${GLINT_LAVAPIPE_CACHE:-$PWD/.cache/lavapipe}"
mkdir -p "$cache"
cache="$(cd "$cache" && pwd)"
# The layout before Mesa 26 kept 25's files at the top of the cache folder.
if [ -d "$cache/root" ] && [ ! -e "$cache/25" ]; then
    say "moving the cached Mesa 25 into $cache/25"
    mkdir -p "$cache/25"
    for f in apt debs root version; do
        if [ -e "$cache/$f" ]; then mv "$cache/$f" "$cache/25/"; fi
    done
    rm -f "$cache/lvp_icd.json" # names the old path; written again below
fi
dir="$cache/$want"
root="$dir/root"
icd="$dir/lvp_icd.json"
runner="$dir/run"
mkdir -p "$dir"

mesa_major_of() { sed -n 's/^\([0-9]*\)\..*/\1/p' <<<"$1"; }

require_bookworm() {
    . /etc/os-release 2>/dev/null || true
    [ "${ID:-}" = debian ] && [ "${VERSION_CODENAME:-}" = bookworm ] ||
        die "this script knows how to fetch Mesa $want on Debian 12 (bookworm) only; this is ${PRETTY_NAME:-unknown}. Install Mesa >= $want and set VK_ICD_FILENAMES to its lvp_icd json."
}

# ---- Mesa 25.0: bookworm-backports, on Debian 12's own libc ---------------------------
fetch_25() {
    require_bookworm
    local uri keyring apt_dir debs pkg v d version
    uri="$(archive_uri)"
    keyring=/usr/share/keyrings/debian-archive-keyring.gpg
    [ -f "$keyring" ] || die "missing $keyring (package debian-archive-keyring)"
    apt_dir="$dir/apt"
    private_apt "$apt_dir" "deb [signed-by=$keyring target=Packages] $uri bookworm-backports main"
    say "fetching the bookworm-backports package lists (private apt configuration in $apt_dir)"
    apt_update bookworm-backports
    debs="$dir/debs"
    rm -rf "$debs" "$root" "$dir/version"
    mkdir -p "$debs" "$root"
    for pkg in mesa-vulkan-drivers libdrm2 libdrm-amdgpu1; do
        v="$(version_in "$pkg" bookworm-backports)"
        [ -n "$v" ] || die "bookworm-backports has no $pkg"
        say "downloading $pkg $v"
        (cd "$debs" && apt-get "${apt_opts[@]}" download -qq "$pkg=$v" >&2) ||
            die "apt-get download $pkg=$v failed"
    done
    for d in "$debs"/*.deb; do dpkg -x "$d" "$root"; done
    version="$(dpkg-deb -f "$debs"/mesa-vulkan-drivers_*.deb Version)"
    version="${version#*:}"
    [ "$(mesa_major_of "$version")" -ge 25 ] ||
        die "bookworm-backports offers mesa-vulkan-drivers $version, older than 25"
    echo "$version" >"$dir/version"
    say "Mesa $version unpacked in $root"
}

# ---- Mesa 26.1: trixie-backports, on trixie's own libc through its dynamic loader ----------

fetch_26() {
    require_bookworm
    [ "$(dpkg --print-architecture)" = amd64 ] ||
        die "fetching Mesa 26 is written for amd64 only (its dynamic loader is ld-linux-x86-64.so.2)"
    local uri keyring apt_dir v deb debs version start=$SECONDS
    uri="$(archive_uri)"
    keyring="$(trixie_keyring "$uri" "$dir")"
    apt_dir="$dir/apt"
    trixie_apt "$apt_dir" "$keyring" "$uri"
    v="$(version_in mesa-vulkan-drivers trixie-backports)"
    [ -n "$v" ] || die "trixie-backports has no mesa-vulkan-drivers"
    [ "$(mesa_major_of "${v#*:}")" -ge 26 ] ||
        die "trixie-backports offers mesa-vulkan-drivers $v, older than 26"
    say "downloading mesa-vulkan-drivers $v, libvulkan1 and their dependencies"
    rm -rf "$root" "$dir/version" "$apt_dir/archives"
    mkdir -p "$apt_dir/archives/partial" "$root"
    apt-get "${apt_opts[@]}" install --download-only -y -qq \
        "mesa-vulkan-drivers/trixie-backports" libvulkan1 >&2 ||
        die "apt-get install --download-only of mesa-vulkan-drivers/trixie-backports failed"
    for deb in "$apt_dir"/archives/*.deb; do dpkg -x "$deb" "$root"; done
    version="$(dpkg-deb -f "$apt_dir"/archives/mesa-vulkan-drivers_*.deb Version)"
    version="${version#*:}"
    [ "$(mesa_major_of "$version")" -ge 26 ] ||
        die "apt chose mesa-vulkan-drivers $version, older than 26"
    echo "$version" >"$dir/version"
    debs=("$apt_dir"/archives/*.deb)
    say "Mesa $version and ${#debs[@]} packages in all unpacked in $root in $((SECONDS - start)) s"
}

# The ICD json for the unpacked driver, naming its absolute path (written again when the
# cache folder has moved).
write_icd() {
    local lib src_json
    lib="$(find "$root" -name libvulkan_lvp.so | head -n 1)"
    [ -n "$lib" ] || die "the unpacked packages have no libvulkan_lvp.so"
    if [ -f "$icd" ] && grep -qF "\"$lib\"" "$icd"; then return; fi
    src_json="$(find "$root" -name 'lvp_icd*.json' | head -n 1)"
    [ -n "$src_json" ] || die "the unpacked packages have no lvp_icd json"
    sed "s#\"library_path\": *\"[^\"]*\"#\"library_path\": \"$lib\"#" "$src_json" | write_if_changed "$icd"
    grep -qF "\"$lib\"" "$icd" || die "could not rewrite library_path in $src_json"
}

# The runner: `$runner PROGRAM ARGS...`. LOADER empty: the system's driver, started as it is.
write_runner() {
    local loader="$1" libpath="$2" version="$3" icd_path="$4"
    write_if_changed "$runner" 755 <<EOF
#!/usr/bin/env bash
# Written by .ci/lavapipe.sh (do not edit): runs PROGRAM ARGS... on lavapipe, Mesa $version.
# An ELF program (not cargo or rustup: they locate themselves through /proc/self/exe, which
# would name the loader) starts through the dynamic loader of the unpacked tree, whose glibc,
# libstdc++ and LLVM the driver needs; anything else starts as it is, with this runner as
# cargo's runner, so that the binaries cargo runs start through it.
# Usage: $runner PROGRAM ARGS...
set -euo pipefail
loader=$(printf %q "$loader")
libpath=$(printf %q "$libpath")
export VK_ICD_FILENAMES=$(printf %q "$icd_path")
export GLINT_MESA_VERSION=$(printf %q "$version")
export GLINT_LAVAPIPE_LOADER=$(printf %q "$runner")
export CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_RUNNER=$(printf %q "$runner")
[ \$# -gt 0 ] || { echo "usage: \$0 PROGRAM ARGS..." >&2; exit 2; }
arg0="\$1"
shift
prog="\$arg0"
case "\$prog" in
*/*) ;;
*) prog="\$(type -P -- "\$prog")" || { echo "\$0: \$arg0: command not found" >&2; exit 127; } ;;
esac
if [ -n "\$loader" ] && [ -f "\$prog" ] &&
    [ "\$(head -c 4 -- "\$prog" | od -An -tx1 | tr -d ' \\n')" = 7f454c46 ]; then
    case "\${prog##*/}" in
    cargo | cargo-* | rustup | rustc | rustdoc) ;;
    *) exec "\$loader" --library-path "\$libpath" --argv0 "\$arg0" "\$prog" "\$@" ;;
    esac
fi
exec "\$prog" "\$@"
EOF
}

# ---- the driver: the system's, or unpacked here ---------------------------------------
settings=()
sys_version="$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)"
sys_version="${sys_version#*:}"
if [ -n "$sys_version" ] && [ "$(mesa_major_of "$sys_version")" -ge "$want" ] 2>/dev/null; then
    sys_icd="$(ls /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null | head -n 1 || true)"
    [ -n "$sys_icd" ] || die "mesa-vulkan-drivers $sys_version is installed but has no lvp_icd json"
    say "the system's own lavapipe is Mesa $sys_version (>= $want): using it"
    version="$sys_version"
    settings+=("VK_ICD_FILENAMES=$sys_icd")
    if [ "$want" = 26 ]; then write_runner "" "" "$version" "$sys_icd"; fi
else
    if [ -s "$dir/version" ] && [ -d "$root" ]; then
        say "Mesa $(cat "$dir/version") already unpacked in $dir"
    else
        # One fetch at a time per version; the lock is closed before anything is run.
        exec 9>"$dir/.lock"
        flock 9
        if [ -s "$dir/version" ] && [ -d "$root" ]; then
            say "Mesa $(cat "$dir/version") unpacked in $dir meanwhile"
        else
            "fetch_$want"
        fi
        exec 9>&-
    fi
    version="$(cat "$dir/version")"
    write_icd
    settings+=("VK_ICD_FILENAMES=$icd")
    if [ "$want" = 25 ]; then
        libdir="$(dirname "$(find "$root" -name 'libdrm.so.2' | head -n 1)")"
        settings+=("LD_LIBRARY_PATH=$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}")
    else
        loader=""
        for l in "$root/usr/lib64/ld-linux-x86-64.so.2" "$root/lib64/ld-linux-x86-64.so.2" \
            "$root/usr/lib/x86_64-linux-gnu/ld-linux-x86-64.so.2"; do
            if [ -f "$l" ]; then
                loader="$l"
                break
            fi
        done
        [ -n "$loader" ] || die "the unpacked tree in $root has no ld-linux-x86-64.so.2"
        libpath=""
        for l in "$root/usr/lib/x86_64-linux-gnu" "$root/lib/x86_64-linux-gnu"; do
            if [ -d "$l" ]; then libpath="${libpath:+$libpath:}$l"; fi
        done
        write_runner "$loader" "$libpath" "$version" "$icd"
    fi
fi
settings+=("GLINT_MESA_VERSION=$version")
if [ "$want" = 26 ]; then
    settings+=("GLINT_LAVAPIPE_LOADER=$runner" "CARGO_TARGET_X86_64_UNKNOWN_LINUX_GNU_RUNNER=$runner")
fi

if [ "$run" = 0 ]; then
    for s in "${settings[@]}"; do printf 'export %s=%q\n' "${s%%=*}" "${s#*=}"; done
    exit 0
fi
for s in "${settings[@]}"; do export "${s%%=*}=${s#*=}"; done
if [ "$want" = 26 ]; then exec "$runner" "$@"; fi
exec "$@"
