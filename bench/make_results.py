#!/usr/bin/env python3
"""Turns the benchmark outputs in docs/results/ into plots (PNG) and docs/RESULTS.md.

Reads: walkthrough.md and walkthrough_frames.csv when present (raycache_walkthrough_bench: the headline, at
the top), table_5_2.md, tables.md, table_5_2.csv, figure_5_9.csv, quality.csv, table_5_3.csv (raycache_bench),
rsh_frames.csv and rsh.md when present (raycache_rsh_bench; bench/rsh_results.py makes that section),
vulkan_tables.md and table_5_1.csv when present (raycache_vulkan_bench), dynamic.md when present
(raycache_dynamic_bench), xeon16_h100/README.md and h200_vulkan/README.md when present (runs on lent machines, summarised by hand)
and micro.json
(raycache_micro_bench, Google Benchmark's JSON). Usage: make_results.py RESULTS_DIR OUTPUT_MD
"""
import csv
import json
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import rsh_results  # noqa: E402  (bench/rsh_results.py, beside this file)


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def micro(path):
    """Google Benchmark's JSON, read once: (name -> run, medians when repetitions were aggregated; the
    processor it ran on, from its context, or None for files written before the benchmark said)."""
    with open(path) as f:
        data = json.load(f)
    runs = data["benchmarks"]
    medians = {r["run_name"]: r for r in runs if r.get("aggregate_name") == "median"}
    by_name = medians or {r["name"]: r for r in runs if r.get("run_type", "iteration") == "iteration"}
    return by_name, data.get("context", {}).get("machine")


def speedup_plot(ax, fig, title, path, xlabel="N reflective spheres behind the camera"):
    """The common frame of the speed-up plots: the 1x line, axes, legend, saved as PNG."""
    ax.axhline(1.0, color="lightgray", lw=1)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("speed-up over the cache off")
    ax.set_title(title)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_table_5_2(results, out):
    """CCT speed-up against N on grid-N and behind-N (ceilings dashed) beside the thesis's Table 5.2."""
    data = rows(os.path.join(results, "table_5_2.csv"))
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for scene, color in [("grid", "tab:blue"), ("behind", "tab:orange")]:
        part = [r for r in data if r.get("scene", "behind") == scene]
        if not part:
            continue
        n = [int(r["n"]) for r in part]
        ax.plot(n, [float(r["cct_speedup"]) for r in part], "o-", color=color, label=f"{scene}-N: CCT")
        ax.plot(n, [float(r["ceiling_speedup"]) for r in part], "--", color=color, alpha=0.6,
                label=f"{scene}-N: ceiling (no cache can beat it)")
    thesis = sorted({(int(r["n"]), float(r["thesis_cct_speedup"])) for r in data if r["thesis_cct_speedup"]})
    if thesis:
        ax.plot([t[0] for t in thesis], [t[1] for t in thesis], "x:", color="gray", label="thesis CCT (Table 5.2, grid, OptiX)")
    ax.set_xscale("log", base=2)
    ax.set_xticks([1, 2, 4, 8, 16, 32])
    ax.set_xticklabels(["1", "2", "4", "8", "16", "32"])
    speedup_plot(ax, fig, "Embree tracer, conventional ray tracing, warm caches (Table 5.2)",
                 os.path.join(out, "table_5_2.png"), "N cached mirror spheres")


