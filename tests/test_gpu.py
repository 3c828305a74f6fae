"""The CUDA backend's code path in numba's CUDA simulator, against the CPU backend; the
no-device report.

The simulator runs in a fresh interpreter (``NUMBA_ENABLE_CUDASIM`` is read when numba is
first imported) with ``NUMBA_DISABLE_JIT=1``: ``run_cases`` and everything it calls
(``rk4.advance``, ``evaluate``, the contact law, the wear map) then run as the Python
source that the CUDA compiler compiles, not the CPU build. This test process runs the
same sweep on the CPU backend, compiled, and compares. Cases are tiny (Python speed).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from clearsweep.cli import sweep_command
from clearsweep.core import jointset
from clearsweep.core.layout import N_ANGLE_BINS

ROOT = Path(__file__).resolve().parents[1]

#: Five cases of 300 steps (3 ms) on a [6, 12] wear map: clearance at B, at A and B, the
#: centred start (impacts), the centred start with contact laws of the literature (Flores
#: damping on the onset impact velocity, Hertz's elastic law: the kernel's other branches),
#: and clearance at the crank's bearing O too (the revolute joint, the crank free in its
#: bearing's plane, the seated journal sliding on its bearing from the start); ``store:
#: full`` so that the CPU sweep keeps series too. The Poincare section at
#: 0.72 degrees falls at t = 2 ms: one section per case (the device's ``sec`` results).
SWEEP = {
    "name": "gpu_sim", "store": "full",
    "base": {"joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4}},
             "wear": {"map": [6, 12], "amplification": 1000.0},
             "metrics": {"settle_time": 0.001},
             "outputs": {"poincare_phase_deg": 0.72},
             "solver": {"duration": 0.003}},
    # the last variant: an elastic bushing at O (issue 42 item 3)
    "sweep": {"zip": [{"name": "variant",
                       "labels": ["B", "AB", "AB_centred", "AB_laws", "ABO", "AB_Obushing"],
                       "joints.A.clearance": [0.0, 2.5e-4, 2.5e-4, 2.5e-4, 2.5e-4, 2.5e-4],
                       "joints.O.clearance": [0.0, 0.0, 0.0, 0.0, 2.5e-4, 0.0],
                       "joints.O.type": ["revolute"] * 5 + ["bushing"],
                       "initial.joints": ["seated", "seated", "centred", "centred", "seated",
                                          "seated"],
                       "contact.damping": ["paper", "paper", "paper", "flores", "paper", "paper"],
                       "contact.impact_velocity": ["max", "max", "max", "onset", "max", "max"],
                       "contact.elastic": ["paper", "paper", "paper", "hertz", "paper",
                                           "paper"]}]},
}

SCRIPT = r"""
import json, sys
import xarray as xr
from clearsweep.core import device, dynamics, rk4
from clearsweep.sweeping import drop_timing, run_sweep

