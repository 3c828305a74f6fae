"""``reliability``: Kaplan-Meier reliability R(N) per design and limit, or B10."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib import colormaps
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure

from .common import MAX_CYCLE_COLOURS, _require, axis_label, log_ticks, quantity_text

#: Hatching of the confidence bands, one per design in turn.
BAND_HATCHES = ("//", "\\\\", "||", "--", "+", "x", ".", "o")


def _draw_reliability(fig: Figure, ds: xr.Dataset, b10: bool) -> None:
    _require(ds, ("reliability", "reliability_ci_low", "reliability_ci_high", "b10"),
             "--kind reliability")
    if "limit" in ds.coords and "limit" not in ds.dims:    # --select limit=NAME: that limit alone
        ds = ds.expand_dims("limit")
    limits = [str(v) for v in ds["limit"].values]
    designs = [d for d in ds["b10"].dims if d != "limit"]
    flat = ds.stack(design=designs) if designs else ds.expand_dims(design=[0])
    labels = [", ".join(f"{d}={quantity_text(flat[d], flat[d].values[k])}" for d in designs) or "design"
              for k in range(flat.sizes["design"])]
    colours = colormaps["tab10"] if len(labels) <= MAX_CYCLE_COLOURS else colormaps["viridis"]
    ncols = min(3, len(limits))
    nrows = -(-len(limits) // ncols)
    level = float(ds.attrs.get("reliability_confidence_level", 0.95))
    for k, limit in enumerate(limits):
        ax = fig.add_subplot(nrows, ncols, k + 1)
        case = flat.sel(limit=limit)
        for i, label in enumerate(labels):
            colour = colours(i if len(labels) <= MAX_CYCLE_COLOURS else i / max(len(labels) - 1, 1))
            one = case.isel(design=i)
            if b10:
                value = float(one["b10"])
                low, high = float(one["b10_ci_low"]), float(one["b10_ci_high"])
                top = float(ds["revolutions"].max())
                shown = value if np.isfinite(value) else top
                err = [[max(shown - low, 0.0) if np.isfinite(low) else 0.0],
                       [max((high if np.isfinite(high) else top) - shown, 0.0)]]
                ax.errorbar([i], [shown], yerr=err, fmt="o" if np.isfinite(value) else "^",
                            color=colour, capsize=4)
                continue
            n = ds["revolutions"].values
            ax.step(n, one["reliability"].values, where="post", color=colour, label=label)
            # each band hatched and outlined in its design's colour: where bands overlap, the
            # hatching tells them apart (a blend of two tints is a colour no legend shows)
            ax.fill_between(n, one["reliability_ci_low"].values, one["reliability_ci_high"].values,
                            step="post", facecolor=(*to_rgb(colour), 0.08), edgecolor=colour,
                            hatch=BAND_HATCHES[i % len(BAND_HATCHES)], lw=0.6,
                            label=f"{label}: {level:.0%} band")
        ax.set_title(f"limit: {limit}", fontsize="medium")
        if b10:
            ax.set_yscale("log")
            low, high = ax.get_ylim()
            if low > 0:
                log_ticks(ax.yaxis, low, high)
            ax.set_xticks(range(len(labels)), labels, rotation=30, ha="right", fontsize="x-small")
            ax.set_ylabel(f"B10 [revolutions], bars: {level:.0%} interval")
        else:
            ax.set_xscale("log")
            ax.set_xlim(float(ds["revolutions"].min()), float(ds["revolutions"].max()))
            log_ticks(ax.xaxis, *ax.get_xlim())
            ax.set_ylim(-0.02, 1.02)
            ax.axhline(0.9, color="0.5", lw=0.8, ls=":")
            ax.set_xlabel(axis_label(ds["revolutions"], "crank revolutions N"))
            ax.set_ylabel("reliability R(N) [-]")
            if k == 0:
                handles, texts = ax.get_legend_handles_labels()
                fig.legend(handles, texts, loc="outside lower center", fontsize="x-small",
                           ncol=min(len(texts), 4))
        ax.grid(alpha=0.3)
    what = "B10 per design (triangle: beyond the revolutions reached)" if b10 else \
        f"Kaplan-Meier reliability per design, bands: {level:.0%} Greenwood"
    fig.suptitle(f"{what}; {ds.sizes.get('member', 0)} members per design")

