"""Sweeps: expansion and naming, backends, failed cases, resume after a kill, the CLI.

The running tests use the real simulation with short cases (10 ms of motion
unless a test needs the cases to last).
"""

from __future__ import annotations

import collections
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml
from click.testing import CliRunner

from clearsweep import cli as cli_module
from clearsweep import sweeping
from clearsweep.budget import estimate
from clearsweep.cli import sweep_command
from clearsweep.config import ConfigError
from clearsweep.dataset import open_results
from clearsweep.sweeping import CasesFailedWarning, drop_timing, expand, run_sweep
from clearsweep.sweeping import backends as sweep_backends
from clearsweep.sweeping import plan as sweep_plan
from clearsweep.sweeping import run as sweep_run
from clearsweep.sweeping import stores as sweep_stores
from clearsweep.sweeping.parts import PartStore, parts_dir_for

ROOT = Path(__file__).resolve().parents[1]
BASE = {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.01}}
#: Two coatings x {clearance at B only, at A and B}: four short, well-behaved cases.
SMALL = {"grid": {"joints.B.coating": ["none", "PTFE"]},
         "zip": [{"name": "clearance_joints", "labels": ["B", "AB"],
                  "joints.A.clearance": [0.0, 2.5e-4]}]}


def write_sweep(tmp_path: Path, sweep: dict, base=BASE, name: str = "s", **top) -> Path:
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump({"name": name, "base": base, "sweep": sweep, **top},
                                   sort_keys=False))
    return path


def cli(*args: str):
    return CliRunner().invoke(sweep_command, [str(a) for a in args], catch_exceptions=False)


# ---------------------------------------------------------------------------- expansion

def test_dimension_names():
    assert sweep_plan.dimension_name("joints.B.coating") == "B_coating"
    assert sweep_plan.dimension_name("joints.B.clearance") == "B_clearance"
    assert sweep_plan.dimension_name("mechanism.speed_rpm") == "speed_rpm"
    assert sweep_plan.dimension_name("wear.amplification") == "amplification"
    assert sweep_plan.dimension_name("materials_file") == "materials_file"


def test_grid_is_a_cartesian_product_in_file_order():
    plan = expand({"base": BASE, "sweep": {"grid": {
        "joints.B.coating": ["none", "MoS2", "PTFE"], "mechanism.speed_rpm": [30, 60]}}})
    assert plan.dims == {"B_coating": 3, "speed_rpm": 2}
    assert [c.index for c in plan.cases] == [(i, j) for i in range(3) for j in range(2)]
    case = plan.cases[3]                                    # (MoS2, 60)
    assert plan.label(case) == {"B_coating": "MoS2", "speed_rpm": 60}
    assert case.config.joints.B.coating == "MoS2"
    assert case.config.mechanism.speed_rpm == 60.0
    assert len({c.hash for c in plan.cases}) == 6
    coords = plan.to_dataset()
    assert coords["B_coating"].values.tolist() == ["none", "MoS2", "PTFE"]   # strings as given
    assert coords["speed_rpm"].dtype == np.int64                              # ints as given
    assert coords.sel(B_coating="PTFE")["B_coating"].item() == "PTFE"


def test_zip_group_is_one_dimension():
    plan = expand({"base": BASE, "sweep": {"zip": [
        {"joints.A.clearance": [0.0, 1e-4, 2e-4], "joints.B.coating": ["none", "lead", "PTFE"]}]}})
    assert plan.dims == {"A_clearance_zip": 3}
    ds = plan.to_dataset()
    assert set(ds.coords) == {"A_clearance", "B_coating"}
    assert ds["B_coating"].dims == ("A_clearance_zip",) and not ds.indexes
    assert [(c.config.joints.A.clearance, c.config.joints.B.coating)
            for c in plan.cases] == [(0.0, "none"), (1e-4, "lead"), (2e-4, "PTFE")]

    named = expand({"base": BASE, "sweep": SMALL}).to_dataset()
    assert named.sizes == {"B_coating": 2, "clearance_joints": 2}
    assert named.sel(clearance_joints="AB")["A_clearance"].item() == 2.5e-4


def test_colliding_names_take_the_full_path():
    plan = expand({"base": BASE, "sweep": {"grid": {
        "friction.enabled": [True, False], "wear.enabled": [True, False], "solver.dt": [1e-5]}}})
    assert list(plan.dims) == ["friction_enabled", "wear_enabled", "dt"]
    assert plan.to_dataset()["wear_enabled"].dtype == bool