# the device path runs as Python source: no compiled kernel anywhere in this process
assert device.SIMULATED
assert not hasattr(rk4.advance, "py_func") and not hasattr(dynamics.evaluate, "py_func")
doc = json.loads(sys.argv[1])
gpu = run_sweep(doc, sys.argv[2], backend="cuda", keep_series=[1], progress=False)
again = run_sweep(doc, backend="cuda", keep_series=[1], progress=False)
xr.testing.assert_identical(drop_timing(gpu), drop_timing(again))
"""

#: Largest relative difference allowed between a summary of the device code path (run as
#: Python in the simulator) and the CPU backend's. Both are IEEE float64 arithmetic in the
#: same order calling the same libm here, and they agree to the last bit on the machine
#: that wrote this test (measured: 0). The margin covers a numba build whose compiled math
#: differs from Python's ``math`` in the last bit (SVML, LLVM's folding of ``x ** 2``),
#: which 300 steps of contact dynamics can amplify. A real device is another matter
#: (libdevice, fused multiply-adds): benchmarks/bench_gpu.py measures that agreement.
SIMULATOR_RTOL = 1e-9


def run_simulated(script: str, *argv: str) -> subprocess.CompletedProcess:
    """``script`` (with ``argv``) run in the CUDA simulator, in a process of its own (the
    simulator is chosen when numba is imported); fails the test where it fails."""
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1", "NUMBA_DISABLE_JIT": "1",
           "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", script, *argv], capture_output=True,
                          text=True, env=env, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return proc


def assert_summaries_agree(cpu, gpu) -> list[str]:
    """Every summary variable of the CPU backend's results ``cpu`` (but the wall time and the
    status) in the device's ``gpu``: class names word for word, numbers of the same shape,
    NaN in the same places and within :data:`SIMULATOR_RTOL`. Returns the names compared."""
    from clearsweep.summary import SUMMARY_ORDER

    compared = []
    for name in SUMMARY_ORDER:
        if name in ("wall_time", "status") or name not in cpu:
            continue
        if cpu[name].dtype.kind in "USO":       # a class name (motion_class): the same words
            assert [str(v) for v in np.ravel(gpu[name].values)] == \
                [str(v) for v in np.ravel(cpu[name].values)], name
            compared.append(name)
            continue
        a = np.asarray(cpu[name].values, dtype=float)
        b = np.asarray(gpu[name].values, dtype=float)
        assert a.shape == b.shape, name
        assert np.array_equal(np.isnan(a), np.isnan(b)), name
        np.testing.assert_allclose(b, a, rtol=SIMULATOR_RTOL, atol=0.0, equal_nan=True,
                                   err_msg=name)
        compared.append(name)
    return compared


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    from clearsweep.sweeping import run_sweep

    out = tmp_path_factory.mktemp("gpu_sim") / "gpu.nc"
    run_simulated(SCRIPT, json.dumps(SWEEP), str(out))
    cpu = run_sweep(SWEEP, workers=1, progress=False)
    with xr.open_dataset(out) as gpu:
        return cpu, gpu.load()


@pytest.mark.slow
def test_simulated_cuda_summaries_agree_with_the_cpu_backend(simulated):

    cpu, gpu = simulated
    assert [str(s) for s in cpu["status"].values] == ["ok"] * 6
    assert [str(s) for s in gpu["status"].values] == ["ok"] * 6
    # the bearing case wears its bearing, on both paths
    assert float(cpu["wear_volume"].sel(variant="ABO", joint="O")) > 0.0
    compared = assert_summaries_agree(cpu, gpu)
    assert "slider_acceleration_peak_settled" in compared
    assert "wear_depth_axis_max" in compared
    assert "impact_count" in compared
    assert "wear_volume" in compared        # kept by the CUDA summaries too
    assert "poincare_velocity" in compared and "poincare_slider_acc" in compared
    assert np.isfinite(gpu["poincare_offset"].sel(joint="B").values).all()


@pytest.mark.slow
def test_simulated_cuda_keeps_series_only_for_the_selected_cases(simulated):
    _, gpu = simulated
    series = [bool(np.isfinite(gpu["slider_acceleration"].isel(variant=i).values).any())
              for i in range(4)]
    assert series == [False, True, False, False]


def test_cuda_backend_without_a_device_says_so(tmp_path, monkeypatch):
    """No GPU and no simulator: exit status 2 and the one-line hint (this test process has
    the simulator off; on a machine with a GPU the backend would run instead)."""
    from clearsweep import gpu

    if gpu.simulated():
        pytest.skip("the simulator is on in this process")
    try:
        gpu.device_name()
    except gpu.NoCudaDevice:
        pass
    else:
        pytest.skip("a CUDA device is present")
    path = tmp_path / "s.yaml"
    path.write_text(json.dumps(SWEEP))
    result = CliRunner().invoke(sweep_command, [str(path), "--backend", "cuda", "-o",
                                                str(tmp_path / "s.nc")])
    assert result.exit_code == 2
    assert "no CUDA device: use --backend processes" in result.output
    assert not (tmp_path / "s.nc").exists()


def test_keep_series_needs_the_cuda_backend(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(json.dumps(SWEEP))
    result = CliRunner().invoke(sweep_command, [str(path), "--keep-series", "0"])
    assert result.exit_code == 2
    assert "--keep-series" in result.output


def test_case_bytes_of_the_default_map():
    from clearsweep.gpu import case_bytes

    per_case = case_bytes((144, 288), 8)
    assert 1.43e6 < per_case < 1.49e6      # the figure docs/architecture.md states


@pytest.mark.parametrize("store, key", [("summary", "solver.method"), ("life", "store")])
def test_cuda_backend_refuses_what_the_device_does_not_run(tmp_path, store, key):
    """dopri5 cases and life runs are CPU-only: refused by name before the device is even
    looked for, never run silently as something else."""
    from clearsweep.config import ConfigError
    from clearsweep.sweeping import run_sweep

    doc = json.loads(json.dumps(SWEEP))
    doc["store"] = store
    if store == "summary":
        doc["base"]["solver"]["method"] = "dopri5"
    with pytest.raises(ConfigError, match=key) as info:
        run_sweep(doc, tmp_path / "s.nc", backend="cuda", progress=False)
    assert "--backend processes" in str(info.value)
    assert not (tmp_path / "s.nc").exists()


def test_batch_window_fills_the_device_within_the_host_bound(monkeypatch):
    """A sweep's CUDA window takes half the host memory available now, at what a case holds
    on the host (its batch arrays and its results): on a device host of 128 GiB with 120
    available, nearly a full launch of the largest capacity of default-map two-clearance
    cases (before: 16 GiB at most, 23,132 of them at 0.74 MB each, where each held 2.1 MB);
    never more than one such launch; where the machine does not say, the fixed 16 GiB; the
    environment's CLEARSWEEP_HOST_MEMORY in place of either."""
    from clearsweep import gpu
    from clearsweep.config import Config

    monkeypatch.delenv(gpu.HOST_MEMORY_ENV, raising=False)
    cfg = Config().replace(joints__A__clearance=2.5e-4, joints__B__clearance=2.5e-4)
    cases = [cfg] * 40_000
    per_case = gpu.host_case_bytes(cfg)
    gib = 1 << 30
    monkeypatch.setattr(gpu, "available_memory", lambda: 120 * gib)
    assert gpu.batch_window(cases) == 60 * gib // per_case
    assert 30_000 < gpu.batch_window(cases) < gpu.CAPACITIES[-1]
    assert gpu.batch_window(cases[:3]) == 3
    # ideal cases: no maps on the device, every joint's in their results; a full launch
    ideal = gpu.host_case_bytes(Config())
    assert gpu.batch_window([Config()] * 40_000) == gpu.CAPACITIES[-1] < 60 * gib // ideal
    monkeypatch.setattr(gpu, "available_memory", lambda: 4 * gib)
    assert gpu.batch_window(cases) == 2 * gib // per_case
    monkeypatch.setattr(gpu, "available_memory", lambda: None)
    assert gpu.batch_window(cases) == gpu.HOST_BATCH_BYTES // per_case
    monkeypatch.setenv(gpu.HOST_MEMORY_ENV, "1T")
    assert gpu.batch_window(cases) == gpu.CAPACITIES[-1]       # one full launch at most
    monkeypatch.setenv(gpu.HOST_MEMORY_ENV, "8G")
    monkeypatch.setattr(gpu, "available_memory", lambda: 120 * gib)
    assert gpu.batch_window(cases) == 8 * gib // per_case


