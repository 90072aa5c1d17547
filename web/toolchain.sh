#!/usr/bin/env bash
# Provides a Rust toolchain that compiles to wasm32-unknown-unknown, and prints the
# environment settings that select it:
#
#     eval "$(bash web/toolchain.sh)"
#     "$GLINT_WASM_CARGO" build --release --target wasm32-unknown-unknown
#
# Settings printed (bash `export` lines, for eval):
#   GLINT_WASM_CARGO          the cargo to run for wasm builds.
#   GLINT_WASM_RUSTC_VERSION  its rustc's version (e.g. 1.97.1).
#   and, for the Debian toolchain below only:
#   GLINT_WASM_RUSTC, RUSTC   the rustc wrapper (RUSTC so that a cargo started some other way
#                             uses it too; note it then applies to every cargo of that
#                             shell, the system's included).
#   CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER   the wasm-ld wrapper.
#   (GLINT_WASM_CARGO sets all three itself; it needs none of them exported.)
#
# - First the normal toolchain: where `rustc --print target-libdir --target
#   wasm32-unknown-unknown` holds a libstd-*.rlib (a rustup-installed target), or
#   `rustup target add wasm32-unknown-unknown` succeeds, it says so (on stderr) and prints
#   GLINT_WASM_CARGO=cargo: the system's cargo, nothing else needed (and `unset` lines for
#   RUSTC and the linker where an earlier eval in that shell pointed them at the Debian
#   toolchain's wrappers).
# - Otherwise, on Debian 12 (bookworm), where Debian's rustc has no wasm32 standard library
#   and rustup cannot add one: it fetches `rustc`, `cargo` and `libstd-rust-dev-wasm32` from
#   Debian 13's `trixie-backports` (all of rustc's source package pinned there, as
#   backports are not taken by default), and for its wasm-ld the `lld-NN` of rustc's own
#   LLVM (the one libstd-rust-dev-wasm32 recommends: lld-22, from trixie, for rustc 1.97 and 1.98),
#   with all their dependencies from `trixie` and `trixie-backports`, resolved against an EMPTY
#   private dpkg status file, so apt takes every dependency as not installed (libc6,
#   libstdc++6 and libLLVM among them). Those programs need a newer glibc, libstdc++ and LLVM
#   than Debian 12's, and a process has one glibc: its dynamic loader and libc.so.6 must
#   match. So each runs through the unpacked tree's own dynamic loader:
#       ROOT/usr/lib64/ld-linux-x86-64.so.2 --library-path ROOT/usr/lib/x86_64-linux-gnu:… \
#           --argv0 PROGRAM PROGRAM ARGS...
#   by a wrapper script written here: $cache/bin/rustc, $cache/bin/cargo and
#   $cache/bin/wasm-ld. What such a process starts runs on the system's glibc again, so:
#     - the cargo wrapper exports RUSTC (the rustc wrapper), so that cargo's rustc goes
#       through the loader too, and CARGO (itself), and makes itself cargo's argv[0]: in a
#       process started through the loader /proc/self/exe (Rust's `current_exe`) names the
#       loader, so cargo hands build scripts (as CARGO) its argv[0] where that names a cargo,
#       else $CARGO, and the bare trixie cargo would not start;
#     - Debian's wasm32 target names `rust-lld` as its linker, which Debian does not ship:
#       CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER names the wasm-ld wrapper instead;
#     - the host's programs (build scripts, proc-macros) are linked by the system's `cc`
#       (Debian 12's gcc and binutils) against trixie's Rust standard library, which links
#       statically; the libc is the system's. Build scripts then run as they are; proc-macro
#       libraries are loaded into the rustc process, on trixie's glibc (newer than what they
#       were linked against, which is fine). (rustc's dependencies bring trixie's gcc,
#       binutils and libc6-dev into the tree too; they are not used.)
#   (rustc finds its sysroot, ROOT/usr, from the path of its librustc_driver, not from
#   /proc/self/exe, so it needs no --sysroot.)
#   cargo reads the same $CARGO_HOME (default ~/.cargo) as the system's: its config.toml
#   (a registry mirror, say) and registry cache are shared.
#   Packages come through a private apt configuration (its own sources list, lists, cache
#   and dpkg status, all under the cache folder) and are unpacked with `dpkg -x`. The
#   archive's address is read from the machine's own bookworm apt source; none is written
#   here. Signatures are always checked: against
#   /usr/share/keyrings/debian-archive-keyring.gpg, which holds trixie's keys since
#   debian-archive-keyring 2023.3+deb12u1; where it is older, the newest
#   debian-archive-keyring from bookworm itself (verified with the bookworm keys) is fetched
#   and its keyring used for trixie.
# - GLINT_WASM_TOOLCHAIN=debian forces the Debian toolchain (where rustup would do, too);
#   GLINT_WASM_TOOLCHAIN=system allows only the normal one (an error where it cannot).
# - Idempotent: a second run finds the unpacked toolchain and answers at once (the first
#   downloads about 280 MB, 92 packages, and unpacks them: about 40 s).
#
# Cache folder: $GLINT_WASM_CACHE, default `.cache/wasm-toolchain` in the repository (ignored
# by git). Layout:
#     apt/ root/ bin/{rustc,cargo,wasm-ld} version .lock [keyring/]
#     (about 1.1 GB, nearly all of it root/: the .debs are deleted once unpacked; keyring/
#     only where the system's debian-archive-keyring lacks trixie's keys)
# Exit status: 0 with the settings on stdout, non-zero with the reason on stderr.
set -euo pipefail
self="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
cd "$(dirname "$0")/.."

