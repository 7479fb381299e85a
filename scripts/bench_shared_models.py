#!/usr/bin/python3
"""Issue 17's accuracy and speed targets on every model of ../shared/data.

For each valid glTF model there (the invalid ones are refused by `build`, as tested), writes a
`views` scenario like bench/representations-*.json — built as format 2 with --stand-ins
--splats 8, brute force and the default (auto) at eps 1, the issue's six views (1.2, 2.5, 6
radii x 8 and 20 degrees up, 30 about, 640x480) against the 4x4 reference — runs them all with
`farfield bench`, and summarises: per model, the worst dB below brute force and the range of
frame time over brute force's. Writes OUT/shared-models.csv, .md and .png beside the per-model
reports.

    scripts/bench_shared_models.py [--farfield build-dev/viewer/farfield] [--out DIR] [--frames N] [--quick]
"""

import argparse
import csv
import json
import os
import pathlib
import subprocess
import sys

VIEWS = [
    {"label": f"d{d} e{e}", "distance": d, "azimuth": 30, "elevation": e}
    for d in (1.2, 2.5, 6)
    for e in (8, 20)
]


def models(shared: pathlib.Path):
    found = sorted(
        p for p in shared.rglob("*")
        if p.suffix in (".gltf", ".glb") and "invalid" not in p.parts
    )
    for path in found:
        relative = path.relative_to(shared)
        # static/Box/glTF-Embedded/Box.gltf -> static-box-gltf-embedded
        parts = [relative.parts[0], relative.parts[1]]
        if len(relative.parts) > 3:
            parts.append(relative.parts[2])
        name = "-".join(parts).lower().replace("_", "-")
        yield name, relative


def scenario(relative: pathlib.Path) -> dict:
    return {
        "title": f"{relative}: stand-ins and splats against brute force",
        "description": "Issue 17's target on every model of ../shared/data (scripts/bench_shared_models.py).",
        "kind": "views",
        "scene": {"gltf": "${shared}/" + str(relative)},
        "build": ["--format", "2", "--stand-ins", "--splats", "8"],
        "size": [640, 480],
        "views": VIEWS,
        "reference": {"supersample": 4},
        "methods": [
            {"label": "full", "method": "full"},
            {"label": "auto", "representation": "auto"},
        ],
        "quick": {"size": [160, 120]},
    }


def summarise(out: pathlib.Path, names, frames: int):
    rows = []
    for name, relative in names:
        table = list(csv.DictReader(open(out / f"{name}.csv")))
        full = {r["view"]: r for r in table if r["method"] == "full"}
        auto = [r for r in table if r["method"] == "auto"]
        below = [float(full[r["view"]]["psnr_srgb"]) - float(r["psnr_srgb"]) for r in auto]
        ratio = [float(r["frame_ms"]) / float(full[r["view"]]["frame_ms"]) for r in auto]
        rows.append({
            "model": str(relative),
            "triangles": auto[0]["scene_triangles"],
            "worst_db_below_full": f"{max(below):.2f}",
            "min_frame_ratio": f"{min(ratio):.2f}",
            "max_frame_ratio": f"{max(ratio):.2f}",
            "median_frame_ratio": f"{sorted(ratio)[len(ratio) // 2]:.2f}",
            "stand_ins_drawn": max(int(r["stand_ins"]) for r in auto),
            "splat_sets_drawn": max(int(r["splat_sets"]) for r in auto),
            "full_ms_median": f"{sorted(float(r['frame_ms']) for r in full.values())[3]:.2f}",
        })
    with open(out / "shared-models.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
    with open(out / "shared-models.md", "w") as f:
        f.write("# Every model of ../shared/data: the default (auto, eps 1) against brute force\n\n")
        f.write("Built as format 2 with `--stand-ins --splats 8`; six views (1.2, 2.5, 6 radii x 8 and 20 "
                f"degrees up, 30 about), 640x480, against the 4x4 reference; median of {frames} frames. "
                "Command: `scripts/bench_shared_models.py`. Per model: the worst PSNR loss against brute "
                "force over the views, and frame time over brute force's (min, median, max).\n\n")
        f.write("| " + " | ".join(rows[0].keys()) + " |\n")
        f.write("|" + "---|" * len(rows[0]) + "\n")
        for r in rows:
            f.write("| " + " | ".join(str(v) for v in r.values()) + " |\n")
        f.write("\n![shared models](shared-models.png)\n")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 0.32 * len(rows) + 1.5), sharey=True)
    labels = [r["model"] for r in rows]
    y = range(len(rows))
    a.barh(y, [float(r["worst_db_below_full"]) for r in rows], color="tab:blue")
    a.axvline(2.0, color="tab:red", linestyle="--", label="target: 2 dB")
    a.set_yticks(list(y), labels, fontsize=7)
    a.set_xlabel("worst dB below brute force (6 views)")
    a.legend(fontsize=7)
    b.errorbar([float(r["median_frame_ratio"]) for r in rows], list(y),
               xerr=[[float(r["median_frame_ratio"]) - float(r["min_frame_ratio"]) for r in rows],
                     [float(r["max_frame_ratio"]) - float(r["median_frame_ratio"]) for r in rows]],
               fmt="o", color="tab:green")
    b.axvline(1.1, color="tab:red", linestyle="--", label="target: 1.1 x")
    b.set_xlabel("frame time / brute force (min, median, max)")
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "shared-models.png", dpi=110)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--farfield", default="build-dev/viewer/farfield")
    parser.add_argument("--out", default="/tmp/shared-models")
    parser.add_argument("--shared", default=str(pathlib.Path(__file__).resolve().parents[2] / "shared"))
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--frames", type=int, default=3, help="timed frames a measurement (the median is kept)")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    (out / "scenarios").mkdir(parents=True, exist_ok=True)
    names = list(models(pathlib.Path(args.shared) / "data"))
    files = []
    for name, relative in names:
        path = out / "scenarios" / f"{name}.json"
        path.write_text(json.dumps(scenario(relative), indent=2) + "\n")
        files.append(str(path))
    command = [args.farfield, "bench", *files, "--out", str(out), "--frames", str(args.frames)]
    if args.quick:
        command.append("--quick")
    env = dict(os.environ, FF_SHARED_DATA=str(pathlib.Path(args.shared) / "data"))
    subprocess.run(command, check=True, env=env)
    summarise(out, names, args.frames)
    print(f"{out}/shared-models.md")


if __name__ == "__main__":
    sys.exit(main())