def test_host_case_bytes_hold_the_results_in_the_cpu_kernels_shape():
    """What a window's case holds on the host: its device arrays and, until its part is
    written, its results' wear map and projections for every joint (the CPU kernel's shape),
    1.36 MB on the default map: 2.07 MB for the two-clearance case."""
    from clearsweep import gpu
    from clearsweep.config import load_config

    cfg = load_config(str(ROOT / "configs" / "two_clearances.yaml"))
    results = 8 * (4 * 144 * 288 + 4 * 3 * N_ANGLE_BINS)
    assert gpu.host_case_bytes(cfg) - gpu.config_bytes(cfg) == results == 1_361_664
    assert gpu.host_case_bytes(cfg) == 2_073_632


@pytest.mark.parametrize("text, expected", [
    ("64G", 64 << 30), ("64GiB", 64 << 30), ("512m", 512 << 20), ("1T", 1 << 40),
    ("123456789", 123456789), ("8KB", 8 << 10), (" 2G ", 2 << 30),
    ("0", None), ("-5G", None), ("1.5G", None), ("12x", None), ("G", None), ("2\u00b2", None),
    ("64 P", None)])
def test_host_memory_setting(text, expected):
    from clearsweep import gpu
    from clearsweep.config import ConfigError

    if expected is not None:
        assert gpu.host_memory_setting(text) == expected
        return
    with pytest.raises(ConfigError, match=f"{gpu.HOST_MEMORY_ENV}: got") as info:
        gpu.host_memory_setting(text)
    assert "64G" in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("meminfo, cgroup, expected", [
    ("MemTotal: 24683792 kB\nMemFree: 2013 kB\nMemAvailable: 23166124 kB\n", None,
     23166124 * 1024),
    ("MemTotal: 24683792 kB\nMemAvailable: 23166124 kB\n", ("max", "100"), 23166124 * 1024),
    ("MemTotal: 24683792 kB\nMemAvailable: 23166124 kB\n", (str(8 << 30), str(3 << 30)),
     5 << 30),
    (None, (str(8 << 30), str(3 << 30)), 5 << 30)])
def test_available_memory_reads_meminfo_and_the_cgroups_limit(tmp_path, monkeypatch, meminfo,
                                                              cgroup, expected):
    """MemAvailable of /proc/meminfo, or less where the memory cgroup leaves less (a
    container's limit: MemAvailable is the whole machine's there)."""
    from clearsweep import gpu

    info = tmp_path / "meminfo"
    if meminfo is not None:
        info.write_text(meminfo)
    limit, usage = tmp_path / "memory.max", tmp_path / "memory.current"
    if cgroup is not None:
        limit.write_text(cgroup[0] + "\n")
        usage.write_text(cgroup[1] + "\n")
    monkeypatch.setattr(gpu, "MEMINFO", str(info))
    monkeypatch.setattr(gpu, "CGROUP_MEMORY", ((str(limit), str(usage)),))
    if meminfo is None:
        monkeypatch.setattr("os.sysconf", lambda name: {"SC_AVPHYS_PAGES": 4 << 20,
                                                        "SC_PAGE_SIZE": 4096}[name])
    assert gpu.available_memory() == expected


LAYOUT_SCRIPT = r"""
import sys
import numpy as np
from clearsweep.config import DEFAULTS, resolve_materials
from clearsweep.params import pack
from clearsweep import gpu

base = DEFAULTS.replace(solver__duration=0.002, wear__map=[6, 12], wear__amplification=1000.0,
                        metrics__settle_time=0.001, outputs__poincare_phase_deg=0.72)
cfgs = [base.replace(joints__A__clearance=2.5e-4, joints__B__clearance=2.5e-4),
        base.replace(joints__B__clearance=2.5e-4, joints__O__clearance=2.5e-4,
                     initial__joints="centred"),
        base]
packed = [pack(c, resolve_materials(c)) for c in cfgs]
aos = gpu.run_packed(packed, layout="aos")
pairs = []
for layout in ("soa", "soa-local", "soa-one-evaluate"):
    pairs += list(zip(aos, gpu.run_packed(packed, layout=layout)))
for k, (a, b) in enumerate(pairs):
    assert a.status == b.status == "ok", (k, a.status, b.status)
    for name in ("stats", "wmap", "proj", "wvol", "sec", "first_impact"):
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), (k, name)
        assert getattr(b, name).flags.c_contiguous, (k, name)     # as the CPU kernel's
    assert (a.residual_max, a.ke_peak, a.rk4_steps, a.deepest) == (b.residual_max, b.ke_peak, b.rk4_steps, b.deepest), k
impacts = float(aos[1].stats[0].max())
print("compared", len(pairs), "cases; largest statistic", impacts)
"""


@pytest.mark.slow
def test_simulated_layouts_agree_bit_for_bit():
    """The structure-of-arrays kernel (strided views of arrays padded to a launch capacity),
    the same with the fixed-size work arrays in each thread's local memory ("soa-local",
    their launch arrays placeholders), the same with each step's evaluations at one call
    site ("soa-one-evaluate", ``core.onestep``) and the case-by-case one compute the same bits in the
    simulator, where each runs the kernel's Python source: clearance at A and B, at B and O
    from the centred start (impacts), and ideal joints, in one batch."""
    proc = run_simulated(LAYOUT_SCRIPT)
    assert "compared 9 cases" in proc.stdout


