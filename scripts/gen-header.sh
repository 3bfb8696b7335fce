#!/usr/bin/env bash
# Regenerates include/illum.h from src/capi/ with cbindgen (cargo install cbindgen --locked).
# tests/capi.rs compiles a C program against the committed header, so a stale one fails there.
set -euo pipefail
cd "$(dirname "$0")/.."
command -v cbindgen >/dev/null || { echo "gen-header: install cbindgen: cargo install cbindgen --locked" >&2; exit 1; }
cbindgen --config cbindgen.toml --crate illum --output include/illum.h --quiet
echo "gen-header: include/illum.h"
