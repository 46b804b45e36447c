#!/bin/sh
# previews.sh BUILD: regenerates the pictures of docs/images (but the gallery
# and presets-spot.png, which `make gallery` writes, and the Blender add-on's
# screenshot) from today's code, so that the documentation shows what the
# program makes now (make previews).
#
#   BUILD/previews/SCENE/          each shipped scene's run (xml_scenes/)
#   BUILD/previews/house-masks/    the house with docs/masks.md's <Masks>
#
# The mask previews are the program's own PNGs (white at the larger of 1 and
# the 99th percentile); the TextureMaps on their models are drawn by
# build/tools/render_texture from a camera the scenes do not have.
set -eu
build=$1
images=docs/images
dir=$build/previews
mkdir -p "$dir"
w=$build/weathering

for scene in building teapot bunny spot rusty_tank stained_house old_house; do
    echo "previews: $scene" >&2
    rm -rf "${dir:?}/$scene"
    "$w" run "xml_scenes/$scene.xml" --out "$dir/$scene" -q
done
for scene in building teapot bunny spot; do
    cp "$dir/$scene/mask.png" "$images/$scene-mask.png"
done
for m in ao dirt moss mossy rust sun water; do
    cp "$dir/rusty_tank/mask_$m.png" "$images/rusty_tank-$m.png"
done
cp "$dir/stained_house/mask_stains.png" "$images/stained_house-stains.png"
# The old house's seasons 4, 8, 12 and 20, painted (rust, cracks, peeling, stains).
python3 tests/tools/old_house_seasons.py "$build" "$dir/old_house" "$images/old_house-seasons.png"

# The TextureMaps: the layout as written, and drawn on the model.
cp "$dir/building/building_texture.png" "$images/building-texture-layout.png"
cp "$dir/spot/spot_texture.png" "$images/spot-texture-layout.png"
"$build/tools/render_texture" xml_scenes/meshes/building.obj "$dir/building/building_texture.exr" \
    --view "12 9 20 0 5.5 0 0 1 0 17 17 768" --png "$images/building-texture-on-model.png"
"$build/tools/render_texture" xml_scenes/meshes/spot.obj "$dir/spot/spot_texture.exr" \
    --view "2.6 1.5 2.8 0 0.1 0.2 0 1 0 2.3 2.3 768" --png "$images/spot-texture-on-model.png"

# The derived masks of docs/masks.md on the house.
echo "previews: the house's masks" >&2
rm -rf "${dir:?}/house-masks"
mkdir -p "$dir/house-masks"
sed -e 's|file="meshes/|file="'"$PWD"'/xml_scenes/meshes/|g' \
    -e '/<\/Weathering>/i\
  <Masks>\
    <Accessibility name="ao" rays="64" distance="2"/>\
    <Exposure name="sun" elevation="40" azimuth="60" sideWeight="0.5" sideElevation="0.6" sideSpread="50"/>\
    <Curvature name="curvature" radius="0.1"/>\
    <Height name="height"/>\
    <Combine name="grime" scale="1">\
      <Term substance="dirt" weight="1" offset="20" steepness="0.01"/>\
      <Term mask="ao" weight="-0.6" offset="0.7" steepness="20"/>\
      <Term constant="0.3"/>\
    </Combine>\
  </Masks>' xml_scenes/building.xml > "$dir/house-masks/house.xml"
"$w" run "$dir/house-masks/house.xml" --out "$dir/house-masks/out" -q
for m in ao sun curvature height grime; do
    cp "$dir/house-masks/out/mask_$m.png" "$images/masks-house-$m.png"
done

echo "previews: wrote $images" >&2
