"""``life``: a life run's histories against revolutions and its wear-map snapshots."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.colors import Normalize
from matplotlib.figure import Figure

from ..analysis import value_text
from .common import (
    AXIS_LABEL_CHARACTERS,
    DIMENSIONLESS,
    _clearance_joints,
    _edges,
    _note_span,
    _require,
    axis_label,
    guide_extent,
    joint_kind,
    joint_name,
    log_ticks,
    run_config,
    scaled,
    wrapped_label,
)

#: The life figure draws at most this many wear-map snapshots (the first, the last and
#: evenly spread ones between); it says which stored snapshots it leaves out.
LIFE_SNAPSHOT_PANELS = 6


def _draw_life(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("cycle", "wear_depth_max", "wear_map_snapshot", "stop_reason"), "--kind life")
    cycles = ds["cycle"].values
    xlabel = axis_label(ds["cycle"], "crank revolutions")
    limits = {"wear_depth_max": "life.max_clearance_growth",
              "normal_force_peak_settled": "life.max_normal_force",
              "slider_acceleration_rms_settled": "life.max_rms_acceleration"}
    config = run_config(ds)     # {} where the config attribute is not a mapping
    panels = ("wear_depth_max", "clearance_effective", "coating_remaining", "normal_force_peak_settled",
              "slider_acceleration_rms_settled", "impacts_per_revolution")
    grid = fig.add_gridspec(3, 4)
    for k, name in enumerate(panels):
        ax = fig.add_subplot(grid[k // 2, k % 2])
        var = ds[name]
        if not np.isfinite(var.values.astype(float)).any():
            # nothing to draw (no coating has no coating remaining): a note, not empty axes
            ax.set_axis_off()
            ax.text(0.5, 0.5, wrapped_label(f"{var.attrs.get('long_name', name)}: no data",
                                            AXIS_LABEL_CHARACTERS),
                    ha="center", va="center", transform=ax.transAxes, fontsize="small",
                    color="0.4")
            continue
        factor, unit = scaled(var)
        if "joint" in var.dims:
            for joint in var["joint"].values:
                values = var.sel(joint=joint).values / factor
                if np.isfinite(values).any():
                    ax.plot(cycles, values, marker=".", label=joint_name(value_text(joint), ds))
        else:
            ax.plot(cycles, var.values / factor, marker=".")
        limit = _life_limit(config, limits.get(name))
        top = float(np.nanmax(np.abs(var.values))) / factor if np.isfinite(var.values).any() else 0.0
        if limit is not None and limit / factor <= 2.0 * top:
            ax.axhline(limit / factor, color="r", linestyle="--", label=limits[name])
        elif limit is not None:     # far above the data: a note, the axis stays on the data
            ax.text(0.02, 0.98, f"{limits[name]} = {limit / factor:.3g} {unit} (above the axis)",
                    transform=ax.transAxes, ha="left", va="top", fontsize="x-small", color="r")
        _note_span(ax, var.values / factor)
        ax.set_xscale("log")
        if cycles.size and np.nanmin(cycles) > 0:
            log_ticks(ax.xaxis, float(np.nanmin(cycles)), float(np.nanmax(cycles)))
        ax.set_xlabel(xlabel)
        # wrapped: a long label ran past its panel's top into the figure's title
        ax.set_ylabel(wrapped_label(axis_label(var, var.attrs.get("long_name", name), unit),
                                    AXIS_LABEL_CHARACTERS))
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="x-small")
    snaps = ds["wear_map_snapshot"]
    # the most worn of the joints the run's config gives a clearance (B where none wore)
    joints = [value_text(j) for j in _clearance_joints(ds, snaps, "life")]
    joint = max(joints, key=lambda j: (float(snaps.sel(joint=j).max()), j == "B"))
    picks = np.unique(np.linspace(0, snaps.sizes["snapshot"] - 1, LIFE_SNAPSHOT_PANELS)
                      .round().astype(int))
    factor, unit = scaled(snaps)
    maps = snaps.sel(joint=joint) / factor
    peak = float(maps.max())
    norm = Normalize(0.0, peak if np.isfinite(peak) and peak > 0 else 1.0)
    polar = _edges(ds["polar"].values, 0.0, 180.0)
    azimuth = _edges(ds["azimuth"].values, -180.0, 180.0)
    guide = joint_kind(ds, joint).wear_figure == "walls"
    mesh = None
    for k, s in enumerate(picks):
        ax = fig.add_subplot(grid[k // 2, 2 + k % 2])
        if guide:
            mesh = _guide_snapshot(ax, maps.isel(snapshot=s).values, guide_extent(ds), norm)
        else:
            mesh = ax.pcolormesh(azimuth, polar, maps.isel(snapshot=s).values, cmap="viridis",
                                 norm=norm, shading="flat")
            ax.set_ylim(180.0, 0.0)
            ax.set_xlabel(axis_label(ds["azimuth"], "azimuth"), fontsize="x-small")
            ax.set_ylabel(axis_label(ds["polar"], "polar"), fontsize="x-small")
        ax.set_title(f"{joint_name(joint, ds)}, {float(ds['snapshot_cycle'][s]):.3g} revolutions", fontsize="small")
    if mesh is not None:
        fig.colorbar(mesh, ax=fig.axes[-len(picks):]).set_label(axis_label(snaps, "wear depth", unit))
    fig.suptitle(f"Service life: stopped by {ds['stop_reason'].values}\n"
                 + snapshot_note(ds["snapshot_cycle"].values, picks, joint))


def _guide_snapshot(ax, depth: np.ndarray, extent, norm):
    """A guide's wall maps (docs/physics.md 5.7) in one snapshot panel: its four bands (+y,
    -y, +z, -z walls, ``core.prismatic.WALLS``) as strips one above the other, each across
    its wall (rows) by along the guide [mm]; white lines between the walls."""
    from ..core.prismatic import WALLS

    nrow, ncol = depth.shape
    band = nrow // len(WALLS)
    if extent is not None:
        x0, span = extent[0], extent[1]
        x_edges = 1e3 * (x0 + span * np.arange(ncol + 1) / ncol)
        ax.set_xlabel("along the guide x [mm]", fontsize="x-small")
    else:
        x_edges = np.arange(ncol + 1.0)
        ax.set_xlabel(f"bin along the guide [{DIMENSIONLESS}]", fontsize="x-small")
    mesh = ax.pcolormesh(x_edges, np.arange(nrow + 1.0), depth, cmap="viridis", norm=norm,
                         shading="flat")
    ax.set_ylim(float(nrow), 0.0)
    for w in range(1, len(WALLS)):
        ax.axhline(w * band, color="white", lw=1.0)
    ax.set_yticks([(w + 0.5) * band for w in range(len(WALLS))], [f"{w} wall" for w in WALLS],
                  fontsize="x-small")
    ax.set_ylabel("across each wall", fontsize="x-small")
    return mesh


def snapshot_note(cycles: np.ndarray, picks: np.ndarray, joint: str) -> str:
    """Which of the stored wear-map snapshots (at ``cycles`` revolutions) the life figure
    draws (positions ``picks``).

    >>> snapshot_note(np.array([1.0, 10.0, 100.0]), np.array([0, 1, 2]), "B")
    'wear maps of joint B: all 3 stored snapshots'
    >>> snapshot_note(np.array([1.0, 10.0, 100.0]), np.array([0, 2]), "B")
    'wear maps of joint B: 2 of the 3 stored snapshots (not drawn: 10 revolutions)'
    """
    n = len(cycles)
    if len(picks) == n:
        return f"wear maps of {joint_name(joint)}: all {n} stored snapshots"
    left = [float(c) for i, c in enumerate(cycles) if i not in set(picks.tolist())]
    listed = ", ".join(f"{c:.3g}" for c in left[:4]) + (", ..." if len(left) > 4 else "")
    return (f"wear maps of {joint_name(joint)}: {len(picks)} of the {n} stored snapshots "
            f"(not drawn: {listed} revolutions)")


def _life_limit(config: dict, key: str | None) -> float | None:
    """The value of a life limit ``key`` ("life.max_...") in the dataset's config, if set."""
    if key is None:
        return None
    value = config.get("life", {}).get(key.split(".")[1])
    return None if value is None else float(value)

