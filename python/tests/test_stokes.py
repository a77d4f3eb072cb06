"""The Stokes dynamics from Python: the keys pass through `Scene` (and are refused where the
command line refuses them), and the records carry the flow's columns, as timeseries.csv does."""

import numpy as np
import pytest
import vesicle

from conftest import ROOT, ellipse


def stokes(**extra):
    """The ellipse on the full periodic box in a fluid."""
    scene = ellipse(symmetry=[], dynamics="stokes", flow={"viscosity": 1.0, "mobility": 0.01},
                    area={"method": "fixed", "sigma": 0.01}, adaptive=False, dt=0.5)
    scene.update(extra)
    return scene


def test_stokes_records_carry_the_flow_columns():
    sim = vesicle.Simulation(stokes(max_steps=6))
    sim.run()
    r = sim.record
    assert r["max_speed"] > 0.0 and r["dissipation"] > 0.0
    assert r["sigma"] == 0.01
    assert len(sim.history["max_speed"]) == len(sim.history["step"])


def test_flow_without_stokes_is_refused_naming_the_key():
    with pytest.raises(vesicle.InvalidInput) as err:
        vesicle.Scene(ellipse(flow={"viscosity": 1.0, "mobility": 0.01}))
    assert err.value.field == "flow"


def test_stokes_on_a_quarter_box_runs_and_a_sheared_mirror_is_refused_naming_the_key():
    """Every axis mirrored (the quarter box) runs the flow; under an imposed shear along x a
    mirror plane normal to y is not a symmetry and is refused."""
    quarter = vesicle.Simulation(stokes(symmetry=["x", "y"], max_steps=2))
    quarter.run()
    assert quarter.record["max_speed"] > 0.0
    sheared = {"viscosity": 1.0, "mobility": 0.01, "shear_rate": 1e-3}
    with pytest.raises(vesicle.InvalidInput) as err:
        vesicle.Scene(stokes(symmetry=["y"], flow=sheared))
    assert err.value.field == "symmetry"


def test_walls_bound_a_couette_flow():
    """Between walls across y the imposed shear is plane Couette flow; the vesicle is measured
    alone (its enclosed area, held exactly, that of the same start on the periodic box), and a
    wall across the flow is refused naming the key."""
    sheared = dict(flow={"viscosity": 1.0, "mobility": 0.01, "shear_rate": 1e-3}, max_steps=30)
    walled = vesicle.Simulation(stokes(walls=["y"], **sheared))
    periodic = vesicle.Simulation(stokes(**sheared))
    walled.run()
    periodic.run()
    assert walled.record["volume"] == pytest.approx(periodic.record["volume"], rel=1e-10)
    assert walled.record["max_speed"] > 0.0
    with pytest.raises(vesicle.InvalidInput) as err:
        vesicle.Scene(stokes(walls=["x"], **sheared))
    assert err.value.field == "walls"


def test_unequal_viscosities_solve_iteratively_and_refuse_mirror_planes():
    """`flow.viscosity_inside` passes through `Scene`: the Stokes solve then iterates (the
    records' `stokes_iterations` > 0, against 0 at equal viscosities), a more viscous inside
    moves the fluid more slowly (smaller max|u| after the same steps from the same start), and a
    mirror plane is refused naming the key."""
    equal = vesicle.Simulation(stokes(max_steps=4))
    viscous = vesicle.Simulation(
        stokes(max_steps=4, flow={"viscosity": 1.0, "mobility": 0.01, "viscosity_inside": 5.0}))
    equal.run()
    viscous.run()
    assert equal.record["stokes_iterations"] == 0
    assert viscous.record["stokes_iterations"] > 0
    assert viscous.record["max_speed"] < equal.record["max_speed"]
    contrast = {"viscosity": 1.0, "mobility": 0.01, "viscosity_inside": 5.0}
    with pytest.raises(vesicle.InvalidInput) as err:
        vesicle.Scene(stokes(symmetry=["x"], flow=contrast))
    assert err.value.field == "symmetry"


def test_the_inextensible_membrane_passes_through_scene():
    """`flow.inextensible` passes through `Scene`: the tension field's solve iterates (the
    records' `stokes_iterations` > 0), and walls or a viscosity contrast beside it are refused
    naming the key."""
    flow = {"viscosity": 1.0, "mobility": 0.01, "inextensible": True}
    sim = vesicle.Simulation(stokes(max_steps=3, flow=flow))
    sim.run()
    assert sim.record["stokes_iterations"] > 0
    with pytest.raises(vesicle.InvalidInput) as err:
        vesicle.Scene(stokes(walls=["y"], flow=flow))
    assert err.value.field == "walls"
    with pytest.raises(vesicle.InvalidInput) as err:
        vesicle.Scene(stokes(flow={**flow, "viscosity_inside": 2.0}))
    assert err.value.field == "flow.inextensible"


def test_the_rates_study_takes_a_list_of_boxes_to_free_space(tmp_path):
    """`runs/studies/rates_free.json --quick` runs the circle's n = 2 at R = 8 and 12ε, each in
    the boxes 8R and 10R: cases.csv has a row per (size, box), and rates.csv one row whose
    ratio at each size is taken to L → ∞ linearly in (R/L)², from the two boxes' ratios."""
    tables = vesicle.study("rates", ROOT / "runs" / "studies" / "rates_free.json", tmp_path / "out",
                           quick=True)
    cases, rates = tables["cases"], tables["rates"]
    assert list(cases["size"]) == [8, 8, 12, 12] and list(cases["box"]) == [8, 10, 8, 10]
    assert list(rates["boxes"]) == ["8 10 -> inf"]
    x = 1.0 / cases["box"] ** 2
    r = cases["ratio"]
    free = [(r[i + 1] * x[i] - r[i] * x[i + 1]) / (x[i] - x[i + 1]) for i in (0, 2)]
    printed = [float(s) for s in rates["ratios"][0].split()]
    assert np.allclose(printed, free, atol=5e-5), (printed, free)
