"""Type stubs of the native module tdcr._native (the Rust crate tdcr through PyO3)."""

from os import PathLike
from typing import Any, Dict, Iterator, List, Literal, Mapping, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
ArrayLike = npt.ArrayLike

__all__ = [
    "__version__",
    "TIP_S",
    "TIP_H",
    "Robot",
    "Solution",
    "SolveReport",
    "State",
    "TipSensitivities",
    "InverseResult",
    "Calibration",
    "solve",
    "solve_batch",
    "solve_parameters",
    "sweep",
    "Sweep",
    "history",
    "History",
    "trace",
    "Trace",
    "Solver",
    "figure",
    "PlausibilityWarning",
    "PoorFitWarning",
    "Event",
    "tip_sensitivities",
    "linearize",
    "Linearization",
    "solve_tensions",
    "solve_displacements",
    "calibrate",
    "compare",
    "case_s",
    "case_h",
    "prototype",
    "example",
    "Error",
    "InvalidInput",
    "FileError",
    "SingularRouting",
    "ModelLimit",
    "Breakdown",
    "NotConverged",
    "IntervalCap",
]

__version__: str
#: Tip of case S (m), `tdcr::cases::TIP_S`.
TIP_S: List[float]
#: Tip of case H (m), `tdcr::cases::TIP_H`.
TIP_H: List[float]

class Error(Exception):
    """The base class of every tdcr exception."""

class InvalidInput(Error):
    """A robot, an option or a parameter is not acceptable (CLI exit code 2)."""

class FileError(InvalidInput):
    """A robot file (or dict) breaks a rule; one line per problem."""

    problems: List[Tuple[Optional[int], Optional[int], str, str]]

class SingularRouting(InvalidInput):
    """A tendon's path has (nearly) no tangent."""

class ModelLimit(Error):
    """The input is valid but the model cannot answer it (CLI exit code 4)."""

class Breakdown(Error):
    """The model equations broke down numerically."""

class NotConverged(Error):
    """A solver stopped without meeting its tolerances."""

    report: SolveReport
    likely_causes: List[str]

class IntervalCap(Error):
    """Adaptive refinement reached `max_intervals` before the tip tolerance was met."""

@final
class Robot:
    """A robot (SI units) with its `[solver]` settings; the robot file's fields and rules."""

    def __new__(
        cls,
        rod: Optional[Mapping[str, Any]] = None,
        tendons: Optional[Sequence[Mapping[str, Any]]] = None,
        loads: Optional[Mapping[str, Any]] = None,
        base: Optional[Mapping[str, Any]] = None,
        solver: Optional[Mapping[str, Any]] = None,
        model: Optional[Mapping[str, Any]] = None,
        disks: Optional[Mapping[str, Any]] = None,
        segments: Optional[Sequence[Mapping[str, Any]]] = None,
    ) -> Robot: ...
    @staticmethod
    def from_dict(tables: Mapping[str, Any]) -> Robot:
        """A robot from a dict of the robot file's tables."""
    @staticmethod
    def from_toml(text: str, name: str = "<string>") -> Robot:
        """A robot from robot-file text; `name` is the file name in messages."""
    @staticmethod
    def from_file(path: Union[str, PathLike[str]]) -> Robot:
        """A robot from a robot file (a regular file of at most 16 MiB)."""
    def to_toml(self) -> str:
        """The robot as robot-file text that reads back to the same robot, bitwise."""
    def with_tensions(self, tensions: Sequence[float]) -> Robot:
        """A copy with the tensions (N) of all tendons, in file order; all tension-controlled."""
    def with_displacements(self, displacements: Sequence[Optional[float]]) -> Robot:
        """A copy with actuator pull-ins (m) per tendon; None: tension-controlled."""
    def with_parameters(self, parameters: Mapping[str, float]) -> Robot:
        """A copy with named parameters set (`tension.1`, `tip_force.z`, `friction.1`, ...;
        docs/parameters.md).

        `tension.I` makes tendon I tension-controlled, as `with_tensions` does."""
    @property
    def length(self) -> float:
        """Rod length L (m)."""
    @property
    def tendon_count(self) -> int:
        """Number of tendons."""
    @property
    def tensions(self) -> FloatArray:
        """Tendon tensions (N), shape (k,)."""
    @property
    def displacements(self) -> List[Optional[float]]:
        """Actuator pull-ins (m) of displacement-controlled tendons, None for the others."""
    @property
    def tendon_stiffnesses(self) -> List[Optional[float]]:
        """Axial stiffnesses E_t A_t (N) of elastic tendons, None for inextensible ones."""
    @property
    def frictions(self) -> List[Optional[float]]:
        """Friction coefficients of the tendons with friction, None for the others."""
    @property
    def motions(self) -> List[Optional[str]]:
        """"pull" or "release" for the tendons with friction (full slip), None for the others."""
    @property
    def free_lengths(self) -> FloatArray:
        """Free lengths (m) between base and actuator, shape (k,)."""
    @property
    def tip_force(self) -> FloatArray:
        """Tip force (N, world frame), shape (3,)."""
    @property
    def tip_moment(self) -> FloatArray:
        """Tip moment (N m, world frame), shape (3,)."""
    @property
    def base_position(self) -> FloatArray:
        """Base position (m), shape (3,)."""
    @property
    def base_rotation(self) -> FloatArray:
        """Base rotation, body to world, shape (3, 3)."""
    @property
    def model(self) -> Dict[str, Any]:
        """The `[model]` table: `corner_forces` (bool), `tendons` ("coupled" or "point_moment") and
        `rod` ("cosserat" or "kirchhoff")."""
    @property
    def method(self) -> str:
        """The `[solver]` method: "collocation" or "shooting"."""