def test_a_speed_sweep_in_revolutions_resolves_each_cases_seconds():
    """Issue 41, item 8: no hand-zipped durations; each case's seconds are revolutions * 60
    / its speed, and the planner's steps follow them."""
    base = {"joints": {"B": {"clearance": 2.5e-4}},
            "solver": {"revolutions": 2}, "metrics": {"settle_revolutions": 1}}
    speeds = [300, 600, 900]
    plan = expand({"base": base, "sweep": {"grid": {"mechanism.speed_rpm": speeds}}})
    for rpm, case in zip(speeds, plan.cases):
        assert case.config.solver.duration == 2 * 60.0 / rpm
        assert case.config.metrics.settle_time == 60.0 / rpm
    steps = [estimate(case.config).steps for case in plan.cases]
    assert steps == [40000, 20000, 13340]       # 2 revolutions of dt = 1e-5 s in rows of 10
    assert "solver:\n    dt: 1.0e-05\n    duration: null\n    revolutions: 2.0" in plan.text


def test_the_revolutions_are_swept_over_a_base_in_seconds():
    plan = expand({"base": BASE, "sweep": {"grid": {"solver.revolutions": [0.5, 1],
                                                    "mechanism.speed_rpm": [600, 1200]}}})
    assert plan.dims == {"revolutions": 2, "speed_rpm": 2}
    assert [c.config.solver.duration for c in plan.cases] == [0.05, 0.025, 0.1, 0.05]
    assert [c.config.solver.revolutions for c in plan.cases] == [0.5, 0.5, 1.0, 1.0]
    # and the settle time in revolutions, by --set on the base
    plan = expand({"base": BASE, "sweep": {"grid": {"mechanism.speed_rpm": [600, 1200]}}},
                  ["metrics.settle_revolutions=0.25"])
    assert [c.config.metrics.settle_time for c in plan.cases] == [0.025, 0.0125]
    assert [c.config.solver.duration for c in plan.cases] == [0.01, 0.01]


def test_values_that_are_lists_become_json_text():
    plan = expand({"base": BASE, "sweep": {"grid": {"solver.baumgarte": [[5.0, 5.0], [50.0, 50.0]]}}})
    assert plan.to_dataset()["baumgarte"].values.tolist() == ["[5.0, 5.0]", "[50.0, 50.0]"]
    assert plan.cases[1].config.solver.baumgarte == (50.0, 50.0)


@pytest.mark.parametrize("sweep, key, fragment", [
    ({"grid": {"joints.B.clearance": [1e-4, 0.02]}}, "joints.B.clearance", "B_clearance=0.02"),
    ({"grid": {"joints.B.socket_radius": [0.015, 1e-4]}}, "joints.B.socket_radius",
     "B_socket_radius=0.0001"),
    ({"zip": [{"joints.B.coating": ["none", "PTFX"], "joints.A.clearance": [0.0, 1e-4]}]},
     "joints.B.coating", "'PTFE'"),
])
def test_invalid_combination_names_the_sweep_key_and_value(sweep, key, fragment):
    with pytest.raises(ConfigError) as info:
        expand({"base": BASE, "sweep": sweep})
    assert info.value.key == key
    assert fragment in str(info.value) and "sweep case" in str(info.value)


@pytest.mark.parametrize("doc, match", [
    ({"base": BASE, "sweep": {"grid": {"joints.B.coatng": ["none"]}}}, "did you mean 'joints.B.coating'"),
    ({"base": BASE, "sweep": {"grid": {"joints.B": ["none"]}}}, "a section"),
    ({"base": BASE, "sweep": {"grid": {"joints.B.coating": "PTFE"}}}, "non-empty list"),
    ({"base": BASE, "sweep": {"grid": {"joints.B.coating": ["PTFE", "PTFE"]}}}, "distinct"),
    ({"base": BASE, "sweep": {"zip": [{"joints.B.coating": ["none", "PTFE"],
                                       "joints.A.clearance": [0.0]}]}}, "zip group"),
    ({"base": BASE, "sweep": {"grid": {"joints.B.coating": ["none"]},
                              "zip": [{"joints.B.coating": ["PTFE"]}]}}, "swept twice"),
    ({"base": BASE, "sweeps": {}}, "did you mean 'sweep'"),
    ({"base": BASE, "store": "summaries"}, "did you mean 'summary'"),
    ({"base": BASE, "sweep": {"grid": {"joints.B.coating": ["none", "PTFE"]},
                              "skip": [{"B_coatin": "none"}]}}, "did you mean 'B_coating'"),
    ({"base": BASE, "sweep": {"grid": {"joints.B.coating": ["none", "PTFE"]},
                              "skip": [{"B_coating": "lead"}]}}, "swept values"),
    ({"base": {"solver": {"dt": -1.0}}}, "solver.dt"),
])
def test_malformed_sweeps_are_config_errors(doc, match):
    with pytest.raises(ConfigError, match=match):
        expand(doc)


def test_overrides_apply_to_the_base_but_not_to_swept_keys():
    plan = expand({"base": BASE, "sweep": SMALL}, overrides=["solver.duration=0.02"])
    assert all(c.config.solver.duration == 0.02 for c in plan.cases)
    with pytest.raises(ConfigError, match="does not vary"):
        expand({"base": BASE, "sweep": SMALL}, overrides=["joints.B.coating=lead"])


