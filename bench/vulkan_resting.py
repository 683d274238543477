#!/usr/bin/env python3
"""Resting cubes on the Vulkan tracer, as docs/results/vulkan_resting/ holds it: every scene x path x technique
with the default threshold (`--min-hit-rate` unset: CCT 0.5, CDCT 0.6) and with cubes that never rest
(`--min-hit-rate 0`), RUNS runs each (rotating, so a slow stretch of a shared machine hits every variant),
each run 12 frames at 256x256 beside the uncached frames in the same process (`--compare`). Writes runs.txt
(every run's command and output) and README.md (the table, medians over the runs) into OUT.

    bench/vulkan_resting.py build-release/examples/vulkan_whitted/raycache_vulkan_whitted OUT [RUNS]
"""
import os
import re
import statistics

from vulkan_runs import command_line, machine_name, run_rotating, speedup_cell, write_results

SCENES = ["behind-32", "grid-32", "reflective-32"]
PATHS = ["orbit", "pan"]
MODES = ["cct", "cdct"]
RATES = [None, 0.0]  # None: the technique's default


def parse(output):
    """speed-up and GPU speed-up after the first frame, PSNR mean and min over frames 1 on, frames with a
    resting cube, and the share of frames 1 on's leaving rays that resting cubes let through (%)."""
    uncached = re.search(r"summary uncached: .*speed-up ([\d.]+)x after the first frame", output)
    gpu = re.search(r"summary GPU time .*speed-up ([\d.]+)x", output)
    frames = re.findall(r"^\s*(\d+)\s+[\d.]+\s+\S+\s+\S+\s+[\d.]+%\s+[\d.]+\s+[\d.]+x\s+(\S+)(.*)$", output, re.M)
    if not (uncached and frames):
        raise RuntimeError("unexpected tracer output:\n" + output)
    later = [(float(p), rest) for f, p, rest in frames if int(f) > 0]
    psnrs = [p for p, _ in later]
    resting = [re.search(r"cubes rested \(([\d.]+)%", rest) for _, rest in later]
    return (float(uncached.group(1)), float(gpu.group(1)) if gpu else float("nan"), statistics.mean(psnrs), min(psnrs),
            sum(1 for r in resting if r), statistics.mean(float(r.group(1)) if r else 0.0 for r in resting))


def main():
    tracer, out, runs = command_line(__doc__)
    variants = [(s, p, m, r) for s in SCENES for p in PATHS for m in MODES for r in RATES]

    def arguments_of(v):
        scene, path, mode, rate = v
        return [tracer, "--scene", scene, "--size", "256x256", "--path", path, "--frames", "12", "--cache", mode,
                "--face-size", "auto", "--compare"] + (["--min-hit-rate", str(rate)] if rate is not None else [])

    # The log is written with the table at the end, so a run that stops early leaves the old files.
    done = run_rotating("vulkan resting", variants, runs, 5, arguments_of, parse)
    if done is None:
        return
    results, device, log = done
    rows = []
    for scene in SCENES:
        for path in PATHS:
            for mode in MODES:
                cells = []
                for rate in RATES:
                    r = results[(scene, path, mode, rate)]
                    cells.append(f"{speedup_cell([x[0] for x in r])}; "
                                 f"GPU {statistics.median(x[1] for x in r):.2f}x; {r[0][2]:.1f} / {r[0][3]:.1f} dB")
                rested = results[(scene, path, mode, None)][0]
                rows.append(f"| {scene} | {path} | {mode.upper()} | {cells[0]} | {rested[4]} of 11; {rested[5]:.0f}% | {cells[1]} |")
    write_results(out, log, f"""## Resting cubes on the Vulkan tracer (lavapipe)

Written by `bench/vulkan_resting.py` from `raycache_vulkan_whitted` runs (`runs.txt` beside this file holds
every run's full output and command line). Machine: {machine_name()}, {os.cpu_count()} hardware threads,
Vulkan on {device or 'the device found'}, validation off. 256x256, 12 frames along each path, adaptive faces
(`--face-size auto`), with resting cubes at the default threshold (CCT 0.5, CDCT 0.6) and with cubes that
never rest (`--min-hit-rate 0`). Speed-up: the uncached frames rendered beside the cached ones in the same
process over the cached frames' whole cost (tracing, end-of-frame passes, resizing), after the first frame;
median of {runs} runs, each run in brackets; GPU: the same in timestamped GPU time. PSNR mean / minimum over
frames 1 to 11 against the uncached frames (the same in every run: frames do not depend on timing).
Resting: frames with at least one resting cube, and the mean share of the leaving rays they let through.

| scene | path | mode | resting (default) | resting: frames; rays let through | never resting |
|---|---|---|---|---|---|
""" + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
