#!/usr/bin/env bash
# Peak resident memory of renders of the default scene, whole and in bands (src/render/bands.rs).
# Run from the repository root after `cargo build --release`; writes results.txt here.
set -u
out=docs/logs/bands-2026-12-03/results.txt
: >"$out"
run() {
    local label=$1; shift
    /usr/bin/time -f "%e %M" -o /tmp/bands-time target/release/illum render scenes/default.json \
        -o /tmp/bands.exr "$@" 2>/tmp/bands-err
    local rc=$?
    read -r secs kb </tmp/bands-time
    local px=$(( $2 * $4 ))
    echo "$label | $* | rc $rc | $secs s | peak $((kb / 1024)) MiB | $(( kb * 1024 / px )) B/pixel" | tee -a "$out"
    grep -h "bands\|needs about" /tmp/bands-err | tee -a "$out"
}
run "1080p 1 spp, whole"      --width 1920 --height 1080 --spp 1
run "1080p 1 spp, bands"      --width 1920 --height 1080 --spp 1 --memory-limit 900M
run "1080p 64 spp, whole"     --width 1920 --height 1080 --spp 64
run "1080p 64 spp, bands"     --width 1920 --height 1080 --spp 64 --memory-limit 900M
run "4096^2 1 spp, whole"     --width 4096 --height 4096 --spp 1
run "4096^2 1 spp, bands"     --width 4096 --height 4096 --spp 1 --memory-limit 4G
run "256^2 1024 spp, whole"   --width 256 --height 256 --spp 1024
run "8192x4320 1 spp, default limit" --width 8192 --height 4320 --spp 1