def test_base_path_is_relative_to_the_sweep_file(tmp_path):
    (tmp_path / "cases").mkdir()
    (tmp_path / "cases" / "base.yaml").write_text(yaml.safe_dump(BASE))
    (tmp_path / "cases" / "sweep.yaml").write_text(yaml.safe_dump({"base": "base.yaml", "sweep": SMALL}))
    plan = expand(tmp_path / "cases" / "sweep.yaml")
    assert plan.name == "sweep" and plan.cases[0].config.solver.duration == 0.01


def test_skip_rules_and_shipped_configs():
    paper = expand(ROOT / "configs" / "paper.yaml")
    assert paper.dims == {"clearance_joints": 3, "coating_joints": 4}
    assert len(paper.runnable()) == 7
    skipped = [paper.label(c) for c in paper.cases if c.hash is None]
    assert {(s["clearance_joints"], s["coating_joints"]) for s in skipped} == {
        ("none", "B"), ("none", "A"), ("none", "AB"), ("B", "A"), ("B", "AB")}
    main = expand(ROOT / "configs" / "coating_clearance.yaml")
    assert main.dims == {"B_coating": 4, "B_clearance": 6, "clearance_joints": 2}
    assert len(main.runnable()) == 48
    # 6 crank revolutions at 150 r/min, the first one settling
    assert all(c.config.solver.duration == pytest.approx(2.4) for c in main.cases)
    assert all(c.config.metrics.settle_time == pytest.approx(0.4) for c in main.cases)


# ---------------------------------------------------------------------------- running

@pytest.mark.slow
def test_serial_processes_and_dask_give_identical_results(tmp_path, process_pool, dask_cluster):
    """One process, the session's warm pool, a Dask client and a scheduler address
    (tests/conftest.py); test_a_worker_that_dies_once_is_retried_on_a_fresh_one runs a
    sweep on a pool of its own."""
    from distributed import Client

    cfg = write_sweep(tmp_path, SMALL)
    serial = run_sweep(cfg, tmp_path / "serial.nc", workers=1, progress=False)
    pool = run_sweep(cfg, tmp_path / "pool.nc", client=process_pool, progress=False)
    with Client(dask_cluster) as client:
        dask = run_sweep(cfg, tmp_path / "dask.nc", client=client, progress=False)
    by_address = run_sweep(cfg, tmp_path / "address.nc", client=dask_cluster.scheduler_address,
                           progress=False)
    with serial, pool, dask, by_address:
        assert (serial["status"] == "ok").all()
        assert serial.attrs["sweep_dims"] == "B_coating clearance_joints"
        reference = drop_timing(serial.load())
        for other in (pool, dask, by_address):
            xr.testing.assert_identical(reference, drop_timing(other.load()))
    assert not parts_dir_for(tmp_path / "pool.nc").exists()


@pytest.mark.slow
def test_local_dask_workers_write_their_parts(tmp_path, dask_cluster, monkeypatch):
    """Workers of a LocalCluster share this file system: they write their parts, as pool
    workers do (was: every case sent back and compressed by the driver, one at a time); a
    client by address leaves the writing to the driver, which cannot know where they run."""
    from distributed import Client

    cfg = write_sweep(tmp_path, SMALL)
    written = []
    real = PartStore.write
    monkeypatch.setattr(PartStore, "write",
                        lambda self, h, part: (written.append(h), real(self, h, part))[1])
    with Client(dask_cluster) as client:
        local = run_sweep(cfg, tmp_path / "local.nc", client=client, progress=False)
    assert written == []
    by_address = run_sweep(cfg, tmp_path / "address.nc", client=dask_cluster.scheduler_address,
                           progress=False)
    with local, by_address:
        assert len(written) == local.attrs["sweep_cases"] == 4
        xr.testing.assert_identical(drop_timing(local.load()), drop_timing(by_address.load()))


def test_results_open_with_both_engines_and_select_by_material(tmp_path):
    out = tmp_path / "r.nc"
    run_sweep(write_sweep(tmp_path, SMALL), out, workers=1, progress=False).close()
    for engine in ("netcdf4", "h5netcdf"):
        with xr.open_dataset(out, engine=engine) as ds:
            ptfe = ds.sel(B_coating="PTFE", clearance_joints="AB")
            assert ptfe["status"].item() == "ok"
            assert ptfe["slider_acceleration"].dims == ("time",)
            assert ptfe["normal_force_peak"].sel(joint="A") > 0
            assert ds["B_coating"].values.tolist() == ["none", "PTFE"]
            assert ds.attrs["sweep_name"] == "s" and "joints.B.coating" in ds.attrs["sweep_config"]
            assert {"numba_version", "numpy_version", "history"} <= set(ds.attrs)


