#!/usr/bin/python3
"""Charts for `farfield bench`: reads a scenario's CSV, writes PNG charts named after it.

usage: plot_bench.py {table2|forest|build|paging|views|path|replay|render|codec} CSV OUTDIR

CSV is OUT/NAME.csv (paging: OUT/NAME-working-set.csv, with OUT/NAME-teleports.csv beside it);
the charts are OUTDIR/NAME.png (views with a sweep also NAME-sweep.png; paging
NAME-working-set.png and NAME-teleports.png; path through a streaming cache also NAME-bytes.png).
"""
import math
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


def number(text):
    """A CSV cell as a float; empty cells are NaN, 'inf' stays infinite."""
    return float(text) if text not in ("", None) else math.nan


INF_NOTE = "; identical = top"


def capped(values, margin=3.0, among=None):
    """Infinite PSNR (identical images) drawn just above the largest finite value of `among`
    (default: `values`; pass every series of a chart so they share one top), and the axis label
    then says so, with INF_NOTE."""
    finite = [v for v in (values if among is None else among) if math.isfinite(v)]
    top = (max(finite) if finite else 60.0) + margin
    return [top if v == math.inf else v for v in values]


def table2(data, out, name):
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
    fig.savefig(out / f"{name}.png", dpi=110)


def forest(data, out, name):
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
        if sel and sel[0].get("occlusion_ms"):
            ax.plot(tri, [float(r["occlusion_ms"]) for r in sel], "^-", color=f"C{2 * i + 6}",
                    label=f"hierarchical + occlusion culling {label}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("triangles in the scene (log)")
    ax.set_ylabel("frame time (ms, log)")
    ax.set_title("forest of %s .. %s trees, fixed view" % (data[0]["trees"], data[-1]["trees"]))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / f"{name}.png", dpi=110)


def build(data, out, name):
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
    fig.savefig(out / f"{name}.png", dpi=110)


