"""``poincare``: the Poincare section, once per crank revolution (docs/physics.md 8.4).

Per clearance joint, the ball-centre offset over the clearance at each revolution's section,
on the plane of the two socket-frame axes along which the sections spread most (a ball
seated on its socket moves along the wall, across the mean contact normal: the two axes
that show that motion, with the clearance circle); then the slider acceleration at each
section against the revolution. One point per joint and revolution: a periodic motion of
period n draws n points, once its start has died away.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..analysis import ideal_joints, value_text
from .common import (
    PlotError,
    _case_label,
    _cases,
    _legend_note,
    _require,
    axis_label,
    figure_legend,
    file_figures,
    joint_kind,
    joint_name,
    keep_relative_span,
    section_axes,
)

#: Fewest revolutions a ``poincare`` figure draws: one section shows no return.
MIN_REVOLUTIONS = 2


def _draw_poincare(fig: Figure, ds: xr.Dataset) -> None:
    if not file_figures(ds).sections or "poincare_time" in ds:
        _require(ds, ("poincare_offset", "poincare_slider_acc", "poincare_time"), "--kind poincare")
    # revolutions with a section in any case (a run shorter than one has none)
    taken = 0
    if "poincare_time" in ds:
        times = ds["poincare_time"].transpose("revolution", ...).values
        taken = int(np.isfinite(times.reshape(times.shape[0], -1)).any(axis=1).sum())
    if taken < MIN_REVOLUTIONS:
        raise PlotError(f"--kind poincare needs at least {MIN_REVOLUTIONS} crank revolutions "
                        f"(one Poincare section each); these results hold {taken}: run for "
                        "solver.revolutions >= 2 (solver.duration >= 2 x 60 / "
                        "mechanism.speed_rpm s)")
    offset = ds["poincare_offset"]
    cases = _cases(ds)
    # a joint without offsets gets no panel; an ideal joint (no offsets) is not named
    ideal = ideal_joints(ds)
    joints = [j for j in offset["joint"].values if np.isfinite(offset.sel(joint=j).values).any()]
    empty = [value_text(j) for j in offset["joint"].values
             if j not in joints and value_text(j) not in ideal]
    panels = len(joints) + 1
    fig.set_size_inches(max(4.6 * panels, 8.0), 5.4)
    circle = np.linspace(0.0, 2.0 * np.pi, 361)
    for p, joint in enumerate(joints):
        ax = fig.add_subplot(1, panels, p + 1)
        sel = offset.sel(joint=joint)
        a, b = section_axes(np.moveaxis(sel.values, sel.dims.index("axis"), -1),
                            sel["axis"].values)
        for text, case, colour in cases:
            d = case["poincare_offset"].sel(joint=joint)
            ax.plot(d.sel(axis=a).values, d.sel(axis=b).values, ls="none", marker="o", ms=3.5,
                    color=colour, label=_case_label(text, len(cases), "section"))
        ax.plot(np.cos(circle), np.sin(circle), lw=0.8, ls="--", color="0.45",
                label="clearance circle |d| = c")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(axis_label(offset, f"d_{a} / c"))
        ax.set_ylabel(axis_label(offset, f"d_{b} / c"))
        centre = joint_kind(ds, joint).centre
        ax.set_title(f"{joint_name(value_text(joint), ds)}: {centre} centre, {a}{b} plane",
                     fontsize="small")
        ax.grid(alpha=0.3)
    ax = fig.add_subplot(1, panels, panels)
    acc = ds["poincare_slider_acc"]
    for text, case, colour in cases:
        ax.plot(case["revolution"].values, case["poincare_slider_acc"].values, ls="none",
                marker="o", ms=3.5, color=colour, label=_case_label(text, len(cases), "section"))
    ax.set_xlabel(axis_label(ds["revolution"], "revolution"))
    ax.set_ylabel(axis_label(acc, "slider acceleration"))
    # a fixed point (a spread of round-off) draws as one point, not as that spread at full scale
    note = keep_relative_span(ax, acc.values)
    ax.set_title("slider acceleration at the section" + (f"\n({note})" if note else ""),
                 fontsize="small")
    ax.grid(alpha=0.3)
    figure_legend(fig)
    left_out = f"\nnot drawn: {', '.join(map(joint_name, empty))}, no section" if empty else ""
    fig.suptitle("Poincare section, once per crank revolution" + _legend_note(len(cases))
                 + left_out)
