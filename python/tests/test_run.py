"""Running from Python: the same fields as the command line bit for bit, stop rules,
callbacks, checkpoints, and the errors a user catches."""

import csv
import json
import subprocess
import threading
import time

import numpy as np
import pytest
import vesicle

from conftest import ellipse, explicit, prolate3d


def cli_run(cli, scene, out):
    path = out.parent / (out.name + ".json")
    path.write_text(json.dumps(scene))
    done = subprocess.run([cli, "run", str(path), "--out", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    with open(out / "timeseries.csv") as f:
        rows = list(csv.DictReader(f))
    return np.load(out / "phi_final.npy"), rows, json.loads((out / "summary.json").read_text())


@pytest.mark.parametrize("scene", [ellipse(), prolate3d()], ids=["2d-quarter-box", "3d-eighth-box"])
def test_a_python_run_gives_the_command_lines_field_bit_for_bit(tmp_path, cli, scene):
    phi_cli, rows, summary = cli_run(cli, scene, tmp_path / "out")
    sim = vesicle.Simulation(scene)
    assert sim.run() == summary["stopped"] == "max_steps"
    phi = sim.phi
    # The same engine, the same steps, the same thread count: identical bits, and the
    # reduced box unfolded to the full box exactly as phi_final.npy.
    assert phi.shape == tuple(scene["n"]) == phi_cli.shape
    assert np.array_equal(phi, phi_cli)
    history = sim.history
    for column in ("step", "t", "dt", "energy", "area", "volume", "sigma", "residual"):
        assert list(history[column]) == [float(r[column]) for r in rows], column
    assert sim.scene.to_dict()["area"]["target"] == summary["spec"]["area"]["target"]


def test_phi_is_read_only_and_a_copy():
    sim = vesicle.Simulation(ellipse(max_steps=2))
    phi = sim.phi
    with pytest.raises(ValueError):
        phi[0, 0] = 1.0
    sim.run()
    assert not np.array_equal(phi, sim.phi)


def test_steps_taken_in_pieces_match_one_run():
    whole = vesicle.Simulation(ellipse())
    whole.run(max_steps=30)
    pieces = vesicle.Simulation(ellipse())
    assert pieces.step(10) == "max_steps"
    assert pieces.step_count == 10
    pieces.step(7)
    pieces.run(max_steps=30)
    assert pieces.step_count == whole.step_count == 30
    assert pieces.t == whole.t
    assert np.array_equal(pieces.phi, whole.phi)


def test_until_lands_on_the_time():
    sim = vesicle.Simulation(ellipse())
    assert sim.run(until=0.5) == "t_end"
    assert sim.t == pytest.approx(0.5, rel=0, abs=1e-12)


def test_the_state_reads_as_its_record():
    sim = vesicle.Simulation(ellipse(max_steps=5))
    sim.run()
    r = sim.record
    assert r["step"] == sim.step_count == 5
    assert (r["t"], r["energy"], r["area"], r["volume"]) == (sim.t, sim.energy, sim.area, sim.volume)
    assert (r["sigma"], r["residual"]) == (sim.sigma, sim.residual)
    assert (r["reduced_energy"], r["reduced_volume"]) == (sim.reduced_energy, sim.reduced_volume)
    # A relaxation lowers the bending energy.
    h = sim.history
    assert h["energy"][-1] < h["energy"][0]


def test_a_callback_sees_every_kth_record_and_false_stops_the_run():
    seen = []

    def watch(record):
        seen.append(record["step"])
        return record["step"] < 12

    sim = vesicle.Simulation(ellipse())
    assert sim.run(callback=watch, every=4) == "callback"
    assert seen == [4, 8, 12]
    assert sim.step_count == 12
    # None (a callback without a return) does not stop a run.
    assert sim.run(max_steps=20, callback=lambda r: None) == "max_steps"


def test_a_callbacks_exception_stops_the_run_and_propagates():
    def fail(record):
        if record["step"] == 6:
            raise ZeroDivisionError("from the callback")

    sim = vesicle.Simulation(ellipse())
    with pytest.raises(ZeroDivisionError, match="from the callback"):
        sim.run(callback=fail)
    # Stopped after the step that raised, and still usable.
    assert sim.step_count == 6
    assert sim.step(2) == "max_steps" and sim.step_count == 8


def test_the_engine_runs_without_the_gil():
    """A Python thread counting in a loop runs on while the engine steps: its counting rate
    during the run is at least a fifth of its rate while the main thread sleeps for as long.
    Measured 0.5-0.56 on a busy 2-core machine (the engine's thread and other jobs compete for
    the cores, and the main thread takes the GIL every 50 ms to check for signals); a C call
    that holds the GIL for as long (`sum(range(30_000_000))`) gives 0.013-0.019."""
    sim = vesicle.Simulation(ellipse(n=128, max_steps=10**7, adaptive=False, dt=0.05))

    def run_half_a_second():
        # Blocks of 1000 steps until half a second has passed: long enough to measure on any
        # machine, however fast.
        start = time.perf_counter()
        while time.perf_counter() - start < 0.5:
            sim.run(max_steps=sim.step_count + 1000)
    ticks = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks[0] += 1

    def rate(action):
        before, start = ticks[0], time.perf_counter()
        action()
        seconds = time.perf_counter() - start
        return (ticks[0] - before) / seconds, seconds

    counter = threading.Thread(target=count)
    counter.start()
    while ticks[0] == 0:
        pass
    try:
        running, seconds = rate(run_half_a_second)
        sleeping, _ = rate(lambda: time.sleep(seconds))
    finally:
        stop.set()
        counter.join()
    assert sim.step_count >= 1000 and seconds >= 0.5, "a run long enough to measure"
    assert running >= 0.2 * sleeping, f"{running:.3g} counts/s while running, {sleeping:.3g} asleep"


def test_a_failed_step_raises_blowup_and_keeps_the_last_good_state():
    scene = explicit(ellipse(max_steps=100, prepare_steps=0, allow_unstable=True), dt=2.0)
    sim = vesicle.Simulation(scene)
    with pytest.raises(vesicle.BlowUp) as raised:
        sim.run()
    e = raised.value
    assert isinstance(e, RuntimeError)
    assert e.step == sim.step_count + 1
    assert e.dt == pytest.approx(2.0)
    assert e.t == pytest.approx(sim.t + 2.0)
    assert e.check and e.check in str(e)
    assert np.isfinite(sim.phi).all()


def test_an_unstable_fixed_step_is_invalid_input_on_field_dt():
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.Simulation(explicit(ellipse(), dt=2.0))
    assert raised.value.field == "dt"


def test_writing_into_a_missing_folder_is_an_os_error(tmp_path):
    sim = vesicle.Simulation(ellipse(max_steps=1))
    with pytest.raises(FileNotFoundError):
        sim.write_npy(tmp_path / "missing" / "phi.npy")
    with pytest.raises(OSError):
        sim.write_png(tmp_path / "missing" / "phi.png")


def test_a_checkpoint_resumes_exactly(tmp_path):
    straight = vesicle.Simulation(ellipse())
    straight.run(max_steps=30)
    first = vesicle.Simulation(ellipse())
    first.run(max_steps=14)
    first.checkpoint(tmp_path / "cp")
    assert (tmp_path / "cp" / "checkpoint.bin").is_file()
    resumed = vesicle.Simulation.resume(tmp_path / "cp")
    assert (resumed.step_count, resumed.t) == (14, first.t)
    resumed.run(max_steps=30)
    assert np.array_equal(resumed.phi, straight.phi)
    # The history: the checkpointed run's rows (its last state, step 14, included), then
    # the continuation's, equal to the straight run's at the same steps.
    steps = list(resumed.history["step"])
    assert steps == [0, 4, 8, 12, 14, 16, 20, 24, 28, 30]
    common = [i for i, s in enumerate(steps) if s != 14]
    for column, values in straight.history.items():
        if column != "wall_seconds":
            assert np.array_equal(resumed.history[column][common], values, equal_nan=True), column


def test_a_command_line_run_folder_resumes_in_python(tmp_path, cli):
    phi_cli, _, _ = cli_run(cli, ellipse(max_steps=20), tmp_path / "out")
    straight = vesicle.Simulation(ellipse())
    straight.run(max_steps=30)
    resumed = vesicle.Simulation.resume(tmp_path / "out", overrides={"max_steps": 30})
    assert np.array_equal(resumed.phi, phi_cli)
    assert resumed.run() == "max_steps"
    assert np.array_equal(resumed.phi, straight.phi)


def test_a_damaged_checkpoint_or_a_frozen_key_is_invalid_input(tmp_path):
    sim = vesicle.Simulation(ellipse(max_steps=2))
    sim.run()
    sim.checkpoint(tmp_path)
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.Simulation.resume(tmp_path, overrides={"dt": 0.5})
    assert raised.value.field == "dt"
    data = bytearray((tmp_path / "checkpoint.bin").read_bytes())
    data[-10] ^= 0xFF
    (tmp_path / "checkpoint.bin").write_bytes(bytes(data))
    with pytest.raises(vesicle.InvalidInput, match="checksum") as raised:
        vesicle.Simulation.resume(tmp_path)
    assert raised.value.field == "checkpoint"
