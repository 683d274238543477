"""The ray-space hierarchy's section of docs/RESULTS.md (imported by make_results.py).

Reads rsh_frames.csv and rsh.md (raycache_rsh_bench) from the results folder; writes rsh_time.png (time per
frame against the triangle count, both paths: paper Figures 10 and 14), rsh_phases.png (the hierarchy
path's frame split into its phases, stacked: Figure 9a) and rsh_tests.png (cone-sphere tests against frame
time, with Pearson's r: Figure 13b); returns the section's Markdown lines (tables: Figure 13a's triangles
kept per ray, time to first picture, the crossover).
"""
import csv
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PHASES = [("build_ms", "hierarchy build"), ("tests_ms", "cone-sphere tests"), ("compaction_ms", "compaction"),
          ("final_ms", "final intersection")]


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _mean(values):
    return sum(values) / len(values) if values else float("nan")


def _pearson(xs, ys):
    if len(xs) < 3:
        return float("nan")
    mx, my = _mean(xs), _mean(ys)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    sxx = sum((x - mx) ** 2 for x in xs)
    syy = sum((y - my) ** 2 for y in ys)
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else float("nan")


def _line(xs, ys):
    """Least-squares y = a + b x."""
    mx, my = _mean(xs), _mean(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else 0.0
    return my - b * mx, b


def _scenes(data):
    """Per (spheres, level): the mean over moved frames of each path, in the CSV's order."""
    out = []
    for key in dict.fromkeys((r["spheres"], r["level"]) for r in data):
        part = [r for r in data if (r["spheres"], r["level"]) == key]
        bvh = [r for r in part if r["path"] == "bvh"]
        rsh = [r for r in part if r["path"] == "rsh"]
        if not bvh or not rsh:
            continue
        m = lambda rows, k: _mean([float(r[k]) for r in rows])  # noqa: E731
        s = {"spheres": int(key[0]), "level": int(key[1]), "triangles": int(part[0]["triangles"]),
             "primitives": int(part[0]["primitives"]), "frames": len(rsh),
             "bvh_ms": m(bvh, "ms"), "bvh_update_ms": m(bvh, "update_ms"), "rsh_ms": m(rsh, "ms"),
             "rsh_update_ms": m(rsh, "update_ms"), "tests": m(rsh, "cone_sphere_tests"),
             "leaf_pairs": m(rsh, "leaf_pairs"), "slots": m(rsh, "ray_slots"), "rays": m(rsh, "rays"),
             "batches": m(rsh, "batches"), "overflows": m(rsh, "overflows"),
             "bvh_first_ms": float(bvh[0]["first_picture_ms"]), "rsh_first_ms": float(rsh[0]["first_picture_ms"])}
        for k, _ in PHASES:
            s[k] = m(rsh, k)
        s["other_ms"] = max(0.0, s["rsh_ms"] - s["rsh_update_ms"] - sum(s[k] for k, _ in PHASES))
        out.append(s)
    return out


def _save(fig, ax, xlabel, ylabel, title, path, legend_size=7):
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=legend_size)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_time(scenes, path):
    fig, ax = plt.subplots(figsize=(7, 4.2))
    t = [s["triangles"] for s in scenes]
    ax.plot(t, [s["bvh_ms"] for s in scenes], "o-", color="tab:blue", label="BVH: rebuild + upload + frame")
    ax.plot(t, [s["bvh_update_ms"] for s in scenes], "o:", color="tab:blue", alpha=0.6, label="BVH: rebuild + upload alone")
    ax.plot(t, [s["rsh_ms"] for s in scenes], "s-", color="tab:red", label="RSH: upload + frame")
    ax.set_xscale("log")
    ax.set_yscale("log")
    _save(fig, ax, "triangles in the scene (moving spheres tessellated)", "ms per moved frame (mean)",
          "RSH vs a BVH rebuilt every frame (cf. paper Fig. 10, 14)", path)


