"""``orbit``: the ball-centre offset in the socket frame inside the clearance circle, and the
guide block's centre inside its rectangular gap. A planar mechanism's joints (the
slider-crank's) get one panel each, the plane of the socket frame the centre moves in."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..analysis import bushing_joints, configured_clearances, guide_gap, is_planar, value_text
from .common import (
    QUANTITY_UNITS,
    PlotError,
    _case_label,
    _cases,
    _clearance_joints,
    _legend_note,
    _require,
    axis_label,
    figure_legend,
    joint_kind,
    joint_name,
    keep_relative_span,
    section_axes,
)

#: A planar mechanism's centre off its plane by more than this fraction of the largest offset
#: drawn is named in its panel's title (round-off stays near 1e-12 of it).
OFF_PLANE_NOTE_FRACTION = 1e-6

#: Line styles of the clearance circles of ``orbit``, one per clearance drawn.
_CIRCLE_STYLES = ("--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)), (0, (8, 2)))


def _clearance(case: xr.Dataset, joint: str, configured: dict[str, float]) -> tuple[float, str] | None:
    """Radial clearance of ``joint`` in ``case`` [m] and where it came from; None for an ideal joint.

    A swept clearance (sweep coordinate ``{joint}_clearance``, or
    ``joints_{joint}_clearance`` where the short name was taken) wins over the
    ``configured`` one; without either, the largest eccentricity stands in.
    """
    for name in (f"{joint}_clearance", f"joints_{joint}_clearance"):
        if name in case.coords and case[name].ndim == 0:
            swept = float(case[name])
            return (swept, "swept") if swept > 0 else None
    if joint in configured:
        return (configured[joint], "config") if configured[joint] > 0 else None
    if "eccentricity" in case:
        largest = float(case["eccentricity"].sel(joint=joint).max())
        if np.isfinite(largest) and largest > 0:
            return largest, "max eccentricity"
    return None


def _gap(case: xr.Dataset, configured: tuple[float, float] | None) -> tuple[float, float] | None:
    """The guide P's half-gaps (y, z) [m] in ``case``: a swept ``P_clearance_y``/``_z`` wins over
    the ``configured`` one; None where neither gives both."""
    if configured is None:
        return None
    cy, cz = configured
    for name in ("P_clearance_y", "joints_P_clearance_y"):
        if name in case.coords and case[name].ndim == 0:
            cy = float(case[name])
    for name in ("P_clearance_z", "joints_P_clearance_z"):
        if name in case.coords and case[name].ndim == 0:
            cz = float(case[name])
    return (cy, cz) if cy > 0 and cz > 0 else None


def _draw_orbit(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("ball_offset",), "--kind orbit")
    offset = ds["ball_offset"]
    planes = (("x", "y"), ("x", "z"), ("y", "z"))
    # a planar mechanism's joints move in the crank's plane: one panel per joint, side by
    # side, the socket frame's two axes that the centre moves along (a socket on the rod
    # has the rod's x along it; on the slider or the ground, the global y and z)
    planar = is_planar(ds)
    cases = _cases(ds)
    circle = np.linspace(0.0, 2.0 * np.pi, 361)
    configured = configured_clearances(ds)
    gap = guide_gap(ds)
    # a ball that stays in the centre gets no panel of a point at the origin; an ideal
    # joint's is not named either
    # and a bushing's deflection (no clearance: no circle)
    bushings = bushing_joints(ds)
    try:
        named = _clearance_joints(ds, offset, "orbit")
    except PlotError:
        if not bushings:
            raise
        named = []
    named += [j for j in offset["joint"].values
              if value_text(j) in bushings and value_text(j) not in map(value_text, named)]
    joints = [j for j in named if np.nan_to_num(offset.sel(joint=j).values).any()] or named
    empty = [value_text(j) for j in named if j not in joints]
    # in the unit of a clearance (common.QUANTITY_UNITS), whatever the orbit's size: the
    # axes, the circles and their legend read in the unit every figure gives a clearance in
    factor, unit = QUANTITY_UNITS["length"]
    if planar:
        fig.set_size_inches(max(4.8 * len(joints), 6.4), 5.2)
    elif len(joints) == 1:        # one row of panels: no empty band where the other was
        fig.set_size_inches(fig.get_figwidth(), 4.8)
    per_joint: list[dict[float, str]] = []   # per joint: clearance [m] -> where it was read
    for joint in joints:
        found_here: dict[float, str] = {}
        for _, case, _ in cases:
            found = _clearance(case, str(joint), configured)
            if found is not None:
                found_here.setdefault(found[0], found[1])
        per_joint.append(found_here)
    # one style per clearance in the whole figure, so that the legend tells the circles apart
    radii = sorted({r for found_here in per_joint for r in found_here})
    styles = {r: (_CIRCLE_STYLES[k % len(_CIRCLE_STYLES)],
                  str(0.15 + 0.5 * k / max(len(radii) - 1, 1))) for k, r in enumerate(radii)}
    for j, (joint, clearances) in enumerate(zip(joints, per_joint)):
        # a journal moves in its bearing's plane (y, z) only: one panel
        gap_shape = joint_kind(ds, joint).orbit_gap
        bearing = gap_shape == "circle"
        # the guide block moves across its guide (y, z) only, in a rectangular gap
        guide = gap_shape == "rectangle"
        gaps = {g for g in (_gap(case, gap) for _, case, _ in cases) if g is not None} if guide else set()
        across = joint_kind(ds, joint).axial_ideal      # on its axis: its yz plane only
        shown = planes[2:] if across else planes
        off_plane = ""
        if planar and not across:
            sel = offset.sel(joint=joint)
            values = np.moveaxis(sel.values, sel.dims.index("axis"), -1)
            shown = (section_axes(values, sel["axis"].values),)
            dropped = [k for k, name in enumerate(sel["axis"].values) if str(name) not in shown[0]]
            finite = values[np.isfinite(values).all(axis=-1)]
            if len(finite):
                largest, out = float(np.abs(finite).max()), float(np.abs(finite[:, dropped]).max())
                if out > OFF_PLANE_NOTE_FRACTION * largest:
                    name = str(sel["axis"].values[dropped[0]])
                    off_plane = f"; off it, |d_{name}| up to {out / factor:.3g} {unit}"
        for p, (a, b) in enumerate(shown):
            ax = (fig.add_subplot(1, len(joints), j + 1) if planar
                  else fig.add_subplot(len(joints), len(planes), j * len(planes) + p + 1))
            for text, case, colour in cases:
                d = case["ball_offset"].sel(joint=joint)
                ax.plot(d.sel(axis=a).values / factor, d.sel(axis=b).values / factor, lw=0.6,
                        color=colour,
                        label=_case_label(text, len(cases), "ball or journal centre"))
            for k, (cy, cz) in enumerate(sorted(gaps)):
                ax.plot(np.array([-cy, cy, cy, -cy, -cy]) / factor,
                        np.array([-cz, -cz, cz, cz, -cz]) / factor, lw=0.9,
                        ls=_CIRCLE_STYLES[k % len(_CIRCLE_STYLES)], color="0.3",
                        label=f"guide {value_text(joint)} gap \u00b1{cy / factor:.3g} x "
                              f"\u00b1{cz / factor:.3g} {unit}")
            circles = () if gaps or gap_shape not in ("sphere", "circle") else clearances.items()
            for radius, source in sorted(circles):
                ax.plot(radius / factor * np.cos(circle), radius / factor * np.sin(circle), lw=0.9,
                        ls=styles[radius][0], color=styles[radius][1],
                        label=f"{joint_name(value_text(joint), ds)} clearance {radius / factor:.3g} {unit} "
                              f"({source})")
            # a ball at a fixed point (a round-off spread) draws as one point, not as that
            # spread at full scale: each axis spans at least MIN_RELATIVE_SPAN of the offset's
            # magnitude (the clearance's outline, where drawn, is wider already)
            drawn = [case["ball_offset"].sel(joint=joint) / factor for _, case, _ in cases]
            size = max((float(np.nanmax(np.abs(d.values))) for d in drawn
                        if np.isfinite(d.values).any()), default=0.0)
            for name, ax_name in ((a, "x"), (b, "y")):
                keep_relative_span(ax, [d.sel(axis=name).values for d in drawn], ax_name, size)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel(axis_label(offset, f"d_{a}", unit))
            ax.set_ylabel(axis_label(offset, f"d_{b}", unit))
            ideal = ("" if clearances else " (bushing)" if value_text(joint) in bushings
                     else " (ideal joint)")
            where = ("journal in the bearing's plane, yz" if bearing
                     else "block across its guide, yz (y: its side, -x, held)" if guide and planar
                     else "block across its guide, yz" if guide
                     else f"the mechanism's plane, {a}{b}{off_plane}" if planar
                     else f"{a}{b} plane")
            ax.set_title(f"{joint_name(value_text(joint), ds)}{ideal}: {where}", fontsize="small")
            ax.grid(alpha=0.3)
    # one legend below the panels: the cases, then each joint's clearance circles once
    figure_legend(fig)
    left_out = f"\nnot drawn: joint {', '.join(empty)}, ball at the centre" if empty else ""
    shapes = {joint_kind(ds, joint).orbit_gap for joint in joints}
    title = ("Journal-centre orbit in the bearing's frame" if shapes == {"circle"}
             else "Block-centre orbit in the guide's frame" if shapes == {"rectangle"}
             else "Ball-centre orbit in the socket frame")
    fig.suptitle(title + _legend_note(len(cases)) + left_out)

