"""The ROS gravity-compensation YAML reads back as written, whatever the frame names (a YAML emitter writes it)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import yaml

from ftcal.experiment import ToolLoad
from ftcal.experiment._tool_load import tool_gravity_compensation_yaml

#: Names a plain YAML scalar would misread (null, booleans, numbers, aliases, tags, flow and block syntax, comments).
NASTY_NAMES = ["null", "Null", "~", "yes", "no", "on", "true", "0x10", "0o17", "1e3", ".inf", "12:30", "*ref",
               "&anchor", "!tag", "%directive", "@at", "`tick", "[x]", "{y}", "a, b", "a: b", "#hash", "a #b",
               "- item", "? key", "|", ">", "'quoted'", '"double"', " padded ", "ü_frame", "tool/ft sensor"]


def _tool() -> ToolLoad:
    return ToolLoad(mass=1.25, center_of_mass=np.array([0.01, -0.002, 0.1]),
                    bias=np.array([0.5, -0.25, 3.0, 0.01, -0.02, 0.003]))


@pytest.mark.parametrize("name", NASTY_NAMES)
def test_frame_names_read_back_as_the_same_strings(name):
    tool = _tool()
    text = tool_gravity_compensation_yaml(tool, sensor_frame=name, world_frame=name)
    doc = yaml.safe_load(text)
    params = doc["gravity_compensation"]["ros__parameters"]
    assert params["sensor_frame"] == name and params["world_frame"] == name and doc["gripper_com_frame_id"] == name
    np.testing.assert_array_equal(params["CoG"]["pos"], tool.center_of_mass)  # numbers stay numbers, exactly
    np.testing.assert_array_equal(doc["bias"], tool.bias)
    assert doc["gripper_mass"] == tool.mass


@pytest.mark.parametrize("name", ["", "   ", "a\nb", "tab\there"])
def test_an_empty_or_unprintable_frame_name_is_refused(name):
    with pytest.raises(ValueError, match="sensor_frame .* must be a frame / node name"):
        tool_gravity_compensation_yaml(_tool(), sensor_frame=name)


@pytest.mark.parametrize("sensor_frame, world_frame", [("null", "*ref"), ("yes", "0x10"), ("a: b", "[x]")])
def test_export_ros_writes_yaml_that_parses_to_the_given_names(tmp_path, sensor_frame, world_frame):
    _tool().save(tmp_path / "tool.tool.json")
    out = tmp_path / "gc.yaml"
    proc = subprocess.run([sys.executable, "-m", "ftcal", "export", str(tmp_path / "tool.tool.json"), "--format", "ros",
                           "--sensor-frame", sensor_frame, "--world-frame", world_frame, "--output", str(out), "-q"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    params = yaml.safe_load(out.read_text(encoding="utf-8"))["gravity_compensation"]["ros__parameters"]
    assert (params["sensor_frame"], params["world_frame"]) == (sensor_frame, world_frame)
