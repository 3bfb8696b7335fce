#!/bin/sh
# Counts the traversal copies a kernel holds for a feature set, as the driver sees them after
# specialization and inlining: freezes the FEATURES specialization constant (id 0), inlines and
# folds with spirv-opt, then counts ray-query initializations (closest hit: flags 0; shadow rays:
# TerminateOnFirstHit, 4). Use a kernel's rq variant (the bvh variant has the same call sites).
#   scripts/trace-copies.sh target/release/build/illum-*/out/full.rq.spv 0xe
set -e
spv=$1
features=$(printf '%d' "${2:-0xffffffff}")
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
spirv-opt --set-spec-const-default-value "0:$features" --freeze-spec-const -O "$spv" -o "$tmp"
spirv-dis "$tmp" | awk '
    /OpConstant %uint 0$/ { zero = $1 }
    /OpConstant %uint 4$/ { four = $1 }
    $1 == "OpRayQueryInitializeKHR" { n[$4]++ }
    END { printf "closest-hit %d shadow-ray %d\n", n[zero] + 0, n[four] + 0 }'
