#!/usr/bin/env bash
# The whole test suite, as CI runs it: formatting and lints, then every test on lavapipe with the
# Vulkan validation layers on (the tests enable them; any message fails the test), on each trace
# path and on a driver without ray queries.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
# No second process racing each render (src/cli/fast_start/): tests/fast_start.rs turns it on
# where it tests it; elsewhere it would only add load and make exit paths depend on the clock.
export ILLUM_FAST_START=0
# Each stage prints the seconds since the start, so a slow CI run shows where its time went.
stage() { echo "== [${SECONDS} s] $*"; }

stage "formatting and lints"
cargo fmt --all -- --check
cargo clippy --release --all-targets -- -D warnings
cargo clippy --release -p illum-python -- -D warnings
scripts/test-k8s.sh

stage "Mesa 25 lavapipe (bookworm-backports), trace path auto"
# The lib's staticlib (libillum.a), which tests/capi.rs links a C program against: `cargo test`
# builds only the rlib. The same compilation serves the tests.
cargo build --release --lib
cargo test --release

stage "Slurm: one render in 4 parts on a single-node cluster, a task killed and resubmitted"
scripts/test-slurm.sh

stage "Mesa 25 lavapipe, ray queries forced"
# Auto takes illum's compute BVH on lavapipe (faster than its ray queries: src/trace/mod.rs), so
# the stage above ran the BVH path; this one runs the ray-query path.
ILLUM_TEST_TRACE=rayquery cargo test --release --test render --test direct --test report --test updates

stage "Debian's stock Mesa 22.3.6 lavapipe: no VK_KHR_ray_query, so the compute BVH"
# Everything that can differ on this driver (the compute BVH, one sample per dispatch, no
# ray-query device features, older LLVM). Left out, for CI time: the estimator-only statistics
# of shadow_rays.rs, stratified.rs, control_variates.rs, control_variates_bias.rs and control_variates_dome.rs
# and the cache-against-brute-force, furnace, glossy-furnace and caustic comparisons of
# indirect.rs (no trace-path or driver code of their own; they run on Mesa 25 above; indirect.rs
# took 134 s of this driver's time with the last two, 87 s without, 21 s without the furnace
# too). The indirect tests that do run here cover the cache's determinism and its merges.
stock="$PWD/.vk/mesa-stock/icd.json"
tests=()
for t in tests/*.rs; do
    name=$(basename "$t" .rs)
    case "$name" in
        shadow_rays | stratified | control_variates | control_variates_bias | control_variates_dome) ;;
        # Scenario statistics over kernels that every other test here runs too: extreme scenes
        # (stress.rs, 53 s of this driver's time), emitters against lights (fidelity.rs, 29 s),
        # many lights (many_lights.rs, 29 s) and direct lighting's closed forms (direct.rs, 31 s;
        # tests/regression.rs checks this driver's direct image bit for bit). On Mesa 25 above.
        stress | fidelity | many_lights | direct) ;;
        # The allocation pilot: estimator statistics and host logic over the kernels that run
        # here in every other test (its merges took 57 s of this driver's time: 0.17 M camera
        # samples/s against Mesa 25's 2-4 M); it runs on Mesa 25 above.
        allocation) ;;
        # Host code only (the farm's scripts, faults and fuzzing of the command line and
        # loaders, output files): nothing there depends on the driver; they run on Mesa 25 above.
        farm | cli_faults | fuzz | cli_outputs | scene_load | output | layers) ;;
        *) tests+=(--test "$name") ;;
    esac
done
# Of tests/adaptive.rs only the merges and the command line run here (the packed dispatches at
# one sample each); its statistics took 4 of this driver's minutes and have no code of their own.
# Likewise the denoiser's error statistics (tests/denoise.rs: 118 s here, 14 s on Mesa 25).
VK_DRIVER_FILES="$stock" VK_ICD_FILENAMES="$stock" cargo test --release --lib --bins "${tests[@]}" \
    -- --skip the_cache_agrees_with_brute_force --skip a_glossy_ball_in_the_furnace_keeps_its_light \
    --skip a_mirror_balls_caustic_agrees_with_path --skip adaptive_sampling_is_unbiased \
    --skip adaptive_sampling_agrees_with_uniform_sampling --skip the_noise_threshold_reaches_its_target \
    --skip denoising_lowers_the_error_of_a_16_spp_render --skip the_furnace_reads_le_over_one_minus_rho
stage "The Python module (python/, import illum): built by maturin, tested by pytest"
# Last: its build changes the library's fingerprint, so that a cargo test after it compiles
# illum and links every test binary again (97 s on 2 cores). Against the CLI built above, with
# the validation layers on (any message fails a test).
rm -rf target/wheels
.venv-py/bin/maturin build --release --quiet -m python/Cargo.toml -o target/wheels
.venv-py/bin/pip install -q --disable-pip-version-check --force-reinstall --no-deps target/wheels/illum-*.whl
ILLUM_VALIDATION=1 ILLUM_BIN="$PWD/target/release/illum" .venv-py/bin/python -m pytest -q -p no:cacheprovider python/tests

stage "done"
