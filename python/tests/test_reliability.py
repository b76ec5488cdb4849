"""Reliability (issue 30): no input crashes the interpreter or reaches Python as a panic,
options are checked, everything returned or raised pickles, the batch functions work in a
forked child, and long calls stop on Ctrl-C. Each test reproduces probes of the issue."""

import json
import threading

import numpy as np
import pytest

import tdcr

ROD = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125}


def nested_list(depth):
    value = 1.0
    for _ in range(depth):
        value = [value]
    return value


class TolistItself:
    def tolist(self):
        return self


def test_deep_or_self_containing_values_are_invalid_input_naming_the_field():
    looped = [1.0]
    looped.append(looped)
    deep_dict = {}
    for _ in range(100_000):
        deep_dict = {"a": deep_dict}
    for value, fragment in [
        (nested_list(10_000), "nested more than 32 levels"),
        (looped, "`rod.x[2]` contains itself"),
        (TolistItself(), "`rod.x` contains itself"),
        (deep_dict, "nested more than 32 levels"),
    ]:
        with pytest.raises(tdcr.InvalidInput, match="rod.x") as e:
            tdcr.Robot(rod=dict(ROD, x=value))
        assert fragment in str(e.value)
    with pytest.raises(tdcr.InvalidInput, match="nested more than"):
        tdcr.Robot.from_dict({"rod": deep_dict})
    with pytest.raises(tdcr.InvalidInput, match="`rod.length` is 1180591620717411303424, beyond the 64-bit"):
        tdcr.Robot(rod=dict(ROD, length=2**70))
    with pytest.raises(tdcr.InvalidInput, match="parameter `tension.1` must be a 1-D sequence"):
        tdcr.solve_batch(tdcr.cases.case_h(), {"tension.1": looped})


def test_deep_values_in_a_thread_with_a_small_stack():
    # Depth 500 crashed a thread with a 256 KiB stack; the conversion stops at depth 32.
    caught = []

    def build():
        try:
            tdcr.Robot(rod=dict(ROD, x=nested_list(500)))
        except tdcr.InvalidInput as e:
            caught.append(e)

    old = threading.stack_size(256 * 1024)
    try:
        thread = threading.Thread(target=build)
        thread.start()
        thread.join()
    finally:
        threading.stack_size(old)
    assert len(caught) == 1 and "nested more than 32" in str(caught[0])


def test_former_panics_are_typed_errors():
    # `length = 1e308` overflowed the first mesh's capacity; now an InvalidInput or a
    # solver error (as 1e300 always was), never a PanicException.
    with pytest.raises(tdcr.Error):
        tdcr.solve(tdcr.Robot(rod=dict(ROD, length=1e308)))
    robot = tdcr.cases.case_h()
    solution = tdcr.solve(robot)
    text = json.loads(solution.to_json())

    def edited(edit):
        value = json.loads(json.dumps(text))
        edit(value)
        return json.dumps(value)

    def no_tendons(v):
        v["tendons"] = []

    # Empty tendons read fine (a solution may have none) but are not this robot's.
    no_tendon_solution = tdcr.Solution.from_json(edited(no_tendons))
    with pytest.raises(tdcr.InvalidInput, match="has 0 tendon state\\(s\\), but the robot has 5"):
        tdcr.tip_sensitivities(robot, no_tendon_solution)

    def reverse(v):
        v["nodes"] = v["nodes"][::-1]

    def nan_s(v):
        v["nodes"][3]["s"] = None

    def negative_s(v):
        v["nodes"][0]["s"] = -1.0

    def all_zero(v):
        for node in v["nodes"]:
            node["s"] = 0.0

    def not_rotation(v):
        v["nodes"][2]["R"][0][0] = 2.0

    for edit, fragment in [
        (reverse, "never decrease"),
        (nan_s, "nodes[3].s = NaN m"),
        (negative_s, "nodes[0].s = -1 m"),
        (all_zero, "the last node is the tip"),
        (not_rotation, "nodes[2].R is not a rotation"),
    ]:
        with pytest.raises(tdcr.InvalidInput, match="`solution`") as e:
            tdcr.Solution.from_json(edited(edit))
        assert fragment in str(e.value)


def test_robot_files_are_read_only_when_regular(tmp_path):
    for path in ["/dev/zero", str(tmp_path)]:
        with pytest.raises(tdcr.InvalidInput, match="not a regular file"):
            tdcr.Robot.from_file(path)
    fifo = tmp_path / "fifo"
    import os

    os.mkfifo(fifo)
    # A FIFO without a writer used to block every Python thread.
    with pytest.raises(tdcr.InvalidInput, match="not a regular file"):
        tdcr.Robot.from_file(fifo)
    big = tmp_path / "big.toml"
    with open(big, "wb") as f:
        f.truncate((16 << 20) + 1)
    with pytest.raises(tdcr.InvalidInput, match="more than the 16777216"):
        tdcr.Robot.from_file(big)
