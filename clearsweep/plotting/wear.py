"""Socket wear: ``wear-map`` (polar x azimuth and on a sphere) and ``wear-polar`` (the
worn profile per joint and axis); Figures 11, 16."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib import colormaps
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure

from ..analysis import SelectionError, value_text
from ..jointtypes import KINDS
from .common import (
    DIMENSIONLESS,
    _case_label,
    _cases,
    _clearance_joints,
    _edges,
    _legend_note,
    _one_case,
    _require,
    axis_label,
    display_scale,
    figure_legend,
    guide_extent,
    joint_kind,
    joint_name,
    scaled,
)

#: On ``wear-polar`` the largest depth of a joint is drawn as this fraction of the unit radius.
WEAR_POLAR_EXAGGERATION = 0.3


def _life_wear_map(ds: xr.Dataset, select) -> xr.Dataset:
    """The wear map of a life run (``clearsweep life``) as a one-case dataset: the final
    map, or with ``--select snapshot=K`` its K-th snapshot (0-based, in revolutions order).

    Raises
    ------
    SelectionError
        Any other selection; the message lists the snapshots and their revolutions.
    """
    cycles = ds["snapshot_cycle"].values if "snapshot_cycle" in ds else np.full(ds.sizes["snapshot"], np.nan)
    offer = ", ".join(f"{k} ({float(c):.4g} revolutions)" for k, c in enumerate(cycles))
    items = list(select.items()) if isinstance(select, Mapping) else \
        [tuple(str(i).partition("=")[::2]) for i in (select or ())]
    if not items:
        return ds[["wear_map"]]
    name, text = items[0]
    k = int(text) if str(text).strip().lstrip("-").isdigit() else -1
    if len(items) > 1 or name != "snapshot" or not 0 <= k < ds.sizes["snapshot"]:
        raise SelectionError(
            f"a life run's --kind wear-map draws its final map (no --select) or one snapshot: "
            f"--select snapshot=K, K one of {offer}", name=str(name), value=str(text),
            choices=[str(k) for k in range(ds.sizes["snapshot"])])
    snapshot = ds["wear_map_snapshot"].isel(snapshot=k, drop=True)
    # the run's attributes (its config: the case, the start and which joints are ideal)
    return xr.Dataset({"wear_map": snapshot.assign_attrs(ds["wear_map"].attrs)},
                      attrs={**ds.attrs, "snapshot": f"{k} at {float(cycles[k]):.4g} revolutions"})


def _draw_bearing_map(fig: Figure, at: tuple, depth: xr.DataArray, peak: float,
                      unit: str, label: str, joint: str, ds: xr.Dataset | None = None) -> None:
    """A revolute joint's bearing map (docs/physics.md 5.6: its first row, the depth around
    the bearing, uniform along its length): the depth against the angle around the bearing
    in its frame (the slider-crank's A: the rod's, y along the rod), and the bearing's
    cross-section with the worn profile exaggerated (``at``: the two slots of the figure's
    grid; ``ds``: the run, whose recorded types name the joint)."""
    ring = depth.isel(polar=0)
    phi = ring["azimuth"].values
    ax = fig.add_subplot(at[0])
    ax.plot(phi, ring.values, color="C0", lw=1.0)
    ax.set_xlim(-180.0, 180.0)
    ax.set_xlabel(axis_label(ring["azimuth"], "angle around the bearing, atan2(z, y)"))
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
    ax.set_title(f"{joint_name(joint, ds)}: wear around the bearing (max {peak:.3g} {unit})",
                 fontsize="small")
    polar_ax = fig.add_subplot(at[1], projection="polar")
    scale = WEAR_POLAR_EXAGGERATION / peak if np.isfinite(peak) and peak > 0 else 0.0
    closed = np.radians(np.append(phi, phi[0] + 360.0))
    polar_ax.plot(closed, np.ones_like(closed), color="0.5", lw=0.8, ls="--")
    profile = np.append(ring.values, ring.values[0])
    polar_ax.plot(closed, 1.0 + scale * np.nan_to_num(profile), color="C3", lw=1.2)
    polar_ax.set_ylim(0.0, 1.0 + 1.2 * WEAR_POLAR_EXAGGERATION)
    polar_ax.set_yticks([])
    polar_ax.set_title(f"{joint_name(joint, ds)}: cross-section (y right, z up), worn profile "
                       f"exaggerated", fontsize="small", pad=12)


#: The guide's walls and axes as the slider-crank names them: its guide along y, the
#: prismatic type's frame turned into it (``core.prismatic.PLANAR_GUIDE``: x' = y, y' = -x);
#: its +y' and -y' walls face across the mechanism's plane (at -x and +x), the +z and -z
#: walls (the upper and lower) within it.
PLANAR_WALLS = ("-x (side, across the plane)", "+x (side, across the plane)", "+z (upper)",
                "-z (lower)")


def _draw_guide_map(fig: Figure, spec, depth: xr.DataArray, peak: float, unit: str, label: str,
                    joint: str, extent, planar: bool = False) -> None:
    """A prismatic joint's wall maps (docs/physics.md 5.7): the map's rows in four bands, one
    per wall (+y, -y, +z, -z, ``core.prismatic.WALLS``), each ``npolar // 4`` rows across the
    wall by ``nazim`` columns along the guide, drawn as four strips one above the other in
    ``spec`` (a slot of the figure's grid), on one depth colour scale, against the position
    along the guide [mm] and across the wall [mm] (bins where the config cannot be read).
    ``planar``: the slider-crank's guide along y, its walls named as :data:`PLANAR_WALLS`."""
    from ..core.prismatic import WALLS

    names = PLANAR_WALLS if planar else WALLS

    band = depth.sizes["polar"] // 4
    ncol = depth.sizes["azimuth"]
    norm = Normalize(0.0, peak if np.isfinite(peak) and peak > 0 else 1.0)
    strips = spec.subgridspec(len(WALLS), 1)
    axes: list = []
    mesh = None
    for w, wall in enumerate(names):
        ax = fig.add_subplot(strips[w, 0], sharex=axes[0] if axes else None)
        if extent is not None:
            x0, span, half_y_wall, half_z_wall = extent
            half = half_y_wall if w < 2 else half_z_wall
            x_edges = 1e3 * (x0 + span * np.arange(ncol + 1) / ncol)
            a_edges = 1e3 * half * (2.0 * np.arange(band + 1) / band - 1.0)
            xlabel = f"position along the guide {'y' if planar else 'x'} [mm]"
            across = "z - z_s [mm]" if w < 2 else ("-x [mm]" if planar else "y [mm]")
        else:
            x_edges = np.arange(ncol + 1.0)
            a_edges = np.arange(band + 1.0)
            xlabel = f"bin along the guide [{DIMENSIONLESS}]"
            across = f"bin across [{DIMENSIONLESS}]"
        values = depth.values[w * band:(w + 1) * band]
        mesh = ax.pcolormesh(x_edges, a_edges, values, cmap="viridis", norm=norm, shading="flat")
        wall_peak = float(np.nanmax(values)) if np.isfinite(values).any() else float("nan")
        ax.set_ylabel(across, fontsize="x-small")
        ax.tick_params(labelsize="x-small")
        ax.set_title(f"{joint_name(joint)}: {wall} wall (max {wall_peak:.3g} {unit})",
                     fontsize="x-small", pad=2)
        if w < len(WALLS) - 1:
            ax.tick_params(labelbottom=False)
        else:
            ax.set_xlabel(xlabel, fontsize="small")
        axes.append(ax)
    if mesh is not None:
        fig.colorbar(mesh, ax=axes, shrink=0.9).set_label(label)


def _draw_wear_map(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("wear_map",), "--kind wear-map")
    ds = _one_case(ds, "wear-map")
    wear = ds["wear_map"]
    polar = np.radians(_edges(wear["polar"].values, 0.0, 180.0))
    azimuth = np.radians(_edges(wear["azimuth"].values, -180.0, 180.0))
    grid_p, grid_a = np.meshgrid(polar, azimuth, indexing="ij")
    sphere = (np.sin(grid_p) * np.cos(grid_a), np.sin(grid_p) * np.sin(grid_a), np.cos(grid_p))
    cmap = colormaps["viridis"]
    # a joint without wear gets no panel: its map would be one flat colour; the title names
    # one with a clearance, never an ideal one
    named = _clearance_joints(ds, wear, "wear-map")
    joints = [j for j in named if np.nan_to_num(wear.sel(joint=j).values).any()]
    empty = [value_text(j) for j in named if j not in joints]
    factor, unit = scaled(wear)
    label = axis_label(wear, "wear depth", unit)
    if len(joints) == 1:        # one row of panels: no empty band where the other was
        fig.set_size_inches(fig.get_figwidth(), 5.0)
    # the guide's row holds four strips: twice a socket's height, the figure taller for it
    figures = {j: joint_kind(ds, j).wear_figure for j in joints}
    heights = [2.0 if figures[j] == "walls" else 1.0 for j in joints]
    if len(joints) > 1 and max(heights, default=1.0) > 1.0:
        fig.set_size_inches(fig.get_figwidth(), fig.get_figheight() * sum(heights) / len(heights))
    grid = fig.add_gridspec(max(len(joints), 1), 2, height_ratios=heights or None)
    for j, joint in enumerate(joints):
        depth = wear.sel(joint=joint) / factor
        peak = float(depth.max())
        if figures[joint] == "bearing":
            _draw_bearing_map(fig, (grid[j, 0], grid[j, 1]), depth, peak, unit, label,
                              value_text(joint), ds)
            continue
        if figures[joint] == "walls":
            # the depth of the corners' tracks along the guide (docs/physics.md 5.7)
            _draw_guide_map(fig, grid[j, :], depth, peak, unit,
                            axis_label(wear, "track depth", unit), value_text(joint),
                            guide_extent(ds), ds.attrs.get("mechanism") == "slider_crank")
            continue
        norm = Normalize(0.0, peak if np.isfinite(peak) and peak > 0 else 1.0)
        ax = fig.add_subplot(grid[j, 0])
        mesh = ax.pcolormesh(np.degrees(azimuth), np.degrees(polar), depth.values, cmap=cmap,
                             norm=norm, shading="flat")
        ax.set_ylim(180.0, 0.0)
        ax.set_xlabel(axis_label(ds["azimuth"], "azimuth"))
        ax.set_ylabel(axis_label(ds["polar"], "polar angle from +z"))
        ax.set_title(f"{joint_name(value_text(joint), ds)}: socket wear map (max {peak:.3g} {unit})",
                     fontsize="small")
        fig.colorbar(mesh, ax=ax).set_label(label)
        ax3 = fig.add_subplot(grid[j, 1], projection="3d")
        ax3.plot_surface(*sphere, facecolors=cmap(norm(depth.values)), rstride=1, cstride=1,
                         shade=False, linewidth=0, antialiased=False)
        ax3.set_box_aspect((1, 1, 1))
        if peak > 0:
            # Look at the most worn bin.
            ip, ia = np.unravel_index(int(np.nanargmax(depth.values)), depth.shape)
            ax3.view_init(elev=90.0 - float(depth["polar"][ip]), azim=float(depth["azimuth"][ia]))
        # the axes name the socket frame's directions; tick labels of the unit sphere would
        # only crowd the panel title
        for set_label, set_ticks, name in ((ax3.set_xlabel, ax3.set_xticks, "x"),
                                           (ax3.set_ylabel, ax3.set_yticks, "y"),
                                           (ax3.set_zlabel, ax3.set_zticks, "z")):
            set_ticks([-1.0, 0.0, 1.0], ["", "", ""])
            set_label(f"{name} [{DIMENSIONLESS}]", labelpad=-12)
        ax3.set_title(f"{joint_name(value_text(joint), ds)}: unit sphere, socket frame", fontsize="small",
                      pad=12)
        fig.colorbar(ScalarMappable(norm, cmap), ax=ax3, shrink=0.7).set_label(label)
    snapshot = ds.attrs.get("snapshot")     # a life run's snapshot (_life_wear_map)
    left_out = f"\nnot drawn: {', '.join(map(joint_name, empty))}, no wear" if empty else ""
    # the surfaces drawn: a figure of the guide alone is no socket's
    kinds = [joint_kind(ds, j) for j in joints]
    surfaces = list(dict.fromkeys(k.surface for k in KINDS.values() if k in kinds))
    said = (" and ".join(surfaces) if len(surfaces) < 3
            else ", ".join(surfaces[:-1]) + " and " + surfaces[-1])
    fig.suptitle((f"{said.capitalize()} wear depth" if said else "Wear depth")
                 + (f", snapshot {snapshot}" if snapshot else "") + left_out)


def _draw_wear_polar(fig: Figure, ds: xr.Dataset) -> None:
    _require(ds, ("wear_projection",), "--kind wear-polar")
    projection = ds["wear_projection"]
    theta = np.radians(projection["angle"].values)
    closed = np.append(theta, theta[0])
    cases = _cases(ds)
    axes_names = projection["axis"].values
    # a joint with a clearance but no wear gets no row of unworn circles: the title says so;
    # an ideal joint is not named
    named = _clearance_joints(ds, projection, "wear-polar")
    # the guide P's walls are flat: a profile about an axis does not apply to them (wear-map
    # draws their strips)
    guides = [j for j in named if not joint_kind(ds, j).wear_profile]
    named = [j for j in named if j not in guides]
    joints = [j for j in named if np.nan_to_num(projection.sel(joint=j).values).any()] or named
    scales = [f"{joint_name(value_text(j), ds)}: no wear" for j in named if j not in joints]
    scales += [f"{joint_name(value_text(j), ds)}: not applicable (flat walls, see wear-map)"
               for j in guides]
    if len(joints) == 1:        # one row of panels: no empty band where the other was
        fig.set_size_inches(fig.get_figwidth(), 5.6)
    for j, joint in enumerate(joints):
        peak = float(projection.sel(joint=joint).max())
        scale = WEAR_POLAR_EXAGGERATION / peak if np.isfinite(peak) and peak > 0 else 0.0
        factor, unit = display_scale([peak], "m")
        # a no-break space keeps the value and its unit on one line of the wrapped title
        scales.append(f"{joint_name(value_text(joint), ds)}: {peak / factor:.3g}\u00a0{unit}" if scale
                      else f"{joint_name(value_text(joint), ds)}: no wear")
        for k, axis in enumerate(axes_names):
            ax = fig.add_subplot(len(joints), len(axes_names), j * len(axes_names) + k + 1,
                                 projection="polar")
            ax.plot(closed, np.ones_like(closed), ls="--", lw=0.8, color="0.5", label="unworn")
            for text, case, colour in cases:
                depth = np.nan_to_num(case["wear_projection"].sel(joint=joint, axis=axis).values)
                radius = 1.0 + scale * depth
                ax.plot(closed, np.append(radius, radius[0]), lw=1.0, color=colour,
                        label=_case_label(text, len(cases), "worn profile"))
            # a PolarAxes (projection="polar"); matplotlib's stubs type add_subplot as Axes
            ax.set_thetalim(-np.pi, np.pi)  # type: ignore[attr-defined]
            ax.set_rlim(  # type: ignore[attr-defined]
                0.0, 1.0 + 1.15 * WEAR_POLAR_EXAGGERATION)
            ax.set_yticks([])
            ax.set_title(f"{joint_name(value_text(joint), ds)}, about {axis}", fontsize="small")
            ax.set_xlabel(axis_label(ds["angle"], f"angle about {axis}"), fontsize="small")
    # one legend below the panels, in two columns where an entry is long (three of a sweep's
    # long case labels ran off the figure's sides)
    figure_legend(fig)
    fig.suptitle("Projected wear profile, radius 1 + depth x scale; largest depth drawn as "
                 f"{WEAR_POLAR_EXAGGERATION:g} of the radius ({'; '.join(scales)})"
                 + _legend_note(len(cases)), fontsize="medium")

