#!/usr/bin/env bash
# A/B renders for a change that must not change behaviour: every value of every enum flag of
# `umbra render`, each mode, tiny images (24×24, 4 spp; about 40 s on lavapipe).
#
#   scripts/ab-renders.sh BIN DIR          render with the umbra binary BIN into DIR
#   scripts/ab-renders.sh --compare A B    compare two such folders byte for byte
#
# Typical use: build the base (`cargo build --bin umbra`), copy target/debug/umbra to /tmp/base,
# render with it, make the change, build, render again, compare. Note that umbra and the tests
# build the library with different features, so build the binary the same way both times.
set -uo pipefail
if [ "${1:-}" = "--compare" ]; then
    a=$2; b=$3; differ=0; n=0
    for f in "$a"/*.png "$a"/*.exr; do
        n=$((n + 1))
        if [ ! -e "$b/$(basename "$f")" ]; then
            echo "missing in $b: $(basename "$f")"; differ=$((differ + 1))
        elif ! cmp -s "$f" "$b/$(basename "$f")"; then
            echo "differs: $(basename "$f")"; differ=$((differ + 1))
        fi
    done
    echo "$n files, $differ differ"
    [ "$differ" = 0 ]; exit
fi
B=$(realpath "$1"); d=$(realpath -m "$2"); mkdir -p "$d"; cd "$(dirname "$0")/.."
export VK_DRIVER_FILES=${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.x86_64.json}
S="--size 24x24"; P="$S --spp 4"; failed=0
r() {
    local name=$1; shift
    "$B" render "$@" -o "$d/$name.png" --exr "$d/$name.exr" >/dev/null 2>"$d/$name.err" ||
        { echo "FAILED $name: $(tail -1 "$d/$name.err")"; failed=1; }
}
r pt-default $P
for m in ggx ggx-walter beckmann; do r mf-$m scenes/spheres.glb $P --microfacet $m; done
for h in power balance; do r heur-$h $P --heuristic $h; done
for s in low-discrepancy independent; do r samp-$s $P --sampler $s; done
for e in area solid-angle; do r emit-$e $P --emitter-sampling $e; done
for s in mis bsdf light; do r strat-$s $P --strategy $s; done
for i in megakernel wavefront; do r integ-$i scenes/glass.glb $P --integrator $i; done
for t in clamp aces neutral; do r tone-$t $P --tonemap $t; done
r ris-off scenes/many-lights.glb $P --direct ris
for u in samples spatial both; do r ris-$u scenes/many-lights.glb $P --direct ris --ris-reuse $u; done
r pt-denoise scenes/textured.glb $P --denoise
r hy-default scenes/textured.glb $S --mode hybrid
for s in rt hard pcf pcss moments; do r shadows-$s $S --mode hybrid --shadows $s; done
r shadows-rtsize $S --mode hybrid --rt-light-size
r hy-restir scenes/many-lights.glb $S --mode hybrid --direct restir
r hy-restir-ub scenes/many-lights.glb $S --mode hybrid --direct restir --restir-unbiased --restir-no-temporal
r hy-probes $S --mode hybrid --probes bake --probe-spacing 0.25 --probe-rays 64 --probe-sweeps 1 --probe-bounces 1
r hy-lightmaps $S --mode hybrid --lightmaps --unwrap --lightmap-size 16 --lightmap-samples 4
r hy-noao $S --mode hybrid --no-ao --no-ibl
r ao $S --mode ao
r ao-noblur $S --mode ao --ao-no-blur --ao-samples 8
r rtao $S --mode rtao --ao-samples 4
r inst scenes/instanced.glb $P
r missing-textures scenes/khronos/TextureSettingsTest/TextureSettingsTest.glb $P --missing-textures warn
echo "$(ls "$d"/*.png | wc -l) renders in $d"
exit $failed
