"""Setting φ from an array: validated, the state evaluated again, the run continued."""

import numpy as np
import pytest
import vesicle

from conftest import ellipse, prolate3d


@pytest.mark.parametrize("scene", [ellipse(), prolate3d()], ids=["2d", "3d"])
def test_a_field_set_from_another_simulation_gives_its_state(scene):
    donor = vesicle.Simulation(scene)
    donor.run(max_steps=10)
    sim = vesicle.Simulation(scene)
    sim.run(max_steps=4)
    t, step = sim.t, sim.step_count
    sim.phi = donor.phi
    # A spectral engine holds its spectrum: the field reads back within round-off.
    assert np.allclose(sim.phi, donor.phi, rtol=0, atol=1e-13)
    # Evaluated anew on the donor's field; the clock stays where it was.
    for name in ("energy", "area", "volume", "reduced_volume", "reduced_energy"):
        assert getattr(sim, name) == pytest.approx(getattr(donor, name), rel=1e-12), name
    assert (sim.t, sim.step_count) == (t, step)
    assert sim.record["energy"] == sim.energy
    # The history's row of the current step is the new state.
    assert sim.history["step"][-1] == step
    assert sim.history["energy"][-1] == sim.energy
    assert sim.run(max_steps=8) == "max_steps"
    assert np.isfinite(sim.phi).all() and sim.step_count == 8


def test_a_list_and_an_int_array_are_taken_as_floats():
    sim = vesicle.Simulation(ellipse(max_steps=2))
    phi = -np.ones(tuple(ellipse()["n"]), dtype=np.int64)
    phi[20:28, 20:28] = 1
    sim.phi = phi
    assert sim.phi.dtype == np.float64 and np.allclose(sim.phi, phi, rtol=0, atol=1e-13)
    sim.phi = phi.tolist()
    assert np.allclose(sim.phi, phi, rtol=0, atol=1e-13)


@pytest.mark.parametrize(
    "edit, words",
    [
        (lambda p: p[:-1], "shape"),
        (lambda p: np.where(np.arange(p.size).reshape(p.shape) == 100, np.nan, p), "non-finite"),
        (lambda p: np.where(np.arange(p.size).reshape(p.shape) == 7, 6.0, p), "blow-up limit"),
        (lambda p: np.roll(p, 3, axis=0), "not even about the plane x = 0"),
        (lambda p: "not an array", "not an array of numbers"),
    ],
    ids=["shape", "nan", "range", "mirror", "type"],
)
def test_a_bad_field_is_invalid_input_naming_phi(edit, words):
    sim = vesicle.Simulation(ellipse(max_steps=2))
    before = sim.phi
    with pytest.raises(vesicle.InvalidInput, match=words) as raised:
        sim.phi = edit(before)
    assert raised.value.field == "phi"
    # Nothing changed.
    assert np.array_equal(sim.phi, before)
    assert sim.run() == "max_steps"


def test_the_limit_is_the_engines_blow_up_limit():
    sim = vesicle.Simulation(ellipse(max_steps=2))
    phi = sim.phi.copy()
    inside = phi > 0.9
    phi[inside] = 4.9
    sim.phi = phi
    assert abs(sim.phi).max() == pytest.approx(4.9)
    phi[inside] = 5.001
    with pytest.raises(vesicle.InvalidInput, match="may not exceed 5") as raised:
        sim.phi = phi
    assert raised.value.field == "phi"


def test_phi_cannot_be_set_during_a_run():
    sim = vesicle.Simulation(ellipse())
    errors = []

    def swap(view):
        try:
            sim.phi = view.phi
        except RuntimeError as e:
            errors.append(e)
        return False

    sim.run(callback=swap)
    assert len(errors) == 1
