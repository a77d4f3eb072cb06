"""What driving the engine from Python costs: a 64³ prolate (runs/prolate3d.json at n = 64,
a fixed number of steps) run by the command line, by Simulation.run(), and by
Simulation.run() with a callback on every step.

    python python/bench/bench_overhead.py [--steps 1000] [--repeats 6] [--cli target/release/vesicle]

The three are interleaved in each repeat, in an order that turns from repeat to repeat (use a
multiple of 3 repeats), so a busy machine slows them alike; the medians and their ratios are
printed for

* the step loop's wall time (summary.json "wall_seconds" for the command line, the last
  record's wall_seconds from Python: the same clock around the same loop);
* the whole call's wall time: the command line process (start, set-up, loop, writing
  phi_final.npy and summary.json; pictures off) against Simulation(scene) + run() + phi;
* the CPU time (user + system) of the same calls;

and, for the callback, the median over repeats of each repeat's own ratio (python+callback /
python of the same repeat: a machine whose load drifts between repeats moves both alike) and
what one call costs in microseconds.

The callback is given a StepView; it counts the calls, as the cheapest callback would.
"""

import argparse
import json
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import vesicle

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cpu(who):
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def command_line(cli, scene_file, out):
    c0, w0 = cpu(resource.RUSAGE_CHILDREN), time.perf_counter()
    done = subprocess.run(
        [cli, "run", str(scene_file), "--out", str(out), "--force"], capture_output=True, text=True
    )
    wall, used = time.perf_counter() - w0, cpu(resource.RUSAGE_CHILDREN) - c0
    if done.returncode != 0:
        sys.exit(done.stderr)
    loop = json.loads((out / "summary.json").read_text())["wall_seconds"]
    return loop, wall, used


def python(scene, callback):
    c0, w0 = cpu(resource.RUSAGE_SELF), time.perf_counter()
    sim = vesicle.Simulation(scene)
    sim.run(callback=callback)
    _ = sim.phi
    wall, used = time.perf_counter() - w0, cpu(resource.RUSAGE_SELF) - c0
    return sim.record["wall_seconds"], wall, used


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=6)
    parser.add_argument("--n", type=int, default=64)
    parser.add_argument("--cli", default=str(ROOT / "target" / "release" / "vesicle"))
    args = parser.parse_args()

    # No pictures: the command line then writes only phi_final.npy and summary.json.
    overrides = {
        "n": [args.n] * 3,
        "max_steps": args.steps,
        "stop_residual": None,
        "output.png": False,
        "output.vti": False,
    }
    scene = vesicle.Scene(ROOT / "runs" / "prolate3d.json", overrides=overrides)
    calls = 0

    def every_step(record):
        nonlocal calls
        calls += 1

    results = {"cli": [], "python": [], "python+callback": []}
    with tempfile.TemporaryDirectory() as tmp:
        scene_file = pathlib.Path(tmp) / "scene.json"
        scene_file.write_text(scene.to_json())
        runs = {
            "cli": lambda: command_line(args.cli, scene_file, pathlib.Path(tmp) / "out"),
            "python": lambda: python(scene, None),
            "python+callback": lambda: python(scene, every_step),
        }
        order = list(runs)
        for r in range(args.repeats):
            # The order turns each repeat: a run right after another is a little slower (about
            # 2 % here, seen with two identical Python runs), which would bias a fixed order.
            for name in order[r % 3:] + order[: r % 3]:
                results[name].append(runs[name]())
    assert calls == args.repeats * args.steps

    threads = vesicle.Simulation(scene).threads
    print(f"{args.n}³ prolate (eighth box), {args.steps} steps, {threads} thread(s), "
          f"median of {args.repeats} interleaved repeats")
    print(f"{'':18}{'loop wall s':>12}{'call wall s':>12}{'call CPU s':>12}")
    med = {k: [statistics.median(x[i] for x in v) for i in range(3)] for k, v in results.items()}
    for k, (loop, wall, used) in med.items():
        print(f"{k:18}{loop:12.3f}{wall:12.3f}{used:12.3f}")
    base = med["cli"]
    for k in ("python", "python+callback"):
        ratios = "  ".join(f"{name} {m / b:.3f}" for name, m, b in zip(("loop", "call", "CPU"), med[k], base))
        print(f"{k} / cli: {ratios}")
    ratios = "  ".join(
        f"{name} {c / p:.3f}"
        for name, c, p in zip(("loop", "call", "CPU"), med["python+callback"], med["python"])
    )
    print(f"python+callback / python: {ratios}")
    paired = [
        statistics.median(c[i] / p[i] for c, p in zip(results["python+callback"], results["python"]))
        for i in range(3)
    ]
    ratios = "  ".join(f"{name} {r:.3f}" for name, r in zip(("loop", "call", "CPU"), paired))
    print(f"python+callback / python, paired by repeat: {ratios}")
    per_call = [
        statistics.median((c[i] - p[i]) / args.steps * 1e6 for c, p in zip(results["python+callback"], results["python"]))
        for i in (0, 2)
    ]
    print(f"one callback: {per_call[0]:.1f} µs of loop wall time, {per_call[1]:.1f} µs of CPU time")


if __name__ == "__main__":
    main()