def _plot_phases(scenes, path):
    fig, ax = plt.subplots(figsize=(7, 4.2))
    labels = [f"{s['triangles'] / 1000:.1f}k" for s in scenes]
    bottom = [0.0] * len(scenes)
    for key, label in PHASES + [("other_ms", "shading, ray compaction, submission"),
                                ("rsh_update_ms", "primitive upload")]:
        values = [s[key] for s in scenes]
        ax.bar(labels, values, bottom=bottom, label=label)
        bottom = [b + v for b, v in zip(bottom, values)]
    _save(fig, ax, "triangles in the scene", "ms per moved frame (mean)",
          "RSH frame by phase (cf. paper Fig. 9a); GPU timestamps on lavapipe", path)


def _plot_tests(data, path):
    rsh = [r for r in data if r["path"] == "rsh"]
    x = [float(r["cone_sphere_tests"]) / 1e6 for r in rsh]
    y = [float(r["ms"]) for r in rsh]
    r = _pearson(x, y)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    ax.plot(x, y, "o", color="tab:red", label=f"RSH frames (Pearson r = {r:.3f})")
    if len(x) >= 2:
        a, b = _line(x, y)
        xs = [min(x), max(x)]
        ax.plot(xs, [a + b * v for v in xs], "--", color="gray", label=f"least squares: {b:.0f} ms per million tests")
    _save(fig, ax, "cone-sphere tests per frame (millions)", "RSH ms per moved frame",
          "Time against cone-sphere tests (cf. paper Fig. 13b)", path, legend_size=8)
    return r


def _crossover(scenes):
    """A sentence on where (whether) the RSH becomes faster than the BVH path."""
    faster = [s for s in scenes if s["rsh_ms"] < s["bvh_ms"]]
    if faster:
        return (f"RSH is faster than BVH rebuild + traversal from {faster[0]['triangles']} triangles on "
                f"(of the scenes measured).")
    ratios = ", ".join(f"{s['rsh_ms'] / s['bvh_ms']:.1f}x" for s in scenes)
    t = [s["triangles"] for s in scenes]
    _, rsh_slope = _line(t, [s["rsh_ms"] for s in scenes])
    _, bvh_slope = _line(t, [s["bvh_ms"] for s in scenes])
    text = (f"No crossover on this device: RSH takes {ratios} the BVH path's time per frame, from the fewest to the "
            f"most triangles. Least-squares slopes: RSH {1000 * rsh_slope:.1f} ms, BVH {1000 * bvh_slope:.1f} ms per "
            f"1000 more triangles")
    text += ("; the lines diverge, so (extrapolating) no crossover lies beyond the range either on this device."
             if rsh_slope >= bvh_slope else
             "; extrapolating these lines (not measured) they would meet at about "
             f"{(_line(t, [s['rsh_ms'] for s in scenes])[0] - _line(t, [s['bvh_ms'] for s in scenes])[0]) / (bvh_slope - rsh_slope):.0f} triangles.")
    return text


