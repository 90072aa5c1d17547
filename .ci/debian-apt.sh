# Functions to fetch Debian packages into a private folder without touching the system:
# a private apt configuration (trixie's too), the archive's address, trixie's keyring,
# idempotent writes.
# Sourced by .ci/lavapipe.sh (Mesa's lavapipe) and web/toolchain.sh (the wasm toolchain),
# from the repository's root; the sourcing script defines `say MESSAGE` and `die MESSAGE`
# (which exits) and runs under `set -euo pipefail`.
# shellcheck shell=bash

# The Debian archive's address, as this machine's apt is configured for bookworm (deb822 or
# one-line form).
archive_uri() {
    local f uri=""
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
    [ -n "$uri" ] || die "found no Debian bookworm source in /etc/apt to derive the archive's address from"
    echo "$uri"
}

# private_apt APT_DIR SOURCES_LINE...: a private apt configuration in APT_DIR (sources list,
# lists, cache), in the array apt_opts. The system's apt.conf(.d) still applies (proxies).
# Only the Packages indices are fetched (target=Packages in each line).
private_apt() {
    local apt_dir="$1"
    shift
    mkdir -p "$apt_dir/lists/partial" "$apt_dir/archives/partial" "$apt_dir/etc/preferences.d"
    printf '%s\n' "$@" >"$apt_dir/etc/sources.list"
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
        -o "Acquire::Retries=3"
    )
}

# `apt-get update` with the private configuration (apt_opts), tried again with a growing
# pause while the archive fails: a mirror that answers 503 leaves the lists incomplete with
# only a warning and exit status 0, and a package then seems missing. `what` names the
# lists in messages. Needs the caller's `say` and `die`.
apt_update() { # what
    local err k
    for k in 1 2 3 4 5; do
        if err="$(apt-get "${apt_opts[@]}" update -qq 2>&1)" && ! grep -q '^W: Failed to fetch' <<<"$err"; then
            [ -z "$err" ] || echo "$err" >&2
            return 0
        fi
        echo "$err" >&2
        [ "$k" = 5 ] && break
        say "apt-get update of $1 failed (attempt $k of 5); trying again in $((10 * k)) s"
        sleep $((10 * k))
    done
    die "apt-get update of $1 failed 5 times (the archive's answers above)"
}

# The newest version of PKG that the private configuration's SUITE offers.
version_in() {
    apt-cache "${apt_opts[@]}" madison "$1" 2>/dev/null |
        awk -F'|' -v suite="$2" 'index($3, " " suite "/") { gsub(/ /, "", $2); print $2; exit }'
}

# A keyring that verifies trixie's Release files: the system's, where its
# debian-archive-keyring has trixie's keys (it ships them as separate files too, which is
# how this tells), otherwise bookworm's newest debian-archive-keyring, fetched through a
# private apt configuration verified with the system's bookworm keys, kept in DIR/keyring.
# Usage: trixie_keyring URI DIR.
trixie_keyring() {
    local uri="$1" system=/usr/share/keyrings/debian-archive-keyring.gpg kdir v
    [ -f "$system" ] || die "missing $system (package debian-archive-keyring)"
    if [ -f /usr/share/keyrings/debian-archive-trixie-stable.gpg ] &&
        [ -f /usr/share/keyrings/debian-archive-trixie-automatic.gpg ]; then
        echo "$system"
        return
    fi
    kdir="$2/keyring"
    if [ ! -f "$kdir/usr/share/keyrings/debian-archive-trixie-automatic.gpg" ]; then
        say "the system's debian-archive-keyring lacks trixie's keys; fetching bookworm's newest"
        private_apt "$kdir/apt" "deb [signed-by=$system target=Packages] $uri bookworm main" \
            "deb [signed-by=$system target=Packages] $uri bookworm-updates main"
        apt_update bookworm
        v="$(apt-cache "${apt_opts[@]}" policy debian-archive-keyring 2>/dev/null |
            awk '/Candidate:/ { print $2 }')"
        dpkg --compare-versions "${v:-0}" ge 2023.3+deb12u1 ||
            die "bookworm's debian-archive-keyring ${v:-(none)} has no trixie keys either"
        rm -rf "${kdir:?}/debs" "${kdir:?}/usr"
        mkdir -p "$kdir/debs"
        (cd "$kdir/debs" && apt-get "${apt_opts[@]}" download -qq "debian-archive-keyring=$v" >&2) ||
            die "apt-get download debian-archive-keyring=$v failed"
        dpkg -x "$kdir"/debs/debian-archive-keyring_*.deb "$kdir"
        [ -f "$kdir/usr/share/keyrings/debian-archive-trixie-automatic.gpg" ] ||
            die "debian-archive-keyring $v has no trixie keys"
    fi
    echo "$kdir/usr/share/keyrings/debian-archive-keyring.gpg"
}

# Writes FILE from stdin, replacing it (atomically) only when the content differs.
write_if_changed() {
    local tmp
    tmp="$(mktemp "$1.XXXXXX")"
    cat >"$tmp"
    if cmp -s "$tmp" "$1"; then rm -f "$tmp"; else
        chmod "${2:-644}" "$tmp"
        mv -f "$tmp" "$1"
    fi
}

# trixie_apt APT_DIR KEYRING URI: a private apt configuration (private_apt) for trixie and
# trixie-backports from the archive at URI, verified with KEYRING, with its package lists
# fetched. Its dpkg status is empty: apt resolves every dependency as if nothing were
# installed, so a download is a whole userland (libc6 included), none of it Debian 12's.
# Recommends and Suggests are left out.
trixie_apt() {
    local apt_dir="$1" keyring="$2" uri="$3"
    private_apt "$apt_dir" "deb [signed-by=$keyring target=Packages] $uri trixie main" \
        "deb [signed-by=$keyring target=Packages] $uri trixie-backports main"
    : >"$apt_dir/status"
    apt_opts+=(
        -o "Dir::State::status=$apt_dir/status"
        -o "Dir::State::extended_states=$apt_dir/extended_states"
        -o "Dir::Log=$apt_dir/log"
        -o "APT::Install-Recommends=0"
        -o "APT::Install-Suggests=0"
    )
    say "fetching the trixie and trixie-backports package lists (private apt configuration in $apt_dir)"
    apt_update "trixie and trixie-backports"
}