def test_the_numpy_numba_cuda_pairing_is_pinned_as_the_check_states():
    """pyproject's cuda and test extras pin numba-cuda to the releases gpu.NUMPY_BELOW knows,
    with the numpy bound it states for them (numba-cuda 0.30.4 failed every case under
    numpy 2.5 on a device)."""
    import re

    from clearsweep import gpu

    text = (ROOT / "pyproject.toml").read_text()     # no tomllib before Python 3.11
    for name in ("cuda", "test"):
        listed = re.search(rf"^{name} = \[(.*?)\]$", text, re.MULTILINE | re.DOTALL)
        assert listed is not None, name
        extra = re.findall(r'"([^"]+)"', listed.group(1))
        reqs = {re.split(r"[\[<>=!~ ]", r, maxsplit=1)[0]: r for r in extra}
        nc = re.fullmatch(r"numba-cuda(\[cu12\])?>=(\d+)\.(\d+)\.\d+,<(\d+)\.(\d+)", reqs["numba-cuda"])
        assert nc is not None, reqs["numba-cuda"]
        low, high = (int(nc.group(2)), int(nc.group(3))), (int(nc.group(4)), int(nc.group(5)))
        assert high == (low[0], low[1] + 1), "one numba-cuda minor release"
        below = gpu.NUMPY_BELOW[low]
        assert reqs["numpy"] == f"numpy<{below[0]}.{below[1]}"


@pytest.mark.parametrize("numpy_version, numba_cuda, refused", [
    ("2.4.6", "0.30.4", False), ("2.5.0", "0.30.4", True), ("2.5.0rc1", "0.30.9", True),
    ("3.0.0", "0.30.4", True), ("2.5.0", None, False), ("2.5.0", "0.31.0", False)])
def test_pairing_problem(numpy_version, numba_cuda, refused):
    from clearsweep import gpu

    message = gpu.pairing_problem(numpy_version, numba_cuda)
    assert (message is not None) == refused
    if refused:
        assert "\n" not in message and f"numpy {numpy_version}" in message
        assert "numpy below 2.5" in message and "--backend processes" in message


def test_a_mismatched_pairing_is_one_line_before_any_case_runs(tmp_path, monkeypatch):
    """numba-cuda 0.30.4 with numpy 2.5 (faked): the sweep stops with one error line naming
    both versions and the fix, exit 2, before a case is packed or a file written; the same
    refusal from Python, before the device is even asked for."""
    from clearsweep import gpu
    from clearsweep.sweeping import run_sweep

    if gpu.simulated():
        pytest.skip("the simulator is on in this process")
    monkeypatch.setattr(gpu, "installed_versions", lambda: ("2.5.0", "0.30.4"))
    ran = []
    monkeypatch.setattr(gpu, "run_packed", lambda *a, **k: ran.append(a) or [])
    path = tmp_path / "s.yaml"
    path.write_text(json.dumps(SWEEP))
    result = CliRunner().invoke(sweep_command, [str(path), "--backend", "cuda", "-o",
                                                str(tmp_path / "s.nc")])
    assert result.exit_code == 2
    errors = [line for line in result.output.splitlines() if line.startswith("clearsweep: error")]
    assert errors == ["clearsweep: error: numba-cuda 0.30.4 does not compile the kernel with "
                      "numpy 2.5.0: install numpy below 2.5 (pip install 'clearsweep[cuda]'), "
                      "or use --backend processes"], result.output
    assert not (tmp_path / "s.nc").exists() and ran == []
    with pytest.raises(gpu.NoCudaDevice, match="numba-cuda 0.30.4 does not compile"):
        run_sweep(SWEEP, tmp_path / "t.nc", backend="cuda", progress=False)
    assert not (tmp_path / "t.nc").exists() and ran == []


