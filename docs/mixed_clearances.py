"""The numbers of docs/mixed_clearances.md from the mixed-clearance study's file.

Run from the repository root, after the study:

    .venv/bin/clearsweep sweep configs/mixed_clearances.yaml -o results/mixed.nc --workers 2
    .venv/bin/python docs/mixed_clearances.py results/mixed.nc

Prints each joint's effect on the slider's settled RMS acceleration and each pair's
interaction, averaged over the other joints' settings and both speeds, with the 95 %
interval and its two terms (``analysis.factorial``: h_m the members' spread, h_r the run's
length from the settled window's halves), and each at every speed. Then, per crank speed, the
four designs of the paper's comparison (O and P ideal; A, B each ideal or with clearance),
member means with their spread, and the effects: A alone (B ideal), B alone (A ideal), and
both minus the sum of each alone.

With a second file, the same study run twice as long (``--set solver.revolutions=2N --set
metrics.settle_revolutions=2S``), it prints how far each effect and interaction moved, and
whether the move lies within the first file's interval's half-width; a doubled run of fewer
members (``--set ensemble.members=2``: the same first members) is compared with the first
file's mean over those members:

    .venv/bin/python docs/mixed_clearances.py results/mixed.nc results/mixed_doubled.nc
"""

from __future__ import annotations

import itertools
import sys

import xarray as xr

from clearsweep.analysis import factorial

METRIC = "slider_acceleration_rms_settled"


def interval(found) -> str:
    value, low, high = found
    return f"{value:+.3f} [{low:+.3f}, {high:+.3f}]"


def contrasts(ds: xr.Dataset) -> dict[str, dict[str, tuple]]:
    """Label -> {"all": (value, h_m, h_r), <speed>: (value, h_m, h_r)...} of each joint's
    effect and each pair's interaction on the vibration."""
    f = factorial.clearance_factors(ds)
    on = {j: (f[j][2], f[j][1]) for j in f}
    out = {}
    for terms in [(j,) for j in f] + list(itertools.combinations(f, 2)):
        label = " x ".join(terms)
        chosen = {j: on[j] for j in terms}
        found = {"all": factorial.contrast_parts(ds, METRIC, None, chosen, f)}
        for s, speed in enumerate(ds["speed_rpm"].values):
            found[f"{float(speed):g}"] = factorial.contrast_parts(ds, METRIC, None, chosen, f,
                                                                 {"speed_rpm": s})
        out[label] = found
    return out


def parts_text(parts) -> str:
    value, member, run = parts
    return (f"{interval(factorial.interval(value, member, run))}"
            f"  (h_m {member:.3f}, h_r {run:.3f})")


def main(path: str, doubled: str | None = None) -> None:
    ds = xr.open_dataset(path)
    f = factorial.clearance_factors(ds)
    speeds = [f"{float(s):g}" for s in ds["speed_rpm"].values]
    found = contrasts(ds)
    print("Slider RMS acceleration, settled [m s-2]: effects and interactions, 95 % interval "
          "sqrt(h_m^2 + h_r^2)")
    for label, at in found.items():
        what = f"clearance at {label}" if " x " not in label else f"{label} interaction"
        print(f"  {what}: {parts_text(at['all'])}")
        for speed in speeds:
            print(f"    at {speed} r/min: {parts_text(at[speed])}")
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
            parts = factorial.contrast_parts(ds, METRIC, None, {j: on[j] for j in terms}, f,
                                             dict(where, **fixed))
            print(f"  {label}: {parts_text(parts)}")
    if doubled is None:
        return
    twice = xr.open_dataset(doubled)
    longer = contrasts(twice)
    # a doubled run of fewer members (ensemble.members=2: the same first members, each drawing
    # the same perturbation) is compared with this run's mean over those members
    same = (contrasts(ds.isel(member=slice(0, twice.sizes["member"])))
            if "member" in twice.dims and twice.sizes["member"] < ds.sizes["member"] else found)
    print(f"\nRun doubled ({doubled}): how far each value moved (over the same members) "
          "against this run's interval")
    outside = 0
    for label, at in found.items():
        for where in ["all", *speeds]:
            value, low, high = factorial.interval(*at[where])
            base = same[label][where][0]
            new = longer[label][where][0]
            inside = abs(new - base) <= high - value
            outside += not inside
            name = label + ("" if where == "all" else f" at {where} r/min")
            print(f"  {name:24s} {base:+.3f} -> {new:+.3f} (moved {new - base:+.3f}, "
                  f"half-width {high - value:.3f}): {'inside' if inside else 'OUTSIDE'}")
    print(f"  {outside} of {len(found) * (1 + len(speeds))} outside")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results/mixed.nc",
         sys.argv[2] if len(sys.argv) > 2 else None)
