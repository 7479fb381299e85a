#!/usr/bin/env bash
# Renders a fixed set of images with a given farfield binary and prints one "sha256  name" line
# per image: the demo's and README's views, every method and cube style at several epsilons, the
# generators' failure scenes, glTF models, and every frame of a --sync replay under a small cache.
# A restructuring that must not change what users see runs it before and after and diffs the two
# lists (issue 14):
#   FF=/tmp/ff-old/farfield scripts/image_regression.sh > before.txt
#   FF=build-dev/viewer/farfield scripts/image_regression.sh > after.txt && diff before.txt after.txt
set -euo pipefail

ff=${FF:-build-dev/viewer/farfield}
data=${FF_SHARED_DATA:-../shared/data}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out="$work/images"
mkdir -p "$out"

render() { # scene name [render options...]
    local scene=$1 name=$2
    shift 2
    "$ff" render "$scene" -o "$out/$name.png" "$@" > /dev/null
}

"$ff" build -q --generate forest:trees=64 -o "$work/forest.ffs"
for view in "near 0.8 30 12" "mid 2 30 20" "far 6 30 20"; do
    set -- $view
    render "$work/forest.ffs" "forest-$1" --distance "$2" --azimuth "$3" --elevation "$4"
    render "$work/forest.ffs" "forest-$1-400" --size 400x300 --distance "$2" --azimuth "$3" --elevation "$4"
done
render "$work/forest.ffs" forest-far-full --method full --distance 6 --azimuth 30 --elevation 20
for style in faces points auto; do
    for eps in 0 1 2 4; do
        render "$work/forest.ffs" "forest-$style-eps$eps" --cube-draw "$style" --epsilon "$eps" --distance 3
    done
done
render "$work/forest.ffs" forest-supersampled --supersample 2 --distance 2
render "$work/forest.ffs" forest-coverage --coverage-alpha --distance 6

for scene in "blinds blinds:slabs=40" "molecule molecule:spheres=2000" "terrain terrain:triangles=20000" \
        "sphere sphere:triangles=20000"; do
    set -- $scene
    "$ff" build -q --generate "$2" -o "$work/$1.ffs"
    for style in faces points; do
        render "$work/$1.ffs" "$1-$style" --cube-draw "$style" --epsilon 2 --distance 2.5 --azimuth 40 --elevation 25
    done
    render "$work/$1.ffs" "$1-anisotropy" --cube-anisotropy 0.5 --distance 4
    render "$work/$1.ffs" "$1-inside" --distance 0.2
done

models=(draco/CesiumMilkTruck/glTF-Draco/CesiumMilkTruck.gltf scanned/skull/skull.glb draco/WaterBottle/glTF-Draco/WaterBottle.gltf)
for i in "${!models[@]}"; do
    "$ff" build -q "$data/${models[$i]}" -o "$work/model$i.ffs"
    render "$work/model$i.ffs" "model$i" --size 400x300 --distance 2.3 --azimuth 30 --elevation 15
    render "$work/model$i.ffs" "model$i-far" --distance 20
done

"$ff" path orbit "$work/forest.ffs" -o "$work/orbit.json" --frames 12 > /dev/null
mkdir -p "$work/replay"
"$ff" replay "$work/forest.ffs" "$work/orbit.json" --sync --cache-mb 8 --frames-dir "$work/replay" > /dev/null
for frame in "$work"/replay/*.png; do
    cp "$frame" "$out/replay-sync-$(basename "$frame")"
done
render "$work/forest.ffs" path-frame --path "$work/orbit.json" --path-frame 5

(cd "$out" && sha256sum -- *.png)