def test_case_bytes_shrink_for_a_case_without_O_P_clearance():
    """A structure-of-arrays case carries maps, projections and undo rows for its clearance
    joints alone: the two-clearance benchmark case (A and B) drops P's and O's maps (two of
    npolar x nazim bins), their projections and half the undo buffer (O's and P's rows)
    against every joint's; a bearing-only case holds one map row of nazim bins."""
    from clearsweep import gpu
    from clearsweep.config import load_config

    cfg = load_config(str(ROOT / "configs" / "two_clearances.yaml"))
    npolar, nazim = cfg.wear.map
    level = cfg.solver.max_substep_level
    sections = math.ceil(cfg.solver.duration * cfg.mechanism.speed_rpm / 60.0) + 1
    every = gpu.case_bytes(cfg.wear.map, level, sections)
    mine = gpu.config_bytes(cfg)
    # buf_i and buf_v, 4 columns: every joint's rows at the level cap against A's and B's at
    # the level a launch holds first
    undo_saved = 2 * 4 * (4 * (1 << level) - 2 * (1 << gpu.UNDO_LEVEL))
    assert every - mine == 8 * (2 * npolar * nazim + 2 * 3 * N_ANGLE_BINS) + 8 * undo_saved
    assert mine < 0.52 * every
    bearing = (False, False, True, False)         # the kernel's order: A, B, O, P
    # ideal: one map row and one projection row (no zero-size arrays); the bearing: its row
    # of nazim bins, its three projection rows, its undo rows
    assert (gpu.case_bytes(cfg.wear.map, level, sections, bearing)
            - gpu.case_bytes(cfg.wear.map, level, sections, (False,) * 4)
            == 8 * ((nazim - nazim) + (3 - 1) * N_ANGLE_BINS))
    # half of an 80 GB H100 holds a full launch of the largest capacity for the two-clearance
    # case (before: 27,472 cases fitted, launched 16,384 at a time)
    size, cap = gpu.batch_plan(100_000, int(40e9) // mine)
    assert (size, cap) == (32_768, 32_768)


@pytest.mark.parametrize("present", [tuple(bool(k >> j & 1) for j in range(4)) for k in range(16)])
def test_joint_rows_keep_every_clearance_joints_rows_apart(present):
    """gpu.joint_rows places each clearance joint's rows (the kernel's order A, B, O, P) at
    r0 + j * dj, disjoint and within the array; the spherical pair A, B takes exactly two
    maps and a lone joint exactly its own rows."""
    from clearsweep import gpu

    npolar = 6
    rows = [gpu.MAP_ROWS[name](npolar) if c else 0 for name, c in zip(gpu.JOINT_NAMES, present)]
    r0, dj, total = gpu.joint_rows(rows)
    taken = np.zeros(total, dtype=int)
    for j, r in enumerate(rows):
        if r:
            first = r0 + j * dj
            assert 0 <= first and first + r <= total, (j, first, r, total)
            taken[first:first + r] += 1
    assert taken.max(initial=0) <= 1
    if sum(1 for r in rows if r) <= 1:
        assert total == max(1, max(rows))
    if present == (True, True, False, False):
        assert total == 2 * npolar


SHARED_SCRIPT = r"""
import sys
import numpy as np
from clearsweep.core.layout import P_MAX_LEVEL
from clearsweep.config import DEFAULTS, resolve_materials
from clearsweep.params import pack
from clearsweep import gpu

base = DEFAULTS.replace(solver__duration=0.002, wear__map=[6, 12], wear__amplification=1000.0,
                        metrics__settle_time=0.001, outputs__poincare_phase_deg=0.72,
                        joints__A__clearance=2.5e-4)
cfgs = [base.replace(joints__B__clearance=c) for c in (1.5e-4, 2.5e-4)]
cfgs.append(base.replace(joints__B__clearance=2.0e-4, mechanism__speed_rpm=1500.0))
packed = [pack(c, resolve_materials(c)) for c in cfgs]
seen = []
launch = gpu._run_on_device
def spy(arrays, layout="aos", *build):
    seen.append({k: np.array(arrays[k]) for k in ("p", "jp", "pcols", "geom", "wmap", "proj")})
    return launch(arrays, layout, *build)
gpu._run_on_device = spy
aos = gpu.run_packed(packed, layout="aos")
soa = gpu.run_packed(packed, layout="soa")
batch = seen[-1]
rows = gpu.parameter_rows(packed)
# the launch's level cap: the level its undo buffer holds (gpu.launch_level)
rows[:, P_MAX_LEVEL] = np.minimum(rows[:, P_MAX_LEVEL], gpu.UNDO_LEVEL)
varying = np.flatnonzero((rows != rows[:1]).any(axis=0))
# the per-case array holds the varying parameters alone; the shared row the rest
assert np.array_equal(np.flatnonzero(batch["pcols"] >= 0), varying), (batch["pcols"], varying)
assert batch["p"].shape[0] == varying.size < 10, batch["p"].shape
shared = batch["pcols"] < 0
assert np.array_equal(batch["jp"][shared], rows[0][shared])
# the maps hold A's and B's rows alone: two maps of 6 rows
assert batch["wmap"].shape[0] == 12 and batch["proj"].shape[0] == 6, batch["geom"]
for k, (a, b) in enumerate(zip(aos, soa)):
    assert a.status == b.status == "ok", (k, a.status, b.status)
    for name in ("stats", "wmap", "proj", "wvol", "sec", "first_impact"):
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), (k, name)
    assert (a.residual_max, a.ke_peak, a.rk4_steps) == (b.residual_max, b.ke_peak, b.rk4_steps), k
assert float(soa[2].wvol.sum()) > 0.0
print("shared", int(shared.sum()), "of", shared.size, "parameters; per case", varying.size)
"""


@pytest.mark.slow
def test_shared_parameters_are_read_from_the_batchs_one_row():
    """Parameters equal across a batch travel once, in its shared row; the per-case array
    holds the others alone (B's clearance and the crank speed here, and what they set), so
    the kernel can only have read the shared ones from that row: the results are the
    case-by-case layout's to the bit in the simulator."""
    proc = run_simulated(SHARED_SCRIPT)
    assert "shared" in proc.stdout


MIXED = {
    "name": "gpu_mixed", "store": "summary",
    "base": {"joints": {"B": {"clearance": 2.5e-4}},
             "wear": {"map": [6, 12], "amplification": 1000.0},
             "metrics": {"settle_time": 0.001},
             "solver": {"duration": 0.002},
             "ensemble": {"members": 2, "seed": 3,
                          "perturb": {"crank_phase_deg": 5.0, "wear_coefficient_cv": 0.2}}},
    "sweep": {"grid": {"joints.O.clearance": [0.0, 1.5e-4, 2.5e-4]}},
}

MIXED_SCRIPT = r"""
import json, sys
import numpy as np
from clearsweep.core import device
from clearsweep.sweeping import run_sweep

launches = []
launch = device.launch
def counted(arrays, layout="aos", spec=device.ALL, case_sets=()):
    launches.append((int(arrays["n_steps"].shape[0]), layout, [int(g) for g in np.array(arrays["geom"])],
                     int(spec)))
    return launch(arrays, layout, spec, case_sets)
device.launch = counted
run_sweep(json.loads(sys.argv[1]), sys.argv[2], backend="cuda", progress=False)
print(json.dumps(launches))
"""


@pytest.mark.slow
def test_sweep_cases_and_ensemble_members_share_one_launch(tmp_path):
    """Three sweep cases (the bearing O ideal, and with two clearances) of two ensemble
    members each run as two launches in the simulator, one per kernel build: the two
    members of the ideal bearing on B's build, and the four cases with clearance at O on
    the build of B and O (members and sweep cases of one joint set share a launch, whose
    maps hold B's and O's rows); every summary agrees with the CPU backend's within the
    simulator's tolerance."""
    from clearsweep.sweeping import run_sweep

    out = tmp_path / "mixed.nc"
    proc = run_simulated(MIXED_SCRIPT, json.dumps(MIXED), str(out))
    launches = json.loads(proc.stdout.strip().splitlines()[-1])
    b, bo = jointset.named("B"), jointset.named("B", "O")
    assert sorted((n, layout, spec) for n, layout, _, spec in launches) == \
        [(2, "soa", b), (4, "soa", bo)]
    cpu = run_sweep(MIXED, workers=1, progress=False)
    with xr.open_dataset(out) as gpu:
        gpu = gpu.load()
    assert gpu.sizes["member"] == 2 and gpu.sizes["O_clearance"] == 3
    assert float(gpu["wear_volume"].sel(joint="O").isel(O_clearance=1).min()) > 0.0
    assert_summaries_agree(cpu, gpu)


#: The guide P with clearance on the device path (no case above has it): A, B and P with
#: clearance, P's walls read bilinearly and worn (amplified), from the seated start, where
#: the block rests on its walls from the first step; 300 steps on an [8, 12] map (two rows
#: per wall). Its contact is the device's costliest (benchmarks/README.md, issue 43).
GUIDE = {
    "name": "gpu_guide", "store": "summary",
    "base": {"joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4},
                        "P": {"clearance_y": 1.0e-4, "clearance_z": 1.0e-4}},
             "wear": {"map": [8, 12], "amplification": 1.0e5, "interpolate": True},
             "metrics": {"settle_time": 0.001},
             "solver": {"duration": 0.003}},
    "sweep": {"zip": [{"name": "variant", "labels": ["seated"], "initial.joints": ["seated"]}]},
}

