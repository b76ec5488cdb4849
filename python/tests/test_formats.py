"""One solution JSON for the command line and Python (docs/cli.md, "The solution JSON"): the
file `tdcr solve --format json` writes is read by `Solution.from_json`, and the text of
`Solution.to_json` is the same format, read by `tdcr solve --start`; numbers come back
bitwise."""

import json

import numpy as np
import pytest

import tdcr

# `pulled`: a displacement-controlled tendon, whose tension is solved for.
PULLED = "\n[[tendon]]\nrouting = { kind = \"straight\", x = 0.0, y = 0.008 }\ndisplacement = 0.002\n"


def robots():
    return {"h": tdcr.cases.case_h(), "pulled": tdcr.Robot.from_toml(tdcr.cases.case_s().to_toml() + PULLED)}


def nodes_of(data):
    """The nodes of a solution JSON as arrays, as Python's json module read them (exactly)."""
    nodes = data["nodes"]
    return {key: np.array([n[key] for n in nodes]) for key in ["s", "p", "R", "v", "u", "n", "m"]}


@pytest.mark.parametrize("name", ["h", "pulled"])
def test_a_solution_the_command_line_wrote_reads_in_python_bitwise(cli_text, name):
    robot = robots()[name]
    text = cli_text(["solve", "-", "--format", "json"], robot.to_toml())
    data = json.loads(text)
    back = tdcr.Solution.from_json(text)
    # Every node's state is the file's numbers, bit for bit.
    for key, values in nodes_of(data).items():
        assert np.array_equal(getattr(back, key), values), key
    assert np.array_equal(back.tensions, [t["tension"] for t in data["tendons"]])
    for path, tendon in zip(back.tendon_paths, data["tendons"]):
        assert np.array_equal(path, tendon["path"])
    assert back.report.iterations == data["iterations"] and back.report.residual == data["residual"]
    assert np.array_equal(back.report.history, [h["residual"] for h in data["history"]])
    # And it is the solution Python computes for the same robot (the same computation).
    ours = tdcr.solve(robot)
    for key in ["s", "p", "R", "v", "u", "n", "m", "tensions"]:
        assert np.array_equal(getattr(back, key), getattr(ours, key)), key
    assert back.tendons == ours.tendons
    untimed = lambda r: {k: v for k, v in r.to_dict().items() if not k.startswith("time_")}  # noqa: E731
    assert untimed(back.report) == untimed(ours.report)


@pytest.mark.parametrize("name", ["h", "pulled"])
def test_a_solution_python_wrote_is_the_command_lines_format_and_warm_starts_it(cli_text, tmp_path, name):
    robot = robots()[name]
    (tmp_path / "robot.toml").write_text(robot.to_toml())
    ours = json.loads(tdcr.solve(robot).to_json())
    theirs = json.loads(cli_text(["solve", "robot.toml", "--format", "json"], cwd=tmp_path))
    # The same keys (the command line adds the tendons' `end` and `turns`, which need the
    # robot) and, but for the timings, the same values, bitwise.
    timed = {"solve_time", "timings_ns"}
    assert set(ours) == set(theirs)
    for key in set(ours) - timed - {"tendons"}:
        assert ours[key] == theirs[key], key
    for a, b in zip(ours["tendons"], theirs["tendons"]):
        assert set(b) - set(a) == {"end", "turns"}
        assert all(a[k] == b[k] for k in a)
    # The command line reads Python's file as a warm start: nothing left to do.
    (tmp_path / "saved.json").write_text(tdcr.solve(robot).to_json())
    again = json.loads(cli_text(["solve", "robot.toml", "--start", "saved.json", "--format", "json"], cwd=tmp_path))
    assert again["iterations"] <= 2 and again["converged"]
    assert tdcr.Solution.from_json(json.dumps(again)).length == robot.length


def test_a_bad_or_inconsistent_solution_file_raises_invalid_input():
    data = json.loads(tdcr.solve(tdcr.cases.case_s()).to_json())

    def edited(change):
        copy = json.loads(json.dumps(data))
        change(copy)
        return json.dumps(copy)

    bad = [
        (lambda d: d["nodes"][3].update(s=None), r"nodes\[3\]\.s = NaN m"),
        (lambda d: d["nodes"][0].update(s=-1.0), r"nodes\[0\]\.s = -1 m"),
        (lambda d: d["tendons"][0].update(path=[]), r"tendons\[0\]\.path has 0 points"),
        (lambda d: d["tendons"][0].update(path=d["tendons"][0]["path"] * 2), r"tendons\[0\]\.path has \d+ points"),
        (lambda d: d["nodes"][1].update(v=[1.0, 2.0]), "not a complete solution JSON"),
        (lambda d: d.pop("nodes"), "not a complete solution JSON"),
        (lambda d: d.update(converged=False), "says `converged` false"),
    ]
    for change, message in bad:
        with pytest.raises(tdcr.InvalidInput, match=message):
            tdcr.Solution.from_json(edited(change))
    with pytest.raises(tdcr.InvalidInput, match="is not JSON"):
        tdcr.Solution.from_json("[1,")
