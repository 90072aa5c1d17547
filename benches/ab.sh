#!/usr/bin/env bash
# The A/B guard: builds two commits (default: HEAD~1 as A, the working tree as B), then
# times them interleaved in one run (A B A B ...), scene by scene and tracer by tracer, and
# flags every row where B's median frame is more than 10 % slower than A's.
#
#     bash benches/ab.sh [A_REV] [B_REV|worktree]     # ROUNDS=5, SCENES="a.toml b.toml", SIZE=1024x768
#
# Scenes: the seed scenes and their shadowed variants; the peers scenes (2, 100k and 1M
# triangles + 10 spheres, with and without shadows) when bench-out/peers has them
# (`python3 benches/peer_scene.py`, needs numpy); the mesh scenes when scenes/meshes has
# them (`bash scenes/fetch-meshes.sh`). Tracers: `cpu` and `gpu` (the default adapter, or
# GLINT_ADAPTER). Figures are each process's own frame time ("trace" for the GPU, the
# render time for the CPU), so mesh loading and device start are not counted.
# Output: a markdown table on stdout and in bench-out/ab/last.md. Exit status 3 when a row
# is flagged. No other tool is needed than bash, git, cargo, awk and sort.
#
# WHOLE=1 times whole processes instead (start to PNG, and their peak memory, with GNU
# time), in two rows a scene and tracer: "first", where B's cache folder is empty at every
# run (a first render, its cache writes included), and "cached", where B's cache holds the
# scene (primed once). A runs with the same folders; a build without the cache ignores them.
# Output in bench-out/ab/whole.md.
#
# PINNED=1 compares the CPU tracer's frames with A and B running at the same time, one
# thread each, each pinned to a core of its own (swapped every round), and takes each
# round's B / A of the fastest of RUNS frames (default 15): the tightest comparison on a
# noisy 2-core machine. Output in bench-out/ab/pinned.md.
#
# BENCH=1 compares `glint bench`'s own frames instead (timed runs into a kept image; CPU f32
# and the GPU's specialised pipeline, trace + readback; BACKENDS=cpu adds --no-gpu,
# TRIANGLE picks the algorithm, default watertight): each round A's bench, then B's. Output
# in bench-out/ab/bench.md.
set -euo pipefail
cd "$(dirname "$0")/.."
a_rev="${1:-HEAD~1}"
b_rev="${2:-worktree}"
rounds="${ROUNDS:-5}"
size="${SIZE:-1024x768}"
top="$PWD"
out=bench-out/ab
mkdir -p "$out"

# The sources of the working tree touched: a build of a revision in a worktree (below)
# shares this project's target folder and leaves a fingerprint newer than any file edited
# before it, and cargo then took the working tree for built: the "worktree" binary was the
# revision's (found on 2026-12-02: three A/B runs had compared A with A). Touched, they are
# rebuilt; the user's next `cargo build` is right too.
touch_sources() {
    git ls-files -z -- src shaders tests examples benches build.rs Cargo.toml Cargo.lock |
        xargs -0 touch
}

build() { # rev -> path of its release binary
    local rev="$1" dir sha
    if [ "$rev" = worktree ]; then
        touch_sources
        cargo build --release --locked -q >&2
        cp target/release/glint "$out/glint-worktree"
        echo "$out/glint-worktree"
        return
    fi
    sha="$(git rev-parse --short "$rev")"
    if [ ! -x "$out/glint-$sha" ]; then
        dir="$out/src-$sha"
        rm -rf "$dir"
        git worktree add -f --detach "$dir" "$sha" >&2
        # The project's own target folder: the dependencies are built once. (The binary it
        # leaves in target/release is copied at once; B is built after A.)
        (cd "$dir" && CARGO_TARGET_DIR="$top/target" cargo build --release --locked -q >&2)
        cp target/release/glint "$out/glint-$sha"
        git worktree remove --force "$dir" >&2
        touch_sources
    fi
    echo "$out/glint-$sha"
}
A="$(build "$a_rev")"
B="$(build "$b_rev")"

if [ -n "${SCENES:-}" ]; then
    read -r -a scenes <<<"$SCENES"
