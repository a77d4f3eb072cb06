"""Scenes: from a dict or a file, with overrides, validated as the command line validates."""

import json
import subprocess

import pytest
import vesicle

from conftest import ROOT, ellipse


def test_a_dict_and_its_file_give_the_same_scene(tmp_path):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(ellipse()))
    assert vesicle.Scene(ellipse()).to_dict() == vesicle.Scene(path).to_dict()
    assert vesicle.Scene(str(path)).to_dict() == vesicle.Scene(path).to_dict()


def test_overrides_as_a_dict_or_as_set_strings_agree():
    by_dict = vesicle.Scene(ellipse(), overrides={"dt": 0.02, "initial.r0": 9})
    by_set = vesicle.Scene(ellipse(), overrides=["dt=0.02", "initial.r0=9"])
    assert by_dict.to_dict() == by_set.to_dict()
    assert by_dict.dt == 0.02 and by_dict.to_dict()["initial"]["r0"] == 9.0
    again = vesicle.Scene(ellipse()).with_overrides({"dt": 0.02, "initial.r0": 9})
    assert again.to_dict() == by_dict.to_dict()
    # A value of None removes the key: the default comes back.
    assert vesicle.Scene(ellipse(), overrides={"prepare_steps": None}).to_dict()["prepare_steps"] != 5


def test_the_scene_file_reads_back_through_the_command_line(tmp_path, cli):
    path = tmp_path / "scene.json"
    path.write_text(vesicle.Scene(ellipse()).to_json())
    assert vesicle.Scene(path).to_dict() == vesicle.Scene(ellipse()).to_dict()
    done = subprocess.run([cli, "check", str(path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize(
    "override, field",
    [
        ({"initial.r0": -3}, "initial.r0"),
        ({"dt": "fast"}, "dt"),
        ({"colour": 1}, "colour"),
        ({"n": [48]}, "n"),
        ({"device": "gpu"}, "dim"),
    ],
)
def test_invalid_input_names_the_field_with_the_command_lines_message(tmp_path, cli, override, field):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(ellipse()))
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.Scene(path, overrides=override)
    assert isinstance(raised.value, ValueError)
    assert raised.value.field == field
    (key, value), = override.items()
    done = subprocess.run(
        [cli, "check", str(path), "--set", f"{key}={json.dumps(value)}"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 2
    assert str(raised.value) in done.stderr


def test_a_missing_scene_file_is_invalid_input():
    with pytest.raises(vesicle.InvalidInput) as raised:
        vesicle.Scene(ROOT / "runs" / "no_such_scene.json")
    assert raised.value.field == "(scene file)"


def test_a_spec_of_the_wrong_type_is_a_type_error():
    with pytest.raises(TypeError):
        vesicle.Scene(42)
    with pytest.raises(TypeError):
        vesicle.Scene(ellipse(), overrides=3)