GUIDE_SCRIPT = r"""
import json, sys
from clearsweep.core import device
from clearsweep.sweeping import run_sweep

assert device.SIMULATED
run_sweep(json.loads(sys.argv[1]), sys.argv[2], backend="cuda", progress=False)
"""


@pytest.mark.slow
def test_simulated_guide_agrees_with_the_cpu_backend(tmp_path):
    """A case with clearance at the guide P runs the device path (``prismatic.contact``,
    ``accept`` and ``deposit`` in the kernel's Python source) to the CPU backend's summaries
    within the simulator's tolerance, the guide's walls worn on both."""
    from clearsweep.sweeping import run_sweep

    out = tmp_path / "guide.nc"
    run_simulated(GUIDE_SCRIPT, json.dumps(GUIDE), str(out))
    cpu = run_sweep(GUIDE, workers=1, progress=False)
    with xr.open_dataset(out) as gpu:
        gpu = gpu.load()
    assert [str(s) for s in gpu["status"].values] == [str(s) for s in cpu["status"].values] == ["ok"]
    assert float(cpu["wear_volume"].sel(joint="P").max()) > 0.0
    assert_summaries_agree(cpu, gpu)


#: The planar slider-crank on the device path (its build's guide along y, jointset.SLIDER_CRANK):
#: the benchmark's clearance at the wrist pin B, and at the crank bearing O and the crank pin A
#: too, worn (amplified), 300 steps at the benchmark's 5000 rpm (a quarter revolution in 3 ms:
#: dt 1e-5 s). The Poincare section at 18 degrees falls at t = 0.6 ms: one per case.
SLIDER_CRANK = {
    "name": "gpu_slider_crank", "store": "summary",
    "base": {"mechanism": {"kind": "slider_crank", "preset": "flores_benchmark",
                           "speed_rpm": 5000.0},
             "joints": {"B": {"clearance": 5.0e-4, "socket_radius": 0.01}},
             "wear": {"map": [6, 12], "amplification": 100.0},
             "metrics": {"settle_time": 0.001},
             "outputs": {"poincare_phase_deg": 18.0},
             "solver": {"dt": 1.0e-5, "duration": 0.003}},
    "sweep": {"zip": [{"name": "variant", "labels": ["B", "OAB"],
                       "joints.A.clearance": [0.0, 2.0e-4],
                       "joints.O.clearance": [0.0, 2.0e-4]}]},
}


@pytest.mark.slow
def test_simulated_slider_crank_agrees_with_the_cpu_backend(tmp_path):
    """The slider-crank's cases run the device path with its own build (the guide along y
    folded in, the set from each case's p[P_GUIDE]) to the CPU backend's summaries within
    the simulator's tolerance."""
    from clearsweep.sweeping import run_sweep

    out = tmp_path / "slider_crank.nc"
    run_simulated(GUIDE_SCRIPT, json.dumps(SLIDER_CRANK), str(out))
    cpu = run_sweep(SLIDER_CRANK, workers=1, progress=False)
    with xr.open_dataset(out) as gpu:
        gpu = gpu.load()
    assert [str(s) for s in gpu["status"].values] == [str(s) for s in cpu["status"].values] \
        == ["ok", "ok"]
    assert float(cpu["wear_volume"].sel(joint="B").min()) > 0.0
    assert float(cpu["slider_acceleration_peak"].min()) > 1.0e4     # the benchmark's scale
    assert_summaries_agree(cpu, gpu)


def test_the_undo_buffer_is_held_for_the_first_launchs_level():
    """A launch holds the undo buffer for gpu.UNDO_LEVEL, not the level cap: per undone
    joint 16 rows of (4 int64 + 4 float64) where the default cap of 8 took 256. The
    two-clearance benchmark case (A and B) on the default map at level 8 took 742,688 B with
    the buffer of the cap (case_bytes before this change) and takes 30,720 B less now; the
    two clearances of the bearing O and the spherical joint B likewise."""
    from clearsweep import gpu
    from clearsweep.config import load_config

    cfg = load_config(str(ROOT / "configs" / "two_clearances.yaml"))
    level = cfg.solver.max_substep_level
    assert level == 8 and gpu.UNDO_LEVEL < level
    sections = math.ceil(cfg.solver.duration * cfg.mechanism.speed_rpm / 60.0) + 1
    for joints in [(True, True, False, False), (False, True, True, False)]:
        full = gpu.case_bytes(cfg.wear.map, level, sections, joints)
        first = gpu.case_bytes(cfg.wear.map, gpu.launch_level(level), sections, joints)
        assert full - first == 2 * 2 * 4 * 8 * ((1 << level) - (1 << gpu.UNDO_LEVEL)) == 30_720
    ab = (True, True, False, False)
    assert gpu.case_bytes(cfg.wear.map, level, sections, ab) == 742_688
    assert gpu.config_bytes(cfg) == gpu.case_bytes(cfg.wear.map, gpu.UNDO_LEVEL, sections, ab) \
        == 711_968
    # a cap below the first launch's level keeps its own (smaller) buffer; None: the cap's
    assert gpu.launch_level(2) == 2 and gpu.launch_level(12, None) == 12
    assert gpu.undo_rows(ab, gpu.launch_level(level)) == 2 * 16


