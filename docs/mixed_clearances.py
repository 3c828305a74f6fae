"""The numbers of docs/mixed_clearances.md from the mixed-clearance study's file.

Run from the repository root, after the study:

    .venv/bin/clearsweep sweep configs/mixed_clearances.yaml -o results/mixed.nc --workers 2
    .venv/bin/python docs/mixed_clearances.py results/mixed.nc

Prints, per crank speed, the slider's settled RMS acceleration of the four designs of the
paper's comparison (O and P ideal; A, B each ideal or with clearance), member means with
their spread, and the effects: A alone (B ideal), B alone (A ideal), and both minus the
sum of each alone (``analysis.factorial.contrast``, the members' paired 95 % interval). Then, per speed,
each joint's effect on the vibration averaged over the other joints' settings.
"""

from __future__ import annotations

import sys

import xarray as xr

from clearsweep.analysis import factorial

METRIC = "slider_acceleration_rms_settled"


def interval(found) -> str:
    value, low, high = found
    return f"{value:+.3f} [{low:+.3f}, {high:+.3f}]"


def main(path: str) -> None:
    ds = xr.open_dataset(path)
    f = factorial.clearance_factors(ds)
    on = {j: (f[j][2], f[j][1]) for j in f}
    for s, speed in enumerate(ds["speed_rpm"].values):
        print(f"\n{float(speed):g} r/min, O and P ideal: slider RMS acceleration, settled [m s-2]")
        where = {f["O"][0]: f["O"][1], f["P"][0]: f["P"][1], "speed_rpm": s}
        mean = ds[METRIC + "_mean"].isel(where)
        std = ds[METRIC + "_std"].isel(where)
        for a in (0, 1):
            for b in (0, 1):
                at = {f["A"][0]: (f["A"][1], f["A"][2])[a], f["B"][0]: (f["B"][1], f["B"][2])[b]}
                name = {(0, 0): "ideal", (1, 0): "A", (0, 1): "B", (1, 1): "A and B"}[(a, b)]
                print(f"  {name:8s} {float(mean.isel(at)):.3f} +- {float(std.isel(at)):.3f} (std)")
        for label, terms, fixed in (("A alone", ["A"], {f["B"][0]: f["B"][1]}),
                                    ("B alone", ["B"], {f["A"][0]: f["A"][1]}),
                                    ("A and B minus each alone", ["A", "B"], {})):
            found = factorial.contrast(ds, METRIC, None, {j: on[j] for j in terms}, f,
                                       dict(where, **fixed))
            print(f"  {label}: {interval(found)}")
        print(f"{float(speed):g} r/min, each joint's effect averaged over the others' settings:")
        for j in f:
            found = factorial.contrast(ds, METRIC, None, {j: on[j]}, f, {"speed_rpm": s})
            print(f"  clearance at {j}: {interval(found)}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results/mixed.nc")