say() { echo "toolchain.sh: $*" >&2; }
die() {
    say "$*"
    exit 1
}
# The private apt helpers shared with .ci/lavapipe.sh.
# shellcheck source=.ci/debian-apt.sh
. .ci/debian-apt.sh
usage="usage: [GLINT_WASM_TOOLCHAIN=auto|system|debian] bash web/toolchain.sh"

case "${1:-}" in
-h | --help)
    sed -n '2,/^set -euo/p' "$self" | sed -e '$d' -e 's/^# \{0,1\}//'
    exit 0
    ;;
"") ;;
*) die "unexpected '$1'; $usage" ;;
esac
mode="${GLINT_WASM_TOOLCHAIN:-auto}"
case "$mode" in
auto | system | debian) ;;
*) die "GLINT_WASM_TOOLCHAIN='$mode': auto, system or debian; $usage" ;;
esac

cache="${GLINT_WASM_CACHE:-$PWD/.cache/wasm-toolchain}"
settings=()
emit() {
    local s
    for s in "${settings[@]}"; do printf 'export %s=%q\n' "${s%%=*}" "${s#*=}"; done
    exit 0
}

# ---- the normal toolchain: a wasm32 standard library in rustc's target libdir -----------
# The system's rustc (from PATH, not $RUSTC, which an earlier eval may have pointed here).
system_has_wasm_std() {
    local libdir
    libdir="$(rustc --print target-libdir --target wasm32-unknown-unknown 2>/dev/null)" || return 1
    compgen -G "$libdir/libstd-*.rlib" >/dev/null
}

use_system() {
    local v var c
    v="$(rustc -V | awk '{ print $2 }')"
    say "using the system's toolchain ($1): rustc $v, cargo from PATH"
    # An earlier eval of the Debian toolchain's settings in this shell would steer the
    # system's cargo there: those are unset.
    if c="$(cd "$cache" 2>/dev/null && pwd)"; then
        for var in RUSTC CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER GLINT_WASM_RUSTC; do
            case "${!var:-}" in "$c/bin/"*) echo "unset $var" ;; esac
        done
    fi
    settings+=("GLINT_WASM_CARGO=cargo" "GLINT_WASM_RUSTC_VERSION=$v")
    emit
}

if [ "$mode" != debian ] && command -v rustc >/dev/null 2>&1; then
    if system_has_wasm_std; then
        use_system "its wasm32-unknown-unknown standard library is installed"
    fi
    if command -v rustup >/dev/null 2>&1; then
        say "no wasm32-unknown-unknown standard library; trying rustup target add wasm32-unknown-unknown"
        if rustup target add wasm32-unknown-unknown >&2 && system_has_wasm_std; then
            use_system "rustup added wasm32-unknown-unknown"
        fi
        say "rustup could not add wasm32-unknown-unknown"
    fi
fi
if [ "$mode" = system ]; then
    die "GLINT_WASM_TOOLCHAIN=system: the system's rustc has no wasm32-unknown-unknown standard library and rustup cannot add one"
fi

# ---- the Debian toolchain: trixie-backports, on trixie's own libc through its loader ----
mkdir -p "$cache"
cache="$(cd "$cache" && pwd)"
dir="$cache"
root="$dir/root"
bin="$dir/bin"

