#!/usr/bin/env python3
"""Where the cache pays as rays get costlier, as docs/results/costly_rays/ holds it: the Embree tracer on
behind-32 and reflective-32, fixed camera and orbit, with a point light and with soft shadows of 4 and 16
shadow rays a shaded hit (`--light-samples`), which make every traced ray costlier and leave the cache's own
work as it is. Each variant (CCT and CDCT with resting thresholds from what the traced rays cost, the
default, and with the fixed ones, `--lookup-work 0`; the ceiling) is one process beside the uncached frames
(`--compare`, 512x512, 10 frames), RUNS runs in a rotating order. Writes runs.txt, README.md (medians; the share of the
ceiling's gain, (off/mode - 1) / (off/ceiling - 1), from the medians) and, with matplotlib, share.png.

    bench/costly_rays.py build-release/examples/embree_whitted/raycache_embree_whitted OUT [RUNS]
    bench/costly_rays.py --replot OUT      (share.png again from OUT/runs.txt)
"""
import os
import re
import statistics
import sys

from vulkan_runs import command_line, machine_name, run_rotating, write_results

SCENES = ["behind-32", "reflective-32"]
PATHS = ["fixed", "orbit"]
SAMPLES = [1, 4, 16]
MODES = ["cct", "cdct", "cct-fixed", "cdct-fixed", "ceiling"]  # -fixed: --lookup-work 0 (CCT 0.5, CDCT 0.6)


def parse(output):
    """(speed-up after the first frame, PSNR mean, uncached ms a frame after the first, hits % of the lookups
    after the first frame)."""
    summary = re.search(r"summary uncached: mean [\d.]+ ms/frame \(([\d.]+) ms after the first\); speed-up ([\d.]+)x "
                        r"after the first frame; PSNR min\s+(\S+) dB, mean of finite\s+(\S+) dB", output)
    if not summary:
        raise RuntimeError("unexpected tracer output:\n" + output)
    misses = re.search(r"summary misses, share of lookups: (.*?) \(", output)
    hits = 100.0 - sum(float(x) for x in re.findall(r"([\d.]+)%", misses.group(1))) if misses else float("nan")
    psnr = float(summary.group(4)) if summary.group(4) != "-" else float("inf")
    return float(summary.group(2)), psnr, float(summary.group(1)), hits


def share(mode, ceiling):
    """The share of the ceiling's gain a speed-up reaches."""
    return (mode - 1.0) / (ceiling - 1.0) if ceiling > 1.0 else float("nan")


def plot(results, out):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing (scripts/install-deps.sh --bench): no plot")
        return
    fig, axes = plt.subplots(1, len(SCENES), figsize=(5 * len(SCENES), 3.6), sharey=True)
    for ax, scene in zip(axes, SCENES):
        for path in PATHS:
            for mode, style in (("cct", "-o"), ("cdct", "-s"), ("cct-fixed", ":o"), ("cdct-fixed", ":s")):
                y = [share(results[(scene, path, n, mode)], results[(scene, path, n, "ceiling")]) for n in SAMPLES]
                technique, _, fixed = mode.partition("-")
                threshold = "fixed threshold" if fixed else "threshold from work"
                camera = "fixed camera" if path == "fixed" else path
                ax.plot(SAMPLES, y, style, label=f"{technique.upper()}, {camera}, {threshold}")
        ax.axhline(0.0, color="grey", linewidth=0.8)
        ax.set_xscale("log", base=2)
        ax.set_xticks(SAMPLES, [str(n) for n in SAMPLES])
        ax.set_xlabel("shadow rays a shaded hit")
        ax.set_title(scene)
    axes[0].set_ylabel("share of the ceiling's gain")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "share.png"), dpi=110)


def replot(out):
    """share.png again from OUT/runs.txt (each run's output under a `=== scene_path_samples_mode_runN` line)."""
    speeds = {}
    with open(os.path.join(out, "runs.txt")) as f:
        for block in f.read().split("=== ")[1:]:
            scene, path, samples, mode, _ = block.split("\n", 1)[0].split("_")
            speeds.setdefault((scene, path, int(samples), mode), []).append(parse(block)[0])
    plot({v: statistics.median(s) for v, s in speeds.items()}, out)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--replot":
        replot(sys.argv[2])
        return
    tracer, out, runs = command_line(__doc__)
    variants = [(s, p, n, m) for s in SCENES for p in PATHS for n in SAMPLES for m in MODES]

    def arguments_of(v):
        scene, path, samples, mode = v
        fixed = mode.endswith("-fixed")
        return [tracer, "--scene", scene, "--size", "512x512", "--path", path, "--frames", "10",
                "--cache", mode.split("-")[0], "--light-samples", str(samples), "--compare", "-q"] + \
            (["--lookup-work", "0"] if fixed else [])

    done = run_rotating("costly rays", variants, runs, 7, arguments_of, parse)
    if done is None:
        return
    results_all, _, log = done
    median = {v: tuple(statistics.median(r[i] for r in rs) for i in range(4)) for v, rs in results_all.items()}
    speed = {v: m[0] for v, m in median.items()}
    lines = [
        "# Where the cache pays as rays get costlier\n\n",
        f"Embree tracer, 512x512, 10 frames, every ratio beside the uncached frames in the same process, median of "
        f"{runs} run(s), on {machine_name()} ({os.cpu_count()} threads); `bench/costly_rays.py`. Soft shadows "
        "(`--light-samples N`: N shadow rays a shaded hit to a disc light) make every traced ray costlier; the "
        "cache's own work stays as it is. Share = (off/mode - 1) / (off/ceiling - 1). Hits: share of the "
        "lookups of the frames after the first (resting rays count as misses). CCT and CDCT: resting thresholds from "
        "what the traced rays cost (the default); fixed: `--lookup-work 0`, the CCT's 0.5 and the CDCT's 0.6.\n\n",
        "| scene | path | shadow rays | uncached ms | ceiling | CCT (share; hits; PSNR) | CDCT (share; hits; PSNR) "
        "| CCT, fixed 0.5 | CDCT, fixed 0.6 |\n",
        "|---|---|---|---|---|---|---|---|---|\n",
    ]
    for scene in SCENES:
        for path in PATHS:
            for n in SAMPLES:
                c = speed[(scene, path, n, "ceiling")]
                cells = []
                for mode in ("cct", "cdct", "cct-fixed", "cdct-fixed"):
                    s, psnr, _, hits = median[(scene, path, n, mode)]
                    cells.append(f"{s:.2f}x ({share(s, c):.2f}; {hits:.0f}%; {psnr:.1f} dB)")
                lines.append(f"| {scene} | {path} | {n} | {median[(scene, path, n, 'cct')][2]:.0f} | {c:.2f}x | "
                             + " | ".join(cells) + " |\n")
    os.makedirs(out, exist_ok=True)
    plot(speed, out)
    write_results(out, log, "".join(lines) + "\n![share of the ceiling's gain](share.png)\n")


if __name__ == "__main__":
    main()
