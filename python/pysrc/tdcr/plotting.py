"""Plots with matplotlib (the `plot` extra: pip install "./python[plot]").

`plot(solution)` draws a solved shape in 3-D: the backbone, each tendon's path (slack
tendons dashed) and the tip. `plot_history(history)` draws a load history's hysteresis loop
as `tdcr sweep --history --plot` does. `tdcr.figure` writes the command line's own SVG/PNG
picture without matplotlib.
"""

from typing import Any, Optional


def _pyplot() -> Any:
    """matplotlib.pyplot, or an ImportError that says how to install it."""
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            'tdcr.plot needs matplotlib: pip install "./python[plot]" (or pip install matplotlib); '
            "tdcr.figure(robot, solution, 'shape.png') draws without it"
        ) from e
    return plt


def plot(solution: Any, ax: Optional[Any] = None, *, tendons: bool = True, label: Optional[str] = None) -> Any:
    """Draws `solution` (a `tdcr.Solution`) into the 3-D axes `ax` (new ones in a new figure
    when None): the backbone in black (labelled `label`), the tendon paths in the colours of
    matplotlib's cycle (slack tendons dashed) when `tendons`, and the tip as a dot, with a
    legend of the axes' labelled lines (each tendon's tension). Axes in metres with equal
    scales. Returns the axes."""
    plt = _pyplot()
    if ax is None:
        figure = plt.figure()
        ax = figure.add_subplot(projection="3d")
    p = solution.p
    ax.plot(p[:, 0], p[:, 1], p[:, 2], color="black", linewidth=2.0, label=label or "backbone")
    if tendons:
        for i, (path, state) in enumerate(zip(solution.tendon_paths, solution.tendons)):
            slack = state["tension"] <= 0.0
            ax.plot(
                path[:, 0],
                path[:, 1],
                path[:, 2],
                linestyle="--" if slack else "-",
                linewidth=0.8 if slack else 1.2,
                label=f"tendon {i + 1}" + (" (slack)" if slack else f" ({state['tension']:.3g} N)"),
            )
    tip = solution.tip_position
    ax.scatter([tip[0]], [tip[1]], [tip[2]], color="black", s=12)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.legend(fontsize="small")
    # Equal scales on the three axes: a bend looks like a bend.
    ax.set_aspect("equal")
    return ax


def plot_history(history: Any, ax: Optional[Any] = None, *, y: str = "tip_displacement") -> Any:
    """Draws the hysteresis loop of `history` (a `tdcr.History`) into the 2-D axes `ax` (new
    ones in a new figure when None), as `tdcr sweep --history --plot --loop-y Y` does: `y`
    (`History.loop_axis`: "tip_displacement", the tip's distance from its place at the first
    step in mm, by default; "bending_angle" in degrees; "tip_x", "tip_y" or "tip_z" in mm)
    against the swept input (`History.loop_x`: the first input that changes, labelled with
    its unit as the command line labels it), the steps where it rises solid,
    those where it falls dashed. Returns the axes."""
    label_y, values = history.loop_axis(y)
    plt = _pyplot()
    if ax is None:
        ax = plt.figure().add_subplot()
    if len(history) == 0:
        return ax
    label_x, x = history.loop_x()
    directions = history.directions
    labelled = set()
    for k in range(1, len(x)):
        rising = directions[k] != "down"
        label = "loading: the input rises" if rising else "unloading: the input falls"
        ax.plot(
            [x[k - 1], x[k]],
            [values[k - 1], values[k]],
            color="#1f5fa8" if rising else "#e07b00",
            linestyle="-" if rising else "--",
            label=None if label in labelled else label,
        )
        labelled.add(label)
    ax.set_xlabel(label_x)
    ax.set_ylabel(label_y)
    ax.legend()
    return ax
