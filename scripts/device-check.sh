#!/usr/bin/env bash
# The GPU figures of docs/performance-gpu.md (an NVIDIA H200) in one run on a
# lent device machine: the devices, the trace benchmark, renders under the validation layers, the
# first image on a cold shader cache, camera samples per second, and illum against Mitsuba 3's
# cuda_ad_rgb variant at equal time (scripts/compare-mitsuba.py). Beside the tracked files it needs
# (made here, ignored by git, carried to the device):
#   .gl/*.deb              the Vulkan loader and libglvnd, which NVIDIA's Vulkan driver loads through
#                          (apt-get download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0
#                          libgles2), unpacked into /
#   .dev/illum.xz          a stripped release build of illum
#   .dev/layers.tar.xz     layers/: libVkLayer_khronos_validation.so and its manifest
#                          (library_path "./libVkLayer_khronos_validation.so")
#   .dev/mi312.tar.xz      site/: the mitsuba 3.9.1 and drjit 1.5.0 wheels for Python 3.12,
#                          unpacked, cuda_ad_rgb and the plugins of scenes/bench/mitsuba-* only
# Writes its log under $OUT (or /tmp/device-check). Each stage has its own time limit, so that a
# failing stage leaves the others' figures. SMOKE=1 runs it here first (no loader unpacked, small
# figures) to check the script before device time is spent. STAGES picks stages (default: all but
# tests); "tests" runs the integration tests built here (.dev/tests.tar.xz: tests/<name>, stripped
# `cargo test --release --no-run` binaries) on the GPU. CMP_SCENES and CMP_SETS (compare-mitsuba.py
# --set arguments, e.g. --set default= --set "1/1=--light-samples 1"), CMP_MI (--mi-settings), CMP_T
# (seconds), CMP_REF, CMP_ROUNDS and CMP_TIMEOUT change the comparison.
set -u
smoke=${SMOKE:-}
stages=" ${STAGES:-devices first validation trace throughput where compare} "
# Also: stats (each kernel's register count and other driver statistics, ILLUM_KERNEL_STATS=1),
# submit (camera samples/s and kernel time against the samples of one submission), fps (1280x720
# frames of one sample each, the interactive view's unit of work), ab (this build against
# .dev/illum-before.xz, another stripped build, alternately on the same scenes).
want() { [[ $stages == *" $1 "* ]]; }
out=${OUT:-/tmp/device-check}
mkdir -p "$out"
exec > >(tee "$out/log.txt") 2>&1
stage() { printf '\n== %s (%s)\n' "$*" "$(date +%T)"; }

if [ -z "$smoke" ]; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
if [ -z "$smoke" ]; then
    # The NVIDIA driver's Vulkan manifest, wherever this image mounts it.
    icd=$(timeout 20 find /usr /etc -name 'nvidia_icd*.json' 2>/dev/null | head -1)
    [ -n "$icd" ] && export VK_DRIVER_FILES=$icd
    echo "VK_DRIVER_FILES=${VK_DRIVER_FILES:-unset}"
fi
dev=/tmp/illum-dev
mkdir -p "$dev"
xz -dc .dev/illum.xz >"$dev/illum" && chmod +x "$dev/illum"
tar -xJf .dev/layers.tar.xz -C "$dev"
I=$dev/illum
scenes="scenes/bench/mitsuba-dome.json scenes/bench/mitsuba-rect.json scenes/bench/mitsuba-veach.json
    scenes/bench/mitsuba-lights64.json"
rays=4194304 big="--width 1280 --height 960" t=${CMP_T:-1} ref=20 variant=cuda_ad_rgb
if [ -n "$smoke" ]; then
    scenes=scenes/bench/mitsuba-rect.json rays=65536 big="--width 160 --height 120" t=0.3 ref=1
    variant=llvm_ad_rgb
fi
TIMEFORMAT='wall %R s'


want devices && {
stage devices
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv
nproc
python3 -c "import numpy; print('python', __import__('sys').version.split()[0], 'numpy', numpy.__version__)"
}
VK_LOADER_DEBUG=error,warn "$I" devices

want first && {
stage "first image, cold shader cache (NVIDIA's disk cache off)"
for i in 1 2; do
    time __GL_SHADER_DISK_CACHE=0 MESA_SHADER_CACHE_DISABLE=true ILLUM_KERNEL_TIMES=1 \
        timeout 60 "$I" render --width 256 --height 128 --spp 1 -o "$dev/first.exr" --quiet
done
stage "first image, warm (disk cache on, second run)"
for i in 1 2; do
    time timeout 60 "$I" render --width 256 --height 128 --spp 1 -o "$dev/first.exr" --quiet
done

}
want validation && {
stage "validation layers on: default scene (full integrator) and the dome"
export VK_LAYER_PATH=$dev/layers
timeout 90 "$I" render --width 320 --height 160 --spp 64 --validate -o "$dev/val-default.exr"
echo "rc $?"
timeout 90 "$I" render scenes/bench/mitsuba-dome.json --spp 64 --validate -o "$dev/val-dome.exr"
echo "rc $?"
timeout 90 "$I" bench trace --triangles 100000 --rays 65536 --repeat 1 --validate
echo "rc $?"
unset VK_LAYER_PATH
}

