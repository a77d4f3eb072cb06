"""Fields out: the φ = 0 surface as arrays, the writers, and the axisymmetric reference."""

import math

import numpy as np
import pytest
import vesicle

from conftest import ellipse, prolate3d


@pytest.fixture(scope="module")
def sim3d():
    sim = vesicle.Simulation(prolate3d(max_steps=4))
    sim.run()
    return sim


def test_the_surface_arrays_carry_the_measures_they_come_with(sim3d):
    vertices, faces, area, volume, v = sim3d.surface()
    assert vertices.shape[1] == 3 and faces.shape[1] == 3
    assert faces.min() >= 0 and faces.max() < len(vertices)
    # Area and enclosed volume recomputed here from the triangles (|ab × ac|/2 and the
    # divergence theorem) agree with the level set's to round-off.
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    cross = np.cross(b - a, c - a)
    assert np.linalg.norm(cross, axis=1).sum() / 2 == pytest.approx(area, rel=1e-9)
    assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6 == pytest.approx(volume, rel=1e-9)
    assert v == pytest.approx(6 * math.sqrt(math.pi) * volume / area**1.5, rel=1e-12)
    # Every edge is shared by exactly two triangles: the surface is closed.
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert (counts == 2).all()
    assert sim3d.levelset() == {"area": area, "volume": volume, "reduced_volume": v}


def test_surface_of_a_2d_scene_is_refused():
    sim = vesicle.Simulation(ellipse(max_steps=1))
    with pytest.raises(vesicle.InvalidInput):
        sim.surface()
    # The level set of a 2D field: the perimeter and the enclosed area, v of a 2D shape.
    ls = sim.levelset()
    assert ls["reduced_volume"] == pytest.approx(4 * math.pi * ls["volume"] / ls["area"] ** 2)


def test_the_writers_write_what_they_say(tmp_path, sim3d):
    sim3d.write_npy(tmp_path / "phi.npy")
    assert np.array_equal(np.load(tmp_path / "phi.npy"), sim3d.phi)
    sim3d.write_vti(tmp_path / "phi.vti")
    assert b'<VTKFile type="ImageData"' in (tmp_path / "phi.vti").read_bytes()[:400]
    sim3d.write_ply(tmp_path / "surface.ply")
    header = (tmp_path / "surface.ply").read_bytes()[:300]
    vertices, faces, *_ = sim3d.surface()
    assert f"element vertex {len(vertices)}".encode() in header
    assert f"element face {len(faces)}".encode() in header
    sim3d.write_png(tmp_path / "phi.png")
    sim3d.write_charts(tmp_path)
    for name in ("phi.png", "energy.png", "residual.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_axisymmetric_sphere_and_the_pressure_as_de_dv():
    # Near v = 1 the prolate is nearly a sphere, whose reduced energy is 1.
    near = vesicle.axisym.solve("prolate", 0.999, nodes=81)
    assert near["e"] == pytest.approx(1.0, abs=1e-2)
    assert near["r"][0] == 0 and abs(near["r"][-1]) < 1e-9
    # P = 6 de/dv along the branch: a centred difference of e(v) from three solves.
    dv = 1e-3
    shapes = vesicle.axisym.follow("prolate", [0.85 - dv, 0.85, 0.85 + dv], nodes=81)
    assert list(shapes["v"]) == pytest.approx([0.85 - dv, 0.85, 0.85 + dv])
    slope = (shapes["e"][2] - shapes["e"][0]) / (2 * dv)
    assert shapes["pressure"][1] == pytest.approx(6 * slope, rel=1e-4)
    assert shapes["sigma"][1] == pytest.approx(shapes["pressure"][1] * 0.85 / 2, rel=1e-12)


def test_an_unknown_branch_or_volume_is_invalid_input():
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.axisym.solve("discocyte", 0.8)
    assert raised.value.field == "branch"
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.axisym.solve("prolate", 1.5)
    assert raised.value.field == "v"
