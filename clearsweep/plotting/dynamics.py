"""``dynamics-map``: the period (1 to ``motion.MAX_PERIOD``, none, undetermined) of every case
of a two-parameter grid sweep as a categorical map, each cell without a period marked with
its motion class, and beside it the 0-1 test's K for chaos and, where the sweep computed it,
the largest Lyapunov exponent, on continuous scales (docs/physics.md section 11)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ..analysis import (
    CHAOS_THRESHOLD,
    MAX_PERIOD,
    PERIOD_NONE,
    PERIOD_UNKNOWN,
    design_dims,
    report_summary,
    value_text,
)
from .common import DIMENSIONLESS, PlotError, values_offer

#: The colours of the categories: undetermined, none, then periods 1 to ``MAX_PERIOD``.
UNDETERMINED_COLOUR = "#ffffff"
NONE_COLOUR = "#404040"
PERIOD_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
                  "#bcbd22")
#: The mark a cell without a period carries for its motion class (``summary.motion_class``).
CLASS_MARKS = {"quasi-periodic": "QP", "chaotic": "C", "transient": "T", "non-periodic": "NP",
               "undetermined": "?"}
#: Units a swept coordinate is drawn in: its ``units`` attribute -> (factor, unit text): the
#: drawn value is the stored one / factor.
AXIS_UNITS = {"m": (1.0e-3, "mm"), "rpm": (1.0, "r/min"), "r/min": (1.0, "r/min"),
              "min-1": (1.0, "r/min"), "1/min": (1.0, "r/min")}


def category_text(period: int) -> str:
    """The legend's text of a period: ``"period 3"``, ``"none (no period up to 8)"``,
    ``"undetermined"``."""
    if period == PERIOD_UNKNOWN:
        return "undetermined"
    if period == PERIOD_NONE:
        return f"none (no period up to {MAX_PERIOD})"
    return f"period {period}"


def _categories() -> tuple[ListedColormap, BoundaryNorm]:
    """A colour map and norm that draw each period value (-1, 0, 1 ... MAX_PERIOD) in its
    own colour: the mesh's array holds the periods themselves."""
    colours = [UNDETERMINED_COLOUR, NONE_COLOUR, *PERIOD_COLOURS[:MAX_PERIOD]]
    bounds = np.arange(PERIOD_UNKNOWN, MAX_PERIOD + 2) - 0.5
    return ListedColormap(colours), BoundaryNorm(bounds, len(colours))


def map_axes(ds: xr.Dataset, x: str | None, y: str | None) -> tuple[str, str]:
    """(x, y): the two swept dimensions a dynamics map draws, every other swept dimension
    fixed by ``--select`` already. Raises ``PlotError`` saying what is needed."""
    dims = [d for d in design_dims(ds) if ds.sizes[d] > 1]
    if len(dims) < 2:
        raise PlotError("--kind dynamics-map draws a grid sweep over two parameters; this file "
                        f"sweeps {len(dims) or 'no'} parameter{'s' if len(dims) != 1 else ''}"
                        f"{' (' + ', '.join(dims) + ')' if dims else ''}: draw a one-parameter "
                        "sweep with --kind bifurcation, or sweep two keys on a grid "
                        "(configs/dynamics_map.yaml)")
    if x is None or y is None:
        raise PlotError(f"--kind dynamics-map needs --x and --y, the two swept keys to draw: "
                        f"two of {', '.join(dims)}")
    for option, key in (("--x", x), ("--y", y)):
        if key not in ds.dims or key not in dims:
            raise PlotError(f"{option} {key}: not a swept key of this file that varies; "
                            f"--kind dynamics-map draws two of {', '.join(dims)}")
    if x == y:
        raise PlotError(f"--x and --y both name {x}: --kind dynamics-map draws two different "
                        "swept keys")
    others = [d for d in dims if d not in (x, y)]
    if others:
        offer = values_offer(ds, others)
        raise PlotError(f"--kind dynamics-map draws two swept keys; this file also sweeps "
                        f"{', '.join(others)}: choose one value of each with --select "
                        f"DIM=VALUE ({offer})")
    return x, y


def _axis(ds: xr.Dataset, dim: str) -> tuple[list[str], str]:
    """(tick texts, axis label with units) of a swept dimension, lengths in mm, speeds in
    r/min."""
    coord = ds[dim] if dim in ds.coords else None
    if coord is None:
        return [str(i) for i in range(ds.sizes[dim])], f"{dim} [{DIMENSIONLESS}]"
    units = str(coord.attrs.get("units", ""))
    factor, unit = AXIS_UNITS.get(units, (1.0, units))
    values = coord.values
    numeric = np.issubdtype(values.dtype, np.number)
    ticks = [f"{float(v) / factor:g}" if numeric else value_text(v) for v in values]
    name = str(coord.attrs.get("long_name") or dim)
    return ticks, f"{name} [{unit if unit not in ('', '1') else DIMENSIONLESS}]"