@final
class State:
    """The state at one arc length."""

    s: float
    p: FloatArray
    R: FloatArray
    v: FloatArray
    u: FloatArray

@final
class SolveReport:
    """What a solve did."""

    @property
    def method(self) -> str: ...
    @property
    def termination(self) -> str:
        """Why Newton stopped, as a sentence (the solution JSON's `termination`)."""
    @property
    def termination_code(self) -> str:
        """"converged", "max_iterations", "line_search_failed", "singular_jacobian", "non_finite" or
        "zones_unsettled" (a load-history step whose stick/slip zones did not settle)."""
    @property
    def termination_message(self) -> str:
        """The same sentence as `termination` (its name before 2026-12-08)."""
    @property
    def converged(self) -> bool: ...
    @property
    def iterations(self) -> int:
        """newton_steps + chord_steps, over load steps and meshes."""
    @property
    def newton_steps(self) -> int: ...
    @property
    def chord_steps(self) -> int: ...
    @property
    def jacobian_evaluations(self) -> int: ...
    @property
    def load_steps(self) -> int:
        """Continuation steps along the load path; 0 for a direct solve."""
    @property
    def meshes(self) -> int: ...
    @property
    def residual(self) -> float: ...
    @property
    def history(self) -> FloatArray:
        """Scaled residual before each step of the last Newton run."""
    @property
    def intervals(self) -> int: ...
    @property
    def unknowns(self) -> int: ...
    @property
    def tip_error_estimate(self) -> Optional[float]:
        """Estimated tip position error (m); None for shooting."""
    @property
    def error_estimate(self) -> Optional[Dict[str, float]]:
        """{"tip_position_m", "tip_rotation_rad", "backbone_max_m", "order"} (order: 4, or 6 for
        the deferred-corrected answer at tolerances of 1e-8 and below, or 2 for a history
        step with a stuck stretch, solved on split meshes); None for shooting."""
    @property
    def tolerance(self) -> Optional[float]:
        """The tip tolerance relative to the rod length; None on a fixed mesh."""
    @property
    def tolerance_met(self) -> Optional[bool]:
        """Whether the estimate meets the tolerance; None on a fixed mesh."""
    @property
    def stability(self) -> Literal["stable", "unstable", "unknown"]: ...
    @property
    def stability_message(self) -> str: ...
    @property
    def stability_detail(self) -> Dict[str, Any]:
        """{"verdict", "unstable_directions", "conjugate_point_s", "reason"}."""
    @property
    def path(self) -> Literal["direct", "from_warm_start", "load_path", "fallback"]: ...
    @property
    def folds(self) -> List[float]: ...
    @property
    def bifurcations(self) -> List[float]: ...
    @property
    def notes(self) -> List[str]:
        """What to know about the choice of the answer, one sentence each (a side picked at a
        symmetric bifurcation, a fallback's stalled path); the command line's `note:` lines."""
    @property
    def timings(self) -> Dict[str, float]:
        """Seconds: assembly, factorization, solve, estimate, stability, total."""
    @property
    def evaluations(self) -> Dict[str, int]:
        """Counts: residual, jacobian, equations."""
    def to_dict(self) -> Dict[str, Any]:
        """The report's scalars as one flat dict."""

