"""The scene's output schedules in Simulation.run(): records, snapshots and checkpoints as
`vesicle run` keeps them, into a folder (out=) or, for snapshots, in memory."""

import csv
import json
import subprocess
import sys
import time

import numpy as np
import pytest
import vesicle

from conftest import ellipse

# Snapshots on simulated time (steps land on every 0.3), checkpoints every 5 steps.
OUTPUT = {
    "record_every": 4,
    "snapshots": {"every_time": 0.3},
    "checkpoints": {"every_steps": 5},
    "png": False,
}


def scheduled(**extra):
    return ellipse(max_steps=20, output=dict(OUTPUT), **extra)


def cli_run(cli, scene, out, *args):
    path = out.parent / (out.name + ".json")
    path.write_text(json.dumps(scene))
    done = subprocess.run([cli, "run", str(path), "--out", str(out), *args], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return out


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def snapshot_files(folder):
    return sorted(p.name for p in (folder / "snapshots").glob("*.npy"))


def test_a_run_into_a_folder_writes_what_the_command_line_writes(tmp_path, cli):
    scene = scheduled()
    theirs = cli_run(cli, scene, tmp_path / "cli")
    sim = vesicle.Simulation(scene)
    assert sim.run(out=tmp_path / "py") == "max_steps"
    ours = tmp_path / "py"
    # Steps landed on the snapshot times exactly as the command line lands them.
    assert np.array_equal(sim.phi, np.load(theirs / "phi_final.npy"))
    names = snapshot_files(theirs)
    assert names and names == snapshot_files(ours)
    assert names[0] == "phi_00000000.npy"
    for name in names:
        assert np.array_equal(np.load(ours / "snapshots" / name), np.load(theirs / "snapshots" / name)), name
    # The time series row by row, every column but the wall clock's.
    a, b = rows(ours / "timeseries.csv"), rows(theirs / "timeseries.csv")
    assert [r["step"] for r in a] == [r["step"] for r in b]
    for x, y in zip(a, b):
        x.pop("wall_seconds"), y.pop("wall_seconds")
        assert x == y
    assert list(sim.history["step"]) == [int(r["step"]) for r in b]
    # No lock is left, and the checkpoint continues the run on the command line, exactly.
    assert not (ours / ".lock").exists()
    assert (ours / "checkpoint.bin").is_file()
    done = subprocess.run([cli, "resume", str(ours), "--set", "max_steps=30"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    straight = vesicle.Simulation(scene)
    straight.run(max_steps=30)
    assert np.array_equal(np.load(ours / "phi_final.npy"), straight.phi)


def test_checkpoints_are_written_on_their_schedule_during_the_run(tmp_path):
    sim = vesicle.Simulation(scheduled())
    written = []

    def look(view):
        path = tmp_path / "checkpoint.bin"
        written.append((view["step"], path.is_file() and path.stat().st_mtime_ns))

    sim.run(max_steps=12, callback=look, out=tmp_path)
    # The checkpointer runs after the callback: at step 5 the file appears at step 6's call.
    first = next(step for step, seen in written if seen)
    assert first == 6, written
    resumed = vesicle.Simulation.resume(tmp_path)
    assert resumed.step_count == 12


def test_successive_runs_continue_one_folder(tmp_path):
    scene = scheduled()
    sim = vesicle.Simulation(scene)
    sim.run(max_steps=8, out=tmp_path)
    sim.run(max_steps=20, out=tmp_path)
    whole = vesicle.Simulation(scene)
    whole.run(out=tmp_path / "whole")
    assert snapshot_files(tmp_path) == snapshot_files(tmp_path / "whole")
    steps = [r["step"] for r in rows(tmp_path / "timeseries.csv")]
    assert steps == [str(s) for s in sim.history["step"]]
    assert np.array_equal(sim.phi, whole.phi)


def test_without_a_folder_snapshots_are_kept_in_memory(tmp_path, cli):
    scene = scheduled()
    theirs = cli_run(cli, scene, tmp_path / "cli")
    sim = vesicle.Simulation(scene)
    sim.run()
    assert np.array_equal(sim.phi, np.load(theirs / "phi_final.npy"))
    kept = sim.take_snapshots()
    assert sim.take_snapshots() == []
    names = snapshot_files(theirs)
    assert [f"phi_{step:08d}.npy" for step, _, _ in kept] == names
    for (step, t, phi), name in zip(kept, names):
        assert phi.shape == tuple(scene["n"]) and not phi.flags.writeable
        assert np.array_equal(phi, np.load(theirs / "snapshots" / name))
    times = [t for _, t, _ in kept]
    assert times[0] == 0.0
    assert times[1:] == pytest.approx([0.3 * k for k in range(1, len(times))], abs=1e-9)


HOLDER = """
import pathlib, sys, time, vesicle
folder = pathlib.Path(sys.argv[1])
scene = {scene!r}

def wait(view):
    (folder / "ready").write_text("")
    while not (folder / "done").exists():
        time.sleep(0.02)
    return False

vesicle.Simulation(scene).run(out=folder, callback=wait)
"""


def test_a_folder_another_run_holds_is_refused(tmp_path):
    # Another process runs into the folder (its callback waits), holding its lock.
    holder = subprocess.Popen([sys.executable, "-c", HOLDER.format(scene=scheduled()), str(tmp_path)])
    try:
        deadline = time.monotonic() + 60
        while not (tmp_path / "ready").exists():
            assert holder.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
        sim = vesicle.Simulation(scheduled())
        with pytest.raises(vesicle.InvalidInput, match="another vesicle run") as raised:
            sim.run(out=tmp_path)
        assert raised.value.field == "--out"
        assert sim.step_count == 0
    finally:
        (tmp_path / "done").write_text("")
        assert holder.wait(timeout=60) == 0
    # Released: the folder is free again.
    assert vesicle.Simulation(scheduled()).run(max_steps=2, out=tmp_path) == "max_steps"
