"""What a callback is given: a StepView of the step (its record as a mapping, its φ while the
callback runs)."""

import collections.abc

import numpy as np
import pytest
import vesicle

from conftest import ellipse, prolate3d

COLUMNS = ["step", "t", "dt", "energy", "area", "volume", "reduced_volume", "reduced_energy", "sigma",
           "residual", "rate", "rejected", "wall_seconds"]


def test_the_view_reads_as_the_record():
    seen = []

    def look(view):
        seen.append(view)
        assert isinstance(view, collections.abc.Mapping)
        assert view["step"] == view.step and isinstance(view["step"], int)
        assert isinstance(view["rejected"], int) and isinstance(view["t"], float)
        assert list(view) == list(view.keys()) == COLUMNS
        assert len(view) == 13 and "residual" in view and "phi" not in view
        assert dict(view) == view.to_dict() == dict(view.items())
        assert view.get("missing", 7) == 7
        with pytest.raises(KeyError):
            view["missing"]
        with pytest.raises(AttributeError):
            view.missing

    sim = vesicle.Simulation(ellipse())
    sim.run(max_steps=8, callback=look, every=4)
    # The record stays readable after the run; it equals the simulation's record at its step.
    assert [v["step"] for v in seen] == [4, 8]
    last, record = seen[-1].to_dict(), sim.record
    last.pop("wall_seconds"), record.pop("wall_seconds")  # the run's clock stops after the step
    assert last == record
    assert "step=8" in repr(seen[-1])


@pytest.mark.parametrize("scene", [ellipse(), prolate3d()], ids=["2d", "3d"])
def test_phi_in_a_callback_is_the_steps_field(scene):
    fields = {}

    def look(view):
        fields[view["step"]] = view.phi

    sim = vesicle.Simulation(scene)
    sim.run(max_steps=6, callback=look, every=3)
    assert sorted(fields) == [3, 6]
    assert np.array_equal(fields[6], sim.phi)
    assert fields[3].shape == tuple(scene["n"]) and not fields[3].flags.writeable
    again = vesicle.Simulation(scene)
    again.run(max_steps=3)
    assert np.array_equal(fields[3], again.phi)


def test_phi_is_refused_once_the_callback_has_returned():
    kept = []
    sim = vesicle.Simulation(ellipse())
    sim.run(max_steps=2, callback=kept.append)
    with pytest.raises(RuntimeError, match="inside the callback"):
        kept[0].phi
    assert kept[0]["step"] == 1


def test_the_simulation_itself_is_busy_during_a_callback():
    sim = vesicle.Simulation(ellipse())
    errors = []

    def read(view):
        try:
            sim.phi
        except RuntimeError as e:
            errors.append(str(e))
        return False

    assert sim.run(callback=read) == "callback"
    assert errors and "StepView" in errors[0]
