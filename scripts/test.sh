#!/usr/bin/env bash
# The whole test suite, as CI runs it: formatting and lints, then every test on lavapipe with the
# Vulkan validation layers on (the tests enable them; any message fails the test).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never

cargo fmt --all -- --check
cargo clippy --release --all-targets -- -D warnings

# Mesa 25 lavapipe from bookworm-backports (ray queries), default trace path.
cargo test --release
