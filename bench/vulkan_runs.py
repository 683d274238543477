"""What the Vulkan tracer's benchmark scripts share (bench/vulkan_single_image.py, bench/vulkan_resting.py):
the machine's name, and running every variant RUNS times in a rotating order, so a slow stretch of a shared
machine hits every variant, with the validation layer off."""
import os
import platform
import re
import subprocess
import sys
import tempfile


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
