"""The RK4 step with one ``evaluate`` call site (``core.onestep``, issue 43 item 6), a device
build's arrangement: the same bits as ``rk4.advance``.

Both run here as the kernel's Python source (``NUMBA_DISABLE_JIT=1``, in a fresh
interpreter), ``rk4.integrate`` calling ``rk4.advance`` and then, swapped in its place,
``onestep.advance_one_call``: split steps (the paper's preset at the default step), the
guide's multi-contact wear, impacts that change the contact state within a step and a
Poincare section (the slider-crank's benchmark).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = r"""
import json
import numpy as np
import clearsweep.core.rk4 as rk4
from clearsweep.core import onestep
from clearsweep.config import load_config, resolve_materials
from clearsweep.params import pack
from clearsweep.simulation import run_kernel

assert not hasattr(rk4.advance, "py_func")      # the Python source, not a compiled kernel
cases = {
    "paper_deep": load_config("configs/paper_case.yaml", [
        "solver.dt=1e-5", "solver.duration=0.0002", "solver.max_substep_level=8",
        "mechanism.speed_rpm=30", "wear.map=[6,12]", "wear.amplification=1000.0"]),
    # the slider-crank's preset at 1e-5 s from the seated start, the default Baumgarte
    # constants: attempts rejected and redone deeper (its steps reach level 5)
    "rejected": load_config({
        "mechanism": {"kind": "slider_crank", "preset": "flores_benchmark", "speed_rpm": 5000.0},
        "joints": {"A": {"clearance": 2.0e-4}, "B": {"clearance": 5.0e-4, "socket_radius": 0.01},
                   "O": {"clearance": 2.0e-4}},
        "wear": {"map": [6, 12], "amplification": 100.0}, "metrics": {"settle_time": 0.0005},
        "solver": {"dt": 1.0e-5, "duration": 0.001}}),
    "guide": load_config("configs/two_clearances.yaml", [
        "solver.duration=0.0005", "joints.P.clearance_y=1e-4", "joints.P.clearance_z=1e-4",
        "wear.map=[8,12]", "wear.amplification=1e5", "wear.interpolate=true"]),
    # the slider-crank's benchmark (centred, 5000 r/min: B's impacts from 0.35 ms on) with
    # clearance at O and A too; its section at 18 degrees falls at 0.6 ms
    "slider_crank": load_config("configs/slider_crank.yaml", [
        "solver.duration=0.001", "wear.map=[6,12]", "outputs.poincare_phase_deg=18",
        "joints.A.clearance=2e-4", "joints.O.clearance=2e-4"]),
}
keep = rk4.advance
changes = []
accept = rk4.accept_substep
def counted(*args):
    changed, nbuf = accept(*args)
    changes.append(bool(changed))
    return changed, nbuf
# the acceptance both attempts share (rk4.accept_end): how often the one-call attempt
# evaluates again (counted over its run alone)
rk4.accept_substep = counted
found = {}
for name, cfg in cases.items():
    pk = pack(cfg, resolve_materials(cfg))
    rk4.advance = keep
    a = run_kernel(pk)
    rk4.advance = onestep.advance_one_call
    changes.clear()
    b = run_kernel(pk)
    for field in ("t", "y", "d", "wmax", "wmap", "proj", "wvol", "stats", "sec", "first_impact"):
        x, y = np.asarray(getattr(a, field)), np.asarray(getattr(b, field))
        assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), (name, field)
    for field in ("status", "n_saved", "deepest", "t_end", "rk4_steps", "residual_max", "ke_peak"):
        assert getattr(a, field) == getattr(b, field), (name, field)
    found[name] = {"status": a.status, "deepest": a.deepest, "steps": int(round(a.t_end / cfg.solver.dt)),
                   "substeps": a.rk4_steps, "evaluated_again": sum(changes),
                   "accepted": len(changes),
                   "sections": int(np.isfinite(a.sec).any(axis=1).sum()),
                   "wvol": [float(v) for v in a.wvol]}
print("FOUND " + json.dumps(found))
"""


@pytest.mark.slow
def test_one_call_site_gives_the_bits_of_advance():
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=900)
    assert proc.returncode == 0, proc.stderr[-4000:]
    line = [x for x in proc.stdout.splitlines() if x.startswith("FOUND")][-1]
    found = json.loads(line.split(" ", 1)[1])
    assert all(f["status"] == "ok" for f in found.values()), found
    # what each case exercises: split steps (the paper's preset reaches level 6), the
    # guide's wear, the slider-crank's section
    deep = found["paper_deep"]
    assert deep["deepest"] >= 5 and deep["substeps"] > 4 * deep["steps"]
    # sub-steps whose contact state changed (impacts), so that the sub-step's end was
    # evaluated again (the one call site's fifth phase)
    assert found["slider_crank"]["evaluated_again"] > 0, found
    # sub-steps accepted in attempts then rejected (undone) and redone deeper
    assert found["rejected"]["accepted"] > found["rejected"]["substeps"], found
    assert found["guide"]["wvol"][3] > 0.0
    assert found["slider_crank"]["sections"] == 1
