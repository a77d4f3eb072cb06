"""The command line in process: the diagram's tables as arrays, errors as exceptions."""

import json

import numpy as np
import pytest
import vesicle

# One prolate point at R0 = 8, 9 and 10ε: a few seconds.
QUICK = {"branches": {"prolate": [0.8]}, "r0": [8, 9, 10], "thumbnails": [0.8]}


def test_the_diagram_returns_its_tables_and_writes_its_charts(tmp_path):
    file = tmp_path / "quick.json"
    file.write_text(json.dumps(QUICK))
    tables = vesicle.diagram(file, tmp_path / "out", jobs=1)
    assert {"diagram", "cases", "reference"} <= set(tables)
    cases = tables["cases"]
    # Three resolutions of the one point; the relaxed φ = 0 surface's reduced volume moves
    # from the sharp start's 0.8 by the diffuse-interface error, which shrinks as R0/ε grows.
    order = np.argsort(cases["r0"])
    assert list(cases["r0"][order]) == [8, 9, 10]
    v = cases["v"][order]
    assert v[0] > v[1] > v[2] > 0.8, v
    assert list((tmp_path / "out").glob("*.png"))
    one = vesicle.diagram(file, tmp_path / "out", case=0, force=True)
    assert one["index"] == 0 and one["branch"] == "prolate"


def test_bad_arguments_and_bad_files_raise_invalid_input(tmp_path):
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.cli("run")
    assert raised.value.field == "(command line)"
    file = tmp_path / "bad.json"
    file.write_text(json.dumps({"branches": {"prolate": [0.8]}, "r0": [10]}))
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.diagram(file, tmp_path / "out")
    assert raised.value.field == "r0"
    with pytest.raises(ValueError):
        vesicle.study("speed", file, tmp_path / "out")


def test_help_prints_and_returns_zero(capsys):
    assert vesicle.cli("--version") == 0
