"""tdcr: shapes of tendon-driven continuum robots (Cosserat rod model) from Python.

The Rust crate tdcr is the one implementation; this package converts types and calls it.

    import tdcr
    robot = tdcr.cases.case_h()            # or tdcr.Robot.from_file("robot.toml")
    solution = tdcr.solve(robot, tol=1e-9) # tip error to 1e-9 x rod length
    solution.tip_position                  # (3,) float64, m
    solution.p, solution.R                 # (N, 3), (N, 3, 3)

Robots: `Robot` (from TOML text, a file, keyword arguments or a dict; the robot file's
fields and rules). Solving: `solve`, `Solver` (stateful, warm starts and control
Jacobians for control loops), `solve_batch` (all cores, GIL released), `sweep`
(warm-started sequence with its events), `trace` (a branch of equilibria through folds), `history` (a load history with
stick/slip friction: the hysteresis loop),
`solve_parameters` (arrays in, arrays out), `dataset` (sampled rows solved in chunks to .npz or
.parquet, resumable). Analyses:
`tip_sensitivities` (Jacobians, compliance), `linearize` (gradients by the adjoint; `tdcr.torch`
and `tdcr.jax` wrap it, with the `torch` and `jax` extras), `solve_tensions` and `solve_displacements` (inverse statics), `calibrate` (E and base angles from measured tips). Cases:
`tdcr.cases`. A cluster: `tdcr.distributed` (Dask). Errors: `Error` and its subclasses
`InvalidInput` (with `FileError`, `SingularRouting`), `ModelLimit`, `NotConverged`,
`IntervalCap`, `Breakdown`; warnings: `PlausibilityWarning`, `PoorFitWarning`. Pictures: `plot` and `Solution.plot`
(matplotlib, the `plot` extra), `figure` (the command line's SVG/PNG picture). docs/python.md
is the walk-through.
"""

from ._native import (
    Breakdown,
    Calibration,
    Error,
    Event,
    FileError,
    PlausibilityWarning,
    PoorFitWarning,
    IntervalCap,
    InvalidInput,
    InverseResult,
    Linearization,
    ModelLimit,
    NotConverged,
    Robot,
    SingularRouting,
    Solution,
    SolveReport,
    Solver,
    State,
    History,
    Sweep,
    TipSensitivities,
    Trace,
    __version__,
    calibrate,
    compare,
    example,
    figure,
    history,
    linearize,
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
from ._dataset import dataset
from .plotting import plot, plot_history

__all__ = [
    "Breakdown",
    "Calibration",
    "Error",
    "Event",
    "FileError",
    "History",
    "PlausibilityWarning",
    "PoorFitWarning",
    "IntervalCap",
    "InvalidInput",
    "InverseResult",
    "Linearization",
    "ModelLimit",
    "NotConverged",
    "Robot",
    "SingularRouting",
    "Solution",
    "SolveReport",
    "Solver",
    "State",
    "Sweep",
    "TipSensitivities",
    "Trace",
    "__version__",
    "calibrate",
    "cases",
    "compare",
    "dataset",
    "example",
    "figure",
    "history",
    "linearize",
    "plot",
    "plot_history",
    "solve",
    "solve_batch",
    "solve_displacements",
    "solve_parameters",
    "solve_tensions",
    "sweep",
    "tip_sensitivities",
    "trace",
]
