#!/usr/bin/python3
"""Charts for `farfield bench`: reads the benchmark's CSV, writes PNG charts beside it.

usage: plot_bench.py {table2|forest|build} CSV OUTDIR
"""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def pareto(points):
    """Points (time, error) not beaten in both by another point: lower time, higher PSNR."""
    best = []
    for t, q in sorted(points):
        if not best or q > best[-1][1]:
            best.append((t, q))
    return best


def table2(data, out):
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for size in sorted({(r["width"], r["height"]) for r in data}, key=lambda s: int(s[0])):
        sel = [r for r in data if (r["width"], r["height"]) == size]
        label = f"{size[0]}x{size[1]}"
        ax1.plot([float(r["hierarchical_ms"]) for r in sel], [float(r["psnr_hierarchical_db"]) for r in sel],
                 "o-", label=f"hierarchical {label}")
        ax1.plot([float(r["full_ms"]) for r in sel], [float(r["psnr_full_db"]) for r in sel],
                 "s--", label=f"full {label}")
        for r in sel:
            ax1.annotate(f"d={r['distance_radii']}", (float(r["hierarchical_ms"]), float(r["psnr_hierarchical_db"])),
                         fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax2.plot([float(r["distance_radii"]) for r in sel], [float(r["speedup"]) for r in sel], "o-", label=label)
        points = [(float(r["hierarchical_ms"]), float(r["psnr_hierarchical_db"])) for r in sel]
        points += [(float(r["full_ms"]), float(r["psnr_full_db"])) for r in sel]
        front = pareto(points)
        ax1.plot([p[0] for p in front], [p[1] for p in front], color="0.6", linewidth=4, alpha=0.35, zorder=0,
                 label=f"Pareto front {label}")
    paper = {1.75: 0.4, 3.5: 0.5, 7: 1.3, 14: 5.4}
    ax2.plot(list(paper), list(paper.values()), "k:", label="Chamberlain et al. (124x124)")
    ax1.set_xscale("log")
    ax1.set_xlabel("frame time (ms, log)")
    ax1.set_ylabel("PSNR against 4x4 reference (dB)")
    ax1.set_title("speed against accuracy")
    ax1.legend(fontsize=7)
    ax2.set_xscale("log", base=2)
    ax2.set_yscale("log")
    ax2.set_xlabel("distance (scene radii)")
    ax2.set_ylabel("speedup over full geometry")
    ax2.set_title("speedup by distance")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "table2.png", dpi=110)


def forest(data, out):
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for i, size in enumerate(sorted({(r["width"], r["height"]) for r in data}, key=lambda s: int(s[0]))):
        sel = [r for r in data if (r["width"], r["height"]) == size]
        label = f"{size[0]}x{size[1]}"
        tri = [float(r["triangles"]) for r in sel]
        measured = [r["full_measured"] == "1" for r in sel]
        full = [float(r["full_ms"]) for r in sel]
        hier = [float(r["hierarchical_ms"]) for r in sel]
        color_full, color_hier = f"C{2 * i}", f"C{2 * i + 1}"
        ax.plot([t for t, m in zip(tri, measured) if m], [f for f, m in zip(full, measured) if m], "s-",
                color=color_full, label=f"full {label}, measured")
        if not all(measured):
            last = max(k for k, m in enumerate(measured) if m)
            ax.plot(tri[last:], full[last:], "s--", color=color_full, alpha=0.6,
                    label=f"full {label}, extrapolated from per-triangle cost")
        ax.plot(tri, hier, "o-", color=color_hier, label=f"hierarchical {label} (epsilon = 1)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("triangles in the scene (log)")
    ax.set_ylabel("frame time (ms, log)")
    ax.set_title("forest of 1 .. %s trees, fixed view" % data[-1]["trees"])
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "forest.png", dpi=110)


def build(data, out):
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for budget in sorted({r["budget"] for r in data}, key=lambda b: int([r for r in data if r["budget"] == b][0]["budget_bytes"])):
        sel = sorted([r for r in data if r["budget"] == budget], key=lambda r: int(r["triangles"]))
        tri = [float(r["triangles"]) for r in sel]
        ax1.plot(tri, [float(r["triangles_per_second_per_core"]) / 1e6 for r in sel], "o-", label=f"budget {budget}")
        ax2.plot(tri, [float(r["peak_rss_bytes"]) / 2**20 for r in sel], "o-", label=f"peak RSS, budget {budget}")
        ax2.axhline(float(sel[0]["budget_bytes"]) / 2**20 + 64, linestyle=":", color=ax2.lines[-1].get_color(),
                    label=f"budget {budget} + 64 MiB")
    ax1.axhline(1.0, color="k", linestyle=":", label="target 1 M/s per core")
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xlabel("terrain triangles (log)")
        ax.legend(fontsize=7)
    ax1.set_ylabel("M triangles / s / core (end to end)")
    ax2.set_ylabel("MiB")
    ax1.set_title("builder throughput")
    ax2.set_title("peak resident memory")
    fig.tight_layout()
    fig.savefig(out / "build.png", dpi=110)


def paging(data, out):
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for family in sorted({r["family"] for r in data}):
        sel = [r for r in data if r["family"] == family]
        line, = ax.plot([float(r["triangles"]) for r in sel], [float(r["complete_frame_bytes"]) / 2**20 for r in sel],
                        "o-", label=family)
        if sel and "node_page_bytes" in sel[0]:
            ax.plot([float(r["triangles"]) for r in sel], [float(r["node_page_bytes"]) / 2**20 for r in sel], "--",
                    color=line.get_color(), alpha=0.7, label=family + ": node pages")
    ax.axhline(64, color="k", linestyle=":", label="target: 64 MB at 10^9 triangles")
    ax.set_xscale("log")
    ax.set_xlabel("triangles in the scene (log)")
    ax.set_ylabel("resident for one complete frame (MiB)")
    ax.set_title("working set against scene size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "paging-working-set.png", dpi=110)

    frames = rows(out / "paging-teleports.csv")
    if frames:
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True)
        x = [int(r["frame"]) for r in frames]
        ax1.plot(x, [float(r["frame_ms"]) for r in frames], label="frame ms")
        ax1.set_ylabel("frame time (ms)")
        ax1b = ax1.twinx()
        ax1b.plot(x, [float(r["nodes_deferred"]) for r in frames], color="C3", alpha=0.6, label="debt (nodes deferred)")
        ax1b.set_ylabel("debt", color="C3")
        ax2.plot(x, [float(r["resident_bytes"]) / 2**20 for r in frames], label="resident MiB")
        ax2.plot(x, [float(r["bytes_read"]) / 2**20 for r in frames], label="MiB read this frame")
        ax2.set_xlabel("frame")
        ax2.set_ylabel("MiB")
        ax2.legend(fontsize=8)
        ax1.set_title("teleports with a cold cache")
        fig.tight_layout()
        fig.savefig(out / "paging-teleports.png", dpi=110)


def main():
    kind, path, out = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    data = rows(path)
    if not data:
        sys.exit(f"{path}: no rows")
    {"table2": table2, "forest": forest, "build": build, "paging": paging}[kind](data, out)


if __name__ == "__main__":
    main()