def test_failed_cases_are_recorded_and_the_others_run(tmp_path):
    """From the centred start: paper inertia + PTFE at h = 1e-5 s stops unstable (~6 ms); a
    penetration limit of 1e-4 c stops at the first contact (~5.8 ms); steel alone runs the
    10 ms."""
    cfg = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none", "PTFE"],
                                          "contact.max_penetration_fraction": [0.5, 1e-4]}},
                      base={"mechanism": {"preset": "paper"}, "solver": {"duration": 0.01},
                            "initial": {"joints": "centred"},
                            "joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4}}})
    out = tmp_path / "f.nc"
    result = cli(cfg, "-o", out, "--workers", "1")
    assert result.exit_code == 1
    assert "3 of 4 cases failed" in result.stderr
    assert "failed=3" in result.stderr                    # progress bar postfix
    with open_results(out) as ds:
        status = ds["status"]
        frac = "max_penetration_fraction"
        assert status.sel(B_coating="none", **{frac: 0.5}).item() == "ok"
        assert status.sel(B_coating="PTFE", **{frac: 0.5}).item() == "unstable_step"
        assert status.sel(B_coating="none", **{frac: 1e-4}).item() == "penetration_exceeded"
        assert "'unstable_step' at t = " in ds["message"].sel(B_coating="PTFE", **{frac: 0.5}).item()
        assert ds["message"].sel(B_coating="none", **{frac: 0.5}).item() == ""
        assert ds.attrs["sweep_failed"] == 3
        ok = ds.sel(B_coating="none", **{frac: 0.5})
        assert np.isfinite(ok["slider_acceleration"]).all()
        failed = ds.sel(B_coating="PTFE", **{frac: 0.5})
        assert np.isnan(failed["slider_acceleration"]).all()
        assert np.isnan(failed["wear_depth_max_final"]).all()


def test_summary_store_keeps_summaries_only(tmp_path):
    with run_sweep(write_sweep(tmp_path, SMALL, store="summary"), tmp_path / "s.nc", workers=1,
                   progress=False) as ds:
        assert "time" not in ds.dims and "slider_acceleration" not in ds
        assert ds["slider_acceleration_peak"].dims == ("B_coating", "clearance_joints")
        assert ds["wear_depth_axis_max"].dims == ("B_coating", "clearance_joints", "joint", "axis")


def test_summary_store_keeps_the_worn_volume_of_the_full_store(tmp_path):
    """The worn volume, the one wear figure that does not depend on the map's grid, was
    missing from summary stores; it is the full store's, bit for bit, and report prints it
    beside the largest depth."""
    summary = write_sweep(tmp_path, SMALL, store="summary", name="summary")
    full = write_sweep(tmp_path, SMALL, name="full")
    with run_sweep(summary, tmp_path / "s.nc", workers=1, progress=False) as s, \
            run_sweep(full, tmp_path / "f.nc", workers=1, progress=False) as f:
        assert s["wear_volume"].dims == ("B_coating", "clearance_joints", "joint")
        assert s["wear_volume"].attrs["units"] == "m3"
        np.testing.assert_array_equal(s["wear_volume"].values, f["wear_volume"].values)
        assert (s["wear_volume"].sel(joint="B") > 0).all()
    from clearsweep.cli import report_command

    report = CliRunner().invoke(report_command, [str(tmp_path / "s.nc"), "--full"],
                                catch_exceptions=False)
    assert report.exit_code == 0, report.output
    assert "- worn volume sum of k F_N dS, joint B [m3]" in report.output     # the summary
    block = report.output.split("Wear at the end of the run")[1]
    assert "Max depth, largest map bin [nm]" in block and "Worn volume [m3]" in block


def test_without_out_the_result_is_in_memory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    ds = run_sweep({"base": BASE, "sweep": {"grid": {"joints.B.coating": ["none", "lead"]}}},
                   workers=1, progress=False)
    assert ds["status"].values.tolist() == ["ok", "ok"]
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------- command line

def test_cli_invalid_combination_exits_2_without_output(tmp_path):
    cfg = write_sweep(tmp_path, {"grid": {"joints.B.clearance": [1e-4, 0.02]}})
    out = tmp_path / "o.nc"
    result = cli(cfg, "-o", out)
    assert result.exit_code == 2
    assert result.stderr.startswith("clearsweep: error: ")
    assert "joints.B.clearance: got 0.02" in result.stderr
    assert not out.exists() and not parts_dir_for(out).exists()


def test_cli_refuses_parts_of_an_earlier_run(tmp_path):
    cfg = write_sweep(tmp_path, SMALL)
    out = tmp_path / "o.nc"
    with PartStore(parts_dir_for(out)) as store:
        store.open()
        store.write("0123456789abcdef", xr.Dataset({"status": ((), "ok")}))
    result = cli(cfg, "-o", out, "--workers", "1", "--no-progress")
    assert result.exit_code == 2 and "--discard-parts" in result.stderr and "--overwrite" in result.stderr
    assert not out.exists()
    assert cli(cfg, "-o", out, "--resume", "--overwrite").exit_code == 2
    result = cli(cfg, "-o", out, "--workers", "1", "--no-progress", "--overwrite")
    assert result.exit_code == 0, result.stderr
    assert out.exists() and not parts_dir_for(out).exists()


def test_parts_of_another_sweep_are_never_deleted_silently(tmp_path):
    """Resuming (or starting) a sweep over another sweep's parts refuses and keeps them."""
    first = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none", "PTFE"]}}, name="first")
    other = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["lead"]}}, name="other")
    out = tmp_path / "o.nc"
    parts = parts_dir_for(out)
    run_sweep(first, out, workers=1, progress=False, keep_parts=True).close()
    out.unlink()
    kept = sorted(p.name for p in parts.glob("*.nc"))
    assert len(kept) == 2

    for options in (["--resume"], []):
        result = cli(other, "-o", out, "--workers", "1", "--no-progress", *options)
        assert result.exit_code == 2, result.stderr
        assert result.stderr.splitlines()[-1].startswith("clearsweep: error: ")
        assert "'first'" in result.stderr and str(first) in result.stderr
        assert "2 cases" in result.stderr and "--discard-parts" in result.stderr
        assert sorted(p.name for p in parts.glob("*.nc")) == kept and not out.exists()

    result = cli(other, "-o", out, "--workers", "1", "--no-progress", "--resume", "--discard-parts")
    assert result.exit_code == 0, result.stderr
    with open_results(out) as ds:
        assert ds["B_coating"].values.tolist() == ["lead"] and (ds["status"] == "ok").all()


