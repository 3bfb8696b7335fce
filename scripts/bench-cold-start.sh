#!/usr/bin/env bash
# Process start to exit of `illum render` on an empty Mesa shader cache, with the fast start
# (src/cli/fast_start/) off and on, interleaved, and whose image each run wrote
# (docs/performance-kernels.md, "Fast start").
#
#   scripts/bench-cold-start.sh [RUNS] [RENDER ARGS...]
#   scripts/bench-cold-start.sh 3 scenes/default.json --width 256 --height 128 --spp 1
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
shift || true
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(scenes/default.json --width 256 --height 128 --spp 1)
bin=target/release/illum
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "illum render ${args[*]}: seconds from start to exit, empty Mesa cache each run"
for i in $(seq "$runs"); do
    for mode in 0 auto; do
        cache=$(mktemp -d "$work/cache.XXXX")
        env=(MESA_SHADER_CACHE_DIR="$cache")
        if [ "$mode" = 0 ]; then env+=(ILLUM_FAST_START=0); fi
        start=$(date +%s.%N)
        env -u ILLUM_FAST_START "${env[@]}" "$bin" render "${args[@]}" -o "$work/out.exr" \
            > "$work/log" 2>&1 || { cat "$work/log"; exit 1; }
        end=$(date +%s.%N)
        whose=first
        grep -q "fast start: this image" "$work/log" && whose=second
        printf "fast start %-4s %6.2f s  (the %s process's image)\n" \
            "$([ "$mode" = 0 ] && echo off || echo on)" "$(echo "$end - $start" | bc)" "$whose"
        # A fast start that won leaves a background compile writing into this cache: wait for it.
        while grep -lqs "ILLUM_FAST_START_COMPILE=1" /proc/[0-9]*/environ 2>/dev/null; do
            sleep 0.1
        done
        rm -rf "$cache"
    done
done
