"""The motion's character: ``spectrum`` (the slider acceleration's Welch spectrum against
crank orders, cases overlaid) and ``bifurcation`` (the Poincaré samples of the last
revolutions of each case of a one-parameter sweep against the swept value);
docs/physics.md section 11."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..analysis import (
    HIGH_ORDER,
    SelectionError,
    crank_speed,
    order_spectrum,
    parse_selection,
    settle_time,
    spectrum_summary,
    sweep_dims,
    value_text,
)
from .common import (
    DIMENSIONLESS,
    PlotError,
    _cases,
    _legend,
    _legend_note,
    _require,
    axis_label,
    joint_kind,
    joint_name,
    percent_text,
    quantity_unit,
    values_offer,
)

#: Highest crank order the spectrum's abscissa shows.
SPECTRUM_MAX_ORDER = 50.0
#: Revolutions of each case a bifurcation diagram draws: its last ones with samples. Enough
#: to show a period up to ``motion.MAX_PERIOD`` once over, few enough that a sweep of 20
#: revolutions a case draws its second half only (the first is start-up).
BIFURCATION_REVOLUTIONS = 10


def _spectrum_needs(case: xr.Dataset, omega: float, start: float) -> str:
    t = case["time"].values
    finite = t[np.isfinite(case["slider_acceleration"].values)]
    end = float(finite[-1]) if finite.size else float("nan")
    revolutions = (end - start) * omega / (2.0 * np.pi)
    return (f"--kind spectrum needs at least 2 crank revolutions in the settled window "
            f"(t >= {start:g} s, metrics.settle_time or settle_revolutions); the run holds "
            f"{max(revolutions, 0.0):.2g} there (it ends at {end:g} s, a revolution every "
            f"{2.0 * np.pi / omega:.3g} s): run longer (solver.duration or solver.revolutions)")


def _draw_spectrum(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("slider_acceleration", "crank_angle"), "--kind spectrum")
    cases = _cases(ds)
    ax = fig.subplots(1, 1)
    t = ds["time"].values.astype(float)
    drawn, notes, top = 0, [], 0.0
    for text, case, colour in cases:
        omega = crank_speed(t, case["crank_angle"].values)
        start = settle_time(case)
        orders, power = order_spectrum(t, case["slider_acceleration"].values, omega, start)
        if orders.size == 0:
            if len(cases) == 1:
                raise PlotError(_spectrum_needs(case, omega, start))
            continue
        shown = (orders > 0) & (orders <= SPECTRUM_MAX_ORDER) & (power > 0)
        ax.semilogy(orders[shown], power[shown], color=colour, lw=0.9, label=text or None)
        top = max(top, float(orders[shown].max(initial=0.0)))
        dominant, share = spectrum_summary(orders, power)
        notes.append(f"dominant order {dominant:.3g}, {percent_text(share)} of the power above "
                     f"order {HIGH_ORDER:g}")
        drawn += 1
    if drawn == 0:
        raise PlotError(_spectrum_needs(cases[0][1], crank_speed(t, cases[0][1]["crank_angle"].values),
                                        settle_time(ds)))
    ax.axvline(HIGH_ORDER, color="grey", ls="--", lw=0.8)
    ax.set_xlim(0.0, min(SPECTRUM_MAX_ORDER, max(top, HIGH_ORDER + 1.0)))
    units = str(ds["slider_acceleration"].attrs.get("units", "m s-2"))
    ax.set_xlabel(f"crank order (frequency / crank frequency) [{DIMENSIONLESS}]")
    ax.set_ylabel(f"power of the slider acceleration [({units})^2]")
    ax.grid(alpha=0.3, which="both")
    _legend(ax, cases)
    title = "Slider acceleration spectrum (Welch, settled window)"
    if drawn == 1:
        title += "\n" + notes[0]
    fig.suptitle(title + _legend_note(len(cases)))


def bifurcation_axis(ds: xr.Dataset, x: str | None) -> tuple[str, str]:
    """(the coordinate a bifurcation diagram's abscissa reads, its sweep dimension): ``x``,
    a sweep dimension of ``ds`` or a coordinate along one (a key of a zip group); ``None``:
    the only sweep dimension (a zip group's first key). Raises ``PlotError`` saying what is
    needed."""
    dims = [d for d in sweep_dims(ds) if ds.sizes[d] > 1]
    along = {str(n): str(c.dims[0]) for n, c in ds.coords.items()
             if c.ndim == 1 and str(c.dims[0]) in dims}
    along.update({d: d for d in dims})
    if not dims:
        raise PlotError("--kind bifurcation draws a sweep over one parameter against the swept "
                        "key; this file sweeps none: run `clearsweep sweep` on a sweep file with "
                        "one swept key (configs/bifurcation.yaml)")
    if x is None:
        if len(dims) > 1:
            raise PlotError(f"--kind bifurcation needs --x, the swept key to draw against: one "
                            f"of {', '.join(dims)} (and --select DIM=VALUE for the others)")
        x = _first_key(ds, dims[0])
    if x not in along:
        raise PlotError(f"--x {x}: not a swept key of this file; --kind bifurcation draws "
                        f"against one of {', '.join(sorted(along))}")
    others = [d for d in dims if d != along[x]]
    if others:
        offer = values_offer(ds, others)
        raise PlotError(f"--kind bifurcation draws a sweep over one parameter; this file also "
                        f"sweeps {', '.join(others)}: choose one value of each with --select "
                        f"DIM=VALUE ({offer})")
    return x, along[x]


def bifurcation_selection(ds: xr.Dataset, select, x: str | None) -> dict[str, object]:
    """``--select`` of ``--kind bifurcation`` as a ``.sel`` dict: each key a swept dimension
    of ``ds``, none of them the one drawn against (``x``'s, or with ``x`` None the only one
    left unselected). Raises ``SelectionError`` or ``PlotError`` saying that a key must be a
    swept dimension, and that the key drawn against is chosen with ``--x``."""
    dims = [d for d in sweep_dims(ds) if ds.sizes[d] > 1]
    along = {str(n): str(c.dims[0]) for n, c in ds.coords.items()
             if c.ndim == 1 and str(c.dims[0]) in dims}
    along.update({d: d for d in dims})
    try:
        selection = parse_selection(ds, select)
    except SelectionError as exc:
        if exc.name in dims:          # a swept dimension given a value it lacks: as it is
            raise
        keys = f" (one of {', '.join(sorted(along))})" if along else ""
        raise SelectionError(f"{exc}; a --select key of --kind bifurcation must be a swept "
                             f"dimension, and the key drawn against is given with --x{keys}",
                             name=exc.name, value=exc.value, choices=exc.choices) from None
    fixed = [d for d in dims if d in selection]
    if x is not None and along.get(x) in fixed:
        raise PlotError(f"--select {along[x]}=...: fixes the dimension of --x {x}, which --kind "
                        "bifurcation draws against; --select fixes the other swept dimensions")
    if x is None and dims and len(fixed) == len(dims):
        raise PlotError(f"--select {fixed[-1]}=...: fixes the last swept dimension, and --kind "
                        "bifurcation draws against one: leave it out of --select (--x names the "
                        "key drawn against)")
    return selection


def _first_key(ds: xr.Dataset, dim: str) -> str:
    """A sweep dimension's abscissa: a zip group's first key (``speed_rpm``, with its units),
    not its labels; the dimension itself otherwise."""
    keys = str(ds[dim].attrs.get("config_keys", "")).split() if dim in ds.coords else []
    for name, coord in ds.coords.items():
        if keys and coord.dims == (dim,) and coord.attrs.get("config_key") == keys[0]:
            return str(name)
    return dim


def last_revolutions(values: np.ndarray, time: np.ndarray,
                     n: int = BIFURCATION_REVOLUTIONS) -> np.ndarray:
    """Index of the last ``n`` revolutions of a case that hold samples (``time`` finite:
    a shorter case of a sweep is NaN-padded)."""
    held = np.flatnonzero(np.isfinite(time))
    return held[-n:]


def clearance_joints(ds: xr.Dataset) -> list[str]:
    """The joints whose Poincaré offsets hold a number somewhere (an ideal joint's are NaN)."""
    if "poincare_offset" not in ds:
        return []
    offset = ds["poincare_offset"]
    held = np.isfinite(offset.values).any(axis=tuple(i for i, d in enumerate(offset.dims)
                                                     if d != "joint"))
    return [str(j) for j, h in zip(offset["joint"].values, held) if h]


def offset_component(offset: xr.DataArray) -> str:
    """The axis of the socket frame along which ``offset`` (one joint, every case and
    revolution drawn) spreads most: the component a bifurcation panel draws."""
    spread = [float(np.nanmax(v) - np.nanmin(v)) if np.isfinite(v).any() else -1.0
              for v in (offset.sel(axis=a).values for a in offset["axis"].values)]
    return str(offset["axis"].values[int(np.argmax(spread))])


def _draw_bifurcation(fig: Figure, ds: xr.Dataset, x: str | None) -> None:
    x, dim = bifurcation_axis(ds, x)            # a missing sweep is the first thing to say
    missing = [n for n in ("poincare_time", "poincare_slider_acc") if n not in ds]
    if missing:
        # a file holds them where a case lasted a revolution: both causes are said
        raise PlotError(f"--kind bifurcation needs the Poincaré samples ({', '.join(missing)}), "
                        "which this file lacks: its runs ended before their first section (one "
                        "a crank revolution: run for solver.duration >= 2 x 60 / "
                        "mechanism.speed_rpm s), or it is a file of an older version of "
                        "clearsweep (run the sweep again: every store keeps them)")
    joints = clearance_joints(ds)
    n_rev = BIFURCATION_REVOLUTIONS
    # the last revolutions of each case: (case, n_rev) arrays, NaN where a case has fewer
    xs = ds[x].values
    time = ds["poincare_time"].transpose(dim, "revolution").values
    picks = [last_revolutions(time[i], time[i], n_rev) for i in range(ds.sizes[dim])]

    def samples(values: np.ndarray) -> np.ndarray:
        out = np.full((len(picks), n_rev), np.nan)
        for i, pick in enumerate(picks):
            out[i, n_rev - pick.size:] = values[i, pick]
        return out

    panels = [("slider acceleration at the section", axis_label(ds["poincare_slider_acc"],
                                                                "slider acceleration"),
               samples(ds["poincare_slider_acc"].transpose(dim, "revolution").values))]
    for joint in joints:
        offset = ds["poincare_offset"].sel(joint=joint)
        axis = offset_component(offset)
        values = offset.sel(axis=axis).transpose(dim, "revolution").values
        centre = joint_kind(ds, joint).centre
        panels.append((f"{joint_name(str(joint))}: {centre}-centre offset {axis} (socket frame)",
                       f"offset {axis} / clearance [{DIMENSIONLESS}]", samples(values)))
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    numeric = np.issubdtype(np.asarray(xs).dtype, np.number)
    factor, unit = quantity_unit(ds[x]) if numeric else (1.0, None)
    positions = np.asarray(xs, dtype=float) / factor if numeric else np.arange(len(xs), dtype=float)
    for ax, (title, label, values) in zip(axes, panels):
        ax.plot(np.repeat(positions[:, None], n_rev, axis=1).ravel(), values.ravel(),
                ls="none", marker="o", ms=1.5, color="black")
        ax.set_title(title, fontsize="small")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    if not numeric:
        axes[-1].set_xticks(positions, [value_text(v) for v in xs])
    axes[-1].set_xlabel(axis_label(ds[x], units=unit))
    fig.suptitle(f"Bifurcation diagram: Poincaré samples of the last {n_rev} revolutions of "
                 f"each case against {x}")
