"""Ctrl-C: a SIGINT raises KeyboardInterrupt in the running process, and the simulation is
left at its last good state, usable and resumable."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

from conftest import ellipse

CHILD = textwrap.dedent(
    """
    import json, signal, sys, time
    import numpy as np
    import vesicle

    # Python installs its KeyboardInterrupt handler only where SIGINT was not ignored at start,
    # and a test run launched from a background job (`cmd &` in a script) hands SIGINT down
    # ignored: install it, as an interactive session has it.
    signal.signal(signal.SIGINT, signal.default_int_handler)

    sim = vesicle.Simulation(json.loads(sys.argv[1]))
    print("running", flush=True)
    try:
        sim.run()
        print("finished", flush=True)
    except KeyboardInterrupt:
        caught = time.monotonic()
        phi = sim.phi
        steps = sim.step_count
        assert np.isfinite(phi).all() and steps > 0
        sim.checkpoint(sys.argv[2])
        resumed = vesicle.Simulation.resume(sys.argv[2])
        assert np.array_equal(resumed.phi, phi)
        assert sim.step(3) == "max_steps" and sim.step_count == steps + 3
        print("interrupted", caught, steps, flush=True)
    """
)


def test_sigint_raises_keyboard_interrupt_and_leaves_a_usable_state(tmp_path):
    # Fixed steps, a million of them: seconds of work that only the interrupt can end.
    scene = ellipse(n=64, adaptive=False, dt=0.05, max_steps=1_000_000)
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, json.dumps(scene), str(tmp_path / "cp")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert child.stdout.readline().strip() == "running"
    time.sleep(0.5)
    sent = time.monotonic()
    os.kill(child.pid, signal.SIGINT)
    out, err = child.communicate(timeout=60)
    assert child.returncode == 0, err
    assert out.split()[:1] == ["interrupted"], f"the run was not interrupted: {out!r}"
    _, caught, steps = out.split()
    # CLOCK_MONOTONIC is system-wide: the delay from the signal to the exception, for the log.
    print(f"KeyboardInterrupt {float(caught) - sent:.3f} s after SIGINT, at step {steps}")
