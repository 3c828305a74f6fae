"""What each RK4 step keeps for a rejection (``rk4.advance``, issue 43 item 3).

A step keeps the state, k1 and the diagnostics of its start (a sub-step changes them before
its stability check); the contact state, the statistics, the first impact times and the
approach rates change only when a sub-step is accepted, so they are kept only in a step of
several sub-steps, once, at its first acceptance (``rk4.keep_accepted``). The results are
the same bits as a copy of everything at every step's start: tests/test_regression.py and
tests/test_kernel_cases.py hold them to the references.

The kernel runs here as Python source (``NUMBA_DISABLE_JIT=1``, in a fresh interpreter) with
its copy functions wrapped to count the values copied into each keeping array.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from clearsweep.core import layout as L

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = r"""
import json, sys
from collections import Counter
import clearsweep.core.rk4 as rk4
from clearsweep.config import load_config
from clearsweep.params import pack
from clearsweep.config import resolve_materials
from clearsweep.simulation import run_kernel

assert not hasattr(rk4.advance, "py_func")      # the Python source, not a compiled kernel
captured = {}
_work = rk4.Rk4Work

def capture(*arrays):
    captured["w"] = _work(*arrays)
    return captured["w"]

rk4.Rk4Work = capture
count = Counter()
KEPT = ("ysave", "k1save", "dgsave", "ssave", "msave", "first_save", "ddot_prev_save")

def counted(copy):
    def wrapped(dst, src):
        work = captured.get("w")
        for name in KEPT:
            if work is not None and dst is getattr(work, name):
                count[name] += src.size
        return copy(dst, src)
    return wrapped

rk4.copy_into = counted(rk4.copy_into)
rk4.copy_rows_into = counted(rk4.copy_rows_into)
cfg = load_config(str(sys.argv[1]), json.loads(sys.argv[2]))
run = run_kernel(pack(cfg, resolve_materials(cfg)))
print(json.dumps({"status": run.status, "steps": int(round(run.t_end / cfg.solver.dt)),
                  "substeps": int(run.rk4_steps), "deepest": int(run.deepest),
                  "copied": dict(count)}))
"""


def kept_values(config: str, overrides: list[str]) -> dict:
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(ROOT / "configs" / config),
                           json.dumps(overrides)], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


#: Values a step keeps whatever happens: the state, k1, the diagnostics.
EVERY_STEP = 2 * L.N_Y + L.N_D
#: Values kept once in a step of several sub-steps: the contact state, both windows'
#: statistics, the first impact times, the approach rates (each step kept them all before:
#: EVERY_STEP + ON_ACCEPT = 314 values).
ON_ACCEPT = L.N_JOINTS * L.N_S + L.N_WINDOWS * L.N_M + 2 * L.N_JOINTS


@pytest.mark.slow
def test_a_step_without_sub_steps_keeps_the_state_k1_and_diagnostics_alone():
    """Two clearances from the centred start (impacts), 3 ms at the 10 us step: no step is
    split, and each keeps 184 values where it kept 314."""
    got = kept_values("two_clearances.yaml", ["solver.duration=0.003", "initial.joints=centred"])
    assert got["status"] == "ok" and got["deepest"] == 0 and got["substeps"] == got["steps"]
    steps = got["steps"]
    assert got["copied"] == {"ysave": steps * L.N_Y, "k1save": steps * L.N_Y,
                             "dgsave": steps * L.N_D}
    assert sum(got["copied"].values()) == steps * EVERY_STEP == steps * 184


@pytest.mark.slow
def test_a_split_step_keeps_the_accepted_state_once():
    """The paper preset splits every step (into two sub-steps or more from the seated
    start): each step keeps what an accepted sub-step changes once, at its first
    acceptance, not once per sub-step."""
    got = kept_values("paper_case.yaml", ["solver.duration=0.0005"])
    assert got["status"] == "ok" and got["deepest"] > 0 and got["substeps"] >= 2 * got["steps"]
    steps = got["steps"]
    copied = got["copied"]
    assert copied["msave"] == steps * L.N_WINDOWS * L.N_M
    assert copied["ssave"] == steps * L.N_JOINTS * L.N_S
    assert sum(copied.values()) == steps * (EVERY_STEP + ON_ACCEPT)
