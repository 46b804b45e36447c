#!/bin/sh
# regather.sh SRC DST BUILD: the gather's share of issue 25's turning test,
# fast. SRC is a folder tests/tools/invariance.sh left (BUILD/invariance/, with
# its four runs model1, model2, turned1, turned2 and their scenes); it is
# copied to DST, each run's folder is gathered again by BUILD/weathering
# (`weathering gather`, which reads the dirt maps the runs wrote: the same
# deposits, no flight), and the seeds' and orientations' differences are
# printed as invariance.sh prints them, with T = sqrt(orientations^2 -
# seeds^2), the part the turn adds to the seeds' noise. A gather variant
# (a temporary switch in a build kept aside) is judged in about 35 s for
# Spot instead of the two minutes of a whole test; the flight stays as SRC's
# build made it (docs/performance.md, "Turned, shifted, re-gathered").
set -eu
src=$1
dst=$2
build=$3
case $build in /*) ;; *) build=$(pwd)/$build ;; esac
rm -rf "$dst"
cp -r "$src" "$dst"
cd "$dst"
for m in model turned; do
    for s in 1 2; do
        "$build/weathering" gather "$m.xml" --out "$m$s" -q
    done
done
c=$build/tools/texture_compare
$c model1/model_texture.exr model2/model_texture.exr Y > seeds_model
$c turned1/turned_texture.exr turned2/turned_texture.exr Y > seeds_turned
$c model1/model_texture.exr turned1/turned_texture.exr Y > turn_1
$c model2/model_texture.exr turned2/turned_texture.exr Y > turn_2
for k in 1 4 16; do
    get() { awk -v k="$k" '$1 == "block" && $2 + 0 == k { print $4 }' "$1"; }
    awk -v k="$k" -v a="$(get seeds_model)" -v b="$(get seeds_turned)" -v c="$(get turn_1)" \
        -v d="$(get turn_2)" 'BEGIN { s = (a + b) / 2; o = (c + d) / 2; t = o * o - s * s
        printf "block %2d: seeds %.4f  orientations %.4f  ratio %.3f  T %.4f\n", k, s, o, o / s,
               (t > 0 ? sqrt(t) : 0) }'
done
