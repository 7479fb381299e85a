#!/usr/bin/env bash
# The main job on the built-in default scene: install, build farfield (Release), build a forest
# of 64 recursively instanced trees (3.4 M triangles) out of core, render a few views and write
# the images, their frame statistics and the build report to out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
cmake -S . -B build-release -G Ninja -DCMAKE_BUILD_TYPE=Release -DFF_BUILD_TESTS=OFF
cmake --build build-release --target farfield ff_oiio

ff=build-release/viewer/farfield
out=out/demo
mkdir -p "$out"
"$ff" build --generate forest:trees=64 -o "$out/forest.ffs" --memory-budget 512MiB --report "$out/build-report.json"
"$ff" check "$out/forest.ffs"
for view in "near 0.8 30 12" "mid 2 30 20" "far 6 30 20"; do
    set -- $view
    "$ff" render "$out/forest.ffs" -o "$out/$1.png" --distance "$2" --azimuth "$3" --elevation "$4" \
        --size 640x480 --stats "$out/$1-stats.json" > /dev/null
done
"$ff" render "$out/forest.ffs" -o "$out/far-full.png" --method full --distance 6 --azimuth 30 --elevation 20 \
    --size 640x480 --stats "$out/far-full-stats.json" > /dev/null
echo
echo "farfield demo: images, frame statistics and the build report are in $out/"
ls -1 "$out"