require_bookworm() {
    # shellcheck disable=SC1091
    . /etc/os-release 2>/dev/null || true
    [ "${ID:-}" = debian ] && [ "${VERSION_CODENAME:-}" = bookworm ] ||
        die "no wasm32-unknown-unknown standard library for the system's rustc, and this script knows how to fetch one on Debian 12 (bookworm) only; this is ${PRETTY_NAME:-unknown}. Install one (rustup target add wasm32-unknown-unknown)."
    [ "$(dpkg --print-architecture)" = amd64 ] ||
        die "fetching the Debian toolchain is written for amd64 only (its dynamic loader is ld-linux-x86-64.so.2)"
}

# The lld-NN whose wasm-ld links what trixie-backports' rustc compiles: the one that
# libstd-rust-dev-wasm32 recommends (that of rustc's own LLVM), else the newest in trixie or
# trixie-backports.
wasm_lld() {
    local p
    p="$(apt-cache "${apt_opts[@]}" show libstd-rust-dev-wasm32/trixie-backports 2>/dev/null |
        sed -n 's/^Recommends:.*\b\(lld-[0-9][0-9]*\)\b.*/\1/p' | head -n 1)"
    if [ -z "$p" ]; then
        p="$(apt-cache "${apt_opts[@]}" pkgnames lld- 2>/dev/null | grep -E '^lld-[0-9]+$' |
            sort -t- -k2,2nr | head -n 1)"
    fi
    echo "$p"
}

fetch() {
    require_bookworm
    local uri keyring apt_dir src v lld deb debs start=$SECONDS
    uri="$(archive_uri)"
    keyring="$(trixie_keyring "$uri" "$dir")"
    apt_dir="$dir/apt"
    trixie_apt "$apt_dir" "$keyring" "$uri"
    # trixie-backports is NotAutomatic: pin all of rustc's source package there, so that
    # rustc's exact-version dependencies (libstd-rust-dev, libstd-rust-1.NN) come from it.
    src="$(apt-cache "${apt_opts[@]}" show rustc/trixie-backports 2>/dev/null |
        awk '/^Source:/ { print $2; exit }')"
    printf 'Package: src:%s\nPin: release n=trixie-backports\nPin-Priority: 500\n' \
        "${src:-rustc}" >"$apt_dir/etc/preferences"
    v="$(version_in rustc trixie-backports)"
    [ -n "$v" ] || die "trixie-backports has no rustc"
    [ -n "$(version_in libstd-rust-dev-wasm32 trixie-backports)" ] ||
        die "trixie-backports has no libstd-rust-dev-wasm32"
    lld="$(wasm_lld)"
    [ -n "$lld" ] || die "neither trixie-backports nor trixie has an lld-NN package"
    say "downloading rustc $v, cargo, libstd-rust-dev-wasm32, $lld and their dependencies"
    rm -rf "$root" "$bin" "$dir/version" "$apt_dir/archives"
    mkdir -p "$apt_dir/archives/partial" "$root"
    apt-get "${apt_opts[@]}" install --download-only -y -qq \
        rustc/trixie-backports cargo/trixie-backports libstd-rust-dev-wasm32/trixie-backports \
        "$lld" >&2 ||
        die "apt-get install --download-only of rustc, cargo, libstd-rust-dev-wasm32 (trixie-backports) and $lld failed"
    for deb in "$apt_dir"/archives/*.deb; do dpkg -x "$deb" "$root"; done
    debs=("$apt_dir"/archives/*.deb)
    rm -f "$apt_dir"/archives/*.deb # about 280 MB, no longer needed
    write_wrappers
    v="$("$bin/rustc" -V | awk '{ print $2 }')" || die "the unpacked rustc does not run: $bin/rustc -V failed"
    [ -n "$v" ] || die "the unpacked rustc printed no version"
    echo "$v" >"$dir/version"
    say "rustc $v and ${#debs[@]} packages in all unpacked in $root in $((SECONDS - start)) s"
}

# The wrappers in $bin (written again when the cache folder has moved).
write_wrappers() {
    local loader="" libpath="" l rustc cargo wasm_ld
    for l in "$root/usr/lib64/ld-linux-x86-64.so.2" "$root/lib64/ld-linux-x86-64.so.2" \
        "$root/usr/lib/x86_64-linux-gnu/ld-linux-x86-64.so.2"; do
        if [ -f "$l" ]; then
            loader="$l"
            break
        fi
    done
    [ -n "$loader" ] || die "the unpacked tree in $root has no ld-linux-x86-64.so.2"
    for l in "$root/usr/lib/x86_64-linux-gnu" "$root/lib/x86_64-linux-gnu"; do
        if [ -d "$l" ]; then libpath="${libpath:+$libpath:}$l"; fi
    done
    rustc="$root/usr/bin/rustc"
    cargo="$root/usr/bin/cargo"
    wasm_ld="$(find "$root/usr/lib" -maxdepth 3 -path '*/llvm-*/bin/wasm-ld' | sort -V | tail -n 1)"
    [ -x "$rustc" ] || die "the unpacked tree in $root has no usr/bin/rustc"
    [ -x "$cargo" ] || die "the unpacked tree in $root has no usr/bin/cargo"
    [ -n "$wasm_ld" ] || die "the unpacked tree in $root has no llvm-NN/bin/wasm-ld"
    mkdir -p "$bin"
    # rustc: it finds its sysroot (the tree's usr) from librustc_driver's path.
    write_if_changed "$bin/rustc" 755 <<EOF