@final
class Solution:
    """A solved shape; arrays are float64, SI units."""

    def plot(self, ax: Optional[Any] = None, *, tendons: bool = True, label: Optional[str] = None) -> Any:
        """Draws the shape with matplotlib (`tdcr.plot`); returns the axes."""

    @property
    def s(self) -> FloatArray:
        """Arc lengths (m), shape (N,)."""
    @property
    def p(self) -> FloatArray:
        """Positions (m), shape (N, 3)."""
    @property
    def R(self) -> FloatArray:
        """Orientations, shape (N, 3, 3)."""
    @property
    def v(self) -> FloatArray:
        """Shear/extension strains (body frame), shape (N, 3)."""
    @property
    def u(self) -> FloatArray:
        """Curvature/twist (rad/m, body frame), shape (N, 3)."""
    @property
    def n(self) -> FloatArray:
        """Internal forces (N), shape (N, 3)."""
    @property
    def m(self) -> FloatArray:
        """Internal moments (N m), shape (N, 3)."""
    @property
    def tendon_paths(self) -> List[FloatArray]:
        """Each tendon's path (m), (N_i, 3) arrays."""
    @property
    def tendons(self) -> List[Dict[str, float]]:
        """Per tendon: tension, delivered_tension, displacement, length, reference_length, slack."""
    @property
    def tendon_tensions(self) -> List[FloatArray]:
        """Each tendon's tension (N) at the points of its path, (N_i,) arrays."""
    @property
    def tensions(self) -> FloatArray:
        """Tendon tensions (N), shape (k,)."""
    @property
    def tip_position(self) -> FloatArray:
        """Tip position (m), shape (3,)."""
    @property
    def tip_rotation(self) -> FloatArray:
        """Tip orientation, shape (3, 3)."""
    @property
    def length(self) -> float: ...
    @property
    def report(self) -> SolveReport: ...
    def at(self, s: float, left: bool = False) -> State:
        """The state at arc length s (m) from the scheme's interpolant."""
    def tension_at(self, i: int, s: float) -> float:
        """The tension (N) of tendon i (from 0) at arc length s (m), log-linear between path points."""
    def to_json(self) -> str:
        """The whole solution as the solution JSON of `tdcr solve --format json` (docs/cli.md)."""
    @staticmethod
    def from_json(text: str) -> Solution:
        """Reads a solution JSON (`to_json`'s or the command line's), bitwise."""

@final
class TipSensitivities:
    """Derivatives of the tip pose (6 rows: position, rotation vector)."""

    @property
    def tension(self) -> FloatArray:
        """(6, k), per N (zero columns for displacement-controlled tendons; a tendon at 0 N,
        with friction too, has the one-sided derivative of its first pull)."""
    @property
    def displacement(self) -> FloatArray:
        """(6, k), per m of pull-in (zero columns for tension-controlled or slack tendons)."""
    @property
    def friction(self) -> FloatArray:
        """(6, k), per unit of the friction coefficient (zero columns without friction)."""
    @property
    def tip_force(self) -> FloatArray:
        """(6, 3), per N."""
    @property
    def tip_moment(self) -> FloatArray:
        """(6, 3), per N m."""
    @property
    def compliance(self) -> FloatArray:
        """(6, 6): tip force then tip moment columns."""
    @property
    def base_position(self) -> FloatArray:
        """(6, 3), per m."""
    @property
    def base_rotation(self) -> FloatArray:
        """(6, 3), per rad."""
    @property
    def youngs_modulus(self) -> Optional[FloatArray]:
        """(6,), per Pa, or None."""