UNDO_SCRIPT = r"""
import json
import numpy as np
from clearsweep.core.layout import P_MAX_LEVEL
from clearsweep.config import load_config, resolve_materials
from clearsweep.core import device
from clearsweep.params import pack
from clearsweep.simulation import run_kernel
from clearsweep import gpu

# the paper's preset (its light rod: fast contact rates) at the default step and level cap,
# seated, 20 steps: at 60 r/min its steps split into 16 sub-steps at most, at 30 r/min into
# 64 (measured: deepest levels 4 and 6)
base = load_config("configs/paper_case.yaml", ["solver.dt=1e-5", "solver.duration=0.0002",
                   "solver.max_substep_level=8", "solver.save_every=1", "wear.map=[6,12]",
                   "wear.amplification=1000.0"])
cfgs = [base, base.replace(mechanism__speed_rpm=30.0)]
packed = [pack(c, resolve_materials(c)) for c in cfgs]
launches = []
launch = device.launch
def spy(arrays, layout="aos", spec=device.ALL, case_sets=()):
    n, col = int(arrays["n_steps"].shape[0]), int(arrays["pcols"][P_MAX_LEVEL])
    caps = arrays["p"][col, :n] if col >= 0 else [arrays["jp"][P_MAX_LEVEL]]
    launches.append([n, int(arrays["buf_i"].shape[0]), sorted({float(v) for v in caps})])
    return launch(arrays, layout, spec, case_sets)
device.launch = spy
first = gpu.run_packed(packed)
once = list(launches)
launches.clear()
full = gpu.run_packed(packed, undo_level=None)
cpu = [run_kernel(pk) for pk in packed]
for k, (a, b, c) in enumerate(zip(first, full, cpu)):
    assert a.status == b.status == c.status == "ok", (k, a.status, b.status, c.status)
    for name in ("stats", "wmap", "proj", "wvol", "sec", "first_impact"):
        x, y, z = (np.asarray(getattr(r, name)) for r in (a, b, c))
        assert np.array_equal(x, y, equal_nan=True) and np.array_equal(x, z, equal_nan=True), (k, name)
    for name in ("residual_max", "ke_peak", "rk4_steps", "deepest", "t_end"):
        assert getattr(a, name) == getattr(b, name) == getattr(c, name), (k, name)
print("LAUNCHES " + json.dumps([once, launches, [r.deepest for r in first]]))
"""


@pytest.mark.slow
def test_a_case_deeper_than_the_undo_buffer_runs_again_to_the_same_bits():
    """Two cases of the paper's preset in one launch, whose steps split to levels 4 and 6:
    the first launch holds A's and B's undo rows of level gpu.UNDO_LEVEL (4: 2 x 16 rows)
    and lowers the cases' level cap to it; the case that needs level 6 stops there, before
    its attempt, and runs again alone with the rows of its cap (8: 2 x 256). Both cases end
    with the bits of one launch of the full buffer and of the CPU kernel (its Python source,
    run in the same process)."""
    proc = run_simulated(UNDO_SCRIPT)
    line = [x for x in proc.stdout.splitlines() if x.startswith("LAUNCHES")][-1]
    once, full, deepest = json.loads(line.split(" ", 1)[1])
    assert deepest == [4, 6]
    assert once == [[2, 2 * 16, [4.0]], [1, 2 * 256, [8.0]]]
    assert full == [[2, 2 * 256, [8.0]]]


HOST_MEMORY_SCRIPT = r"""
import tracemalloc
from clearsweep import gpu
from clearsweep.config import load_config

cfg = load_config("configs/two_clearances.yaml", ["solver.duration=0.00003"])
cfgs = [cfg.replace(joints__B__clearance=2.5e-4 + 1e-6 * k) for k in range(gpu.SIMULATOR_BATCH)]
gpu.simulate_batch(cfgs[:1])            # imports and first uses outside the count
tracemalloc.start()
results = gpu.simulate_batch(cfgs)
peak = tracemalloc.get_traced_memory()[1]
assert not any(isinstance(r, BaseException) for r in results), results
print("PER_CASE", peak / len(cfgs), gpu.host_case_bytes(cfg), gpu.config_bytes(cfg))
"""


@pytest.mark.slow
def test_a_window_holds_what_host_case_bytes_says_per_case():
    """A batch of 64 two-clearance cases on the default map (3 steps each) in the simulator:
    the host's peak of new allocations per case while it runs and its datasets are made
    (tracemalloc) is within 2 % of gpu.host_case_bytes (measured: 2.06 MB of 2.07), near
    three times the 0.71 MB of device arrays (config_bytes) that the window counted before."""
    proc = run_simulated(HOST_MEMORY_SCRIPT)
    line = [x for x in proc.stdout.splitlines() if x.startswith("PER_CASE")][-1]
    peak, estimate, device_bytes = (float(v) for v in line.split()[1:])
    assert 0.98 * estimate <= peak <= 1.02 * estimate, (peak, estimate)
    assert peak > 2.5 * device_bytes


