#!/usr/bin/env bash
# The 8K frame again after bands were capped at 1 GiB of film each (results-8k.txt).
set -u
/usr/bin/time -f "%e s, peak %M KiB" target/release/illum render scenes/default.json \
    --width 8192 --height 4320 --spp 1 -o /tmp/bands.exr 2>&1 | grep -v compiling | tee docs/logs/bands-2026-12-03/results-8k.txt
