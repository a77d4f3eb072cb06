"""The axisymmetric reference at a reduced spontaneous curvature c̄0 = c0 R0."""

import math

import numpy as np
import pytest
import vesicle


def test_c0_zero_is_the_default():
    a = vesicle.axisym.solve("prolate", 0.9)
    b = vesicle.axisym.solve("prolate", 0.9, c0=0.0)
    assert a["c0"] == 0.0 and a["e"] == b["e"]
    assert np.array_equal(a["r"], b["r"])


@pytest.mark.parametrize("c0", [-1.0, 0.5, 1.5])
def test_near_the_sphere_the_energy_is_the_spheres(c0):
    s = vesicle.axisym.solve("prolate", 0.999, nodes=121, c0=c0)
    assert s["c0"] == c0
    # A sphere has e = (1 − c̄0/2)² and J = 1; at v = 0.999 within a few 1e-3.
    assert s["e"] == pytest.approx((1 - c0 / 2) ** 2, abs=5e-3)
    assert s["mean_curvature"] == pytest.approx(1.0, abs=5e-3)
    # σ = P v / 2 + c̄0 J − c̄0²/2 (the module's relation between the multipliers).
    assert s["sigma"] == pytest.approx(s["pressure"] * s["v"] / 2 + c0 * s["mean_curvature"] - c0**2 / 2, rel=1e-9, abs=1e-9)


def test_spontaneous_curvature_changes_the_shape_and_solve_agrees_with_follow():
    plain = vesicle.axisym.solve("prolate", 0.85, nodes=121)
    curved = vesicle.axisym.solve("prolate", 0.85, nodes=121, c0=1.0)
    assert curved["e"] != pytest.approx(plain["e"], rel=1e-3)
    path = vesicle.axisym.follow("prolate", [0.95, 0.9, 0.85], nodes=121, c0=1.0)
    assert path["c0"] == 1.0
    i = int(np.argmin(abs(path["v"] - 0.85)))
    assert path["v"][i] == pytest.approx(0.85)
    assert path["e"][i] == pytest.approx(curved["e"], rel=1e-8)
    assert path["shapes"][i]["c0"] == 1.0


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_c0_that_is_not_finite_is_invalid_input(bad):
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.axisym.solve("oblate", 0.9, c0=bad)
    assert raised.value.field == "c0"
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.axisym.follow("oblate", [0.9], c0=bad)
    assert raised.value.field == "c0"
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.axisym.solve("oblate", 0.9, nodes=3)
    assert raised.value.field == "nodes"