def paging(data, out, name):
    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    for family in sorted({r["family"] for r in data}):
        sel = [r for r in data if r["family"] == family]
        line, = ax.plot([float(r["triangles"]) for r in sel], [float(r["complete_frame_bytes"]) / 2**20 for r in sel],
                        "o-", label=family)
        if sel and "node_page_bytes" in sel[0]:
            ax.plot([float(r["triangles"]) for r in sel], [float(r["node_page_bytes"]) / 2**20 for r in sel], "--",
                    color=line.get_color(), alpha=0.7, label=family + ": node pages")
    ax.axhline(64e6 / 2**20, color="k", linestyle=":", label="target: 64 MB (61 MiB) at 10^9 triangles")
    ax.set_xscale("log")
    ax.set_xlabel("triangles in the scene (log)")
    ax.set_ylabel("resident for one complete frame (MiB)")
    ax.set_title("working set against scene size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    fig.tight_layout()
    fig.savefig(out / f"{name}.png", dpi=110)

    prefix = name.removesuffix("-working-set")
    frames = rows(out / f"{prefix}-teleports.csv")
    if frames:
        timeline(frames, "teleports with a cold cache", out / f"{prefix}-teleports.png")


def timeline(frames, title, png):
    """Per-frame replay telemetry: frame time and debt above, resident and read bytes below."""
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
    ax1.set_title(title)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def replay(data, out, name):
    timeline(data, f"{name}: replay through a cold cache", out / f"{name}.png")


def panels(count, width=5.0, height=4.2):
    fig, axes = plt.subplots(1, count, figsize=(width * count, height), squeeze=False)
    return fig, axes[0]


def setting(r):
    """A method and its sweep value: 'faces' or 'faces eps=2'."""
    if r["sweep_parameter"] and r["sweep_value"]:
        return f"{r['method']} {r['sweep_parameter']}={r['sweep_value']}"
    return r["method"]


def views(data, out, name):
    """Error against frame time per view (Pareto front marked); with a sweep, error and
    coverage error against the swept value."""
    view_names = list(dict.fromkeys(r["view"] for r in data))
    methods = list(dict.fromkeys(r["method"] for r in data))
    color = {m: f"C{i % 10}" for i, m in enumerate(methods)}
    fig, axes = panels(len(view_names))
    for ax, view in zip(axes, view_names):
        sel = [r for r in data if r["view"] == view]
        psnr = capped([number(r["psnr_srgb"]) for r in sel])
        ms = [number(r["frame_ms"]) for r in sel]
        for m in methods:
            idx = [i for i, r in enumerate(sel) if r["method"] == m]
            ax.plot([ms[i] for i in idx], [psnr[i] for i in idx], "o-" if len(idx) > 1 else "o",
                    color=color[m], label=m)
            for i in idx:
                if sel[i]["sweep_value"]:
                    ax.annotate(sel[i]["sweep_value"], (ms[i], psnr[i]), fontsize=7, xytext=(3, 3),
                                textcoords="offset points")
        front = pareto(list(zip(ms, psnr)))
        ax.plot([p[0] for p in front], [p[1] for p in front], color="0.6", linewidth=5, alpha=0.35, zorder=0,
                label="Pareto front")
        ax.set_xscale("log")
        ax.set_xlabel("frame time (ms, log)")
        ax.set_ylabel("PSNR against the reference (dB, higher is better"
                      + (INF_NOTE if math.inf in [number(r["psnr_srgb"]) for r in sel] else "") + ")")
        ax.set_title(f"view {view}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / f"{name}.png", dpi=110)

    swept = [r for r in data if r["sweep_parameter"]]
    if not swept:
        return
    parameter = swept[0]["sweep_parameter"]
    values = list(dict.fromkeys(r["sweep_value"] for r in swept))
    numeric = all(_is_number(v) for v in values)
    x_of = (lambda v: float(v)) if numeric else (lambda v: values.index(v))
    fig, axes = plt.subplots(2, len(view_names), figsize=(5.0 * len(view_names), 7.5), squeeze=False, sharex="col")
    for col, view in enumerate(view_names):
        top, bottom = axes[0][col], axes[1][col]
        for m in methods:
            sel = [r for r in swept if r["view"] == view and r["method"] == m]
            if sel:
                xs = [x_of(r["sweep_value"]) for r in sel]
                top.plot(xs, capped([number(r["psnr_srgb"]) for r in sel]), "o-", color=color[m], label=m)
                bottom.plot(xs, [100 * number(r["holes_fraction"]) for r in sel], "o-", color=color[m],
                            label=f"{m} holes")
                bottom.plot(xs, [100 * number(r["over_coverage_fraction"]) for r in sel], "s--", color=color[m],
                            alpha=0.6, label=f"{m} over-coverage")
            else:  # not swept (full): a horizontal line for comparison
                fixed = [r for r in data if r["view"] == view and r["method"] == m]
                if fixed:
                    top.axhline(capped([number(fixed[0]["psnr_srgb"])])[0], color=color[m], linestyle=":",
                                label=f"{m} (not swept)")
        top.set_title(f"view {view}")
        top.set_ylabel("PSNR (dB, higher is better)")
        bottom.set_ylabel("% of reference-covered pixels")
        bottom.set_xlabel(parameter)
        if not numeric:
            bottom.set_xticks(range(len(values)), values)
        for ax in (top, bottom):
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / f"{name}-sweep.png", dpi=110)


def _is_number(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


def path(data, out, name):
    """Per-frame timelines per method: temporal instability, PSNR, frame time."""
    methods = list(dict.fromkeys(r["method"] for r in data))
    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
    every_psnr = [number(r["psnr_db"]) for r in data]
    for i, m in enumerate(methods):
        sel = [r for r in data if r["method"] == m]
        x = [int(r["frame"]) for r in sel]
        ax1.plot(x, [number(r["instability"]) for r in sel], color=f"C{i % 10}", label=m)
        ax2.plot(x, capped([number(r["psnr_db"]) for r in sel], among=every_psnr), color=f"C{i % 10}", label=m)
        ax3.plot(x, [number(r["frame_ms"]) for r in sel], color=f"C{i % 10}", label=m)
    ax1.set_ylabel("instability (linear luminance)")
    ax1.set_title("temporal instability: change beyond the reference's own (lower is better)")
    ax2.set_ylabel("PSNR (dB" + (INF_NOTE if any(number(r["psnr_db"]) == math.inf for r in data) else "") + ")")
    ax2.set_title("error against the per-frame full reference (higher is better)")
    ax3.set_ylabel("frame time (ms)")
    ax3.set_xlabel("frame")
    for ax in (ax1, ax2, ax3):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / f"{name}.png", dpi=110)

    if any(number(r.get("bytes_read_total", "0")) > 0 for r in data):
        bytes_read(data, methods, out / f"{name}-bytes.png")


def bytes_read(data, methods, png):
    """Error against bytes read: each method's per-frame PSNR against what its cold cache has
    read so far, so a method that reaches the same quality with fewer bytes lies to the left."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, m in enumerate(methods):
        sel = [r for r in data if r["method"] == m]
        ax.plot([number(r["bytes_read_total"]) / 2**20 for r in sel], capped([number(r["psnr_db"]) for r in sel]),
                ".-", color=f"C{i % 10}", label=m, markersize=3)
    ax.set_xlabel("MiB read so far (cold cache)")
    ax.set_ylabel("PSNR against the full reference (dB)")
    ax.set_title("error against bytes read, one point per frame")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def render(data, out, name):
    """Peak RSS of each view's frame against its limit, with the frame's cut beside it; with more
    than one frame a view, the first (cold) and warm frame times beside it."""
    timed = all(number(r.get("frames") or 0) > 1 for r in data)
    if timed:
        fig, (ax, axt) = plt.subplots(1, 2, figsize=(12, 4.5))
        x = range(len(data))
        cold = [number(r["first_total_ms"]) for r in data]
        # The p50 of the frames after the first where the CSV has it (older runs: the last frame).
        median = all(r.get("warm_median_ms") for r in data)
        warm = [number(r["warm_median_ms"] if median else r["total_ms"]) for r in data]
        axt.bar([i - 0.2 for i in x], cold, width=0.4, color="C1", label="first frame (no history)")
        axt.bar([i + 0.2 for i in x], warm, width=0.4, color="C2",
                label="warm: p50 of the frames after the first" if median else "last frame (warm)")
        for i, r in enumerate(data):
            axt.annotate(f"{int(number(r['triangles_drawn'])):,} tris\n{int(number(r['occlusion_queries'])):,} queries",
                         (i + 0.2, warm[i]), ha="center", va="bottom", fontsize=7)
        axt.set_xticks(list(x))
        axt.set_xticklabels([r["view"] for r in data], rotation=40, ha="right", fontsize=8)
        axt.set_yscale("log")
        axt.set_ylabel("frame total_ms (log)")
        axt.set_title("frame time")
        axt.grid(True, axis="y", alpha=0.3)
        axt.legend(fontsize=8)
    else:
        fig, ax = plt.subplots(figsize=(7, 4.5))
    labels = [r["view"] for r in data]
    rss = [number(r["peak_rss_bytes"]) / 2**20 for r in data]
    ax.bar(labels, rss, color="C0", label="peak RSS of the render process")
    ax.tick_params(axis="x", labelrotation=40, labelsize=8)
    for label in ax.get_xticklabels():
        label.set_horizontalalignment("right")
    limits = [number(r["rss_limit_bytes"]) / 2**20 for r in data if r["rss_limit_bytes"]]
    if limits:
        ax.axhline(max(limits), color="C3", linestyle="--", label=f"limit {max(limits):.0f} MiB")
    for i, r in enumerate(data):
        ax.annotate(f"{int(number(r['nodes_visited'])):,} nodes\n{int(number(r['cubes_drawn'])):,} cubes",
                    (i, rss[i]), ha="center", va="bottom", fontsize=7)
    ax.set_ylabel("MiB")
    ax.set_title("memory of one complete frame (farfield render)")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / f"{name}.png", dpi=110)


def codec(data, out, name):
    """Bytes a triangle and decode rate per scene, one bar per variant, v1 and the targets."""
    scenes = list(dict.fromkeys(r["scene"] for r in data))
    variants = list(dict.fromkeys(r["variant"] for r in data))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    width = 0.8 / max(len(variants), 1)
    for i, v in enumerate(variants):
        sel = {r["scene"]: r for r in data if r["variant"] == v}
        xs = [k + (i - (len(variants) - 1) / 2) * width for k in range(len(scenes))]
        ax1.bar(xs, [number(sel[s]["bytes_per_triangle"]) if s in sel else math.nan for s in scenes], width, label=v)
        ax2.bar(xs, [number(sel[s]["decode_gb_per_s"]) if s in sel else math.nan for s in scenes], width, label=v)
    v1 = {r["scene"]: number(r["v1_file_bytes_per_triangle"]) for r in data}
    for k, s in enumerate(scenes):
        ax1.annotate(f"v1 file: {v1[s]:.0f}", (k, 0.2), ha="center", fontsize=7, rotation=90, va="bottom")
    ax1.axhline(8.0, color="k", linestyle=":", label="target 8 B / triangle (whole file)")
    ax2.axhline(1.0, color="k", linestyle=":", label="target 1 GB/s / core")
    for ax in (ax1, ax2):
        ax.set_xticks(range(len(scenes)))
        ax.set_xticklabels(scenes, rotation=20, ha="right", fontsize=8)
        ax.legend(fontsize=7)
    ax1.set_ylabel("cluster bytes / triangle")
    ax2.set_ylabel("decoded GB/s on one core")
    ax1.set_title("compact geometry: size")
    ax2.set_title("compact geometry: decode")
    fig.tight_layout()
    fig.savefig(out / f"{name}.png", dpi=110)


def format_(data, out, name):
    """Bytes a triangle and build time per scene, format 1 beside format 2."""
    scenes = list(dict.fromkeys(r["scene"] for r in data))
    formats = list(dict.fromkeys(r["format"] for r in data))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    width = 0.8 / max(len(formats), 1)
    for i, f in enumerate(formats):
        sel = {r["scene"]: r for r in data if r["format"] == f}
        xs = [k + (i - (len(formats) - 1) / 2) * width for k in range(len(scenes))]
        ax1.bar(xs, [number(sel[s]["bytes_per_triangle"]) if s in sel else math.nan for s in scenes], width,
                label=f"format {f}")
        ax2.bar(xs, [number(sel[s]["build_seconds"]) if s in sel else math.nan for s in scenes], width,
                label=f"format {f}")
    ax1.axhline(8.0, color="k", linestyle=":", label="target 8 B / triangle")
    ax1.set_yscale("log")
    ax2.set_yscale("log")
    for ax in (ax1, ax2):
        ax.set_xticks(range(len(scenes)))
        ax.set_xticklabels(scenes, rotation=20, ha="right", fontsize=8)
        ax.legend(fontsize=7)
    ax1.set_ylabel("file bytes / triangle (log)")
    ax2.set_ylabel("build seconds (log)")
    ax1.set_title("scene file size")
    ax2.set_title("build time")
    fig.tight_layout()
    fig.savefig(out / f"{name}.png", dpi=110)


KINDS = {"format": format_, "table2": table2, "forest": forest, "build": build, "paging": paging, "views": views, "path": path, "replay": replay, "render": render, "codec": codec}


def main():
    if len(sys.argv) != 4 or sys.argv[1] not in KINDS:
        sys.exit(__doc__)
    kind, csv_path, out = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    data = rows(csv_path)
    if not data:
        sys.exit(f"{csv_path}: no rows")
    KINDS[kind](data, out, csv_path.stem)


if __name__ == "__main__":
    main()