def plot_table_5_1(results, out):
    """The Vulkan tracer's speed-ups against N, hybrid and compute, beside the thesis's Table 5.1."""
    path = os.path.join(results, "table_5_1.csv")
    if not os.path.exists(path):
        return False
    data = rows(path)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for pipeline, marker in [("hybrid", "o"), ("compute", "s")]:
        part = [r for r in data if r["pipeline"] == pipeline]
        n = [int(r["n"]) for r in part]
        ax.plot(n, [float(r["ceiling_speedup"]) for r in part], "--", marker=marker, color="black", alpha=0.5,
                label=f"{pipeline}: ceiling")
        ax.plot(n, [float(r["cct_speedup"]) for r in part], "-", marker=marker, color="tab:blue", label=f"{pipeline}: CCT")
        if any(float(r["cdct_speedup"]) > 0 for r in part):
            ax.plot(n, [float(r["cdct_speedup"]) for r in part], "-", marker=marker, color="tab:orange", label=f"{pipeline}: CDCT")
    thesis = [(int(r["n"]), float(r["thesis_cct_speedup"])) for r in data if r["pipeline"] == "hybrid" and r["thesis_cct_speedup"]]
    if thesis:
        ax.plot([t[0] for t in thesis], [t[1] for t in thesis], "x:", color="gray", label="thesis hybrid CCT (Table 5.1)")
    speedup_plot(ax, fig, "Vulkan tracer, behind-N, warm caches (Table 5.1)", os.path.join(out, "table_5_1.png"))
    return True


def plot_figure_5_9(results, out):
    data = rows(os.path.join(results, "figure_5_9.csv"))
    fig, ax = plt.subplots(figsize=(7, 4.2))
    thesis = {128: 3, 256: 31, 512: 73}
    for face in sorted({int(r["face_size"]) for r in data}):
        pts = [(int(r["frame"]), float(r["outdated_percent"])) for r in data if int(r["face_size"]) == face and int(r["frame"]) > 0]
        line, = ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=f"{face} texels")
        if face in thesis:
            ax.plot([1], [thesis[face]], "x", color=line.get_color(), markersize=10)
    ax.set_xlabel("frame (the camera pans 10/3 degrees a frame)")
    ax.set_ylabel("outdated texels before the frame (%)")
    ax.set_title("Update rate (Figure 5.9); x = the thesis after frame 1")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "figure_5_9.png"), dpi=110)
    plt.close(fig)


def plot_walkthrough(results, out):
    """Per scene, speed-up and PSNR against the frame, a line per mode and path; returns the scenes plotted."""
    path = os.path.join(results, "walkthrough_frames.csv")
    if not os.path.exists(path):
        return []
    data = rows(path)
    colors = {"cct": "tab:blue", "cdct": "tab:orange", "ceiling": "black"}
    styles = {"fixed": "-", "orbit": "--", "pan": ":"}
    scenes = list(dict.fromkeys(r["scene"] for r in data))
    for scene in scenes:
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
        part = [r for r in data if r["scene"] == scene and r["mode"] != "off"]
        for mode in dict.fromkeys(r["mode"] for r in part):
            for walk in dict.fromkeys(r["path"] for r in part):
                line = sorted((r for r in part if r["mode"] == mode and r["path"] == walk), key=lambda r: int(r["frame"]))
                frames = [int(r["frame"]) for r in line]
                style = dict(color=colors.get(mode, "gray"), ls=styles.get(walk, "-"), lw=1.3, label=f"{mode}, {walk}")
                top.plot(frames, [float(r["speedup"]) for r in line], **style)
                # An identical frame has an infinite PSNR: a gap in the line.
                bottom.plot(frames, [float(r["psnr"]) if math.isfinite(float(r["psnr"])) else float("nan") for r in line], **style)
        top.axhline(1.0, color="lightgray", lw=1)
        top.set_ylabel("speed-up over the cache off")
        top.set_title(f"{scene}: walkthrough, 1 degree a frame (frame 0 cold)")
        top.legend(fontsize=7, ncol=3)
        bottom.set_xlabel("frame")
        bottom.set_ylabel("PSNR vs uncached (dB)")
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"walkthrough_{scene}.png"), dpi=100)
        plt.close(fig)
        plot_walkthrough_misses(scene, [r for r in part if r.get("miss_empty")], out)
    return scenes


MISS_REASONS = [("empty", "tab:red"), ("fresh", "tab:orange"), ("doubtful", "tab:purple"),
                ("origin", "tab:brown"), ("search", "tab:gray"), ("outside", "black"),
                ("resting", "tab:cyan")]


