#!/usr/bin/env bash
# Renders the README's pictures into docs/images/ with the current Release build: the forest of
# 64 trees from the demo's near, mid and far views, three glTF models from ../shared/data, and a
# terrain drawn as cubes, stand-ins, splats and every triangle.
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
# The 4 M terrain at issue 17's view (2.5 radii, 30 degrees about, 20 up, 640 x 480, epsilon 1):
# color cubes only, the default (stand-ins chosen by measure), splats forced (a file built with
# splats alone), and brute force; two by two.
"$ff" build -q --generate terrain:triangles=4000000 --format 2 --stand-ins --splats 8 -o "$work/terrain.ffs"
"$ff" build -q --generate terrain:triangles=4000000 --format 2 --splats 8 -o "$work/terrain-splats.ffs"
representation() { # scene image flags...
    local scene=$1 image=$2
    shift 2
    "$ff" render "$work/$scene.ffs" -o "$image" --size 640x480 --distance 2.5 --azimuth 30 --elevation 20 "$@" > /dev/null
}
representation terrain "$work/cubes.png" --representation cube
representation terrain "$work/auto.png"
representation terrain-splats "$work/splats.png" --representation splats
representation terrain "$work/full.png" --method full
oiiotool "$work/cubes.png" "$work/auto.png" "$work/splats.png" "$work/full.png" --mosaic 2x2 --resize 960x720 \
    -o docs/images/terrain-representations.png
echo "readme_images: docs/images/forest-views.png, docs/images/gltf-models.png, docs/images/terrain-representations.png"
