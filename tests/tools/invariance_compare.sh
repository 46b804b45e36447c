#!/bin/sh
# invariance_compare.sh DIR BUILD CHANNEL [T]: the figures of tests/tools/invariance.sh
# for the four runs in DIR (model1, model2, turned1, turned2, seeds 1 and 2 of
# each orientation): per block size, the RMS difference over the mean between
# seeds (the two orientations' pairs averaged), between orientations (the two
# seeds' pairs averaged), and their ratio, from BUILD/tools/texture_compare on
# CHANNEL of the TextureMaps. Leaves each comparison in DIR (seeds_model,
# seeds_turned, turn_1, turn_2). With a fourth argument `T`, each line also
# gives T = sqrt(orientations^2 - seeds^2), the part the turn adds to the
# seeds' noise. invariance.sh calls it after its runs, and
# tests/tools/diagnosis/regather.sh (with T) after gathering them again.
set -eu
dir=$1
build=$2
channel=$3
with_t=${4:-}
c=$build/tools/texture_compare
$c "$dir/model1/model_texture.exr" "$dir/model2/model_texture.exr" "$channel" > "$dir/seeds_model"
$c "$dir/turned1/turned_texture.exr" "$dir/turned2/turned_texture.exr" "$channel" > "$dir/seeds_turned"
$c "$dir/model1/model_texture.exr" "$dir/turned1/turned_texture.exr" "$channel" > "$dir/turn_1"
$c "$dir/model2/model_texture.exr" "$dir/turned2/turned_texture.exr" "$channel" > "$dir/turn_2"
for k in 1 2 4 8 16 32; do
    get() { awk -v k="$k" '$1 == "block" && $2 + 0 == k { print $4 }' "$dir/$1"; }
    awk -v k="$k" -v a="$(get seeds_model)" -v b="$(get seeds_turned)" -v c="$(get turn_1)" \
        -v d="$(get turn_2)" -v with_t="$with_t" 'BEGIN { s = (a + b) / 2; o = (c + d) / 2
        printf "block %2d: seeds %.4f  orientations %.4f  ratio %.3f", k, s, o, o / s
        t = o * o - s * s
        if (with_t == "T") printf "  T %.4f", (t > 0 ? sqrt(t) : 0)
        printf "\n" }'
done
