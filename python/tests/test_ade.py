"""Area-difference elasticity and the bilayer couple from Python: the scene keys pass
through `Scene` (and are refused where the command line refuses them), and the records carry
the term's columns, as timeseries.csv does."""

import math

import pytest
import vesicle

from conftest import ellipse, prolate3d


def test_ade_columns_in_records_and_history():
    scene = prolate3d(max_steps=8, ade={"alpha": 1.0, "da0": 1.2})
    sim = vesicle.Simulation(scene)
    sim.run()
    r = sim.record
    for key in ("bending_energy", "da", "w", "c0_eff", "lambda"):
        assert key in r, key
    # w = e + πα(Δa − Δa0)², and reduced_energy is w.
    assert r["w"] == pytest.approx(r["bending_energy"] + math.pi * (r["da"] - 1.2) ** 2, abs=1e-12)
    assert r["reduced_energy"] == r["w"]
    assert len(sim.history["da"]) == len(sim.history["step"])


def test_bilayer_couple_holds_da():
    sim = vesicle.Simulation(prolate3d(max_steps=5, bilayer_couple={"da": 1.1}))
    sim.run()
    assert sim.record["da"] == pytest.approx(1.1, abs=1e-11)


def test_ade_in_2d_is_refused_naming_the_key():
    with pytest.raises(vesicle.InvalidInput, match="ade") as err:
        vesicle.Scene(ellipse(ade={"alpha": 1.0, "da0": 1.1}))
    assert err.value.field == "ade"