@final
class Linearization:
    """Solved rows kept for gradients (`linearize`): outputs and their vector-Jacobian products."""

    @property
    def parameter_names(self) -> List[str]:
        """The parameter columns, the order of the gradient's columns."""
    @property
    def samples(self) -> FloatArray:
        """(K,) arc lengths of the backbone points, m."""
    @property
    def tip_position(self) -> FloatArray:
        """(M, 3) tip positions, m."""
    @property
    def tip_rotation(self) -> FloatArray:
        """(M, 3, 3) tip orientations, body to world."""
    @property
    def points(self) -> FloatArray:
        """(M, K, 3) backbone points at the samples, m."""
    def vjp(
        self,
        tip_position: Optional[ArrayLike] = None,
        tip_rotation: Optional[ArrayLike] = None,
        points: Optional[ArrayLike] = None,
    ) -> FloatArray:
        """(M, P) dloss/dq from cotangents (M, 3), (M, 3, 3), (M, K, 3) (None: zero), by the adjoint."""

def linearize(
    robot: Robot, parameters: Mapping[str, ArrayLike], samples: Optional[ArrayLike] = None, **options: Any
) -> Linearization:
    """Solves the rows (one robot, parameter columns) and keeps them for gradients (docs/python.md)."""

@final
class InverseResult:
    """The result of `solve_tensions` and `solve_displacements`."""

    tensions: FloatArray
    displacements: FloatArray
    bounds: List[Literal["inside", "slack", "saturated", "released", "tension_limit", "held"]]
    solution: Solution
    residual: float
    position_error: float
    orientation_error: Optional[float]
    reachable: bool
    termination: str
    iterations: int
    forward_solves: int
    explanation: str

def solve(
    robot: Robot,
    *,
    warm_start: Optional[Solution] = None,
    method: Optional[Literal["collocation", "shooting"]] = None,
    tol: Optional[float] = None,
    intervals: Optional[int] = None,
    max_intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    continuation: Optional[bool] = None,
    equilibrium: Optional[Literal["load_path", "nearest"]] = None,
    integration_tolerance: Optional[float] = None,
) -> Solution:
    """Solves `robot` (GIL released). `tol` is the tip tolerance relative to the rod
    length L (default 1e-7): the mesh is refined until the estimated tip position error is at
    most tol x L and the orientation error at most tol rad."""

def compare(
    robot: Robot,
    *,
    models: Optional[
        Sequence[Literal["coupled", "point_moment", "constant_curvature", "paper_jumps", "kirchhoff"]]
    ] = None,
    methods: Optional[Sequence[Literal["collocation", "shooting"]]] = None,
    method: Optional[Literal["collocation", "shooting"]] = None,
    tol: Optional[float] = None,
    intervals: Optional[int] = None,
    max_intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    continuation: Optional[bool] = None,
    equilibrium: Optional[Literal["load_path", "nearest"]] = None,
    integration_tolerance: Optional[float] = None,
) -> List[Dict[str, Any]]:
    """`robot` solved as each of `models` (default all five) or by each of `methods`; one
    dict per shape: name, s, p, tip_position, tip_rotation, tip_distance (m) and tip_angle
    (rad) from the first shape's tip."""

def solve_batch(
    robots: Union[Sequence[Robot], Robot],
    parameters: Optional[Mapping[str, ArrayLike]] = None,
    *,
    errors: Literal["raise", "return"] = "raise",
    tol: Optional[float] = None,
    intervals: Optional[int] = None,
    max_intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    continuation: Optional[bool] = None,
    equilibrium: Optional[Literal["load_path", "nearest"]] = None,
) -> List[Any]:
    """Solves many robots on all cores (GIL released), results in input order; stops at the
    first failure with errors="raise"; Ctrl-C raises KeyboardInterrupt with `completed` and
    `partial` (the finished rows)."""

