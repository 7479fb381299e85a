#!/usr/bin/env bash
# Renders the README's pictures into docs/images/ with the current Release build: the forest of
# 64 trees from the demo's near, mid and far views, and three glTF models from ../shared/data.
# Run from the repository root after scripts/demo.sh (which builds build-release). Needs
# oiiotool (Debian: openimageio-tools) to lay the views side by side.
set -euo pipefail

ff=${FF:-build-release/viewer/farfield}
data=${FF_SHARED_DATA:-../shared/data}
command -v oiiotool > /dev/null || { echo "readme_images: needs oiiotool (apt-get install openimageio-tools)" >&2; exit 1; }
[ -x "$ff" ] || { echo "readme_images: no $ff; run scripts/demo.sh first" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

render() { # scene image distance azimuth elevation
    "$ff" render "$1" -o "$2" --size 400x300 --distance "$3" --azimuth "$4" --elevation "$5" > /dev/null
}

"$ff" build -q --generate forest:trees=64 -o "$work/forest.ffs"
render "$work/forest.ffs" "$work/near.png" 0.8 30 12
render "$work/forest.ffs" "$work/mid.png" 2 30 20
render "$work/forest.ffs" "$work/far.png" 6 30 20
oiiotool "$work/near.png" "$work/mid.png" "$work/far.png" --mosaic 3x1 -o docs/images/forest-views.png

models=(draco/CesiumMilkTruck/glTF-Draco/CesiumMilkTruck.gltf scanned/skull/skull.glb draco/WaterBottle/glTF-Draco/WaterBottle.gltf)
images=()
for i in "${!models[@]}"; do
    "$ff" build -q "$data/${models[$i]}" -o "$work/model$i.ffs"
    render "$work/model$i.ffs" "$work/model$i.png" 2.3 30 15
    images+=("$work/model$i.png")
done
oiiotool "${images[@]}" --mosaic 3x1 -o docs/images/gltf-models.png
echo "readme_images: docs/images/forest-views.png, docs/images/gltf-models.png"
