#!/usr/bin/env bash
# make test-blender: docs/mask.md's Blender recipe and the Blender add-on, run
# headless in Blender.
# Usage: tests/blender/run.sh [BUILD]   (BUILD: the build folder, default build)
# Runs `weathering run` on xml_scenes/building.xml (the default scene, its output
# camera facing the facade) and on tests/blender/building_oblique.xml (an oblique,
# non-square output camera) into BUILD/blender-test/, then Blender on
# test_mask_recipe.py, which runs the recipe's blocks from docs/mask.md on
# building.obj and compares each render with its mask.exr and mask.png; then
# Blender on test_addon.py, which runs the add-on blender/weathering/ headless
# (docs/blender.md) on a cube and a sphere; then Blender on test_ao_peer.py, which
# compares the accessibility of a scene `weathering init` writes for the house
# with Cycles' AO bake of its UV layout (and times both).
# The last line is "N passed, M failed"; the exit status is non-zero on failure.
set -u
cd "$(dirname "$0")/../.."
build=${1:-build}
out=$build/blender-test
export GALLIUM_DRIVER=llvmpipe
t0=$SECONDS
pass=0
fail=0
rm -rf "$out"
for scene in xml_scenes/building.xml tests/blender/building_oblique.xml; do
    dir=$out/$(basename "$scene" .xml)
    t=$SECONDS
    if "$build/weathering" run "$scene" --out "$dir" -q; then
        echo "ok   weathering run $scene --out $dir -q ($((SECONDS - t)) s)"
        pass=$((pass + 1))
    else
        echo "FAIL weathering run $scene --out $dir -q"
        echo "$pass passed, $((fail + 1)) failed"
        exit 1
    fi
done
# One Blender script: its output (without Blender's own chatter: render
# progress, version, "Blender quit") and its "N passed, M failed" added to ours.
blender_test() {
    local log status summary p f
    log=$(mktemp)
    blender -b --factory-startup --python "$@" 2>&1 |
        grep --line-buffered -v -E '^(Fra:|Blender quit$|Blender [0-9.]+ *$)' | tee "$log"
    status=${PIPESTATUS[0]}
    summary=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$log" | tail -n 1)
    rm -f "$log"
    if [ -z "$summary" ]; then
        echo "Blender ended without a summary (exit status $status): $1"
        fail=$((fail + 1))
        return
    fi
    p=${summary%% passed*}
    f=${summary#*, }
    f=${f%% failed*}
    pass=$((pass + p))
    fail=$((fail + f))
    if [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "Blender exited with status $status: $1"
        fail=$((fail + 1))
    fi
}
blender_test tests/blender/test_mask_recipe.py -- \
    docs/mask.md xml_scenes/meshes/building.obj "$out/building" "$out/building_oblique"
# The add-on (blender/weathering/): registered from the repository, run on a
# cube and a sphere into $build/blender-test/addon/.
echo "== the Blender add-on"
blender_test tests/blender/test_addon.py -- "$(cd "$build" && pwd)"
# Accessibility against Cycles' AO bake on the default house with init's
# cameras (issue 26, item 4; docs/masks.md, "Against Blender's AO bake"), into
# $build/blender-test/ao_peer/.
echo "== accessibility against Blender's AO bake"
blender_test tests/blender/test_ao_peer.py -- "$build" xml_scenes/meshes/building.obj "$out/ao_peer"
echo "== test-blender took $((SECONDS - t0)) s"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
