#!/usr/bin/env bash
# Provides a second lavapipe, Mesa >= 25, without touching the system's packages or apt
# sources, and prints the two environment settings that select it:
#
#     eval "$(bash .ci/lavapipe.sh)"     # sets VK_ICD_FILENAMES and LD_LIBRARY_PATH
#
# - Where the system's own lavapipe is already Mesa >= 25, it says so (on stderr) and prints
#   the settings for the system's ICD.
# - On Debian 12 it fetches `mesa-vulkan-drivers`, `libdrm2` and `libdrm-amdgpu1` from the
#   `bookworm-backports` suite through a private apt configuration (its own sources list,
#   lists and cache, all under the cache folder). The archive's address is read from the
#   machine's own apt sources; none is written here. The packages are unpacked with
#   `dpkg -x` into the cache folder, and an ICD json naming the absolute path of
#   `libvulkan_lvp.so` is written beside them.
# - Idempotent: a second run finds the unpacked driver and prints the settings at once.
#
# Cache folder: $GLINT_LAVAPIPE_CACHE, default `.cache/lavapipe` in the repository (ignored
# by git). Exit status: 0 with the settings on stdout, non-zero with the reason on stderr.
set -euo pipefail
cd "$(dirname "$0")/.."

say() { echo "lavapipe.sh: $*" >&2; }
die() {
    say "$*"
    exit 1
}

cache="${GLINT_LAVAPIPE_CACHE:-$PWD/.cache/lavapipe}"
mkdir -p "$cache"
cache="$(cd "$cache" && pwd)"
root="$cache/root"
icd="$cache/lvp_icd.json"

mesa_major_of() { sed -n 's/^\([0-9]*\)\..*/\1/p' <<<"$1"; }

# 1. The system's own Mesa, when it is new enough.
sys_version="$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)"
sys_version="${sys_version#*:}"
if [ -n "$sys_version" ] && [ "$(mesa_major_of "$sys_version")" -ge 25 ] 2>/dev/null; then
    sys_icd="$(ls /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null | head -n 1 || true)"
    [ -n "$sys_icd" ] || die "mesa-vulkan-drivers $sys_version is installed but has no lvp_icd json"
    say "the system's own lavapipe is Mesa $sys_version (>= 25): using it"
    echo "export VK_ICD_FILENAMES='$sys_icd'"
    echo "export GLINT_MESA25_VERSION='$sys_version'"
    exit 0
fi

# 2. Already unpacked by an earlier run.
if [ -f "$icd" ] && [ -f "$cache/version" ]; then
    say "Mesa $(cat "$cache/version") already unpacked in $cache"
else
    . /etc/os-release 2>/dev/null || true
    [ "${ID:-}" = debian ] && [ "${VERSION_CODENAME:-}" = bookworm ] ||
        die "this script knows how to fetch Mesa >= 25 on Debian 12 (bookworm) only; this is ${PRETTY_NAME:-unknown}. Install Mesa >= 25 and set VK_ICD_FILENAMES to its lvp_icd json."
    # The archive's address, as this machine's apt is configured (deb822 or one-line form).
    uri=""
    for f in /etc/apt/sources.list.d/*.sources; do
        [ -f "$f" ] || continue
        uri="$(awk '
            /^URIs:/   { u = $2 }
            /^Suites:/ { for (i = 2; i <= NF; i++) if ($i == "bookworm") s = 1 }
            /^$/       { if (u != "" && s) { print u; exit } u = ""; s = 0 }
            END        { if (u != "" && s) print u }' "$f" | head -n 1)"
        [ -n "$uri" ] && break
    done
    if [ -z "$uri" ]; then
        uri="$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null |
            awk '$1 == "deb" { for (i = 2; i <= NF; i++) if ($i !~ /^\[/) { if ($(i+1) == "bookworm") print $i; break } }' |
            head -n 1)"
    fi
    [ -n "$uri" ] || die "found no Debian bookworm source in /etc/apt to derive the backports address from"
    keyring=/usr/share/keyrings/debian-archive-keyring.gpg
    [ -f "$keyring" ] || die "missing $keyring (package debian-archive-keyring)"

    apt_dir="$cache/apt"
    mkdir -p "$apt_dir/lists/partial" "$apt_dir/archives/partial" "$apt_dir/etc/preferences.d"
    echo "deb [signed-by=$keyring] $uri bookworm-backports main" >"$apt_dir/etc/sources.list"
    apt_opts=(
        -o "Dir::Etc::SourceList=$apt_dir/etc/sources.list"
        -o "Dir::Etc::SourceParts=-"
        -o "Dir::Etc::Preferences=$apt_dir/etc/preferences"
        -o "Dir::Etc::PreferencesParts=$apt_dir/etc/preferences.d"
        -o "Dir::State::Lists=$apt_dir/lists"
        -o "Dir::Cache=$apt_dir"
        -o "Dir::Cache::Archives=$apt_dir/archives"
        -o "Debug::NoLocking=1"
        -o "APT::Get::List-Cleanup=0"
        -o "APT::Sandbox::User=$(id -un)"
    )
    say "fetching the bookworm-backports package lists (private apt configuration in $apt_dir)"
    apt-get "${apt_opts[@]}" update -qq >&2 || die "apt-get update of bookworm-backports failed"
    debs="$cache/debs"
    rm -rf "$debs" "$root"
    mkdir -p "$debs" "$root"
    for pkg in mesa-vulkan-drivers libdrm2 libdrm-amdgpu1; do
        v="$(apt-cache "${apt_opts[@]}" madison "$pkg" 2>/dev/null |
            awk -F'|' '$3 ~ /bookworm-backports/ { gsub(/ /, "", $2); print $2; exit }')"
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
    lib="$(find "$root" -name libvulkan_lvp.so | head -n 1)"
    [ -n "$lib" ] || die "the unpacked package has no libvulkan_lvp.so"
    src_json="$(find "$root" -name 'lvp_icd*.json' | head -n 1)"
    [ -n "$src_json" ] || die "the unpacked package has no lvp_icd json"
    sed "s#\"library_path\": *\"[^\"]*\"#\"library_path\": \"$lib\"#" "$src_json" >"$icd"
    grep -q "$lib" "$icd" || die "could not rewrite library_path in $src_json"
    echo "$version" >"$cache/version"
    say "Mesa $version unpacked in $root"
fi

libdir="$(dirname "$(find "$root" -name 'libdrm.so.2' | head -n 1)")"
echo "export VK_ICD_FILENAMES='$icd'"
echo "export LD_LIBRARY_PATH='$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}'"
echo "export GLINT_MESA25_VERSION='$(cat "$cache/version")'"
