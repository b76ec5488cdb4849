"""Rods of segments from Python (issue 27): the `segments` keyword is the robot file's
`[[segment]]` tables, and tendons end at a segment by `end_segment`."""

import pickle

import numpy as np
import pytest

import tdcr

SEGMENTS = [
    {"length": 0.15, "outer_radius": 0.0008, "inner_radius": 0.0005, "youngs_modulus": 60e9, "poisson_ratio": 0.3},
    {
        "length": 0.1,
        "bending_stiffness": 1.2e-3,
        "torsion_stiffness": 0.93e-3,
        "axial_stiffness": 3.0e4,
        "shear_stiffness": 1.15e4,
        "precurvature": [0.0, 3.0, 0.0],
    },
]
TENDONS = [
    {"routing": {"kind": "straight", "radius": 0.004, "angle_deg": 0.0}, "tension": 2.0, "end_segment": 1},
    {"routing": {"kind": "straight", "radius": 0.004, "angle_deg": 90.0}, "tension": 0.4},
]
FILE = """
[[segment]]
length = 0.15
outer_radius = 0.0008
inner_radius = 0.0005
youngs_modulus = 60e9
poisson_ratio = 0.3

[[segment]]
length = 0.1
bending_stiffness = 1.2e-3
torsion_stiffness = 0.93e-3
axial_stiffness = 3.0e4
shear_stiffness = 1.15e4
precurvature = [0.0, 3.0, 0.0]

[[tendon]]
routing = { kind = "straight", radius = 0.004, angle_deg = 0 }
tension = 2.0
end_segment = 1
[[tendon]]
routing = { kind = "straight", radius = 0.004, angle_deg = 90 }
tension = 0.4
"""


def test_the_segments_keyword_is_the_segment_tables():
    from_keywords = tdcr.Robot(segments=SEGMENTS, tendons=TENDONS)
    from_file = tdcr.Robot.from_toml(FILE)
    assert from_keywords.length == from_file.length == 0.25
    tips = [tdcr.solve(r).tip_position for r in [from_keywords, from_file, pickle.loads(pickle.dumps(from_file))]]
    # Bitwise: the keyword, the file and the pickle (written back as [[segment]]) agree.
    for tip in tips[1:]:
        assert np.array_equal(tip, tips[0])
    # The soft, precurved second segment bends the tip well away from the axis.
    assert tips[0][0] > 0.02


def test_bad_segments_raise_file_errors_naming_the_field():
    with pytest.raises(tdcr.FileError, match=r"segment\[2\]\.torsion_stiffness"):
        tdcr.Robot(segments=[SEGMENTS[0], {"length": 0.1, "bending_stiffness": 1e-3}], tendons=TENDONS)
    with pytest.raises(tdcr.FileError, match=r"tendon\[1\]\.end_segment"):
        tdcr.Robot(segments=SEGMENTS[:1], tendons=[{**TENDONS[0], "end_segment": 2}])
