"""Time series of the cases, overlaid: ``slider`` (Figures 9, 12, 13) and ``forces``
(Figures 10, 14, 15)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..analysis import value_text
from .common import (
    _abscissa,
    _cases,
    _legend,
    _legend_note,
    _require,
    axis_label,
    joint_kind,
    joint_name,
    scaled,
)

_AXIS_COLOURS = {"magnitude": "black", "x": "tab:blue", "y": "tab:orange", "z": "tab:green"}


def _draw_slider(fig: Figure, ds: xr.Dataset, x: str) -> None:
    names = ("slider_position", "slider_velocity", "slider_acceleration")
    _require(ds, names, "--kind slider")
    cases = _cases(ds)
    axes = fig.subplots(len(names), 1, sharex=True)
    for ax, name in zip(axes, names):
        factor, unit = scaled(ds[name])
        for text, case, colour in cases:
            xs, xlabel = _abscissa(ds, case, x)
            ax.plot(xs, case[name].values / factor, color=colour, lw=0.8, label=text)
        ax.set_ylabel(axis_label(ds[name], units=unit))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(xlabel)
    _legend(axes[0], cases)
    fig.suptitle("Slider dynamics" + _legend_note(len(cases)))


def _draw_forces(fig: Figure, ds: xr.Dataset, x: str) -> None:
    _require(ds, ("reaction_O", "joint_force"), "--kind forces")
    # (panel title, variable, joint or None)
    rows = [(f"{joint_name('O')}: reaction (ground on crank)", "reaction_O", None)]
    # the revolute joint at O: its force on the journal is the reaction at O, drawn once
    # the prismatic joint's: the guide's force on the slider
    rows += [(f"{joint_name(value_text(j), ds)} (on {joint_kind(ds, j).force_on})", "joint_force", j)
             for j in ds["joint"].values if joint_kind(ds, j).force_on is not None]
    components = ("magnitude", *(str(a) for a in ds["axis"].values))
    cases = _cases(ds)
    axes = fig.subplots(len(rows), len(components), sharex=True, squeeze=False)
    for r, (title, name, joint) in enumerate(rows):
        factor, unit = scaled(ds[name])
        for text, case, colour in cases:
            xs, xlabel = _abscissa(ds, case, x)
            vector = case[name] if joint is None else case[name].sel(joint=joint)
            series = [np.sqrt((vector ** 2).sum("axis"))] + [vector.sel(axis=a) for a in components[1:]]
            for ax, values, component in zip(axes[r], series, components):
                ax.plot(xs, values.values / factor, lw=0.7, label=text,
                        color=colour if len(cases) > 1 else _AXIS_COLOURS.get(component, colour))
        for ax, component in zip(axes[r], components):
            symbol = "|F|" if component == "magnitude" else f"F_{component}"
            ax.set_title(f"{title}: {symbol}", fontsize="small")
            ax.set_ylabel(axis_label(ds[name], symbol, unit))
            ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(xlabel)
    _legend(axes[0, 0], cases)
    fig.suptitle("Joint forces (global frame)" + _legend_note(len(cases)))

