"""benchmarks/device_suite.py, the device measurements in one call, runs in numba's CUDA
simulator on 8 cases: every step it takes on a device but the builds and ncu, which it
records as skipped, so that the call is known to work before device time is spent."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_the_device_suite_runs_in_the_simulator(tmp_path):
    out = tmp_path / "suite"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "device_suite.py"), str(out),
                           "--simulator"], capture_output=True, text=True, env=env, cwd=ROOT,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-4000:]
    assert sorted(p.name for p in out.iterdir()) == ["suite.json", "suite.md"]
    record = json.loads((out / "suite.json").read_text())
    assert record["simulator"] and record["device"] == "numba CUDA simulator"
    kernel = {k["kernel"]: k for k in record["steps"]["kernel"] + record["steps"]["variants"]}
    # step 2, and issue 43 item 6's arrangements (4b): local work arrays, the L1 carve-out,
    # one evaluate call site per step
    assert sorted(kernel) == ["aos", "soa", "soa-local", "soa-maxl1", "soa-one-evaluate"]
    for layout, k in kernel.items():
        assert k["rc"] == 0, k["tail"]
        assert [launch["cases"] for launch in k["launches"]] == [8]
        assert k["launches"][0]["statuses"] == {"ok": 8} and k["launches"][0]["steps_per_s"] > 0
        # the simulator runs the kernel's Python source: the CPU kernel's bits
        assert len(k["agreement"]) == 3
        assert all(a["stats_max_rel"] <= 1e-9 and a["wvol_max_rel"] <= 1e-9 for a in k["agreement"])
    for name in ("sweep_cuda", "sweep_cpu"):
        sweep = record["steps"][name]
        assert sweep["rc"] == 0, sweep["tail"]
        assert sweep["cases"] == 8 and sweep["statuses"] == {"ok": 8} and sweep["failed"] == 0
    assert "--backend" in record["steps"]["sweep_cuda"]["argv"]
    assert record["steps"]["sweep_cuda"]["argv"][-1] == "cuda"
    assert set(record["skipped"]) == {"builds", "ncu"}
    table = (out / "suite.md").read_text()
    assert "| step | layout | cases |" in table
    assert table.count("| kernel | ") == 5 and "device / CPU workers" in table


def _suite_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("device_suite",
                                                  ROOT / "benchmarks" / "device_suite.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_builds_run_in_processes_and_report(tmp_path):
    """The builds step's plumbing, with the one build that needs no device (the CPU
    kernel): a process per build, its report read back; a build that fails is recorded with
    its output, not raised."""
    suite_mod = _suite_module()
    suite = suite_mod.Suite(tmp_path, tmp_path, budget=600.0, simulator=False)
    suite_mod.builds(suite, [("cpu", 0), ("no-such-layout", 0)])
    done = suite.record["steps"]["builds"]["kernels"]
    assert done[0]["layout"] == "cpu" and done[0]["build_s"] >= 0.0
    assert done[1]["layout"] == "no-such-layout" and "error" in done[1]


def test_ncu_csv_is_read_by_metric_name():
    suite_mod = _suite_module()
    text = ('==PROF== Connected to process 1\n'
            '"ID","Kernel Name","Section Name","Metric Name","Metric Unit","Metric Value"\n'
            '"0","run_cases","Occupancy","Achieved Occupancy","%","11.52"\n'
            '"0","run_cases","Memory Workload Analysis","L2 Hit Rate","%","40.10"\n'
            '"0","run_cases","Warp State Statistics","Stall Long Scoreboard","cycle","12.3"\n')
    rows = suite_mod._ncu_rows(text)
    assert rows["Achieved Occupancy"] == "11.52" and rows["L2 Hit Rate"] == "40.10"
    assert suite_mod._ncu_value(text, "DRAM Throughput") is None
    assert "Stall Long Scoreboard" in rows
