"""Bit-identity reference of the kernel's full raw output: tests/data/kernel_cases.npz.

Short cases (a few thousand steps each) that between them take every branch of the
stepping loop: ideal joints, one and two clearance joints, a coated socket, the centred
start (impacts), friction off, the paper slip rule with amplified wear, a deeply
sub-stepped paper-preset case and one that stops with unstable_step (rejected steps
undone). For each case the file keeps every array ``simulation.run_kernel`` returns
(rows, wear map, projections, worn volume, statistics) and its counters.

The file was made with the kernel as it was before the hot loop stopped passing array
views into compiled functions, with

    PYTHONPATH=. python tests/kernel_cases.py tests/data/kernel_cases.npz

except ``worn_bilinear``, added later (commit "kernel_cases: the worn-surface normal's
sloped branch pinned") by ``PYTHONPATH=. python tests/kernel_cases.py --add worn_bilinear FILE``, which
appends one case's arrays and leaves the others' as they are. The restructured kernel's
merge with the worn-surface normal (31fcdbe) had moved that branch's rounding, which no
case here covered: the ball centre's velocity is formed from its position rather than its
body offset (the same value to rounding), and a life run amplifies such a difference
(docs/service_life.md).

The statistics' peak columns (layout.M_FN_PEAK, M_PEN_PEAK, M_ACC_PEAK, M_TORQUE_PEAK)
were rewritten when peaks came to be read within each step (docs/physics.md 8.1) by
``PYTHONPATH=. python tests/kernel_cases.py --peaks FILE``, which replaces those columns
alone and fails unless every other array is still equal bit for bit.

The seated cases with friction (one_clearance, two_clearances, coated, paper_slip,
paper_preset, worn_bilinear) were rewritten, each by ``--add NAME FILE``, when the seated
start came to balance the spherical joints' friction (issue 41); ideal, centred,
friction_off and unstable were kept as they were, and still match.

tests/test_kernel_cases.py asserts that the kernel still reproduces it bit for bit;
regenerate it only for a deliberate change of results, and say so in the commit.

The file predates joint O (the crank's revolute joint, ideal in every case here): the
per-joint blocks of the diagnostics and statistics then held two joints, A and B.
:func:`reference_layout` reads a run's arrays in that layout (A's and B's entries of each
block, the blocks in order), which is what the file is compared with.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

CONFIGS = Path(__file__).resolve().parent.parent / "configs"

#: name -> (config file, overrides)
CASES: dict[str, tuple[str, tuple[str, ...]]] = {
    "ideal": ("ideal.yaml", ("solver.duration=0.02",)),
    "one_clearance": ("one_clearance.yaml", ("solver.duration=0.03",)),
    "two_clearances": ("two_clearances.yaml", ("solver.duration=0.03",)),
    "coated": ("two_clearances.yaml", ("solver.duration=0.03", "joints.B.coating=PTFE",
                                       "joints.A.coating=MoS2")),
    "centred": ("two_clearances.yaml", ("solver.duration=0.03", "initial.joints=centred")),
    "friction_off": ("two_clearances.yaml", ("solver.duration=0.03", "friction.enabled=false")),
    "paper_slip": ("one_clearance.yaml", ("solver.duration=0.03", "wear.slip=paper",
                                          "wear.amplification=1000", "wear.map=[36,72]",
                                          "metrics.settle_time=0.01")),
    "paper_preset": ("paper_case.yaml", ("solver.duration=0.002", "solver.save_every=10")),
    "unstable": ("paper_case.yaml", ("solver.dt=1e-5", "solver.duration=0.02",
                                     "initial.joints=centred", "solver.save_every=1")),
    # the worn-surface normal (docs/physics.md 3.5): the bilinear map read with wear
    # amplified so that the surface slopes within the run, the contact's sloped branch
    "worn_bilinear": ("one_clearance.yaml", ("solver.duration=0.03", "wear.interpolate=true",
                                             "wear.amplification=1e5", "wear.map=[36,72]")),
}

ARRAYS = ("t", "y", "d", "wmax", "wmap", "proj", "wvol", "stats")


def peak_columns() -> list[int]:
    """Columns of the running statistics that hold peaks read within the step."""
    from clearsweep.core import layout as L

    cols = [L.M_ACC_PEAK, L.M_TORQUE_PEAK]
    for j in range(L.N_JOINTS):
        cols += [L.M_FN_PEAK + j, L.M_PEN_PEAK + j]
    return cols


def replace_peaks(path: str) -> None:
    """Rewrite the stored statistics' peak columns from the kernel as it is, after checking
    that every other stored array is unchanged; print each peak that moved."""
    with np.load(path) as ref:
        stored = {key: ref[key] for key in ref.files}
    got = run_all()
    cols = peak_columns()
    for key, old in stored.items():
        new = got[key]
        if not key.endswith("__stats"):
            if key.endswith("__d") and new.shape[1] > old.shape[1]:
                new = new[:, :old.shape[1]]
            assert np.array_equal(new, old, equal_nan=old.dtype.kind == "f"), key
            continue
        keep = np.ones(old.shape[1], dtype=bool)
        keep[cols] = False
        assert np.array_equal(new[:, keep], old[:, keep], equal_nan=True), key
        for w in range(old.shape[0]):
            for c in cols:
                if new[w, c] != old[w, c]:
                    print(f"{key}[{w}, {c}]: {old[w, c]:.9g} -> {new[w, c]:.9g} "
                          f"({100 * (new[w, c] / old[w, c] - 1):+.4f} %)")
        stored[key] = new
    np.savez_compressed(path, **stored)
COUNTERS = ("n_saved", "deepest", "rk4_steps", "t_end", "residual_max", "ke_peak")


def run_case(name: str) -> dict[str, np.ndarray]:
    """The raw kernel output of one case, keyed ``name__field``."""
    from clearsweep.config import load_config
    from clearsweep.simulation import preflight, prepare_kernel, run_kernel

    path, overrides = CASES[name]
    cfg = load_config(str(CONFIGS / path), list(overrides))
    packed = preflight(cfg)
    prepare_kernel()
    raw = run_kernel(packed)
    out = {f"{name}__{key}": np.asarray(getattr(raw, key)) for key in ARRAYS + COUNTERS}
    out[f"{name}__status"] = np.array(raw.status)
    return out


#: The joints the file was made with, the first rows of the joint table.
REFERENCE_JOINTS = 2


def _block_columns(prefix: str, total: int) -> list[int]:
    """Columns of a vector with per-joint blocks (layout names ``prefix``*, ``total`` long) that
    hold the first REFERENCE_JOINTS joints' entries, in the order of the reference's layout."""
    from clearsweep.core import layout as L

    nj = L.N_JOINTS
    starts = sorted((v, k) for k, v in vars(L).items() if k.startswith(prefix) and isinstance(v, int))
    ends = [v for v, _ in starts[1:]] + [total]
    cols: list[int] = []
    for (start, name), end in zip(starts, ends):
        width = end - start
        if name == "D_REACTION_O":      # 3 values, not a per-joint block
            cols += list(range(start, end))
        elif width == nj:
            cols += list(range(start, start + REFERENCE_JOINTS))
        elif width == 3 * nj:
            cols += list(range(start, start + 3 * REFERENCE_JOINTS))
        else:
            cols += list(range(start, end))
    return cols


def reference_layout(key: str, value: np.ndarray) -> np.ndarray:
    """A run's array ``key`` (``name__field``) in the reference file's two-joint layout."""
    from clearsweep.core import layout as L

    field = key.partition("__")[2]
    if field == "d":
        return value[:, _block_columns("D_", L.N_D)]
    if field == "stats":
        return value[:, _block_columns("M_", L.N_M)]
    if field in ("wmap", "proj", "wvol"):
        return value[:REFERENCE_JOINTS]
    if field == "wmax":
        return value[:, :REFERENCE_JOINTS]
    return value


def run_all() -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name in CASES:
        out.update(stored_case(name))
    return out


def stored_case(name: str) -> dict[str, np.ndarray]:
    """One case's arrays as the file keeps them: :func:`reference_layout`'s two joints (a
    case written in the kernel's own layout would not compare with what
    tests/test_kernel_cases.py reads back)."""
    return {key: reference_layout(key, value) for key, value in run_case(name).items()}


if __name__ == "__main__":
    if sys.argv[1] == "--add":
        name, path = sys.argv[2], sys.argv[3]
        with np.load(path) as ref:
            kept = {key: ref[key] for key in ref.files if not key.startswith(name + "__")}
        np.savez_compressed(path, **kept, **stored_case(name))
    elif sys.argv[1] == "--peaks":
        replace_peaks(sys.argv[2])
    else:
        np.savez_compressed(sys.argv[1], **run_all())
