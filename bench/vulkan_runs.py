"""What the tracers' benchmark scripts share (bench/vulkan_single_image.py, bench/vulkan_resting.py, and the
Embree tracer's bench/costly_rays.py):
their command line (TRACER OUT [RUNS]), the machine's name, running every variant RUNS times in a rotating
order, so a slow stretch of a shared machine hits every variant, with the validation layer off, the
speed-up cell of their tables, and writing OUT/runs.txt and OUT/README.md."""
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile


def command_line(doc):
    """(tracer, out, runs) from `script TRACER OUT [RUNS]` (runs: 3 unless given); exits with `doc` otherwise."""
    if len(sys.argv) < 3:
        sys.exit(doc)
    return sys.argv[1], sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 3


def speedup_cell(speedups):
    """'1.02x (1.01, 1.02, 1.04)': the median of the runs' speed-ups, and each run's."""
    return f"{statistics.median(speedups):.2f}x ({', '.join(f'{s:.2f}' for s in speedups)})"


def write_results(out, log, readme):
    """OUT/runs.txt (every run's command and output) and OUT/README.md (`readme`)."""
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "runs.txt"), "w") as f:
        f.write("".join(log))
    with open(os.path.join(out, "README.md"), "w") as f:
        f.write(readme)
    print(f"wrote {os.path.join(out, 'README.md')}")


def machine_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def run_rotating(label, variants, runs, shift, arguments_of, parse):
    """Runs `[tracer arguments] + ["--out", a temporary folder]` for every variant, `runs` times; run r starts
    at variant r * shift. arguments_of(variant) gives the command before --out (the images are not kept);
    parse(output) what is kept of a run. Returns (results: variant -> list of parse() per run, device name,
    log: every run's command and output), or None when there is no Vulkan device. Exits on a failed run."""
    results = {v: [] for v in variants}
    env = dict(os.environ, RCX_VULKAN_VALIDATION="0")
    device = ""
    png = tempfile.mkdtemp(prefix="raycache-" + label.replace(" ", "-") + "-")
    log = []
    for run in range(runs):
        for k in range(len(variants)):
            v = variants[(k + run * shift) % len(variants)]
            command = arguments_of(v) + ["--out", png]
            print(f"[{label}] run {run + 1}/{runs}: {' '.join(map(str, v))}", flush=True)
            done = subprocess.run(command, env=env, capture_output=True, text=True)
            text = done.stdout + done.stderr
            log.append(f"=== {'_'.join(map(str, v))}_run{run + 1}\n{' '.join(command)}\n{text}")
            if done.returncode == 77:
                print(f"[{label}] no Vulkan device: nothing written")
                return None
            if done.returncode != 0:
                sys.exit(f"the tracer failed ({done.returncode}):\n{text}")
            match = re.search(r"^device (.*?) \(validation", text, re.M)
            device = match.group(1) if match else device
            results[v].append(parse(text))
    return results, device, log
