#!/usr/bin/env python3
"""Builds the scenes of docs/results/model.md and runs `farfield stats --paths` on each.

Usage: scripts/model_stats.py [--farfield build-release/viewer/farfield] [--work DIR]
                              [--out docs/results/model.csv] [--data ../shared/data] [--only NAME]
Writes one CSV row per scene and keeps each scene's stats JSON beside the scene in --work.
"""

import argparse
import csv
import json
import os
import subprocess
import sys

SCENES = [
    ("tree", ["--generate", "forest:trees=1"]),
    ("forest16384", ["--generate", "forest:trees=16384"]),
    ("terrain1M", ["--generate", "terrain:triangles=1000000"]),
    ("molecule", ["--generate", "molecule"]),
    ("blinds", ["--generate", "blinds"]),
    ("Avocado", ["static/Avocado/glTF/Avocado.gltf"]),
    ("MetalRoughSpheres", ["static/MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb"]),
    ("WaterBottle-draco", ["draco/WaterBottle/glTF-Draco/WaterBottle.gltf"]),
    ("CesiumMilkTruck-draco", ["draco/CesiumMilkTruck/glTF-Draco/CesiumMilkTruck.gltf"]),
    ("skull", ["scanned/skull/skull.glb"]),
    ("Fox-animated", ["animated/Fox/glTF-Binary/Fox.glb"]),
]

COLUMNS = [
    "scene", "file_bytes", "input_bytes", "input_image_bytes", "file_per_input_byte",
    "stored_triangles", "instanced_triangles", "prototypes", "instances",
    "nodes", "instance_nodes", "inner_cells", "leaf_cells", "small_leaves", "single_child_cells",
    "nodes_per_stored_triangle",
    "node_record_bytes", "cube_bytes", "triangle_bytes", "instance_transform_bytes",
    "prototype_record_bytes", "metadata_bytes", "header_bytes", "trailer_bytes",
    "slack_bytes", "table_slack_bytes",
    "node_pages", "geometry_pages", "table_pages", "node_page_fill", "geometry_page_fill",
    "nodes_with_cube", "cubes_drawn_nodes", "cube_draws", "never_drawn", "never_drawn_bytes",
    "never_drawn_instance", "never_drawn_inner", "never_drawn_leaf",
]


def row_of(name, s):
    b = s["bytes"]
    n = s["nodes"]
    t = s["triangles"]
    c = s.get("cube_usage", {})
    inp = s.get("input") or {}
    return {
        "scene": name,
        "file_bytes": s["file_bytes"],
        "input_bytes": inp.get("bytes", ""),
        "input_image_bytes": inp.get("image_bytes", ""),
        "file_per_input_byte": f'{s["file_per_input_byte"]:.3f}' if s["file_per_input_byte"] else "",
        "stored_triangles": t["stored"],
        "instanced_triangles": t["instanced"],
        "prototypes": t["prototypes"],
        "instances": t["instances"],
        "nodes": n["total"],
        "instance_nodes": n["instance"],
        "inner_cells": n["inner_cell"],
        "leaf_cells": n["leaf_cell"],
        "small_leaves": n["small_leaf"],
        "single_child_cells": n["single_child_cell"],
        "nodes_per_stored_triangle": f'{n["per_stored_triangle"]:.4f}',
        "node_record_bytes": b["node_records"],
        "cube_bytes": b["cubes"],
        "triangle_bytes": b["triangles"],
        "instance_transform_bytes": b["instance_transforms"],
        "prototype_record_bytes": b["prototype_records"],
        "metadata_bytes": b["metadata"],
        "header_bytes": b["header"],
        "trailer_bytes": b["trailers"],
        "slack_bytes": b["header_slack"] + b["node_slack"] + b["geometry_slack"] + b["table_slack"],
        "table_slack_bytes": b["table_slack"],
        "node_pages": s["page_counts"]["nodes"],
        "geometry_pages": s["page_counts"]["geometry"],
        "table_pages": s["page_counts"]["table"],
        "node_page_fill": f'{s["page_fill"]["nodes"]:.3f}',
        "geometry_page_fill": f'{s["page_fill"]["geometry"]:.3f}',
        "nodes_with_cube": c.get("nodes_with_cube", ""),
        "cubes_drawn_nodes": c.get("nodes_drawn", ""),
        "cube_draws": c.get("cube_draws", ""),
        "never_drawn": c.get("never_drawn", ""),
        "never_drawn_bytes": c.get("never_drawn_bytes", ""),
        "never_drawn_instance": c.get("never_drawn_instance", ""),
        "never_drawn_inner": c.get("never_drawn_inner", ""),
        "never_drawn_leaf": c.get("never_drawn_leaf", ""),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--farfield", default="build-release/viewer/farfield")
    ap.add_argument("--work", default="/tmp/farfield-model")
    ap.add_argument("--out", default="docs/results/model.csv")
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--only", default="")
    ap.add_argument("--build-args", default="", help="extra build flags, space separated")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    rows = []
    for name, source in SCENES:
        if args.only and name not in args.only.split(","):
            continue
        if not source[0].startswith("--"):
            source = [os.path.join(args.data, source[0])]
        scene = os.path.join(args.work, name + ".ffs")
        build = [args.farfield, "build", "-q", *source, "-o", scene,
                 "--report", os.path.join(args.work, name + ".build.json"), *args.build_args.split()]
        subprocess.run(build, check=True)
        stats_json = os.path.join(args.work, name + ".stats.json")
        subprocess.run([args.farfield, "stats", scene, "--paths", "--json", stats_json], check=True)
        with open(stats_json) as f:
            rows.append(row_of(name, json.load(f)))
        print(name, "done", file=sys.stderr)
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
