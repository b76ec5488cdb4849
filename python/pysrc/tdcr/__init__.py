"""tdcr: shapes of tendon-driven continuum robots (Cosserat rod model) from Python.

The Rust crate tdcr is the one implementation; this package converts types and calls it.

    import tdcr
    robot = tdcr.cases.case_h()            # or tdcr.Robot.from_file("robot.toml")
    solution = tdcr.solve(robot, tol=1e-9) # tip error to 1e-9 x rod length
    solution.tip_position                  # (3,) float64, m
    solution.p, solution.R                 # (N, 3), (N, 3, 3)

Robots: `Robot` (from TOML text, a file, keyword arguments or a dict; the robot file's
fields and rules). Solving: `solve`, `solve_batch` (all cores, GIL released), `sweep`
(warm-started sequence with its events), `trace` (a branch of equilibria through folds),
`solve_parameters` (arrays in, arrays out). Analyses:
`tip_sensitivities` (Jacobians, compliance), `solve_tensions` and `solve_displacements` (inverse statics), `calibrate` (E and base angles from measured tips). Cases:
`tdcr.cases`. A cluster: `tdcr.distributed` (Dask). Errors: `Error` and its subclasses
`InvalidInput` (with `FileError`, `SingularRouting`), `NotConverged`, `IntervalCap`,
`Breakdown`. docs/python.md is the walk-through.
"""

from ._native import (
    Breakdown,
    Calibration,
    Error,
    Event,
    FileError,
    IntervalCap,
    InvalidInput,
    InverseResult,
    NotConverged,
    Robot,
    SingularRouting,
    Solution,
    SolveReport,
    State,
    Sweep,
    TipSensitivities,
    Trace,
    __version__,
    calibrate,
    compare,
    example,
    solve,
    solve_batch,
    solve_displacements,
    solve_parameters,
    solve_tensions,
    sweep,
    tip_sensitivities,
    trace,
)
from . import cases

__all__ = [
    "Breakdown",
    "Calibration",
    "Error",
    "Event",
    "FileError",
    "IntervalCap",
    "InvalidInput",
    "InverseResult",
    "NotConverged",
    "Robot",
    "SingularRouting",
    "Solution",
    "SolveReport",
    "State",
    "Sweep",
    "TipSensitivities",
    "Trace",
    "__version__",
    "calibrate",
    "cases",
    "compare",
    "example",
    "solve",
    "solve_batch",
    "solve_displacements",
    "solve_parameters",
    "solve_tensions",
    "sweep",
    "tip_sensitivities",
    "trace",
]
