"""The studies: the command line's own list, run by name, their tables typed from the library."""

import csv
import json
import subprocess

import numpy as np
import pytest
import vesicle

from conftest import ROOT

# A tiny budding study: 24 × 24 × 40, R0 = 7ε, two values of c̄0 (a few seconds).
BUDDING = {
    "study": "budding",
    "scene": {"dim": 3, "n": [24, 24, 40], "h": 1.0, "eps": 1.0, "dt": 0.01, "stop_residual": 1e-4,
              "max_steps": 40, "prepare_steps": 5, "threads": 1, "output": {"png": False, "vti": False}},
    "v": 0.8, "r0": 7.0, "c0": [1.0, 1.2], "seed": 0.02,
}


def csv_columns(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: [r[i] for r in rows[1:]] for i, name in enumerate(rows[0])}


def test_the_list_is_the_command_lines(cli):
    names = vesicle.STUDIES
    assert {"convergence", "precision", "stability", "stationary", "budding"} <= set(names)
    assert vesicle.commands.STUDIES is names
    described = vesicle.studies()
    assert list(described) == list(names) and all(described.values())
    helped = subprocess.run([cli, "study", "--help"], capture_output=True, text=True).stdout
    listed = [line.split()[0] for line in helped.split("Commands:")[1].split("Options:")[0].splitlines() if line.strip()]
    assert [n for n in listed if n != "help"] == list(names)


def test_budding_runs_from_python_and_its_tables_are_typed(tmp_path):
    file = tmp_path / "budding.json"
    file.write_text(json.dumps(BUDDING))
    tables = vesicle.study("budding", file, tmp_path / "out")
    assert set(tables) == {"budding"}
    t = tables["budding"]
    on_disk = csv_columns(tmp_path / "out" / "budding.csv")
    assert list(t) == list(on_disk)
    assert list(t["c0"]) == [1.0, 1.2]
    assert t["iterations"].dtype == np.int64 and t["pieces"].dtype == np.int64
    assert t["e"].dtype == np.float64 and t["state"].dtype.kind == "U"
    for name, column in t.items():
        if column.dtype.kind == "U":
            assert list(column) == on_disk[name], name
        else:
            # The same numbers, bit for bit, as the file written from the same rows.
            assert np.array_equal(column, np.array([float(x) if x else np.nan for x in on_disk[name]]), equal_nan=True), name
    assert (tmp_path / "out" / "budding.txt").is_file()
    # An existing folder is refused without force, as on the command line.
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.study("budding", file, tmp_path / "out")
    assert raised.value.field == "--out"


def test_stationary_on_a_scene_file_takes_overrides(tmp_path):
    tables = vesicle.study("stationary", ROOT / "runs" / "ellipse2d.json", tmp_path / "out",
                           overrides={"n": [48, 48], "initial.r0": 8})
    assert {"stationary", "traces", "levels"} <= set(tables)
    s = tables["stationary"]
    assert s["steps"].dtype == np.int64 and s["energy"].dtype == np.float64
    assert s["route"].dtype.kind == "U" and len(s["route"]) > 0
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.study("stationary", ROOT / "runs" / "ellipse2d.json", tmp_path / "quick", quick=True)
    assert raised.value.field == "--quick"


def test_an_unknown_study_is_invalid_input_naming_the_known_ones(tmp_path):
    with pytest.raises(vesicle.InvalidInput, match="budding") as raised:
        vesicle.study("speed", tmp_path / "x.json", tmp_path / "out")
    assert raised.value.field == "study"
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.study("budding", tmp_path / "missing.json", tmp_path / "out")
    assert raised.value.field == "(study file)"
