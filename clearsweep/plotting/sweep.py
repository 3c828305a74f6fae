"""``sweep``: one summary metric over one sweep dimension (lines) or two (heat maps);
an ensemble's mean with its confidence interval."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from ..analysis import CASE_DIMS, MEMBER_DIM, SAMPLE_DIM, iter_points, metric_table, sweep_dims, value_text
from ..choices import DEFAULT_SWEEP_METRIC
from .common import (
    AXIS_LABEL_CHARACTERS,
    MAX_LEGEND_ENTRIES,
    MIN_RELATIVE_SPAN,
    NEGLIGIBLE_VARIATION,
    PlotError,
    _case_label,
    _dim_name,
    _legend_note,
    _note_span,
    axis_label,
    percent_text,
    point_text,
    quantity_unit,
    quantity_values,
    scaled,
    wrapped_label,
)

#: Heat-map cells are annotated with their values up to this many cells.
MAX_ANNOTATED_CELLS = 64

#: Size of one heat-map panel of ``--kind sweep`` (width, height) [inch].
HEATMAP_PANEL_INCHES = (4.2, 3.4)

#: Narrowest figure of ``--kind sweep``, so that its title fits [inch].
MIN_FIGURE_WIDTH_INCHES = 7.0

#: Robust colour limits of a heat map (one outlier would flatten the others): with at least
#: ``ROBUST_MIN_CELLS`` values, a value farther than ``ROBUST_FENCE`` times the range between
#: these percentiles beyond them is an outlier, and the scale stops at the percentile on its side.
ROBUST_PERCENTILES = (2.0, 98.0)
ROBUST_MIN_CELLS = 8
ROBUST_FENCE = 1.0

#: Heat-map annotations turn dark on cells brighter than this (normalised colour value).
ANNOTATION_DARK_TEXT_ABOVE = 0.6


def _category_positions(coord: xr.DataArray) -> tuple[np.ndarray, list[str] | None, str]:
    """Numeric coordinates in their quantity's unit (``common.quantity_unit``); others at 0,
    1, ... with their text as tick labels; and the axis label."""
    if coord.dtype.kind in "fiu":
        xs, label = quantity_values(coord)
        return xs, None, label
    return np.arange(coord.size), [value_text(v) for v in coord.values], axis_label(coord)


def _draw_ensemble_sweep(fig: Figure, ds: xr.Dataset, metric: str) -> None:
    """Ensemble mean of ``metric`` with its confidence interval as error bars, over the
    first design dimension; a line per value of the second (and per joint / axis)."""
    mean = ds[metric + "_mean"]
    dims = tuple(d for d in sweep_dims(mean))
    if not dims or len(dims) > 2:
        raise PlotError(f"--kind sweep draws an ensemble mean over one or two design dimensions; "
                        f"this dataset has {len(dims)} ({', '.join(dims) or 'none'}): fix the "
                        "others with --select DIM=VALUE")
    factor, unit = scaled(mean)
    mean = mean / factor
    mean.attrs = {**ds[metric + "_mean"].attrs, "units": unit}
    low, high = ds[metric + "_ci_low"] / factor, ds[metric + "_ci_high"] / factor
    ax = fig.add_subplot()
    xs, ticks, xlabel = _category_positions(mean[dims[0]])
    series = tuple(str(d) for d in mean.dims if d != dims[0])
    lines: list[tuple[dict, xr.DataArray]] = []
    empty: list[tuple[dict, xr.DataArray]] = []
    for keys, line in iter_points(mean, series):
        # an ideal joint's wear (all 0, no spread) or a metric it lacks (NaN): nothing to show
        values = np.nan_to_num(line.values.astype(float))
        (empty if not values.any() else lines).append((keys, line))
    step = (np.ptp(xs) if len(xs) > 1 else 1.0) * 0.01
    for k, (keys, line) in enumerate(lines):
        y = line.transpose(dims[0]).values.astype(float)
        lo = low.sel(keys).transpose(dims[0]).values.astype(float) if keys else low.values
        hi = high.sel(keys).transpose(dims[0]).values.astype(float) if keys else high.values
        text = point_text(mean, keys)
        # nudge the lines apart so that their error bars do not hide each other
        ax.errorbar(xs + (k - 0.5 * (len(lines) - 1)) * step, y, yerr=[y - lo, hi - y], marker="o",
                    capsize=3, linestyle="none" if ticks is not None else "-",
                    label=_case_label(text, len(lines), metric))
    if ticks is not None:
        ax.set_xticks(xs, ticks)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(wrapped_label(axis_label(mean), AXIS_LABEL_CHARACTERS))
    ax.grid(alpha=0.3)
    _note_span(ax, [low.values, high.values, mean.values])
    if series and len(lines) <= MAX_LEGEND_ENTRIES:
        ax.legend(fontsize="x-small")
    n = ds.sizes[MEMBER_DIM]
    left_out = f"\n{_left_out_text(mean, [k for k, _ in empty], [k for k, _ in lines])}" if empty else ""
    fig.suptitle(f"{mean.attrs.get('long_name', metric)} over {_dim_name(mean, dims[0])}, "
                 f"{n} members per design,\nbars: 95% confidence interval of the mean (Student t)"
                 f"{left_out}")


def _draw_sample_scatter(fig: Figure, values: xr.DataArray, panels: list, factor: float,
                         label: str, title: str) -> None:
    """A sampling sweep: the metric against each sampled input (a coordinate along
    ``sample``), one scatter panel per input, a colour per joint or axis; never a line over
    the point number."""
    inputs = [str(name) for name, coord in values.coords.items()
              if coord.dims == (SAMPLE_DIM,) and name != SAMPLE_DIM and coord.dtype.kind in "fiu"]
    if not inputs:
        raise PlotError("--kind sweep on a sampling sweep draws the metric against its sampled "
                        "inputs, and this dataset has none: use clearsweep sensitivity for its "
                        "Sobol' indices")
    # a joint without the metric (an ideal joint's wear) gets no points and no legend entry
    panels = [(text, panel) for text, panel in panels
              if np.nan_to_num(panel.values.astype(float)).any()] or panels
    ncols = min(2, len(inputs))
    nrows = -(-len(inputs) // ncols)
    fig.set_size_inches(max(4.2 * ncols, MIN_FIGURE_WIDTH_INCHES), 3.2 * nrows + 1.0)
    for k, name in enumerate(inputs):
        ax = fig.add_subplot(nrows, ncols, k + 1)
        coord = values[name]
        x_factor, x_unit = quantity_unit(coord)
        for text, panel in panels:
            ax.scatter(coord.values / x_factor, panel.transpose(SAMPLE_DIM).values / factor, s=6,
                       alpha=0.6, label=_case_label(text, len(panels), "sample point"))
        ax.set_xlabel(axis_label(coord, name, x_unit))
        ax.set_ylabel(wrapped_label(label, AXIS_LABEL_CHARACTERS) if k % ncols == 0 else "")
        ax.grid(alpha=0.3)
        if k == 0 and 1 < len(panels) <= MAX_LEGEND_ENTRIES:
            ax.legend(fontsize="x-small", markerscale=2)
    fig.suptitle(f"{title}\nagainst each sampled input, {values.sizes[SAMPLE_DIM]} sample points "
                 "(Sobol' indices: clearsweep sensitivity)")


def _left_out_text(obj: xr.DataArray, empty: list[dict], drawn: list[dict]) -> str:
    """What the lines left out have in common ("joint A"), or their count."""
    common = {d: v for d, v in empty[0].items()
              if all(k[d] == v for k in empty) and not any(k[d] == v for k in drawn)}
    what = point_text(obj, common) if common else f"{len(empty)} line(s)"
    return f"not drawn: {what}, all 0 or missing"


def _draw_sweep(fig: Figure, ds: xr.Dataset, metric: str | None) -> None:
    metric = metric or DEFAULT_SWEEP_METRIC
    if MEMBER_DIM in ds.dims and metric + "_mean" in ds:
        _draw_ensemble_sweep(fig, ds, metric)
        return
    values = metric_table(ds, metric)
    if values.dtype.kind not in "fiub":
        raise PlotError(f"metric {metric!r} is not numeric; --kind sweep plots numbers")
    dims = sweep_dims(values)
    inner = tuple(d for d in values.dims if d in CASE_DIMS)
    if not dims or len(dims) > 2:
        raise PlotError(f"--kind sweep draws a metric over one or two sweep dimensions; this "
                        f"dataset has {len(dims)} ({', '.join(dims) or 'none'}): fix the others "
                        "with --select DIM=VALUE")
    panels = [(point_text(values, keys), panel) for keys, panel in iter_points(values, inner)]
    factor, unit = scaled(values)
    label = axis_label(values, units=unit)
    title = values.attrs.get("long_name", metric)
    if dims == (SAMPLE_DIM,):
        _draw_sample_scatter(fig, values, panels, factor, label, title)
        return
    if len(dims) == 1:
        ax = fig.add_subplot()
        xs, ticks, xlabel = _category_positions(values[dims[0]])
        for text, panel in panels:
            # categories are not ordered: points, not lines between them
            ax.plot(xs, panel.transpose(dims[0]).values / factor, marker="o",
                    linestyle="none" if ticks is not None else "-",
                    label=_case_label(text, len(panels), metric))
        if ticks is not None:
            ax.set_xticks(xs, ticks)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(wrapped_label(label, AXIS_LABEL_CHARACTERS))
        ax.grid(alpha=0.3)
        _note_span(ax, values.values / factor)
        if inner and len(panels) <= MAX_LEGEND_ENTRIES:
            ax.legend(fontsize="x-small")
        fig.suptitle(f"{title} over {_dim_name(values, dims[0])}"
                     + (_legend_note(len(panels)) if inner else ""))
        return
    failed = _failed_cells(ds, values, dims)
    factor, unit = scaled(values)
    label = axis_label(values, units=unit)
    drawn = [(text, panel) for text, panel in panels
             if np.nan_to_num(panel.values.astype(float)).any()]
    empty = [text for text, panel in panels if not np.nan_to_num(panel.values.astype(float)).any()]
    if not drawn:
        raise PlotError(f"metric {metric!r} is 0 or missing in every case: nothing to draw")
    ncols = min(3, len(drawn))
    nrows = -(-len(drawn) // ncols)
    fig.set_size_inches(max(HEATMAP_PANEL_INCHES[0] * ncols, MIN_FIGURE_WIDTH_INCHES),
                        HEATMAP_PANEL_INCHES[1] * nrows + 0.6)
    for i, (text, panel) in enumerate(drawn):
        ax = fig.add_subplot(nrows, ncols, i + 1)
        grid = panel.transpose(*dims).values.astype(float) / factor
        limits = robust_limits(grid)
        vmin, vmax = limits if limits else (None, None)
        spread = _spread_note(grid)
        if limits is None and spread[1] is not None:
            vmin, vmax = spread[1]
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", vmin=vmin,
                          vmax=vmax)
        rows, row_label = _cell_ticks(values[dims[0]])
        columns, column_label = _cell_ticks(values[dims[1]])
        ax.set_yticks(np.arange(len(rows)), rows)
        ax.set_xticks(np.arange(len(columns)), columns)
        ax.set_ylabel(row_label)
        ax.set_xlabel(column_label)
        ax.tick_params(axis="x", labelrotation=30)
        if grid.size <= MAX_ANNOTATED_CELLS:
            digits = _cell_digits(grid)
            for (r, c), v in np.ndenumerate(grid):
                if (failed is not None and failed[r, c]) or not np.isfinite(v):
                    continue
                bright = float(image.norm(v)) > ANNOTATION_DARK_TEXT_ABOVE  # type: ignore[arg-type]  # a scalar in, a scalar out
                ax.text(c, r, format(v, f".{digits}g"), ha="center", va="center",
                        fontsize="x-small", color="black" if bright else "white",
                        gid=CELL_VALUE_GID)
        if failed is not None:
            for r, c in zip(*np.nonzero(failed)):
                ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1.0, 1.0, fill=False, hatch="xx",
                                       edgecolor="0.4", lw=0.0))
                ax.text(c, r, "failed", ha="center", va="center", fontsize="x-small", color="0.2",
                        gid=CELL_VALUE_GID)
        ax.set_title("\n".join(filter(None, [text, spread[0]])), fontsize="small")
        if limits is None:
            fig.colorbar(image, ax=ax).set_label(wrapped_label(label, COLOURBAR_CHARACTERS))
            continue
        below, above = grid < limits[0], grid > limits[1]
        for r, c in zip(*np.nonzero(below | above)):
            ax.add_patch(Rectangle((c - 0.5, r - 0.5), 1.0, 1.0, fill=False, edgecolor="red",
                                   lw=1.5))
        extend = {(True, True): "both", (True, False): "min", (False, True): "max"}.get(
            (bool(below.any()), bool(above.any())), "neither")
        stops = " and ".join(f"{q:g}th" for q, side in zip(ROBUST_PERCENTILES, (below, above))
                             if side.any())
        fig.colorbar(image, ax=ax, extend=extend).set_label(
            f"{wrapped_label(label, COLOURBAR_CHARACTERS)}\nscale stops at the {stops} "
            f"percentile;\nred outline: {int((below | above).sum())} outlying cell(s)")
    note = ""
    if failed is not None and failed.any():
        note = (f"\nhatched: {int(failed.sum())} case(s) that failed, no value (see the status "
                "and message variables)")
    if empty:
        note += f"\nnot drawn: {', '.join(t or metric for t in empty)}, all 0 or missing"
    fig.suptitle(f"{title}\nover {_dim_name(values, dims[0])} and {_dim_name(values, dims[1])}"
                 f"{note}")


#: A heat-map axis labels at most this many of its cells (every k-th where it has more).
MAX_CELL_TICK_LABELS = 8


def _cell_ticks(coord: xr.DataArray) -> tuple[list[str], str]:
    """Tick labels of a heat-map axis over ``coord``, numbers in their quantity's unit (0.25
    mm, not 0.00025 m: ``common.quantity_unit``), every k-th left blank where there are more
    than :data:`MAX_CELL_TICK_LABELS`; and the axis label with those units."""
    factor, unit = quantity_unit(coord) if coord.dtype.kind in "fiu" else (1.0, None)
    texts = ([format(float(v) / factor, ".4g") for v in coord.values] if factor != 1.0
             else [value_text(v) for v in coord.values])
    step = -(-len(texts) // MAX_CELL_TICK_LABELS)
    return ([t if k % step == 0 else "" for k, t in enumerate(texts)],
            axis_label(coord, units=unit))


def _spread_note(grid: np.ndarray) -> tuple[str, tuple[float, float] | None]:
    """How much a heat map's values vary ("varies by 1.9 % of its mean"), and the colour
    limits that keep a spread below :data:`NEGLIGIBLE_VARIATION` of the mean from filling
    the colour scale (:data:`MIN_RELATIVE_SPAN` of the mean, centred on the values), or None.
    """
    values = grid[np.isfinite(grid)]
    scale = abs(float(values.mean())) if values.size else 0.0
    if values.size < 2 or not scale > 0:
        return "", None
    spread = float(np.ptp(values)) / scale
    note = f"varies by {percent_text(spread)} of its mean"
    if spread >= NEGLIGIBLE_VARIATION:
        return note, None
    centre, half = 0.5 * (values.min() + values.max()), 0.5 * MIN_RELATIVE_SPAN * scale
    return f"{note}; colours span {MIN_RELATIVE_SPAN:.0%} of it", (centre - half, centre + half)


def _cell_digits(grid: np.ndarray) -> int:
    """Significant digits of heat-map cell values: 3, or more where two different values
    would print alike (at most 6)."""
    values = np.unique(grid[np.isfinite(grid)])
    for digits in range(3, 7):
        if len({format(v, f".{digits}g") for v in values}) == values.size:
            return digits
    return 6


#: ``gid`` of the value texts of heat-map cells: :func:`fit_cell_values` removes those that do
#: not fit their cell.
CELL_VALUE_GID = "heat-map cell value"

#: Colour-bar labels of heat maps are wrapped to lines of at most this many characters.
COLOURBAR_CHARACTERS = 28


def fit_cell_values(fig: Figure) -> None:
    """Remove the heat-map cell values (:data:`CELL_VALUE_GID`) wider or taller than their
    cell, so that no value runs over its neighbour or the cell border; the colour says it."""
    texts = [(ax, t) for ax in fig.axes for t in ax.texts if t.get_gid() == CELL_VALUE_GID]
    if not texts:
        return
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = fig.canvas if hasattr(fig.canvas, "get_renderer") else FigureCanvasAgg(fig)
    fig.draw_without_rendering()
    renderer = canvas.get_renderer()
    for ax, text in texts:
        x, y = text.get_position()
        (x0, y0), (x1, y1) = ax.transData.transform([(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)])
        box = text.get_window_extent(renderer)
        if box.width > 0.92 * abs(x1 - x0) or box.height > 0.92 * abs(y1 - y0):
            text.remove()


def robust_limits(grid: np.ndarray) -> tuple[float, float] | None:
    """Colour limits of a heat map that an outlier cannot flatten, or None where the full
    range serves (few cells, no outlier); see :data:`ROBUST_PERCENTILES`.

    >>> robust_limits(np.array([*range(47), 900.0]))
    (0.0, 46.0)
    """
    values = grid[np.isfinite(grid)]
    if values.size < ROBUST_MIN_CELLS:
        return None
    # the values nearest inside the percentiles, not interpolated towards an outlier
    p_lo = float(np.percentile(values, ROBUST_PERCENTILES[0], method="higher"))
    p_hi = float(np.percentile(values, ROBUST_PERCENTILES[1], method="lower"))
    fence = ROBUST_FENCE * (p_hi - p_lo)
    if not fence > 0:
        return None
    lo = p_lo if values.min() < p_lo - fence else float(values.min())
    hi = p_hi if values.max() > p_hi + fence else float(values.max())
    return (lo, hi) if (lo, hi) != (values.min(), values.max()) else None


def _failed_cells(ds: xr.Dataset, values: xr.DataArray, dims: tuple) -> np.ndarray | None:
    """Cells of a heat map over ``dims`` whose case failed (status neither ok nor skipped).

    ``None`` when ``ds`` has no per-case status over exactly these dimensions.
    """
    if "status" not in ds or set(ds["status"].dims) != set(dims):
        return None
    status = ds["status"]
    try:
        status = status.sel({d: values[d].values for d in dims if d in status.indexes})
    except (KeyError, ValueError):
        pass
    status = status.transpose(*dims)
    if status.shape != tuple(values.sizes[d] for d in dims):
        return None
    return ~np.isin(status.values.astype(str), ["ok", "skipped"])