def test_a_huge_grid_is_refused_before_any_case_is_validated(monkeypatch):
    def validated(cfg, **kwargs):
        raise AssertionError("a case was validated before the size of the sweep was checked")

    monkeypatch.setattr(sweep_stores, "preflight", validated)
    grid = {f"{key}": [1e-4 * (i + 1) for i in range(10)] for key in
            ("joints.A.clearance", "joints.B.clearance", "friction.v0", "contact.min_impact_velocity",
             "wear.amplification", "solver.energy_tolerance")}
    with pytest.raises(ConfigError, match=r"sweep: got 1,000,000 cases \(10 A_clearance x 10 "
                                          r"B_clearance x .*expected at most 10,000 cases "
                                          r"\(clearsweep sweep --yes runs them all\)"):
        expand({"base": BASE, "sweep": {"grid": grid}})
    grid["solver.constraint_tolerance"] = grid["friction.v0"]
    with pytest.raises(ConfigError, match=r"10,000,000 cases .*at most 1,000,000 cases, --yes or not"):
        expand({"base": BASE, "sweep": {"grid": grid}}, max_cases=None)


def test_cli_prints_the_size_first_and_needs_yes_above_the_limit(tmp_path, monkeypatch):
    cfg = write_sweep(tmp_path, SMALL)
    out = tmp_path / "o.nc"
    monkeypatch.setattr(cli_module, "MAX_CASES", 3)
    result = cli(cfg, "-o", out, "--workers", "1", "--no-progress")
    assert result.exit_code == 2 and "got 4 cases" in result.stderr and "--yes" in result.stderr
    assert not out.exists() and not parts_dir_for(out).exists()
    result = cli(cfg, "-o", out, "--workers", "1", "--no-progress", "--yes")
    assert result.exit_code == 0, result.stderr
    first = result.stderr.splitlines()[0]
    assert first.startswith("clearsweep: sweep 's': 4 cases, 4 to simulate, 4e+03 RK4 steps: about ")
    assert "on 1 worker " in first and "results up to " in first


@pytest.mark.slow
def test_cli_dask_local_cluster(tmp_path):
    out = tmp_path / "d.nc"
    result = cli(write_sweep(tmp_path, SMALL), "-o", out, "--dask-local", "2", "--no-progress")
    assert result.exit_code == 0, result.stderr
    assert "wrote" in result.stderr and "4 cases" in result.stderr
    with open_results(out) as ds:
        assert (ds["status"] == "ok").all()


def test_cli_usage_errors(tmp_path):
    cfg = write_sweep(tmp_path, SMALL)
    result = cli(cfg, "-o", tmp_path / "o.nc", "--scheduler", "tcp://127.0.0.1:1", "--dask-local", "2")
    assert result.exit_code == 2 and "give one" in result.stderr


def test_cli_output_under_a_file_exits_2_before_any_case(tmp_path):
    """Before: every case ran, then "cannot write .../o.nc.parts: ..." (exit 1)."""
    cfg = write_sweep(tmp_path, SMALL)
    result = cli(cfg, "-o", cfg / "o.nc", "--no-progress")      # its folder is a file
    assert result.exit_code == 2
    assert result.stderr.splitlines()[-1] == (f"clearsweep: error: -o/--out {cfg}/o.nc: {cfg} is "
                                              "a file, not a folder; choose an output in a folder")
    assert sorted(p.name for p in tmp_path.iterdir()) == [cfg.name]


