"""Model variants from Python (issue 27): the `model` keyword and property are the robot
file's `[model]` table."""

import pickle

import numpy as np

import tdcr

# Tendon 1 ends mid-way, tendon 2 goes on at 1 N, and a tip force shears the rod: the corner
# forces of tendon 2 at the termination move the tip.
EXAMPLE = (
    tdcr.example()
    .replace("# end = 0.242 ", "end = 0.121 #")
    .replace("tip_force = [0.0, 0.0, 0.0]", "tip_force = [0.0, 0.1, -0.05]")
    .replace("tension = 0.0", "tension = 1.0", 1)
)


def test_the_model_keyword_is_the_model_table(cli):
    default = tdcr.Robot.from_toml(EXAMPLE)
    assert default.model == {"corner_forces": True, "tendons": "coupled", "rod": "cosserat"}
    tables = tdcr.Robot.from_toml(EXAMPLE)
    for model, flags in [
        ({"corner_forces": False}, ["--corner-forces", "false"]),
        ({"tendons": "point_moment"}, ["--tendons", "point_moment"]),
        ({"rod": "kirchhoff"}, ["--rod", "kirchhoff"]),
    ]:
        table = "\n[model]\n" + "".join(
            f"{k} = {str(v).lower() if isinstance(v, bool) else repr(v).replace(chr(39), chr(34))}\n"
            for k, v in model.items()
        )
        from_file = tdcr.Robot.from_toml(EXAMPLE + table)
        from_dict = tdcr.Robot(**KEYWORDS, model=model)
        assert from_file.model == from_dict.model == {**default.model, **model}
        tips = [tdcr.solve(r).tip_position for r in [from_file, from_dict, pickle.loads(pickle.dumps(from_file))]]
        json = cli(["solve", "-", "--format", "json", *flags], EXAMPLE)
        # Bitwise: the keyword, the table, the pickle and the flag set the same switch.
        for tip in tips[1:] + [np.array(json["tip"]["position"])]:
            assert np.array_equal(tip, tips[0])
        assert not np.array_equal(tips[0], tdcr.solve(default).tip_position)
    keywords = tdcr.Robot(
        {"length": 0.2, "outer_radius": 0.0005, "youngs_modulus": 50e9, "poisson_ratio": 0.3},
        model={"corner_forces": False, "tendons": "point_moment", "rod": "kirchhoff"},
    )
    assert keywords.model == {"corner_forces": False, "tendons": "point_moment", "rod": "kirchhoff"}


# EXAMPLE as keyword arguments.
KEYWORDS = {
    "rod": {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125},
    "base": {"position": [0.0, 0.0, 0.0], "rotation": [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]},
    "loads": {"distributed_force": [0.0, 0.0, -0.47], "tip_force": [0.0, 0.1, -0.05]},
    "tendons": [
        {"routing": {"kind": "straight", "x": 0.008, "y": 0.0}, "tension": 2.94, "end": 0.121},
        {"routing": {"kind": "straight", "x": 0.0, "y": 0.008}, "tension": 1.0},
        {"routing": {"kind": "straight", "x": -0.008, "y": 0.0}, "tension": 0.0},
        {"routing": {"kind": "straight", "x": 0.0, "y": -0.008}, "tension": 0.0},
        {"routing": {"kind": "helical", "radius": 0.008, "turns_per_rod_length": 1.0}, "tension": 0.0},
    ],
}


def test_disks_are_point_loads_that_survive_a_pickle():
    rod = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125}
    tendons = [{"routing": {"kind": "straight", "radius": 0.008, "angle_deg": 90}, "tension": 1.0}]
    base = {"euler_xyz_deg": [0.0, 90.0, 0.0]}
    disks = {"positions": [0.1, 0.242], "mass": 0.005, "gravity": [0.0, 0.0, -9.81]}
    with_disks = tdcr.Robot(rod, tendons=tendons, base=base, disks=disks)
    weight = [0.0, 0.0, 0.005 * -9.81]
    by_hand = tdcr.Robot(
        rod, tendons=tendons, base=base, loads={"point": [{"s": 0.1, "force": weight}, {"s": 0.242, "force": weight}]}
    )
    again = pickle.loads(pickle.dumps(with_disks))
    assert "[disks]" in again.to_toml()
    tips = [tdcr.solve(r).tip_position for r in [with_disks, by_hand, again]]
    # Bitwise: the disks are these point loads, and the pickle keeps them.
    assert np.array_equal(tips[0], tips[1]) and np.array_equal(tips[0], tips[2])
    assert not np.array_equal(tips[0], tdcr.solve(tdcr.Robot(rod, tendons=tendons, base=base)).tip_position)


def test_compare_solves_each_model_and_measures_the_tips():
    robot = tdcr.Robot.from_toml(EXAMPLE + "\n[model]\ncorner_forces = false\n")
    shapes = tdcr.compare(robot)
    assert [c["name"] for c in shapes] == ["coupled", "point_moment", "constant_curvature", "paper_jumps", "kirchhoff"]
    coupled = tdcr.Robot.from_toml(EXAMPLE)
    # Bitwise: each model is the robot with its switches set, solved as tdcr.solve does.
    assert np.array_equal(shapes[0]["tip_position"], tdcr.solve(coupled).tip_position)
    assert np.array_equal(shapes[3]["tip_position"], tdcr.solve(robot).tip_position)
    assert shapes[0]["tip_distance"] == 0.0 and shapes[0]["tip_angle"] == 0.0
    for c in shapes[1:]:
        # 1e-15 relative: the library's and numpy's Euclidean norms sum in different orders,
        # so the same difference can round one unit in the last place apart.
        distance = np.linalg.norm(c["tip_position"] - shapes[0]["tip_position"])
        assert abs(c["tip_distance"] - distance) <= 1e-15 * distance
        assert c["tip_distance"] > 0.0 and c["tip_angle"] > 0.0
        assert c["p"].shape == (c["s"].shape[0], 3)
    methods = tdcr.compare(coupled, methods=["collocation", "shooting"])
    # 1e-8 m: the solvers' agreement at their default tolerances (tests/cross_check.rs)
    assert [c["name"] for c in methods] == ["collocation", "shooting"] and methods[1]["tip_distance"] < 1e-8
    for bad in [{"models": ["kirchoff"]}, {"methods": ["euler"]}, {"models": ["coupled"], "methods": ["shooting"]}]:
        try:
            tdcr.compare(coupled, **bad)
        except tdcr.InvalidInput:
            continue
        raise AssertionError(bad)
