#!/usr/bin/env python3
"""The Vulkan tracer's single image with and without a warm-up pass, as docs/results/vulkan_single_image/
holds it: every scene x technique x first face size x warm-up stride, RUNS runs each (rotating, so a slow
stretch of a shared machine hits every variant), each run one frame beside the uncached one in the same
process (`--frames 1 --compare`). Writes runs.txt (every run's command and output) and README.md (the table,
medians over the runs) into OUT. No plot: single lavapipe frames are too noisy for one.

    bench/vulkan_single_image.py build-release/examples/vulkan_whitted/raycache_vulkan_whitted OUT [RUNS]
"""
import os
import re
import statistics

from vulkan_runs import command_line, machine_name, run_rotating, speedup_cell, write_results

SCENES = ["behind-32", "grid-32", "reflective-32"]
MODES = ["cct", "cdct"]
FIRST_FACES = [256, 64]
WARM_UPS = [0, 2, 4]


def parse(output):
    """speed-up, hit rate (%), PSNR, warm-up ms, frame ms, uncached ms of one run's output."""
    frame = re.search(r"^\s*0\s+[\d.]+\s.*?([\d.]+)%", output, re.M)  # the hit rate: the frame line's first percentage
    cached = re.search(r"mean ([\d.]+) ms/frame .*warm-up, end-frame passes and resizing included", output)
    uncached = re.search(r"summary uncached: mean ([\d.]+) ms/frame .*speed-up ([\d.]+)x.*PSNR min\s+(\S+) dB", output)
    warm = re.search(r"warm-up \(stride \d+\): ([\d.]+) ms", output)
    if not (frame and cached and uncached):
        raise RuntimeError("unexpected tracer output:\n" + output)
    return (float(uncached.group(2)), float(frame.group(1)), uncached.group(3), float(warm.group(1)) if warm else 0.0,
            float(cached.group(1)), float(uncached.group(1)))


def main():
    tracer, out, runs = command_line(__doc__)
    variants = [(s, m, f, w) for s in SCENES for m in MODES for f in FIRST_FACES for w in WARM_UPS]

    def arguments_of(v):
        scene, mode, first, warm = v
        return [tracer, "--scene", scene, "--size", "512x512", "--frames", "1", "--cache", mode, "--face-size", "auto",
                "--first-face-size", str(first), "--warm-up", str(warm), "--compare"]

    # The log is written with the table at the end, so a run that stops early leaves the old files.
    done = run_rotating("vulkan single image", variants, runs, 7, arguments_of, parse)
    if done is None:
        return
    results, device, log = done
    rows = []
    for v in variants:
        scene, mode, first, warm = v
        r = results[v]
        rows.append(f"| {scene} | {mode.upper()} | {first} | {warm or 'none'} | {speedup_cell([x[0] for x in r])} | "
                    f"{r[0][1]:.1f}% | {r[0][2]} | "
                    f"{statistics.median(x[3] for x in r):.0f} | {statistics.median(x[4] for x in r):.0f} | "
                    f"{statistics.median(x[5] for x in r):.0f} |")
    write_results(out, log, f"""## A single image on the Vulkan tracer: the warm-up pass (lavapipe)

Written by `bench/vulkan_single_image.py` from `raycache_vulkan_whitted` runs (`runs.txt` beside this file
holds every run's full output and command line). Machine: {machine_name()}, {os.cpu_count()} hardware threads,
Vulkan on {device or 'the device found'}, validation off. One 512x512 frame (`--frames 1`), adaptive faces
(`--face-size auto`) from 256- or 64-texel first faces, with no warm-up or a warm-up pass over every 2nd or
4th pixel in x and y (`--warm-up S`): its stores are published, the cubes resized to its rays, and the full
pass traces the other pixels and reads them. Speed-up: the uncached frame rendered beside it in the same
process over the cached frame's whole cost (warm-up, tracing, end-of-frame passes, resizing); median of
{runs} runs, each run in brackets. Hit rate: the full pass's leaving rays answered by a cube. PSNR against
that uncached frame.

| scene | mode | first faces | warm-up | speed-up (runs) | hit rate | PSNR dB | warm-up ms | frame ms | uncached ms |
|---|---|---|---|---|---|---|---|---|---|
""" + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