def test_full_disk_during_assembly_keeps_the_parts_and_leaves_no_file(tmp_path, monkeypatch):
    from clearsweep.sweeping import assemble as store

    def full(*args, **kwargs):
        raise RuntimeError("NetCDF: HDF error")          # what netCDF-C says on a full disk

    cfg = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none", "PTFE"]}})
    out = tmp_path / "o.nc"
    monkeypatch.setattr(store, "_define", full)
    result = cli(cfg, "-o", out, "--workers", "1", "--no-progress")
    assert result.exit_code == 1, result.stderr
    last = result.stderr.splitlines()[-1]
    assert last.startswith(f"clearsweep: error: cannot write {out}: NetCDF: HDF error")
    assert "2 finished case(s) are kept" in last and "--resume" in last
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o.nc.parts", "s.yaml"]
    monkeypatch.undo()
    assert cli(cfg, "-o", out, "--workers", "1", "--no-progress", "--resume").exit_code == 0


def test_temporary_file_of_a_killed_assembly_is_removed_by_the_next_run(tmp_path):
    out = tmp_path / "o.nc"
    killed = subprocess.run([sys.executable, "-c", (
        "import os, signal, sys\n"
        "from clearsweep.dataset import replaced_on_success\n"
        "with replaced_on_success(sys.argv[1]) as tmp:\n"
        "    open(tmp, 'wb').write(b'half a sweep file')\n"
        "    os.kill(os.getpid(), signal.SIGKILL)\n"), str(out)])
    assert killed.returncode == -signal.SIGKILL
    stale = list(tmp_path.glob(".o.nc.*.tmp"))
    assert len(stale) == 1
    writer = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        alive = tmp_path / f".o.nc.{writer.pid}.abcd1234.tmp"      # a write in progress
        other_output = tmp_path / ".p.nc.999999999.abcd1234.tmp"
        others = [alive, tmp_path / ".o.nc.backup.tmp", other_output]
        for path in others:
            path.write_bytes(b"not ours to delete")
        cfg = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none"]}})
        run_sweep(cfg, out, workers=1, progress=False).close()
        assert not any(p.exists() for p in stale) and all(p.exists() for p in others)
    finally:
        writer.kill()
        writer.wait()


def test_registered_as_clearsweep_sweep(tmp_path):
    from clearsweep.cli import main

    cfg = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none", "PTFX"]}})
    result = CliRunner().invoke(main, ["sweep", str(cfg), "-o", str(tmp_path / "o.nc")])
    assert result.exit_code == 2
    assert "clearsweep: error:" in result.stderr and "did you mean 'PTFE'" in result.stderr


def die_on_ptfe(cfg):
    """A simulation whose worker process dies on PTFE cases (a crash, not a failed case)."""
    from clearsweep.simulation import simulate

    if cfg.joints.B.coating == "PTFE":
        os._exit(3)
    return simulate(cfg)


def die_once_on_ptfe(cfg):
    """A worker that dies on the first PTFE case it meets, and runs it the second time."""
    from clearsweep.simulation import simulate

    marker = Path(cfg.name + ".died")
    if cfg.joints.B.coating == "PTFE":
        first = not marker.exists()
        with marker.open("a") as f:       # one line per PTFE attempt: the worker's pid
            f.write(f"{os.getpid()}\n")
        if first:
            os._exit(3)
    return simulate(cfg)


@pytest.mark.slow
def test_a_worker_that_dies_every_time_fails_its_case_and_the_sweep_goes_on(tmp_path):
    cfg = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none", "lead", "PTFE", "MoS2"]}})
    out = tmp_path / "w.nc"
    with run_sweep(cfg, out, workers=2, progress=False, _simulate=die_on_ptfe) as ds:
        status = dict(zip(ds["B_coating"].values.tolist(), ds["status"].values.tolist()))
        assert status == {"none": "ok", "lead": "ok", "PTFE": "error", "MoS2": "ok"}
        message = ds["message"].sel(B_coating="PTFE").item()
        # The exit status itself is what the OS reports: 3 here, but a forkserver that has
        # already lost the process reports 255, so only its form is checked.
        assert re.search(r"died twice, .* alone on a fresh worker: (exit code \d+|killed by [\w ]+)",
                         message), message
        assert ds.attrs["sweep_failed"] == 1


@pytest.mark.slow
def test_a_worker_that_dies_once_is_retried_on_a_fresh_one(tmp_path):
    base = {**BASE, "name": str(tmp_path / "case")}
    cfg = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none", "PTFE", "lead"]}}, base=base)
    with run_sweep(cfg, tmp_path / "w.nc", workers=2, progress=False,
                   _simulate=die_once_on_ptfe) as ds:
        assert (ds["status"] == "ok").all()
    # The marker used to be only checked to exist, which it does whether or not the case was
    # retried; the retry is two attempts, the second in another (fresh) worker process.
    attempts = (tmp_path / "case.died").read_text().split()
    assert len(attempts) == 2 and attempts[0] != attempts[1]