MAP_ROWS_SCRIPT = r"""
import json
import numpy as np
from clearsweep.config import DEFAULTS, load_config, resolve_materials
from clearsweep.core import device
from clearsweep.params import pack
from clearsweep.simulation import run_kernel
from clearsweep import gpu

# on a [6, 12] map, whose 6 polar rows the guide's four wall bands use 4 of: A, B and the
# guide P with clearance (seated: the block on its walls from the first step, worn
# amplified); the slider-crank's benchmark with clearance at B, and at O, A and B
rssp = DEFAULTS.replace(solver__duration=0.001, wear__map=[6, 12], wear__amplification=1.0e5,
                        wear__interpolate=True, metrics__settle_time=0.0005,
                        joints__A__clearance=2.5e-4, joints__B__clearance=2.5e-4,
                        joints__P__clearance_y=1.0e-4, joints__P__clearance_z=1.0e-4)
crank = {"mechanism": {"kind": "slider_crank", "preset": "flores_benchmark", "speed_rpm": 5000.0},
         "joints": {"B": {"clearance": 5.0e-4, "socket_radius": 0.01}},
         "wear": {"map": [6, 12], "amplification": 100.0}, "metrics": {"settle_time": 0.0005},
         "solver": {"dt": 1.0e-5, "duration": 0.001}}
oab = json.loads(json.dumps(crank))
oab["joints"].update(A={"clearance": 2.0e-4}, O={"clearance": 2.0e-4})
batches = [[rssp], [load_config(crank), load_config(oab)]]
rows = []
launch = device.launch
def spy(arrays, layout="aos", spec=device.ALL, case_sets=()):
    if layout == "soa":
        rows.append(int(arrays["wmap"].shape[0]))
    return launch(arrays, layout, spec, case_sets)
device.launch = spy
for cfgs in batches:
    packed = [pack(c, resolve_materials(c)) for c in cfgs]
    soa = gpu.run_packed(packed, layout="soa")
    aos = gpu.run_packed(packed, layout="aos")
    cpu = [run_kernel(pk) for pk in packed]
    for k, (a, b, c) in enumerate(zip(soa, aos, cpu)):
        assert a.status == b.status == c.status == "ok", (k, a.status, b.status, c.status)
        for name in ("stats", "wmap", "proj", "wvol", "sec", "first_impact"):
            x, y, z = (np.asarray(getattr(r, name)) for r in (a, b, c))
            assert x.shape == y.shape == z.shape, (k, name)
            assert np.array_equal(x, y, equal_nan=True) and np.array_equal(x, z, equal_nan=True), (k, name)
        for name in ("residual_max", "ke_peak", "rk4_steps", "deepest"):
            assert getattr(a, name) == getattr(b, name) == getattr(c, name), (k, name)
    worn = [float(r.wvol.max()) for r in soa]
    assert min(worn) > 0.0, worn
print("ROWS " + json.dumps([rows, [r.deepest for r in soa], float(soa[1].wmap[0, 0].max()),
                           float(abs(soa[1].wmap[0, 1:]).max())]))
"""


@pytest.mark.slow
def test_each_joint_type_holds_the_map_rows_it_uses_on_the_device():
    """The structure-of-arrays maps hold the rows each clearance joint's type uses: on a
    [6, 12] map the guide P's four wall bands take 4 rows (6 before), so that A, B and P
    take 3 x 6 + 4 = 22 rows (24); the slider-crank's pins A and B, bearings, one row each
    (6 before), so that O, A and B take 3 rows (13). The guide's walls and the pins'
    bearings wear, and every result is the case-by-case layout's (the CPU kernel's map
    shape, every row) and the CPU kernel's (its Python source, in the same process) to the
    bit."""
    proc = run_simulated(MAP_ROWS_SCRIPT)
    line = [x for x in proc.stdout.splitlines() if x.startswith("ROWS")][-1]
    rows, deepest, pin_row0, pin_rest = json.loads(line.split(" ", 1)[1])
    # one launch per build: A, B and P; the slider-crank's B; its O, A and B, whose case
    # reaches sub-step level 5 and runs again with the full undo buffer
    assert rows == [22, 1, 3, 3] and deepest == [3, 5]
    assert pin_row0 > 0.0 and pin_rest == 0.0      # A's bearing: its row 0 alone


def test_case_bytes_of_the_rows_each_type_uses():
    """Device memory per case on the default map [144, 288]: the slider-crank's benchmark
    (B) 371,360 -> 41,888 B (B's map one row, not 144); with clearance at O, A and B
    724,768 -> 65,824 B; with B and the guide P 703,136 -> 373,664 B. The RSSP's guide on
    the default map uses all of its 144 rows (1,375,520 B with A, B and P, as before); on a
    [150, 300] map it uses 148: 1,488,992 -> 1,484,192 B (before: computed by this function
    on the tree before the change)."""
    from clearsweep import gpu
    from clearsweep.config import load_config

    crank = str(ROOT / "configs" / "slider_crank.yaml")
    rssp = str(ROOT / "configs" / "two_clearances.yaml")
    guide = ["joints.P.clearance_z=1e-4", "joints.P.clearance_y=1e-4"]
    cases = [(crank, [], 41_888), (crank, ["joints.A.clearance=2e-4", "joints.O.clearance=2e-4"], 65_824),
             (crank, guide, 373_664), (rssp, guide, 1_375_520),
             (rssp, guide + ["wear.map=[150,300]"], 1_484_192)]
    for path, overrides, expected in cases:
        assert gpu.config_bytes(load_config(path, overrides)) == expected, (path, overrides)
    assert gpu.map_rows((False, True, False, True), 150, slider_crank=True) == [0, 1, 0, 148]
    assert gpu.map_rows((True, True, True, True), 144) == [144, 144, 1, 144]
