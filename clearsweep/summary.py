"""Per-case summaries: the kernel's statistics and the paper's wear table (Tables 4-5).

A summary reduces a one-case or sweep dataset over the case dimensions
(``time``, ``angle``, ``polar``, ``azimuth``); sweep dimensions stay. The
sweep workers summarize every case with :func:`case_summary`; reports
(:mod:`clearsweep.analysis`) build on it. Wear-table conventions: docs/physics.md
section 5 and the :mod:`clearsweep.analysis` docstring.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .variables import STATISTICS, attrs_for

#: A projection bin counts as worn above this fraction of its axis's maximum (docs/physics.md section 5).
WEAR_THRESHOLD_FRACTION = 1.0e-3

#: Variables of the wear table, in the column order of the paper's Tables 4-5
#: (the angle of the maximum, which the paper does not print, last).
WEAR_TABLE_VARIABLES = ("wear_depth_axis_max", "wear_angle_max", "wear_angle_min", "wear_range",
                        "wear_angle_of_max", "wear_arc")

#: Scalars copied from the case dataset into its summary.
PASS_THROUGH_VARIABLES = ("energy_residual_relative", "substeps_used", "rk4_steps", "wall_time")

#: The kernel's every-step statistics (``variables.STATISTICS``), settled window first.
STATISTIC_VARIABLES = tuple(n for n in STATISTICS if n.endswith("_settled")) + tuple(
    n for n in STATISTICS if not n.endswith("_settled"))

#: Order of the variables in ``case_summary``.
SUMMARY_ORDER = ("status", *STATISTIC_VARIABLES, "wear_depth_max_final", *WEAR_TABLE_VARIABLES,
                 *PASS_THROUGH_VARIABLES)


def with_attrs(da: xr.DataArray, name: str, **extra) -> xr.DataArray:
    da = da.rename(name)
    da.attrs = {**attrs_for(name), **extra}
    return da


def worn_arc_deg(worn: np.ndarray) -> float:
    """Shortest arc [degree] between bin centres that holds every worn bin of a full circle.

    Parameters
    ----------
    worn
        One flag per equal angle bin spanning 360 degrees.

    Returns
    -------
    float
        360 minus the widest circular run of unworn bins and one bin width:
        ``hi - lo`` for worn bins on [lo, hi] that do not wrap, 360 when
        every bin is worn, NaN when none is.
    """
    n = worn.size
    index = np.flatnonzero(worn)
    if index.size == 0:
        return math.nan
    width = 360.0 / n
    if index.size == n:
        return 360.0
    gaps = np.append(np.diff(index) - 1, index[0] + n - index[-1] - 1)
    return (n - 1 - int(gaps.max())) * width


def wear_table(ds: xr.Dataset) -> xr.Dataset:
    """Paper Tables 4-5: maximum projected wear depth and the angles with wear.

    Parameters
    ----------
    ds
        One-case or sweep dataset holding ``wear_projection(joint, axis,
        angle)`` [m], or already holding the wear-table variables (a summary
        sweep).

    Returns
    -------
    xr.Dataset
        Over (sweep dims..., joint, axis): ``wear_depth_axis_max`` [m] (max
        over angle), ``wear_angle_of_max`` [degree] (centre of the first bin
        holding the maximum), ``wear_angle_min`` and ``wear_angle_max``
        [degree] (smallest and largest bin centre with depth above
        ``WEAR_THRESHOLD_FRACTION`` of the maximum), ``wear_range`` [degree]
        (max - min); ``wear_arc`` [degree] (shortest arc between bin centres
        that holds every worn bin, see ``worn_arc_deg``). Without any wear on
        a (joint, axis): depth 0, angles, range and arc NaN. Cases whose
        projection is all NaN give NaN depth.
    """
    if "wear_projection" not in ds:
        missing = [v for v in WEAR_TABLE_VARIABLES if v not in ds]
        if missing:
            raise ValueError("a wear table needs wear_projection (a full dataset) or the "
                             f"summary variables {', '.join(WEAR_TABLE_VARIABLES)}; "
                             f"missing: {', '.join(missing)}")
        return xr.Dataset({name: ds[name] for name in WEAR_TABLE_VARIABLES})
    projection = ds["wear_projection"]
    angle = projection["angle"]
    depth = projection.max("angle")
    first_max = projection.fillna(-np.inf).argmax("angle")
    angle_of_max = angle.isel(angle=first_max).drop_vars("angle").where(depth > 0)
    worn = projection > WEAR_THRESHOLD_FRACTION * depth
    worn_angle = angle.where(worn)
    angle_min = worn_angle.min("angle")
    angle_max = worn_angle.max("angle")
    arc = xr.apply_ufunc(worn_arc_deg, worn, input_core_dims=[["angle"]], vectorize=True,
                         output_dtypes=[float])
    threshold = {"wear_threshold_fraction": WEAR_THRESHOLD_FRACTION}
    return xr.Dataset({
        "wear_depth_axis_max": with_attrs(depth, "wear_depth_axis_max"),
        "wear_angle_max": with_attrs(angle_max, "wear_angle_max", **threshold),
        "wear_angle_min": with_attrs(angle_min, "wear_angle_min", **threshold),
        "wear_range": with_attrs(angle_max - angle_min, "wear_range", **threshold),
        "wear_angle_of_max": with_attrs(angle_of_max, "wear_angle_of_max"),
        "wear_arc": with_attrs(arc, "wear_arc", **threshold),
    })


def case_summary(ds: xr.Dataset) -> xr.Dataset:
    """Per-case scalars (and joint / axis arrays) of a one-case or sweep dataset.

    Parameters
    ----------
    ds
        Full dataset, or one that already holds some summaries (a summary
        sweep): a summary whose source variable is absent is copied when
        present.

    Returns
    -------
    xr.Dataset
        ``status``; the kernel's every-step statistics (``variables.STATISTICS``:
        peaks, RMS, impacts, contact fraction; settled window first, then the whole
        run), copied as they are, never recomputed from the saved rows;
        ``wear_depth_max_final(joint)`` [m] (max of ``wear_map``); the
        ``wear_table`` variables; ``energy_residual_relative``,
        ``substeps_used``, ``rk4_steps``, ``wall_time`` [s]. Dataset
        attributes (provenance) are kept.
    """
    out: dict[str, xr.DataArray] = {}
    if "wear_map" in ds:
        out["wear_depth_max_final"] = with_attrs(ds["wear_map"].max(("polar", "azimuth")),
                                                  "wear_depth_max_final")
    if "wear_projection" in ds:
        out.update({str(k): v for k, v in wear_table(ds).data_vars.items()})
    for name in SUMMARY_ORDER:
        if name not in out and name in ds:
            out[name] = ds[name]
    summary = xr.Dataset({name: out[name] for name in SUMMARY_ORDER if name in out})
    summary.attrs = dict(ds.attrs)
    return summary