else
scenes=(scenes/sphere.toml scenes/triangle.toml scenes/umbrella.toml scenes/bb8.toml
    scenes/mitsubishi.toml scenes/bb8-shadows.toml scenes/mitsubishi-shadows.toml)
for t in 2 100000 1000000; do
    for s in bench-out/peers/peers_$t.toml bench-out/peers/peers_${t}_noshadow.toml; do
        [ -f "$s" ] && scenes+=("$s")
    done
done
for s in scenes/bunny.toml scenes/dragon.toml; do
    [ -f "${s%.toml}.toml" ] && grep -q meshes "$s" && ls scenes/meshes/* >/dev/null 2>&1 && scenes+=("$s")
done
fi

# Where `.ci/lavapipe.sh 26` set GLINT_LAVAPIPE_LOADER, each binary runs through it (a
# driver built for a newer C library than the system's; see that script).
frame_ms() { # binary scene backend -> the frame time in ms, or "fail"
    local line
    line="$(${GLINT_LAVAPIPE_LOADER:+"$GLINT_LAVAPIPE_LOADER"} "$1" render "$2" -o "$out/frame.png" --size "$size" --backend "$3" 2>/dev/null)" || {
        echo fail
        return
    }
    if [[ "$line" =~ trace\ ([0-9.]+)\ ms ]]; then
        echo "${BASH_REMATCH[1]}"
    elif [[ "$line" =~ ,\ ([0-9.]+)\ ms,\ cpu ]]; then
        echo "${BASH_REMATCH[1]}"
    else
        echo fail
    fi
}
whole() { # binary scene backend cache-dir -> "wall_ms peak_MiB", or "fail"
    GLINT_CACHE_DIR="$4" /usr/bin/time -o "$out/time.txt" -f '%e %M' \
        "$1" render "$2" -o "$out/frame.png" --size "$size" --backend "$3" >/dev/null 2>&1 || {
        echo fail
        return
    }
    awk '{printf "%.0f %.0f", $1 * 1000, $2 / 1024}' "$out/time.txt"
}
median() { tr ' ' '\n' | grep -v '^$' | sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
flag_if_slower() { # ratio B / A -> sets the row's $flag, and $flagged when B is > 10 % slower
    flag=""
    if awk -v r="$1" 'BEGIN {exit !(r > 1.10)}'; then
        flag="**SLOWER > 10 %**"
        flagged=1
    fi
}

if [ -n "${BENCH:-}" ]; then
    # `glint bench`'s own frames (timed runs into a kept image, CPU f32 and the GPU's
    # specialised pipeline, trace + readback): each round runs A's bench on every scene,
    # then B's; a row's figure is the median over rounds of the bench's medians.
    nogpu=""
    [[ " ${BACKENDS:-cpu gpu} " == *" gpu "* ]] || nogpu=--no-gpu
    for r in $(seq "$rounds"); do
        for x in A B; do
            bin="$A"
            [ "$x" = B ] && bin="$B"
            rm -rf "$out/bench-$x-$r"
            "$bin" bench "${scenes[@]}" --runs 5 --size "$size" --triangle "${TRIANGLE:-watertight}" \
                $nogpu --out "$out/bench-$x-$r" >/dev/null 2>&1
        done
    done
    for x in A B; do
        for r in $(seq "$rounds"); do
            awk -F'|' -v x="$x" '{
                s = $2; t = $3; gsub(/ /, "", s); sub(/^ +/, "", t); split(t, w, " ")
                if (w[1] != "cpu-f32" && w[1] != "gpu") next
                split($8, m, " "); print s, w[1], x, m[1]
            }' "$out/bench-$x-$r/report.md"
        done
    done >"$out/bench-rows.txt"
    {
        echo "A = $a_rev ($A), B = $b_rev ($B); glint bench, $rounds rounds, A B interleaved; $(nproc) cores; $(date -u +%FT%TZ)"
        echo
        echo "| scene | tracer | A median ms | B median ms | B / A | |"
        echo "|---|---|---|---|---|---|"
    } | tee "$out/bench.md"
    flagged=0
    while read -r s t; do
        ma="$(awk -v s="$s" -v t="$t" '$1 == s && $2 == t && $3 == "A" {printf "%s ", $4}' "$out/bench-rows.txt" | median)"
        mb="$(awk -v s="$s" -v t="$t" '$1 == s && $2 == t && $3 == "B" {printf "%s ", $4}' "$out/bench-rows.txt" | median)"
        ratio="$(awk -v a="$ma" -v b="$mb" 'BEGIN {printf "%.3f", b / a}')"
        flag_if_slower "$ratio"
        echo "| $s | $t | $ma | $mb | $ratio | $flag |" | tee -a "$out/bench.md"
    done < <(awk '{print $1, $2}' "$out/bench-rows.txt" | awk '!seen[$0]++')
    [ "$flagged" = 0 ] || exit 3
    exit 0
fi

if [ -n "${PINNED:-}" ]; then
    # The CPU tracer's frames, A and B at the same time: one thread each
    # (RAYON_NUM_THREADS=1), each pinned to a core of its own with `taskset`, the cores
    # swapped every round; per scene and round, the fastest of `glint bench`'s RUNS frames
    # (default 15: the least disturbed by the other process and the machine). The row's
    # ratio is the median over rounds of each round's B / A, taken from two processes
    # that saw the same minute of the machine. On this project's 2-core
    # VM in a quiet stretch the rounds' ratios of such pairs stayed within a few per cent,
    # where one-after-the-other rounds of one build moved by 0.7-1.35; in a noisy stretch
    # they spread as widely: read the per-round column. Needs two cores.
    [ "$(nproc)" -ge 2 ] || { echo "ab.sh: PINNED=1 needs two cores" >&2; exit 2; }
    command -v taskset >/dev/null || { echo "ab.sh: PINNED=1 needs taskset (util-linux)" >&2; exit 2; }
    frame_of() { # report.md -> the cpu-f32 row's fastest frame, ms ("median (min–max)")
        awk -F'|' '{ t = $3; sub(/^ +/, "", t); split(t, w, " ")
            if (w[1] == "cpu-f32") { split($8, m, /[(–)]/); print m[2] + 0; exit } }' "$1"
    }
    : >"$out/pinned-rows.txt"
    for r in $(seq "$rounds"); do
        if ((r % 2)); then ca=0 cb=1; else ca=1 cb=0; fi
        for s in "${scenes[@]}"; do
            rm -rf "$out/pin-A" "$out/pin-B"
            RAYON_NUM_THREADS=1 taskset -c "$ca" "$A" bench "$s" --runs "${RUNS:-15}" --size "$size" \
                --triangle "${TRIANGLE:-watertight}" --no-gpu --out "$out/pin-A" >/dev/null 2>&1 &
            pa=$!
            RAYON_NUM_THREADS=1 taskset -c "$cb" "$B" bench "$s" --runs "${RUNS:-15}" --size "$size" \
                --triangle "${TRIANGLE:-watertight}" --no-gpu --out "$out/pin-B" >/dev/null 2>&1 &
            pb=$!
            wait "$pa" && wait "$pb" || { echo "ab.sh: a bench failed on $s" >&2; exit 1; }
            echo "$(basename "$s" .toml) $r $(frame_of "$out/pin-A/report.md") $(frame_of "$out/pin-B/report.md")" \
                >>"$out/pinned-rows.txt"
        done
    done
    {
        echo "A = $a_rev ($A), B = $b_rev ($B); CPU, one thread each, A and B at once on cores of their own, $rounds rounds; $(nproc) cores; $(date -u +%FT%TZ)"
        echo
        echo "| scene | A fastest ms (median of rounds) | B fastest ms (median of rounds) | B / A per round | B / A (median) | |"
        echo "|---|---|---|---|---|---|"
    } | tee "$out/pinned.md"
    flagged=0
    while read -r s; do
        ma="$(awk -v s="$s" '$1 == s {printf "%s ", $3}' "$out/pinned-rows.txt" | median)"
        mb="$(awk -v s="$s" '$1 == s {printf "%s ", $4}' "$out/pinned-rows.txt" | median)"
        per="$(awk -v s="$s" '$1 == s {printf "%s%.3f", sep, $4 / $3; sep = ", "}' "$out/pinned-rows.txt")"
        ratio="$(awk -v s="$s" '$1 == s {printf "%.6f ", $4 / $3}' "$out/pinned-rows.txt" | median)"
        ratio="$(awk -v r="$ratio" 'BEGIN {printf "%.3f", r}')"
        flag_if_slower "$ratio"
        echo "| $s | $ma | $mb | $per | $ratio | $flag |" | tee -a "$out/pinned.md"
    done < <(awk '{print $1}' "$out/pinned-rows.txt" | awk '!seen[$0]++')
    [ "$flagged" = 0 ] || exit 3
    exit 0
fi

if [ -n "${WHOLE:-}" ]; then
    {
        echo "A = $a_rev ($A), B = $b_rev ($B); whole processes, $rounds rounds, A B interleaved; $(nproc) cores; $(date -u +%FT%TZ)"
        echo
        echo "| scene | tracer | run | A median ms | B median ms | B / A | A peak MiB | B peak MiB |"
        echo "|---|---|---|---|---|---|---|---|"
    } | tee "$out/whole.md"
    for s in "${scenes[@]}"; do
        for backend in ${BACKENDS:-cpu gpu}; do
            rm -rf "$out/cache-warm"
            whole "$B" "$s" "$backend" "$out/cache-warm" >/dev/null
            for run in first cached; do
                ta="" tb="" ma="" mb=""
                for _ in $(seq "$rounds"); do
                    dir="$out/cache-warm"
                    if [ "$run" = first ]; then
                        dir="$out/cache-cold"
                        rm -rf "$dir"
                    fi
                    read -r t m <<<"$(whole "$A" "$s" "$backend" "$dir")"
                    ta+=" $t" ma+=" ${m:-}"
                    [ "$run" = first ] && rm -rf "$dir"
                    read -r t m <<<"$(whole "$B" "$s" "$backend" "$dir")"
                    tb+=" $t" mb+=" ${m:-}"
                done
                if [[ "$ta$tb" == *fail* ]]; then
                    echo "| $(basename "$s" .toml) | $backend | $run | – | – | – | – | failed |" | tee -a "$out/whole.md"
                    continue
                fi
                a="$(median <<<"$ta")" b="$(median <<<"$tb")"
                echo "| $(basename "$s" .toml) | $backend | $run | $a | $b | $(awk -v a="$a" -v b="$b" 'BEGIN {printf "%.3f", b / a}') | $(median <<<"$ma") | $(median <<<"$mb") |" | tee -a "$out/whole.md"
            done
        done
    done
    rm -rf "$out/cache-warm" "$out/cache-cold"
    exit 0
fi

{
    echo "A = $a_rev ($A), B = $b_rev ($B); $rounds rounds, A B interleaved; $(nproc) cores;"
    echo "adapter: $("$B" adapters 2>/dev/null | grep -i -m1 -- "${GLINT_ADAPTER:-}" || echo none); $(date -u +%FT%TZ)"
    echo
    echo "| scene | tracer | A median ms | B median ms | B / A | |"
    echo "|---|---|---|---|---|---|"
} | tee "$out/last.md"
flagged=0
for s in "${scenes[@]}"; do
    for backend in ${BACKENDS:-cpu gpu}; do
        ta="" tb=""
        for _ in $(seq "$rounds"); do
            ta+=" $(frame_ms "$A" "$s" "$backend")"
            tb+=" $(frame_ms "$B" "$s" "$backend")"
        done
        if [[ "$ta$tb" == *fail* ]]; then
            echo "| $(basename "$s" .toml) | $backend | – | – | – | failed to render |" | tee -a "$out/last.md"
            continue
        fi
        ma="$(median <<<"$ta")"
        mb="$(median <<<"$tb")"
        ratio="$(awk -v a="$ma" -v b="$mb" 'BEGIN {printf "%.3f", b / a}')"
        flag_if_slower "$ratio"
        echo "| $(basename "$s" .toml) | $backend | $ma | $mb | $ratio | $flag |" | tee -a "$out/last.md"
    done
done
[ "$flagged" = 0 ] || exit 3