def plot_walkthrough_misses(scene, data, out):
    """Per caching mode (rows) and path (columns), each frame's lookups stacked: hits, then misses by cause."""
    if not data:
        return
    modes = list(dict.fromkeys(r["mode"] for r in data))
    walks = list(dict.fromkeys(r["path"] for r in data))
    fig, axes = plt.subplots(len(modes), len(walks), figsize=(3.2 * len(walks), 2.6 * len(modes)),
                             sharex=True, sharey=True, squeeze=False)
    for i, mode in enumerate(modes):
        for j, walk in enumerate(walks):
            ax = axes[i][j]
            line = sorted((r for r in data if r["mode"] == mode and r["path"] == walk), key=lambda r: int(r["frame"]))
            frames = [int(r["frame"]) for r in line]
            layers = [[100 * float(r["hit_rate"]) for r in line]]
            layers += [[100 * float(r["miss_" + name]) for r in line] for name, _ in MISS_REASONS]
            ax.stackplot(frames, layers, colors=["tab:green"] + [c for _, c in MISS_REASONS],
                         labels=["hit"] + [name for name, _ in MISS_REASONS], lw=0)
            ax.set_title(f"{mode}, {walk}", fontsize=9)
            ax.set_ylim(0, 100)
            if j == 0:
                ax.set_ylabel("lookups (%)")
            if i == len(modes) - 1:
                ax.set_xlabel("frame")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="center right")
    fig.suptitle(f"{scene}: where the lookups went, frame by frame (frame 0 cold)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 0.89, 1))
    fig.savefig(os.path.join(out, f"walkthrough_{scene}_misses.png"), dpi=100)
    plt.close(fig)


def walkthrough_section(results, rel, scenes):
    """walkthrough.md with the per-scene plots after the per-path table (before the start-up section)."""
    path = os.path.join(results, "walkthrough.md")
    if not os.path.exists(path):
        return ["## Walkthrough", "", "Not measured in this run (raycache_walkthrough_bench not run).", ""]
    with open(path) as f:
        text = f.read()
    plots = "".join(f"![walkthrough {s}]({rel}/walkthrough_{s}.png)\n" for s in scenes) + "\n"
    miss_plots = "".join(f"![where the lookups went, {s}]({rel}/walkthrough_{s}_misses.png)\n" for s in scenes
                         if os.path.exists(os.path.join(results, f"walkthrough_{s}_misses.png")))
    head, sep, startup = text.partition("### Start-up")
    paths, why_sep, why = head.partition("### Why lookups miss")
    if why_sep:
        head = paths.rstrip() + "\n\n" + plots + why_sep + why.rstrip() + "\n\n" + miss_plots
        return [head.rstrip() + "\n\n" + sep + startup]
    return [head.rstrip() + "\n\n" + plots + sep + startup]


def targets(results):
    """One line per target of the benchmarks issue: (target, measured, met)."""
    lines = []
    t52 = {int(r["n"]): r for r in rows(os.path.join(results, "table_5_2.csv")) if r.get("scene", "behind") == "behind"}
    if 32 in t52:
        r = t52[32]
        s, ceiling_ratio, psnr = float(r["cct_speedup"]), float(r["cct_ms"]) / float(r["ceiling_ms"]), float(r["cct_psnr"])
        lines.append(("CCT on behind-32 at least 4x faster than the cache off", f"{s:.2f}x", s >= 4.0))
        lines.append(("CCT on behind-32 within 10% of the ceiling", f"CCT ms / ceiling ms = {ceiling_ratio:.2f}", ceiling_ratio <= 1.10))
        lines.append(("CCT on behind-32: PSNR >= 40 dB at the filling viewpoint", f"{psnr:.1f} dB", psnr >= 40.0))
    t53 = [r for r in rows(os.path.join(results, "table_5_3.csv")) if r["scene"] == "reflective-32" and r["setting"].startswith("CDCT")]
    if t53:
        best = max(t53, key=lambda r: float(r["speedup"]))
        lines.append(("CDCT on reflective-32 at least 2x faster than the cache off",
                      f"best {float(best['speedup']):.2f}x ({best['setting']})", float(best["speedup"]) >= 2.0))
        # A search that stops at an empty texel reads one texel: only variants that answer most rays count.
        answering = [r for r in t53 if float(r["hit_rate"]) >= 0.5]
        if answering:
            fewest = min(answering, key=lambda r: float(r["texels_per_lookup"]))
            lines.append(("CDCT on reflective-32: at most 16 texels read per lookup on average (variants answering >= 50% of rays)",
                          f"{float(fewest['texels_per_lookup']):.1f} ({fewest['setting']}, hit rate {100 * float(fewest['hit_rate']):.0f}%); "
                          "the others stop at empty texels (hit rates " +
                          ", ".join(f"{100 * float(r['hit_rate']):.0f}%" for r in t53 if r not in answering) + ")",
                          float(fewest["texels_per_lookup"]) <= 16))
    q = [r for r in rows(os.path.join(results, "quality.csv")) if r["scene"] == "reflective-32" and r["viewpoint"] == "moved"]
    if q:
        cct = next(float(r["psnr"]) for r in q if r["technique"] == "CCT")
        # A CDCT that answers few rays traces the rest exactly: only variants answering most rays count.
        answering = [r for r in q if r["technique"].startswith("CDCT") and float(r["hit_rate"]) >= 0.5]
        if answering:
            best = max(answering, key=lambda r: float(r["psnr"]))
            gain = float(best["psnr"]) - cct
            lines.append(("CDCT at the moved viewpoint: PSNR at least 3 dB above the CCT's (reflective-32; CDCT variants answering >= 50% of rays)",
                          f"{gain:+.1f} dB ({best['technique']} {float(best['psnr']):.1f} dB at hit rate "
                          f"{100 * float(best['hit_rate']):.0f}%, vs CCT {cct:.1f} dB); variants filled only by rendering answer "
                          + ", ".join(f"{100 * float(r['hit_rate']):.1f}%" for r in q if r["technique"].startswith("CDCT") and r not in answering)
                          + " of rays (the rest traced)", gain >= 3.0))
    f59 = [r for r in rows(os.path.join(results, "figure_5_9.csv")) if int(r["face_size"]) == 512 and int(r["frame"]) == 8]
    if f59:
        v = float(f59[0]["outdated_percent"])
        lines.append(("Update rate at 512: at most 1% outdated after 8 frames", f"{v:.1f}%", v <= 1.0))
    mpath = os.path.join(results, "micro.json")
    if os.path.exists(mpath):
        m, where = micro(mpath)
        if "rtc_intersect1" in m and "cct_lookup" in m:
            ratio = float(m["rtc_intersect1"]["real_time"]) / float(m["cct_lookup"]["real_time"])
            lines.append(("One CCT lookup at least 20x cheaper than one rtcIntersect1 (behind-32)",
                          f"{ratio:.1f}x" + (f" (micro-benchmarks, {where})" if where else ""), ratio >= 20))
    return lines


def micro_table(results):
    mpath = os.path.join(results, "micro.json")
    if not os.path.exists(mpath):
        return "(micro-benchmarks not run)\n"
    m, where = micro(mpath)
    out = ["| benchmark | ns per operation | texels per search | hit rate | texels kept |", "|---|---|---|---|---|"]
    to_ns = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
    for name, r in m.items():
        extra = [r.get("texels_per_search"), r.get("hit_rate")]
        extra = [f"{float(x):.2f}" if x is not None else "-" for x in extra]
        kept = f"{100 * float(r['kept']):.1f}%" if r.get("kept") is not None else "-"
        ns = float(r["real_time"]) * to_ns[r.get("time_unit", "ns")]
        shown = re.sub(r"/min_time:[\d.]+", "", name)  # a benchmark's own minimum time is not its name
        out.append(f"| {shown} | {ns:.1f} | {extra[0]} | {extra[1]} | {kept} |")
    if where:
        out += ["", f"Machine: {where}."]
    return "\n".join(out) + "\n"


def main():
    results, output = sys.argv[1], sys.argv[2]
    plot_table_5_2(results, results)
    plot_figure_5_9(results, results)
    vulkan = plot_table_5_1(results, results)
    walk_scenes = plot_walkthrough(results, results)
    rel = os.path.relpath(results, os.path.dirname(os.path.abspath(output)))
    with open(os.path.join(results, "table_5_2.md")) as f:  # raycache_bench's Table 5.2
        tables = f.read().replace("`table_5_2.png`", f"![Table 5.2 speed-ups]({rel}/table_5_2.png)") + "\n"
    with open(os.path.join(results, "tables.md")) as f:  # ... and its other experiments
        tables += f.read().replace("`figure_5_9.png`", f"![update rate]({rel}/figure_5_9.png)")
    if vulkan:
        with open(os.path.join(results, "vulkan_tables.md")) as f:
            tables += "\n" + f.read() + f"![Vulkan behind-N speed-ups]({rel}/table_5_1.png)\n\n"
    else:
        tables += "\n## Table 5.1: the Vulkan tracer\n\nNot measured in this run (no Vulkan device or no Vulkan build).\n\n"
    md = ["# RayCache results", "",
          "Regenerate everything with `scripts/bench.sh` (about 45 minutes on 2 cores). Every speed-up compares renders "
          "interleaved in one process on the same frames: the walkthrough's are ratios of mean times over a camera path, "
          "the thesis tables' ratios of medians of repeated frames; files (CSV, PNG) are in "
          f"[`{rel}/`]({rel}/).", ""]
    md += walkthrough_section(results, rel, walk_scenes)
    dynamic = os.path.join(results, "dynamic.md")
    if os.path.exists(dynamic):  # raycache_dynamic_bench: invalidation in dynamic scenes
        with open(dynamic) as f:
            md += [f.read().rstrip("\n"), ""]
    md += rsh_results.section(results, rel)  # raycache_rsh_bench: the ray-space hierarchy
    # Sections kept beside their runs: written by hand (the lent machines', vulkan_adaptive) or by
    # bench/vulkan_single_image.py, bench/vulkan_resting.py and bench/costly_rays.py. Images they name by file
    # name alone are beside them.
    for folder in ["costly_rays", "xeon16_h100", "vulkan_adaptive", "vulkan_single_image", "vulkan_resting", "h200_vulkan"]:
        readme = os.path.join(results, folder, "README.md")
        if os.path.exists(readme):
            with open(readme) as f:
                text = re.sub(r"\]\(([\w.-]+\.png)\)", lambda m: f"]({rel}/{folder}/{m.group(1)})", f.read())
                md += [text.rstrip("\n"), "", f"Files: [`{rel}/{folder}/`]({rel}/{folder}/).", ""]
    md += ["## Targets", "", "| target | measured | met |", "|---|---|---|"]
    for target, measured, met in targets(results):
        md.append(f"| {target} | {measured} | {'yes' if met else '**no**'} |")
    md += ["", tables, "## Micro-benchmarks (Google Benchmark)", "",
           "One operation on the reflected rays of behind-32's main sphere; CDCT searches on a cube filled by tracing every "
           "texel. `cct_store` stores into a cube emptied every 4096 stores, so most of its stores allocate their tile "
           "(1.4 KiB, zeroed). A secant search's reads form one dependent chain (texel choice, tile table, texel word, "
           "square roots): it costs more than the ray it answers here. `exact_invalidation` is one move's exact invalidation "
           "of behind-32's caches (one of the 32 spheres moved, path records kept: the dynamic benchmark's scene, warmed "
           "for 20 frames at 512 x 512 and loaded from a cache file before each iteration), on 1 thread and on every "
           "core (`/0`): the same state every time, so builds compare side by side.", "", micro_table(results)]
    with open(output, "w") as f:
        f.write("\n".join(md))
    print(f"wrote {output}")


if __name__ == "__main__":
    main()
