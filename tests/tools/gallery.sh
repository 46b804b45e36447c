#!/bin/sh
# gallery.sh BUILD OUT.png: every preset on every shipped model, in one contact
# sheet for people to look at (make gallery; README and docs/presets.md show
# it). Rows: the house, the Utah teapot, the Stanford bunny, Spot, the tank;
# columns: rain, dust, soot, moss, rust, old_paint. Each cell is `weathering run MESH --preset
# P` seen from the scene's output camera: the TextureMap drawn on the mesh by
# build/tools/render_texture where the mesh has UVs, else the mask shaded
# alike by build/tools/gallery (clay to dirt, white at the 99th percentile);
# moss shows moss.Y, rust rust.Y, old_paint peel.Y (where the paint came off),
# the others the dirt. GALLERY_RESOLUTION (default 384) sets
# --resolution; the runs go to BUILD/gallery/MODEL-PRESET/. Spot's row is also
# written alone, larger, as presets-spot.png beside OUT.png (docs/presets.md).
set -eu
presets="rain dust soot moss rust old_paint"
# The channel a preset's cell shows (TextureMap; the mask's is CHANNEL.Y).
channel_of() {
    case $1 in
    moss | rust) echo "$1" ;;
    old_paint) echo peel ;;
    *) echo Y ;;
    esac
}
build=$1
out=$2
res=${GALLERY_RESOLUTION:-384}
dir=$build/gallery
mkdir -p "$dir"
cells=""
for model in building teapot stanford-bunny spot tank; do
    mesh=xml_scenes/meshes/$model.obj
    for preset in $presets; do
        o=$dir/$model-$preset
        rm -rf "$o"
        echo "gallery: $model, $preset" >&2
        "$build/weathering" run "$mesh" --preset "$preset" --resolution "$res" --out "$o" -q
        channel=$(channel_of "$preset")
        texture=$(ls "$o"/*_texture.exr 2>/dev/null | head -1 || true)
        # The output camera's <View>: eye, target, up, width, height, resolution.
        view=$(tr '\n' ' ' < "$o/scene.xml" | sed -e 's/.*out="true">[^<]*<View \([^/]*\)\/>.*/\1/' |
            sed -e 's/[a-z]*="\([^"]*\)"/\1/g' |
            awk '{ print $1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, 640 }')
        if [ -n "$texture" ]; then
            "$build/tools/render_texture" "$mesh" "$texture" --channel "$channel" \
                --view "$view" --png "$o/gallery.png"
            cells="$cells png:$o/gallery.png"
        else
            mask_channel="Y|dirt.Y"
            [ "$channel" != Y ] && mask_channel=$channel.Y
            cells="$cells mask:$o/mask.exr:$mask_channel:$o/shot_normal.exr"
        fi
    done
done
# shellcheck disable=SC2086 # the cells are words
"$build/tools/gallery" "$out" --columns 6 --cell 320 $cells
spot=""
for preset in $presets; do
    spot="$spot png:$dir/spot-$preset/gallery.png"
done
# shellcheck disable=SC2086 # the cells are words
"$build/tools/gallery" "$(dirname "$out")/presets-spot.png" --columns 6 --cell 384 $spot
echo "gallery: wrote $out and $(dirname "$out")/presets-spot.png" >&2