def _draw_dynamics_map(fig: Figure, ds: xr.Dataset, x: str | None, y: str | None) -> None:
    x, y = map_axes(ds, x, y)
    summary = report_summary(ds)
    if "period" not in summary:
        # a file holds the samples where a case lasted a revolution: both causes are said
        raise PlotError("--kind dynamics-map needs each case's period, from the Poincaré "
                        "samples (poincare_time, poincare_slider_acc), which this file lacks: "
                        "its runs ended before their first section (one a crank revolution: "
                        "run for solver.revolutions >= 2, and 100 settled ones for the 0-1 "
                        "test), or it is a file of an older version of clearsweep (run the "
                        "sweep again: every store keeps them)")
    extra = [str(d) for d in summary["period"].dims if d not in (x, y)]
    if extra:       # an ensemble's members: one period each, not one a cell
        raise PlotError(f"--kind dynamics-map draws one period a cell; this file holds one per "
                        f"{', '.join(extra)} too: choose one with --select "
                        f"{extra[0]}=VALUE")
    period = summary["period"].transpose(y, x).values.astype(np.int64)
    chaos = (summary["chaos_k"].transpose(y, x).values.astype(float) if "chaos_k" in summary
             else np.full(period.shape, np.nan))
    exponent = (summary["lyapunov_exponent"].transpose(y, x).values.astype(float)
                if "lyapunov_exponent" in summary else None)
    classes = (summary["motion_class"].transpose(y, x).values.astype(str)
               if "motion_class" in summary and set(summary["motion_class"].dims) == {x, y}
               else None)
    xticks, xlabel = _axis(ds, x)
    yticks, ylabel = _axis(ds, y)
    xedges = np.arange(len(xticks) + 1) - 0.5
    yedges = np.arange(len(yticks) + 1) - 0.5
    axes = fig.subplots(1, 2 if exponent is None else 3)
    ax_period, ax_k = axes[0], axes[1]
    cmap, norm = _categories()
    mesh = ax_period.pcolormesh(xedges, yedges, period, cmap=cmap, norm=norm,
                                edgecolors="0.6", linewidth=0.5)
    mesh.set_gid("period")
    present = sorted(set(period.ravel().tolist()), key=lambda p: (p <= 0, -p if p <= 0 else p))
    ax_period.legend(handles=[Patch(facecolor=cmap(norm(p)), edgecolor="0.6",
                                    label=category_text(p)) for p in present],
                     title="period [revolutions]", loc="upper left", bbox_to_anchor=(1.01, 1.0),
                     fontsize="small", title_fontsize="small")
    marked = []
    if classes is not None:
        for (row, col), name in np.ndenumerate(classes):
            if period[row, col] > 0 or name not in CLASS_MARKS:
                continue
            shade = cmap(norm(period[row, col]))
            light = sum(shade[:3]) > 1.5
            text = ax_period.text(col, row, CLASS_MARKS[name], ha="center", va="center",
                                  fontsize="small", color="black" if light else "white")
            text.set_gid(f"motion_class:{name}")
            marked.append(name)
    ax_period.set_title("Period of the settled Poincaré samples" + (
        "\n" + ", ".join(f"{CLASS_MARKS[n]}: {n}" for n in CLASS_MARKS if n in marked)
        if marked else ""), fontsize="small")
    k_mesh = ax_k.pcolormesh(xedges, yedges, np.ma.masked_invalid(chaos), cmap="viridis",
                             vmin=0.0, vmax=1.0, edgecolors="0.6", linewidth=0.5)
    k_mesh.set_gid("chaos_k")
    ax_k.set_facecolor("0.85")       # a case without K (too few samples): grey
    bar = fig.colorbar(k_mesh, ax=ax_k)
    bar.set_label(f"0-1 test K [{DIMENSIONLESS}] (chaotic above {CHAOS_THRESHOLD:g})")
    missing = int(np.isnan(chaos).sum())
    ax_k.set_title("0-1 test for chaos" + (f" (grey: n/a, {missing} case"
                                            f"{'s' if missing > 1 else ''})" if missing else ""),
                   fontsize="small")
    if exponent is not None:
        ax_l = axes[2]
        finite = np.abs(exponent[np.isfinite(exponent)])
        span = max(float(finite.max()) if finite.size else 0.0, 0.05)
        l_mesh = ax_l.pcolormesh(xedges, yedges, np.ma.masked_invalid(exponent), cmap="RdBu_r",
                                 vmin=-span, vmax=span, edgecolors="0.6", linewidth=0.5)
        l_mesh.set_gid("lyapunov_exponent")
        ax_l.set_facecolor("0.85")
        lbar = fig.colorbar(l_mesh, ax=ax_l)
        lbar.set_label("largest Lyapunov exponent [1/revolution] (chaotic above 0)")
        ax_l.set_title("Largest Lyapunov exponent (twin runs)", fontsize="small")
    for ax in axes:
        ax.set_xticks(np.arange(len(xticks)), xticks)
        ax.set_yticks(np.arange(len(yticks)), yticks)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_xlim(xedges[0], xedges[-1])
        ax.set_ylim(yedges[0], yedges[-1])
    fig.suptitle(f"Dynamics map: period, 0-1 test K{'' if exponent is None else ' and Lyapunov exponent'}"
                 f" over {x} and {y}")