@pytest.mark.slow
def test_a_dying_worker_of_the_callers_pool_stops_the_sweep_and_keeps_finished_cases(tmp_path):
    cfg = write_sweep(tmp_path, {"grid": {"joints.B.coating": ["none", "lead", "PTFE"]}})
    out = tmp_path / "w.nc"
    pool = sweep_backends.process_pool(2)
    try:
        with pytest.raises(sweep_run.SweepFailed, match="--resume"):
            run_sweep(cfg, out, client=pool, progress=False, _simulate=die_on_ptfe)
    finally:
        pool.shutdown(wait=False, cancel_futures=True)
    assert not out.exists()
    with PartStore(parts_dir_for(out)) as store:
        assert store.events("failed")
    # The same sweep without the crash resumes from what was kept.
    with run_sweep(cfg, out, workers=1, resume=True, progress=False) as ds:
        assert (ds["status"] == "ok").all()


def _start_cli(cfg: Path, out: Path, *args: str) -> subprocess.Popen:
    command = [sys.executable, "-c", "from clearsweep.cli import sweep_command; sweep_command()",
               str(cfg), "-o", str(out), "--no-progress", *args]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=cfg.parent)


def _wait_for_parts(parts: Path, n: int, process: subprocess.Popen, timeout: float = 120.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if parts.is_dir() and len(list(parts.glob("*.nc"))) >= n:
            return
        if process.poll() is not None:
            pytest.fail(f"the sweep ended before {n} parts were written: {process.stderr.read()}")
        time.sleep(0.005)
    pytest.fail(f"no {n} parts within {timeout} s")


#: Six cases of 0.4 s of motion each, so that a kill lands in the middle of the sweep.
SLOW = {"grid": {"joints.B.coating": ["none", "lead", "PTFE"]},
        "zip": [{"name": "clearance_joints", "labels": ["B", "AB"],
                 "joints.A.clearance": [0.0, 2.5e-4]}]}
SLOW_BASE = {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.4}}


@pytest.mark.slow
def test_resume_after_sigkill_runs_every_case_once(tmp_path):
    cfg = write_sweep(tmp_path, SLOW, base=SLOW_BASE)
    out = tmp_path / "k.nc"
    parts = parts_dir_for(out)
    process = _start_cli(cfg, out, "--workers", "1")
    _wait_for_parts(parts, 2, process)
    process.kill()
    process.communicate()
    assert not out.exists()
    kept = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in parts.glob("*.nc")}
    assert 2 <= len(kept) < 6
    for name in kept:                    # every visible part is complete
        with xr.open_dataset(parts / name) as part:
            assert part["status"].item() == "ok"

    refused = _start_cli(cfg, out, "--workers", "1")
    assert refused.wait(60) == 2 and "--resume" in refused.stderr.read()

    resumed = _start_cli(cfg, out, "--workers", "1", "--resume", "--keep-parts")
    _, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    for name, stamp in kept.items():     # finished cases were not run again
        assert ((parts / name).stat().st_ino, (parts / name).stat().st_mtime_ns) == stamp
    with PartStore(parts) as store:
        runs = [r["run"] for r in store.events("run")]
        done = store.events("done")
    assert len(runs) == 2
    second = collections.Counter(r["hash"] for r in done if r["run"] == runs[1])
    all_hashes = set(expand(cfg).runnable())
    assert set(second) == all_hashes - {n[:-3] for n in kept}
    assert set(second.values()) == {1}
    assert {r["hash"] for r in done if r["run"] == runs[0]} <= {n[:-3] for n in kept}

    with open_results(out) as resumed_ds, \
            run_sweep(cfg, tmp_path / "reference.nc", workers=1, progress=False) as reference:
        xr.testing.assert_identical(drop_timing(reference.load()), drop_timing(resumed_ds.load()))


@pytest.mark.slow
def test_ctrl_c_stops_cleanly_and_resume_finishes(tmp_path):
    cfg = write_sweep(tmp_path, SLOW, base=SLOW_BASE)
    out = tmp_path / "c.nc"
    process = _start_cli(cfg, out, "--workers", "2")
    _wait_for_parts(parts_dir_for(out), 1, process)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert "--resume" in err and "interrupted" in err
    assert not out.exists()
    with PartStore(parts_dir_for(out)) as store:
        assert store.events("interrupted")
        assert len(store.finished()) >= 1
    resumed = _start_cli(cfg, out, "--workers", "2", "--resume")
    _, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    with open_results(out) as ds:
        assert (ds["status"] == "ok").all()


