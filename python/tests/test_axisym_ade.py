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


def test_a_narrow_neck_stretches_the_contour_parameter():
    # The bilayer-couple prolate at v = 0.9, Δa = 1.33 buds at both poles (necks 0.026 R0): its
    # modes are clustered at both necks, symmetrically (the mirrored map), and its energy is
    # e = 2.864735 at 241 nodes (2.865949 at 121: the stretched basis converges in the nodes).
    s = vesicle.axisym.solve("prolate", 0.9, nodes=121, bc=1.33)
    m = s["neck_map"]
    assert m is not None and m["mirrored"]
    assert 0 < m["centre"] < 0.5 and 0 < m["half_width"] < 0.1
    assert s["e"] == pytest.approx(2.864735, abs=2e-3)
    assert vesicle.axisym.solve("prolate", 0.75, nodes=121, bc=1.2)["neck_map"] is None


def test_bad_model_arguments_are_refused():
    with pytest.raises(vesicle.InvalidInput):
        vesicle.axisym.solve("prolate", 0.85, nodes=121, ade=(-1.0, 1.2))
    with pytest.raises(vesicle.InvalidInput):
        vesicle.axisym.solve("prolate", 0.85, nodes=121, ade=(1.4, 1.2), bc=1.1)
    with pytest.raises(vesicle.InvalidInput):
        vesicle.axisym.solve("pear", 0.85, nodes=121)
    with pytest.raises(vesicle.InvalidInput):
        vesicle.axisym.updown(1.0)


def test_the_budding_prolate_regains_updown_stability():
    # At v = 0.86 the bilayer-couple prolate loses up–down stability where the pear leaves it
    # (Δa = 1.077385, the same at 241 and 481 nodes) and regains it at 1.361915 (241 nodes;
    # 1.361916 at 481), where it buds at both poles with necks of 0.055 R0. Each zero is a
    # shape of the path at its Δa; 1e-4 allows ten times the change from 241 to 481 nodes.
    changes = vesicle.axisym.updown(0.86)
    assert [c["loses"] for c in changes] == [True, False]
    lost, regained = changes[0]["da"], changes[1]["da"]
    assert lost == pytest.approx(1.077385, abs=1e-5)
    assert regained == pytest.approx(1.361916, abs=1e-4)
    assert 0.04 < changes[1]["neck"] < 0.07
    for c in changes:
        assert c["shape"]["branch"] == "prolate" and c["shape"]["model"] == "bc"
        assert c["shape"]["da"] == pytest.approx(c["da"], abs=1e-10)