want trace && {
stage "trace benchmark ($rays rays)"
timeout 150 "$I" bench trace --rays $rays --repeat 3

}

want throughput && {
stage "camera samples per second: $big, 3 s each; the default scene (full) last"
for s in $scenes ""; do
    timeout 40 "$I" render $s $big --time 3 --spp 1000000 -o "$dev/big.exr" 2>&1 |
        grep -E "spp in|rror"
done

}

want where && {
stage "where a camera sample's time goes: the dome at $big, 3 s each, by what the kernel does"
for o in "" "--light-samples 1 --brdf-samples 1" "--technique light --light-samples 1" \
    "--integrator path --max-depth 1" "--integrator path --max-depth 2"; do
    echo "options: ${o:-default}"
    timeout 40 "$I" render scenes/bench/mitsuba-dome.json $big $o --time 3 --spp 1000000 \
        -o "$dev/big.exr" 2>&1 | grep -E "spp in|rror"
done
}

want stats && {
stage "kernel statistics (VK_KHR_pipeline_executable_properties): direct, full, path"
for o in "scenes/bench/mitsuba-dome.json" "" "scenes/interior.json --integrator path"; do
    echo "render ${o:-default scene}"
    ILLUM_KERNEL_STATS=1 timeout 60 "$I" render $o --width 64 --height 48 --spp 1 \
        -o "$dev/stats.exr" 2>&1 | grep -E "statistics|rror"
done
}

want submit && {
stage "camera samples/s against samples per submission: the dome and the default scene at $big"
for s in scenes/bench/mitsuba-dome.json ""; do
    for n in 1048576 16777216 268435456; do
        echo "${s:-default scene}, ILLUM_SAMPLES_PER_SUBMIT=$n"
        ILLUM_SAMPLES_PER_SUBMIT=$n timeout 40 "$I" render $s $big --time 3 --spp 1000000 \
            -o "$dev/big.exr" 2>&1 | grep -E "spp in|rror"
    done
done
}

want fps && {
stage "frames of one sample at 1280x720 (the view's unit of work): default scene, direct and full"
for i in direct full; do
    for n in 262144 1048576; do
        echo "integrator $i, ILLUM_SAMPLES_PER_SUBMIT=$n"
        ILLUM_SAMPLES_PER_SUBMIT=$n timeout 40 "$I" render --width 1280 --height 720 \
            --integrator $i --time 3 --spp 100000 -o "$dev/fps.exr" 2>&1 | grep -E "spp in|rror"
    done
done
}

want ab && {
stage "before and after: .dev/illum-before.xz against this build, alternately, 3 s each at $big"
xz -dc .dev/illum-before.xz >"$dev/illum-before" && chmod +x "$dev/illum-before"
for o in "scenes/bench/mitsuba-dome.json" "" "--integrator direct" "scenes/interior.json --integrator path"; do
    for b in "$dev/illum-before" "$I" "$dev/illum-before" "$I"; do
        echo "$(basename "$b"): ${o:-default scene}"
        timeout 40 "$b" render $o $big --time 3 --spp 1000000 -o "$dev/ab.exr" 2>&1 |
            grep -E "spp in|rror"
    done
done
}

want tests && {
stage "integration tests on this GPU (validation layers on; the trace path it offers)"
tar -xJf .dev/tests.tar.xz -C "$dev"
# tests/cli*.rs run the binary from its build path.
mkdir -p target/release && cp "$I" target/release/illum
export VK_LAYER_PATH=$dev/layers
ls "$dev"/tests | timeout 200 xargs -P 4 -I{} sh -c \
    'timeout 150 "$0/tests/{}" >"$0/{}.log" 2>&1; echo "{}: rc $? $(grep -E "^test result" "$0/{}.log" | tail -1)"' "$dev"
for f in "$dev"/*.log; do printf '\n=== %s\n' "$f"; cat "$f"; done >"$out/tests.log"
unset VK_LAYER_PATH
}

want compare && {
stage "illum against Mitsuba 3 $variant at equal time ($t s; reference $ref s)"
if [ -z "$smoke" ]; then
    tar -xJf .dev/mi312.tar.xz -C "$dev"
    export PYTHONPATH=$dev/site
fi
eval "sets=(${CMP_SETS:-})"
PYTHONUNBUFFERED=1 timeout ${CMP_TIMEOUT:-330} python3 scripts/compare-mitsuba.py ${CMP_SCENES:-$scenes} \
    --variant $variant --time $t --ref-time ${CMP_REF:-$ref} --rounds ${CMP_ROUNDS:-3} --illum "$I" \
    --out "$dev/cmp" ${CMP_MI:+--mi-settings "$CMP_MI"} "${sets[@]}"
echo "rc $?"
}
stage done
