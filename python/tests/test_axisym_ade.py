"""The ADE and bilayer-couple models of the axisymmetric reference through vesicle.axisym.solve."""

import math

import pytest
import vesicle


def test_ade_shape_is_the_sc_shape_at_its_effective_curvature():
    alpha, da0 = 1.4, 1.3
    a = vesicle.axisym.solve("prolate", 0.85, nodes=121, ade=(alpha, da0))
    assert a["model"] == "ade"
    # c̄0,eff = c̄0 + 2πα(Δa0 − Δa) and w = e + πα(Δa − Δa0)² (the model's definitions).
    assert a["c0_eff"] == pytest.approx(2 * math.pi * alpha * (da0 - a["da"]), abs=1e-12)
    assert a["w"] == pytest.approx(a["e"] + math.pi * alpha * (a["da"] - da0) ** 2, abs=1e-12)
    # The closed loop: the SC shape at c0_eff has the same Δa and bending energy at c0 = 0
    # (e0 = e + c Δa − c²/4), to Newton's tolerance.
    c = a["c0_eff"]
    s = vesicle.axisym.solve("prolate", 0.85, nodes=121, c0=c)
    assert s["da"] == pytest.approx(a["da"], abs=1e-8)
    assert s["e"] + c * s["da"] - c * c / 4 == pytest.approx(a["e"], abs=1e-8)
    same = vesicle.axisym.solve("prolate", 0.85, nodes=121, ade={"alpha": alpha, "da0": da0})
    assert same["w"] == a["w"]


def test_bilayer_couple_holds_the_area_difference():
    s = vesicle.axisym.solve("prolate", 0.75, nodes=121, bc=1.2)
    assert s["model"] == "bc"
    assert s["da"] == pytest.approx(1.2, abs=1e-11)
    assert s["w"] == s["e"]


def test_bad_model_arguments_are_refused():
    with pytest.raises(vesicle.InvalidInput):
        vesicle.axisym.solve("prolate", 0.85, nodes=121, ade=(-1.0, 1.2))
    with pytest.raises(vesicle.InvalidInput):
        vesicle.axisym.solve("prolate", 0.85, nodes=121, ade=(1.4, 1.2), bc=1.1)
    with pytest.raises(vesicle.InvalidInput):
        vesicle.axisym.solve("pear", 0.85, nodes=121)