def section(results, rel):
    """RESULTS.md's lines for the RSH section, or [] when raycache_rsh_bench was not run."""
    path = os.path.join(results, "rsh_frames.csv")
    if not os.path.exists(path):
        return []
    data = _rows(path)
    scenes = _scenes(data)
    if not scenes:
        return []
    _plot_time(scenes, os.path.join(results, "rsh_time.png"))
    _plot_phases(scenes, os.path.join(results, "rsh_phases.png"))
    r = _plot_tests(data, os.path.join(results, "rsh_tests.png"))
    how = ""
    if os.path.exists(os.path.join(results, "rsh.md")):
        with open(os.path.join(results, "rsh.md")) as f:
            how = f.read().strip()
    md = ["## Dynamic scenes: the ray-space hierarchy against a BVH rebuilt every frame", "", how, "",
          "llvmpipe is Mesa's lavapipe, a Vulkan driver that runs on the CPU; there is no GPU on this machine. "
          "The Vulkan tracer's two secondary-ray paths on dynamic-N (Roger, Assarsson and Holzschuch, EGSR 2007; "
          "`--secondary rsh` against `--secondary bvh`): the BVH path rebuilds its BVH with Embree on the CPU and "
          "uploads it every frame, the hierarchy path uploads the moved primitives and builds nothing from the scene. "
          "The triangle count grows by tessellating the moving spheres (`rcx::tessellate_moving_spheres`, level L: "
          "4 L (L - 1) triangles a sphere; level 0 = analytic spheres); the Wuson (3732 triangles) and the floor are "
          "in every scene. Per scene the two paths' first pictures, then their moved frames interleaved in one "
          "process. *ms* = mean wall time of a moved frame (set_scene + render); phases are GPU timestamps summed "
          "over the frame's traces (rays and shadow rays of each generation); *other* = the rest of the frame "
          "(shading passes, the compaction of the next generation's rays on the GPU, the frame's one submission "
          "and its read-back). *Kept per ray* "
          "= (ray, primitive) pairs intersected at the leaves / rays traced (shadow and secondary rays; the "
          "paper's Figure 13a: 2.5 to 4.5); *per slot* counts the hierarchy's empty leaves too. First picture = "
          "tracer set-up (shaders, buffers, BVH build for bvh) + first frame. Per frame: `rsh_frames.csv`.", ""]
    md += ["| spheres | level | triangles | BVH ms | of which rebuild + upload | RSH ms | RSH / BVH | build | tests | "
           "compaction | final | other | cone-sphere tests | kept per ray | per slot | batches | first picture BVH / RSH |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in scenes:
        md.append(f"| {s['spheres']} | {s['level']} | {s['triangles']} | {s['bvh_ms']:.1f} | {s['bvh_update_ms']:.1f} | "
                  f"{s['rsh_ms']:.1f} | {s['rsh_ms'] / s['bvh_ms']:.1f}x | {s['build_ms']:.1f} | {s['tests_ms']:.1f} | "
                  f"{s['compaction_ms']:.1f} | {s['final_ms']:.1f} | {s['other_ms']:.1f} | {s['tests'] / 1e6:.2f} M | "
                  f"{s['leaf_pairs'] / s['rays']:.2f} | {s['leaf_pairs'] / s['slots']:.2f} | {s['batches']:.0f} | "
                  f"{s['bvh_first_ms'] / 1000:.2f} s / {s['rsh_first_ms'] / 1000:.2f} s |")
    phase_total = sum(sum(s[k] for k, _ in PHASES) for s in scenes)
    share = {k: sum(s[k] for s in scenes) / phase_total if phase_total > 0 else float("nan") for k, _ in PHASES}
    kept = [s["leaf_pairs"] / s["rays"] for s in scenes]
    md += ["", f"- Crossover: {_crossover(scenes)}",
           f"- Phases (paper Figure 9a: stream reduction about 60%, cone-sphere tests about 15%, build below 1%): "
           f"over all scenes compaction takes {100 * share['compaction_ms']:.0f}%, the cone-sphere tests "
           f"{100 * share['tests_ms']:.0f}%, the hierarchy build {100 * share['build_ms']:.2f}% and the final "
           f"intersection {100 * share['final_ms']:.2f}% of the four GPU phases.",
           f"- Triangles kept per ray at the leaves: {min(kept):.2f} to {max(kept):.2f}, within the paper's 2.5 to 4.5 "
           f"on {sum(2.5 <= k <= 4.5 for k in kept)} of {len(kept)} scenes. Above it, a leaf's cone is its ray, not "
           f"cut at the ray's length (a shadow ray starts at the light and runs on past the point it tests), so every "
           f"tessellated sphere along the ray's whole line keeps the triangles whose bounding spheres the line meets, "
           f"on both of its sides.",
           f"- Cone-sphere tests against frame time over every RSH frame: Pearson r = {r:.3f} (paper Figure 13b: "
           f"time closely follows the tests).",
           "- What lavapipe means here: it runs the compute shaders on the same 2 CPU cores as Embree's BVH "
           "build, so this compares two CPU programs, one of them written for a GPU. The hierarchy's dozens of "
           "small dependent passes per trace (9 per level, several traces a frame) wait for each other at barriers, "
           "and its prefix sums and pair streams do a GPU's kind of work without a GPU's bandwidth; Embree's "
           "rebuild, by contrast, is fast CPU code. The paper's crossover was measured on a 2007 GPU against "
           "GPU BVH builds; no GPU was available for this run, so where the two cross on one is not measured here.",
           "", f"![time against triangles]({rel}/rsh_time.png)", f"![RSH phases]({rel}/rsh_phases.png)",
           f"![tests against time]({rel}/rsh_tests.png)", ""]
    return md