def solve_parameters(
    robot: Robot,
    parameters: Mapping[str, ArrayLike],
    *,
    orientation: bool = False,
    error_estimate: bool = False,
    points: int = 0,
    progress: Optional[bool] = None,
    tol: Optional[float] = None,
    intervals: Optional[int] = None,
    max_intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    continuation: Optional[bool] = None,
    equilibrium: Optional[Literal["load_path", "nearest"]] = None,
) -> Dict[str, Any]:
    """`solve_batch` of parameter rows reduced to arrays (constant memory per row); optional
    `tip_orientation` (M, 4) quaternion (w, x, y, z), `error_estimate` (M,), `points` (M, K, 3)
    at s = j L / (K - 1); `delivered_I` (M,) per tendon I with friction (N, at its
    termination); a progress line on stderr past a second (`progress`, None: on a
    terminal). Ctrl-C raises KeyboardInterrupt with `completed` and `partial`."""

@final
class Event:
    """An event of a sweep or a trace, located to 1e-6 of the range."""

    kind: str
    """`snap`, `bifurcation`, `taut` or `slack` (a sweep); `fold` or `bifurcation` (a trace)."""
    value: Optional[float]
    """The swept or traced input's value at the event."""
    parameter: Optional[str]
    """The input, e.g. `tension.5`."""
    step: Optional[int]
    """A sweep's step (from 0) the event is reported at (the first past it; for a snap from an unstable branch to a stable state, the step that found that state); None in a trace."""
    text: str
    """The event in words."""

@final
class Sweep:
    """The result of `sweep`: every step's solution and the events between steps; also the
    sequence of the solutions."""

    @property
    def solutions(self) -> List[Solution]:
        """The solutions, one per step solved, in order."""
    @property
    def events(self) -> List[Event]:
        """The events between steps, located to 1e-6 of the range (`snap`, `bifurcation`,
        `taut`, `slack`); `tdcr sweep`'s `event` column holds their `text`."""
    @property
    def jumps(self) -> List[int]:
        """The steps (from 0) reached by a snap: the tip jumped off the branch it was on."""
    @property
    def tip_positions(self) -> FloatArray:
        """Tip positions (m, world frame), shape (n, 3)."""
    def __len__(self) -> int: ...
    def __getitem__(self, index: int, /) -> Solution: ...
    def __iter__(self) -> Iterator[Solution]: ...

def sweep(
    robot: Robot,
    parameters: Mapping[str, ArrayLike],
    *,
    tol: Optional[float] = None,
    intervals: Optional[int] = None,
    max_intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    continuation: Optional[bool] = None,
    equilibrium: Optional[Literal["load_path", "nearest"]] = None,
) -> Sweep:
    """Solves parameter rows in order, each warm-started from the last, with the events;
    Ctrl-C raises KeyboardInterrupt with `completed` and `partial` (the Sweep so far)."""

@final
class History:
    """The result of `history`: every step's solution and the stick/slip zones of each
    tendon with friction; also the sequence of the solutions."""

    @property
    def solutions(self) -> List[Solution]:
        """The solutions, one per step solved, in order."""
    @property
    def zones(self) -> List[List[Tuple[int, List[Tuple[float, float, str]]]]]:
        """Per step, per tendon with friction: (tendon index from 0, [(start, end, contact),
        ...]) from its base entry to its termination (m), contact `pull`, `release`, `stick` or `slack` (0 N)."""
    @property
    def inputs(self) -> Dict[str, FloatArray]:
        """Each input's values at the steps solved, by name, shape (n,)."""
    @property
    def directions(self) -> List[str]:
        """Each step's direction of the swept input: "from_rest" (the first step), then "up", "down" or "held"."""
    @property
    def tip_positions(self) -> FloatArray:
        """Tip positions (m, world frame), shape (n, 3)."""
    @property
    def tip_displacements(self) -> FloatArray:
        """The tip's distance from its place at the first step (m), shape (n,)."""
    def loop_axis(
        self, y: Literal["tip_displacement", "bending_angle", "tip_x", "tip_y", "tip_z"] = "tip_displacement"
    ) -> Tuple[str, FloatArray]:
        """The hysteresis loop's y axis as `tdcr sweep --history --plot --loop-y Y` draws it:
        (label with unit, value per step in mm or deg)."""
    def loop_x(self) -> Tuple[str, FloatArray]:
        """The hysteresis loop's x axis as `tdcr sweep --history --plot` draws it: the swept
        input's label with the library's unit (e.g. "tension.1 (N)") and its value per step."""
    def __len__(self) -> int: ...
    def __getitem__(self, index: int, /) -> Solution: ...
    def __iter__(self) -> Iterator[Solution]: ...