#!/usr/bin/env bash
# Written by web/toolchain.sh (do not edit): trixie-backports' rustc, run through the
# unpacked tree's dynamic loader (it needs trixie's glibc, libstdc++ and LLVM).
exec $(printf %q "$loader") --library-path $(printf %q "$libpath") \\
    --argv0 $(printf %q "$rustc") $(printf %q "$rustc") "\$@"
EOF
    # cargo: its rustc, its own path for build scripts ($CARGO) and the wasm linker. Its
    # argv[0] is this wrapper too: where argv[0] names a cargo, cargo hands build scripts
    # that path as CARGO, not $CARGO.
    write_if_changed "$bin/cargo" 755 <<EOF
#!/usr/bin/env bash
# Written by web/toolchain.sh (do not edit): trixie-backports' cargo, run through the
# unpacked tree's dynamic loader, with the rustc wrapper beside it as its rustc, itself as
# \$CARGO (current_exe would name the loader) and the wasm-ld wrapper as the linker of
# wasm32-unknown-unknown (Debian's target names rust-lld, which Debian does not ship).
set -euo pipefail
export RUSTC=$(printf %q "$bin/rustc")
export CARGO=$(printf %q "$bin/cargo")
export CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=$(printf %q "$bin/wasm-ld")
exec $(printf %q "$loader") --library-path $(printf %q "$libpath") \\
    --argv0 $(printf %q "$bin/cargo") $(printf %q "$cargo") "\$@"
EOF
    # wasm-ld: lld picks its flavour from argv[0]'s name.
    write_if_changed "$bin/wasm-ld" 755 <<EOF
#!/usr/bin/env bash
# Written by web/toolchain.sh (do not edit): wasm-ld of trixie's lld, run through the
# unpacked tree's dynamic loader.
exec $(printf %q "$loader") --library-path $(printf %q "$libpath") \\
    --argv0 $(printf %q "$wasm_ld") $(printf %q "$wasm_ld") "\$@"
EOF
}

if [ -s "$dir/version" ] && [ -d "$root" ]; then
    say "rustc $(cat "$dir/version") (trixie-backports) already unpacked in $dir"
else
    # One fetch at a time; the lock is closed before anything is printed.
    exec 9>"$dir/.lock"
    flock 9
    if [ -s "$dir/version" ] && [ -d "$root" ]; then
        say "rustc $(cat "$dir/version") (trixie-backports) unpacked in $dir meanwhile"
    else
        fetch
    fi
    exec 9>&-
fi
version="$(cat "$dir/version")"
write_wrappers
[ -n "$(compgen -G "$root/usr/lib/rustlib/wasm32-unknown-unknown/lib/libstd-*.rlib")" ] ||
    die "the unpacked tree in $root has no wasm32-unknown-unknown libstd-*.rlib"
say "using trixie-backports' rustc $version for wasm32-unknown-unknown ($bin)"
settings+=(
    "GLINT_WASM_CARGO=$bin/cargo"
    "GLINT_WASM_RUSTC=$bin/rustc"
    "RUSTC=$bin/rustc"
    "CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER=$bin/wasm-ld"
    "GLINT_WASM_RUSTC_VERSION=$version"
)
emit
