"""Bit-identity reference of the kernel: tests/data/two_clearances_0p2s.npz.

The file was made on commit 46eb77c, before the kernel's named contact record and
state-layout constants replaced tuple positions and literal indices, with

    PYTHONPATH=. python tests/regression.py tests/data/two_clearances_0p2s.npz

from configs/two_clearances.yaml with solver.duration=0.2. It holds every
statistic without a time dimension, a few rows of the time series and a sha256 of
the bytes of every float variable (wall_time excepted). tests/test_regression.py
asserts that the kernel still reproduces it bit for bit; regenerate it only for a
deliberate change of results, and say so in the commit. The file predates joint O (the
crank's revolute joint, ideal in this config): the snapshot keeps joints A and B, the
rows the file holds, and O's own tests check its row.

The peak statistics (:data:`PEAKS`, whole run and settled) were rewritten when peaks came
to be read within each step (docs/physics.md 8.1), by ``PYTHONPATH=. python
tests/regression.py --peaks FILE``, which replaces their entries alone and fails unless
every other entry is still equal bit for bit.
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import numpy as np

CONFIG = str(Path(__file__).resolve().parent.parent / "configs" / "two_clearances.yaml")
OVERRIDES = ("solver.duration=0.2",)
ROWS = np.array([1, 50, 500, 1000, 1500, 2000])
#: The joints the reference file was made with.
REFERENCE_JOINTS = ("A", "B")
SERIES = ("slider_acceleration", "crank_torque", "normal_force", "penetration",
          "slider_position", "energy_residual", "wear_depth_max", "joint_force")


def digest(values: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(values, dtype="<f8").tobytes()).hexdigest()


def snapshot(ds) -> dict[str, np.ndarray]:
    """The values the reference file keeps of a simulated dataset (joints A and B)."""
    ds = ds.sel(joint=list(REFERENCE_JOINTS))
    out: dict[str, np.ndarray] = {}
    for name, v in ds.data_vars.items():
        if v.dtype.kind in "fiu" and "time" not in v.dims and name not in ("wall_time", "wear_map"):
            out["stat__" + name] = v.values
    out["series_index"] = ROWS
    for name in SERIES:
        out["series__" + name] = ds[name].values[ROWS]
    out["wear_map_sum"] = np.array(ds["wear_map"].values.sum())
    for name, v in ds.data_vars.items():
        if v.dtype.kind == "f" and name != "wall_time":
            out["sha256__" + name] = np.array(digest(v.values))
    return out


#: Statistics read within each step (their ``_settled`` twins too).
PEAKS = ("slider_acceleration_peak", "crank_torque_peak", "normal_force_peak", "penetration_peak")


def is_peak(key: str) -> bool:
    name = key.partition("__")[2]
    return name.removesuffix("_settled") in PEAKS


def replace_peaks(path: str) -> None:
    """Rewrite the stored peak entries from the kernel as it is, after checking that every
    other stored entry is unchanged; print each peak that moved."""
    with np.load(path) as ref:
        stored = {key: ref[key] for key in ref.files}
    got = snapshot(simulate_reference())
    for key, old in stored.items():
        if not is_peak(key):
            assert np.array_equal(got[key], old, equal_nan=old.dtype.kind == "f"), key
        elif key.startswith("stat__"):
            print(f"{key}: {old} -> {got[key]}")
            stored[key] = got[key]
        else:
            stored[key] = got[key]
    np.savez(path, **stored)


def simulate_reference():
    from clearsweep.simulation import simulate

    return simulate(CONFIG, list(OVERRIDES))


if __name__ == "__main__":
    if sys.argv[1] == "--peaks":
        replace_peaks(sys.argv[2])
        sys.exit()
    np.savez(sys.argv[1], **snapshot(simulate_reference()))