def history(
    robot: Robot,
    parameters: Mapping[str, ArrayLike],
    up_down: bool = False,
    *,
    tol: Optional[float] = None,
    intervals: Optional[int] = None,
    max_intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    continuation: Optional[bool] = None,
    equilibrium: Optional[Literal["load_path", "nearest"]] = None,
) -> History:
    """Solves parameter rows in order as a load history with stick/slip friction (each step
    from the tendon state the last left); with `up_down`, up and then back down. The rows may
    be tensions ("tension.I"), pull-ins ("displacement.I": each step finds the base tension
    that holds its pull-in, docs/friction.md section 8) or any other parameter. Every step
    has an error estimate; a step with a stuck stretch is solved on its mesh split in 2, 4,
    ... parts until two answers agree to `tol` (estimate order 2). A failed step raises with
    `index` and `partial` (the History before it)."""

@final
class Trace:
    """The result of `trace`: the points of a branch of equilibria, in the order it passes them."""

    parameter: str
    values: FloatArray
    tip_positions: FloatArray
    unstable_directions: List[Optional[int]]
    stability: List[str]
    fold: List[bool]
    folds: List[float]
    bifurcations: List[float]
    events: List[Event]
    stopped: Optional[str]
    iterations: int

def trace(
    robot: Robot,
    parameter: str,
    start: float,
    stop: float,
    *,
    tol: Optional[float] = None,
    intervals: Optional[int] = None,
    max_intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    continuation: Optional[bool] = None,
    equilibrium: Optional[Literal["load_path", "nearest"]] = None,
) -> Trace:
    """Follows the branch of equilibria from `start` to `stop` of one input, through folds."""

def tip_sensitivities(robot: Robot, solution: Solution) -> TipSensitivities:
    """Tip Jacobians and compliance of a collocation solution."""

def solve_tensions(
    robot: Robot,
    position: ArrayLike,
    rotation: Optional[ArrayLike] = None,
    *,
    max_tension: float,
    tolerance: float = 1e-6,
    max_iterations: int = 50,
    orientation_weight: Optional[float] = None,
    free_tendons: Optional[Sequence[int]] = None,
    intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
) -> InverseResult:
    """Inverse statics: tensions in [0, max_tension] that put the tip at `position`."""

def solve_displacements(
    robot: Robot,
    position: ArrayLike,
    rotation: Optional[ArrayLike] = None,
    *,
    max_displacement: float,
    min_displacement: Optional[float] = None,
    max_tension: float = 0.0,
    tolerance: float = 1e-6,
    max_iterations: int = 50,
    orientation_weight: Optional[float] = None,
    free_tendons: Optional[Sequence[int]] = None,
    intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
) -> InverseResult:
    """Inverse statics in actuator space: pull-ins in [min_displacement, max_displacement]
    (m; min_displacement defaults to -max_displacement) that put the tip at `position`."""

@final
class Calibration:
    """The result of `calibrate`."""

    names: List[str]
    youngs_modulus: float
    euler_deg: FloatArray
    base_position: FloatArray
    offset_scale: float
    friction: float
    """Fitted friction coefficient of the tendons with friction (0 without friction)."""
    standard_errors: Optional[Dict[str, float]]
    """Standard errors of the fitted unknowns keyed by `names`, in the attributes' units
    (E in Pa, alpha/beta/gamma in deg, x0/y0/z0 in m); None when there are no more residuals
    than unknowns or the fit is singular."""
    noise_estimate: float
    """Noise estimate per tip coordinate (m), the sigma of the standard errors."""
    robot: Robot
    tips: FloatArray
    tip_errors: FloatArray
    rms_error: float
    max_error: float
    converged: bool
    termination: str
    iterations: int
    solves: int
    poor_fit: Optional[str]
    """Why the fit does not explain the data (noise estimate far above `noise`, or above
    1.5 % of the rod length without it), with the likely causes; None when it does."""

