"""``effects``: a sweep that switches joints' clearance on and off, read as a two-level
design (``analysis.factorial``): each joint's effect on the slider's vibration and on each
joint's wear, with their 95 % intervals (the members' spread and, for the vibration, the run's
length), and each effect at each speed as a marker where it changes sign with the speed
(docs/mixed_clearances.md)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from ..analysis import factorial
from .common import PlotError, display_scale

#: Volumes drawn in the unit that reads directly (worn volumes are some 1e-15 m^3).
VOLUME_UNITS = ((1e-18, "\u00b5m3"), (1e-9, "mm3"), (1.0, "m3"))
#: Markers of an effect at each setting of the axis (the speed) where it changes sign.
MARKERS = ("o", "s", "^", "v", "D")


def _scale(values: np.ndarray, units: str) -> tuple[float, str]:
    """(factor, unit) to draw ``values`` [``units``]: ``display_scale``'s, and for volumes
    [m3] the largest of :data:`VOLUME_UNITS` not above the largest magnitude."""
    if units != "m3":
        return display_scale(values, units)
    finite = values[np.isfinite(values)]
    peak = float(finite.max()) if finite.size else 0.0
    chosen = VOLUME_UNITS[0]
    for factor, unit in VOLUME_UNITS:
        if peak >= factor:
            chosen = (factor, unit)
    return chosen


def _draw_effects(fig: Figure, ds: xr.Dataset) -> None:
    factors = factorial.clearance_factors(ds)
    if len(factors) < 2 or factorial.VIBRATION[0] not in ds:
        raise PlotError("--kind effects needs a sweep that switches the clearance of two or more "
                        "joints on and off (two values along one dimension each, 0 and > 0, "
                        f"and {factorial.VIBRATION[0]}), as configs/mixed_clearances.yaml does")
    panels = factorial.metrics(ds, factors)
    cols = min(3, len(panels))
    rows = -(-len(panels) // cols)
    for k, (name, joint) in enumerate(panels):
        ax = fig.add_subplot(rows, cols, k + 1)
        effects = factorial.main_effects(ds, name, joint, factors)
        shown = list(effects)
        values = [effects[j][0] for j in shown]
        lows = [effects[j][1] for j in shown]
        highs = [effects[j][2] for j in shown]
        units = str(ds[name].attrs.get("units", ""))
        scale, unit = _scale(np.abs(np.concatenate([values, lows, highs])), units)
        v = np.asarray(values) / scale
        lo = np.asarray(lows) / scale
        hi = np.asarray(highs) / scale
        y = np.arange(len(shown))
        err = np.vstack([v - lo, hi - v])
        colours = ["C3" if (a > 0.0 or b < 0.0) else "0.6" for a, b in zip(lo, hi)]
        ax.barh(y, v, color=colours, height=0.6)
        if np.isfinite(err).all():
            ax.errorbar(v, y, xerr=err, fmt="none", ecolor="k", capsize=3, lw=1.0,
                        label="95 % interval")
        where = {factors[joint][0]: factors[joint][2]} if joint else {}
        labelled = set()
        for row, j in enumerate(shown):
            changes = factorial.sign_changes(ds, name, joint, {j: (factors[j][2], factors[j][1])},
                                             factors, where)
            for dim, found in changes.items():
                for k, (setting, (value, _, _)) in enumerate(found):
                    label = f"at {setting} r/min" if dim == "speed_rpm" else f"at {dim} {setting}"
                    ax.plot(value / scale, row, MARKERS[k % len(MARKERS)], color="k", ms=5,
                            mfc="w", label=None if label in labelled else label)
                    labelled.add(label)
        if labelled:
            ax.legend(fontsize="x-small", loc="best")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.set_yticks(y, [f"clearance at {j}" for j in shown])
        ax.invert_yaxis()
        what = "slider RMS acceleration, settled" if joint is None else f"worn volume at {joint}"
        ax.set_xlabel(f"change of the {what} [{unit}]")
        ax.set_title(what + (f" (cases with clearance at {joint})" if joint else ""),
                     fontsize="small")
        ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
        ax.grid(axis="x", alpha=0.3)
    rest = [d for d in factorial.design_dims(ds) if d not in {f[0] for f in factors.values()}]
    fig.suptitle("Effect of each joint's clearance (ideal -> clear), averaged over the other "
                 "joints" + (f" and {', '.join(rest)}" if rest else "")
                 + "\nred: interval excludes 0; grey: it holds 0; markers: at each "
                 "setting, where the sign changes")