def test_interrupted_sweep_suggests_a_resume_with_the_same_overrides(tmp_path, monkeypatch):
    """The printed command must rebuild the same cases: --set values change every case's hash."""
    def interrupted(*args, **kwargs):
        raise sweep_run.SweepInterrupted(1, 4, tmp_path / "my out.nc.parts")

    monkeypatch.setattr(sweeping, "run_sweep", interrupted)  # what sweep_command calls
    cfg = write_sweep(tmp_path, SMALL)
    result = CliRunner().invoke(sweep_command, [str(cfg), "-o", str(tmp_path / "my out.nc"),
                                                "--set", "solver.duration=0.3"])
    assert result.exit_code == 130
    assert (f"continue with: clearsweep sweep {cfg} -o '{tmp_path / 'my out.nc'}' --resume "
            "--set solver.duration=0.3") in result.stderr


def test_a_sweep_without_axes_is_one_case(tmp_path):
    with run_sweep({"base": BASE}, tmp_path / "one.nc", progress=False) as ds:
        assert ds["status"].item() == "ok" and ds["slider_acceleration"].dims == ("time",)
        assert ds.attrs["sweep_dims"] == "" and ds.attrs["sweep_cases"] == 1


def test_drop_timing():
    ds = xr.Dataset({"wall_time": ((), 1.0), "x": ((), 2.0)}, attrs={"history": "now", "title": "t"})
    out = drop_timing(ds)
    assert list(out.data_vars) == ["x"] and out.attrs == {"title": "t"}
    assert "wall_time" in ds and "history" in ds.attrs


def test_public_names():
    import clearsweep

    assert clearsweep.sweep is run_sweep is sweep_run.run_sweep
    assert clearsweep.open_results is open_results
    assert os.fspath(ROOT / "configs" / "paper.yaml")


def test_step_too_large_for_a_case_is_caught_before_anything_runs():
    """A swept solver.dt that no sub-step level can stabilise is a ConfigError at expansion."""
    doc = {"base": {"joints": {"B": {"clearance": 2.5e-4}}},
           "sweep": {"grid": {"solver.dt": [1e-5, 0.01]}}}
    with pytest.raises(ConfigError, match=r"solver\.dt.*0\.01"):
        expand(doc)


def test_step_too_large_for_a_sweep_without_axes_names_the_key():
    """The one case of a sweep without axes is its base: the error names the base's key."""
    doc = {"base": {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"dt": 0.01}}}
    with pytest.raises(ConfigError, match=r"<sweep>: solver\.dt: got 0\.01; expected a step"):
        expand(doc)


def _raise_for_ptfe(cfg):
    """Stand-in simulate: an unexpected exception in one case (module level: picklable)."""
    if cfg.joints.B.coating == "PTFE":
        raise RuntimeError("boom")
    from clearsweep.simulation import simulate

    return simulate(cfg)


def test_exception_inside_a_case_is_an_error_status_not_a_crash(tmp_path):
    with pytest.warns(CasesFailedWarning, match="2 of 4 cases failed"), \
            run_sweep(write_sweep(tmp_path, SMALL), tmp_path / "e.nc", workers=1, progress=False,
                      _simulate=_raise_for_ptfe) as ds:
        assert (ds["status"].sel(B_coating="PTFE") == "error").all()
        assert "RuntimeError: boom" in ds["message"].sel(B_coating="PTFE").values.ravel()[0]
        assert (ds["status"].sel(B_coating="none") == "ok").all()


def test_sweep_coordinates_carry_units_and_long_names(tmp_path):
    plan = expand({"base": BASE, "sweep": {"grid": {
        "joints.B.clearance": [1e-4, 2.5e-4], "mechanism.speed_rpm": [30, 60],
        "joints.B.coating": ["none", "PTFE"]}}})
    coords = plan.to_dataset()
    assert coords["B_clearance"].attrs["units"] == "m"
    assert coords["B_clearance"].attrs["long_name"] == "radial clearance of joint B"
    assert coords["speed_rpm"].attrs["units"] == "min-1"
    assert "units" not in coords["B_coating"].attrs
    assert coords["B_coating"].attrs["long_name"] == "socket coating of joint B"
    assert all(c.attrs["config_key"] for c in coords.coords.values())


def test_a_swept_materials_file_is_taken_from_the_sweep_files_folder(tmp_path, monkeypatch):
    """configs/measured_friction.yaml sweeps two materials files by relative paths: they are
    read from the sweep file's folder, as the base's materials_file is, whatever the current
    folder (they were read from the current one: the sweep ran only from the repository)."""
    from clearsweep.sweeping.plan import expand

    monkeypatch.chdir(tmp_path)
    plan = expand(ROOT / "configs" / "measured_friction.yaml")
    files = {case.materials_file for case in plan.runnable().values()}
    data = ROOT / "clearsweep" / "data"
    assert files == {str(data / "materials.yaml"), str(data / "materials_measured.yaml")}
