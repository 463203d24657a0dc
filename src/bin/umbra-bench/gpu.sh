#!/usr/bin/env bash
# Every benchmark in one call, for the first GPU machine lent (the device tool's `run`), writing
# JSON and logs under $OUT. Each step has its own time limit and a failed step does not stop the
# others, so one call gives every figure it can.
#
# Prepared here, carried along (ignored by git):
#   cargo build --release --bins && strip target/release/umbra target/release/umbra-bench
#   mkdir -p .gl && (cd .gl && apt-get download libvulkan1)     # the Vulkan loader
# then on the device (from the repository root):
#   bash src/bin/umbra-bench/gpu.sh        # carry: target/release/umbra, target/release/umbra-bench, .gl
#
# Settings (environment): OUT (out/gpu), BIN (target/release), SIZE (1920x1080), REPEATS (20),
# STEP_LIMIT seconds per step (240), SUITE_ARGS (e.g. --quick), VK_DRIVER_FILES (NVIDIA ICD). Checked on lavapipe with
# VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json SIZE=64x64 BIN=target/debug.
# Goals (issue 25): >= 5 Grays/s primary and >= 1.5 Grays/s diffuse on Sponza, a hybrid frame
# <= 1 ms and SSAO <= 0.3 ms at 1080p, path tracing 1080p at >= 1 Gsample-bounce/s.
set -uo pipefail
cd "$(dirname "$0")/../../.."
OUT=${OUT:-out/gpu}
BIN=${BIN:-target/release}
SIZE=${SIZE:-1920x1080}
REPEATS=${REPEATS:-20}
STEP_LIMIT=${STEP_LIMIT:-240}
mkdir -p "$OUT"

# The loader: the machine has the driver, maybe not libvulkan.so.1.
if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1 '; then
    for deb in .gl/*.deb; do dpkg -x "$deb" /tmp/umbra-vk; done
    export LD_LIBRARY_PATH=/tmp/umbra-vk/usr/lib/x86_64-linux-gnu:${LD_LIBRARY_PATH:-}
fi
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}

# shared/ sits in the checkout on the device machine, beside it here; umbra-bench's default
# models (suite's Sponza, paths' and pipelines' sample models) come from UMBRA_ASSETS.
SPONZA=""
for dir in shared ../shared; do
    if [ -f "$dir/assets/gltf/SponzaDabrovic/sponza_dabrovic.glb" ]; then
        SPONZA="$dir/assets/gltf/SponzaDabrovic/sponza_dabrovic.glb"
        export UMBRA_ASSETS="${UMBRA_ASSETS:-$(cd "$dir/assets" && pwd)}"
    fi
done

status=0
step() {  # step NAME COMMAND...: runs it with a time limit, its output in $OUT/NAME.log
    local name=$1
    shift
    local started=$SECONDS
    if timeout "$STEP_LIMIT" "$@" >"$OUT/$name.log" 2>&1; then
        echo "ok      $name ($((SECONDS - started)) s)"
    else
        echo "FAILED  $name ($((SECONDS - started)) s, exit $?): see $OUT/$name.log"
        tail -5 "$OUT/$name.log"
        status=1
    fi
}

step info "$BIN/umbra" info
scene_args=()
if [ -n "$SPONZA" ]; then scene_args=(--gltf "$SPONZA"); fi
step rays "$BIN/umbra-bench" rays --size "$SIZE" --repeats "$REPEATS" "${scene_args[@]}" --out "$OUT/rays"
step passes-cornell "$BIN/umbra-bench" passes --size "$SIZE" --repeats "$REPEATS" --out "$OUT/passes-cornell"
step passes-spheres "$BIN/umbra-bench" passes scenes/spheres.glb --size "$SIZE" --repeats "$REPEATS" --out "$OUT/passes-spheres"
if [ -n "$SPONZA" ]; then
    step passes-sponza "$BIN/umbra-bench" passes "$SPONZA" --size "$SIZE" --repeats "$REPEATS" --out "$OUT/passes-sponza"
fi
step pathtrace-cornell "$BIN/umbra" render --size "$SIZE" --spp 64 -o "$OUT/pathtrace-cornell.png"
step pathtrace-spheres "$BIN/umbra" render scenes/spheres.glb --size "$SIZE" --spp 64 -o "$OUT/pathtrace-spheres.png"
step pathtrace-cornell-wavefront "$BIN/umbra" render --size "$SIZE" --spp 64 --integrator wavefront -o "$OUT/pathtrace-cornell-wavefront.png"
step pathtrace-spheres-wavefront "$BIN/umbra" render scenes/spheres.glb --size "$SIZE" --spp 64 --integrator wavefront -o "$OUT/pathtrace-spheres-wavefront.png"
# The path tracer's throughput (samples and segments per second, warm) on every sample model,
# megakernel and wavefront in turn, and how busy the megakernel's walks keep a warp's lanes.
assets=()
for dir in shared ../shared; do
    if [ -d "$dir/assets/gltf" ]; then assets=(--assets "$dir/assets/gltf"); fi
done
step paths "$BIN/umbra-bench" paths --size "$SIZE" --repeats 5 --integrator megakernel,wavefront --lanes "${assets[@]}" --out "$OUT/paths"
step suite "$BIN/umbra-bench" suite ${SUITE_ARGS:-} --out "$OUT/suite"
sponza_args=()
if [ -n "$SPONZA" ]; then sponza_args=(--sponza "$SPONZA"); fi
step probes "$BIN/umbra-bench" probes --repeats "$REPEATS" "${sponza_args[@]}" --out "$OUT/probes"
# Shadow maps against shadow rays (issue 19's goals: a 2048² sun map of Sponza in <= 0.3 ms, PCF
# lighting at 1080p in <= 0.2 ms), the denoiser against one sample, ReSTIR against power sampling.
if [ -n "$SPONZA" ]; then
    step shadows-sponza "$BIN/umbra-bench" shadows "$SPONZA" --size "$SIZE" --map-size 2048 --repeats "$REPEATS" --out "$OUT/shadows-sponza"
    # The goal's single 2048² sun map, and the cascades' whole windows (what the view marks save).
    step shadows-sponza-1-cascade "$BIN/umbra-bench" shadows "$SPONZA" --size "$SIZE" --map-size 2048 --cascades 1 --repeats "$REPEATS" --out "$OUT/shadows-sponza-1-cascade"
    step shadows-sponza-windows "$BIN/umbra-bench" shadows "$SPONZA" --size "$SIZE" --map-size 2048 --no-view-marks --repeats "$REPEATS" --out "$OUT/shadows-sponza-windows"
fi
step shadows-spheres "$BIN/umbra-bench" shadows scenes/spheres.glb --size "$SIZE" --map-size 2048 --repeats "$REPEATS" --out "$OUT/shadows-spheres"
step denoise "$BIN/umbra-bench" denoise --size "$SIZE" --reference-spp 512 --max-spp 64 --repeats "$REPEATS" --out "$OUT/denoise"
step restir "$BIN/umbra-bench" restir --size "$SIZE" --repeats "$REPEATS" --out "$OUT/restir"
grep -h "^pathtrace:" "$OUT"/pathtrace-*.log 2>/dev/null
echo "wrote $OUT"
exit $status
