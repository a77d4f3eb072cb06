"""Shared fixtures: small scenes, the repository root and the `vesicle` command line."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def ellipse(n=48, **extra):
    """A 2D ellipse of reduced area 0.8 (R0 = 8ε) on the quarter box, spectral SBDF1 with
    adaptive steps: a few dozen steps take well under a second."""
    scene = {
        "dim": 2,
        "n": [n, n],
        "h": 1.0,
        "eps": 1.0,
        "method": "spectral",
        "scheme": "sbdf1",
        "dt": 0.01,
        "adaptive": {"dt_max": 50.0},
        "max_steps": 40,
        "initial": {"shape": "spheroid", "reduced_volume": 0.8, "r0": 8.0, "kind": "prolate"},
        "prepare_steps": 5,
        "symmetry": ["x", "y"],
        "threads": 1,
        "output": {"record_every": 4},
    }
    scene.update(extra)
    return scene


def prolate3d(n=32, **extra):
    """A 3D prolate (v = 0.85, R0 = 6ε) on the eighth box (mirror x, y, z)."""
    scene = {
        "dim": 3,
        "n": [n, n, n],
        "h": 1.0,
        "eps": 1.0,
        "method": "spectral",
        "scheme": "sbdf1",
        "dt": 0.01,
        "adaptive": {"dt_max": 50.0},
        "max_steps": 12,
        "initial": {"shape": "spheroid", "reduced_volume": 0.85, "r0": 6.0, "kind": "prolate"},
        "prepare_steps": 5,
        "symmetry": ["x", "y", "z"],
        "threads": 1,
        "output": {"record_every": 3},
    }
    scene.update(extra)
    return scene


def explicit(scene, dt):
    """`scene` with the finite-difference engine at the fixed step `dt` (the spectral-only
    keys removed)."""
    scene = {k: v for k, v in scene.items() if k not in ("scheme", "adaptive")}
    scene.update(method="fd", dt=dt)
    return scene


@pytest.fixture(scope="session")
def cli():
    """The `vesicle` binary: $VESICLE_BIN, else target/release/vesicle of this checkout (built
    by `cargo test --release`), else one on PATH."""
    for candidate in (os.environ.get("VESICLE_BIN"), ROOT / "target" / "release" / "vesicle"):
        if candidate and pathlib.Path(candidate).is_file():
            return str(candidate)
    found = shutil.which("vesicle")
    if found is None:
        pytest.fail("no `vesicle` binary: run `cargo build --release` first or set VESICLE_BIN")
    return found