def calibrate(
    robot: Robot,
    tensions: ArrayLike,
    tip_forces: ArrayLike,
    measured_tips: ArrayLike,
    *,
    fit: Optional[
        Sequence[
            Literal[
                "youngs_modulus", "euler", "base_position", "offset_scale", "friction", "e", "position", "offset", "mu"
            ]
        ]
    ] = None,
    motions: Optional[Sequence[Optional[Literal["pull", "release"]]]] = None,
    max_iterations: int = 50,
    noise: Optional[float] = None,
    intervals: Optional[int] = None,
    residual_tolerance: Optional[float] = None,
) -> Calibration:
    """Fits E and the base Euler angles (by default) to measured tips; a fit far above the
    measurement `noise` (m per coordinate) sets `poor_fit` and warns (`PoorFitWarning`);
    Ctrl-C raises KeyboardInterrupt (no result)."""

def case_s() -> Robot:
    """Reference case S."""

def case_h() -> Robot:
    """Reference case H."""

def prototype() -> Robot:
    """The prototype, all tendons slack."""

def example() -> str:
    """The commented example robot file."""

@final
class Solver:
    """A collocation solver that keeps its workspace between solves (control loops): warm
    starts on the last solve's factors, and the control Jacobians (only the columns asked
    for) from the same workspace. Options as `solve`'s (collocation)."""

    def __new__(
        cls,
        robot: Optional[Robot] = None,
        *,
        tol: Optional[float] = None,
        intervals: Optional[int] = None,
        max_intervals: Optional[int] = None,
        residual_tolerance: Optional[float] = None,
        max_iterations: Optional[int] = None,
        continuation: Optional[bool] = None,
        equilibrium: Optional[Literal["load_path", "nearest"]] = None,
        method: Optional[Literal["collocation"]] = None,
    ) -> Solver: ...
    def solve(
        self,
        robot: Union[Robot, Mapping[str, float], None] = None,
        /,
        parameters: Optional[Mapping[str, float]] = None,
        *,
        tension: Optional[ArrayLike] = None,
    ) -> Solution:
        """Solves the current robot (replaced by `robot`, changed by `parameters` and
        `tension`, which stay set), warm-started from the last solution."""
    def tip_jacobian(self, wrt: Union[str, Sequence[str], None] = None) -> FloatArray:
        """(6, n): the columns `wrt` (default "tension") of d(tip pose)/dq at the last
        solution, in the layout of `TipSensitivities.tension`."""
    def tip_sensitivities(self, robot: Optional[Robot] = None, solution: Optional[Solution] = None) -> TipSensitivities:
        """Every tip sensitivity at the last solution (or at `solution` of `robot`, given
        both), as `tip_sensitivities(robot, solution)`, from the solver's workspace."""
    def backbone_jacobian(self, s: ArrayLike, wrt: Union[str, Sequence[str], None] = None) -> FloatArray:
        """(len(s), 3, n): d p(s_j)/dq at the arc lengths `s` (m) of the last solution."""
    def keep_tension_columns(self, on: bool) -> None:
        """Whether a warm solve's stability verdict also forms the tension columns'
        right-hand sides for the next `tip_jacobian()` (a few per cent more per solve,
        the same answers; off by default)."""
    def reset(self) -> None:
        """Forgets the workspace, its factors and the last solution (the robot stays)."""
    @property
    def robot(self) -> Optional[Robot]:
        """The current robot, or None."""
    @property
    def solution(self) -> Optional[Solution]:
        """The last solution, or None."""

class PlausibilityWarning(UserWarning):
    """A robot's scales or loads are far from any tendon robot's (a 200 m rod, ...)."""

class PoorFitWarning(UserWarning):
    """A calibration converged but does not explain the data (`Calibration.poor_fit`)."""

def figure(
    robot: Robot,
    solution: Solution,
    path: Union[str, "PathLike[str]"],
    *,
    views: Optional[Sequence[Literal["top", "side", "front", "perspective"]]] = None,
    width: Optional[float] = None,
    font_size: Optional[float] = None,
    title: Optional[str] = None,
    disks: Optional[int] = None,
) -> None:
    """Draws `solution` into `path` as `tdcr solve --plot` does (PNG for .png, else SVG)."""
