"""Ensembles: the member perturbation, the member dimension of a sweep, the statistics.

Cases are short (10 ms of motion, 1000 RK4 steps, a 12 x 24 wear map) and ensembles small.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from clearsweep.config import ConfigError, load_config, resolve_materials
from clearsweep.ensemble import (
    CONFIDENCE_LEVEL,
    distinguishable,
    ensemble_statistics,
    welch_interval,
)
from clearsweep.params import member_perturbation, pack
from clearsweep.simulation import simulate
from clearsweep.sweeping import CasesFailedWarning, drop_timing, expand, run_sweep

BASE = {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.01},
        "wear": {"map": [12, 24]}}
PERTURB = {"ball_offset": 0.5, "crank_phase_deg": 5.0, "wear_coefficient_cv": 0.2}


def ensemble(members=3, seed=1, perturb=PERTURB, **extra):
    return {**BASE, "ensemble": {"members": members, "seed": seed, "perturb": dict(perturb)}, **extra}


def sweep_doc(members=3, seed=1, **base):
    return {"name": "ens", "base": {**ensemble(members, seed), **base},
            "sweep": {"grid": {"joints.B.coating": ["none", "PTFE"]}}}


# ---------------------------------------------------------------------------- configuration

@pytest.mark.parametrize("override, key", [
    ("ensemble.members=0", "ensemble.members"),
    ("ensemble.seed=-1", "ensemble.seed"),
    ("ensemble.perturb.wear_coefficient_cv=-0.1", "ensemble.perturb.wear_coefficient_cv"),
    ("ensemble.perturb.ball_offset=1.5", "ensemble.perturb.ball_offset"),
    ("ensemble.perturb.crank_phase_deg=-1", "ensemble.perturb.crank_phase_deg"),
    ("ensemble.member=3", "ensemble.member"),
])
def test_bad_ensemble_values_name_the_key(override, key):
    with pytest.raises(ConfigError) as info:
        load_config(ensemble(3), [override])
    assert info.value.key == key
    assert key in str(info.value)


def test_ensemble_units_are_in_the_field_metadata():
    from clearsweep.config import field_info

    assert field_info("ensemble.perturb.crank_phase_deg")[0] == "degree"
    assert field_info("ensemble.perturb.ball_offset")[0] == "1"


# ---------------------------------------------------------------------------- perturbation

def test_member_draw_comes_from_seed_and_member_only():
    cfg = load_config(ensemble(8, seed=7), ["ensemble.member=5"])
    draw = member_perturbation(cfg.ensemble)
    # the member-th child of SeedSequence(seed): the same numbers whichever way it is made
    child = np.random.SeedSequence(7).spawn(8)[5]
    rng = np.random.default_rng(child)
    assert draw.crank_phase_rad == np.deg2rad(5.0) * rng.uniform(-1.0, 1.0)
    again = member_perturbation(load_config(ensemble(8, seed=7), ["ensemble.member=5"]).ensemble)
    assert np.array_equal(draw.ball_offset, again.ball_offset)
    other = member_perturbation(cfg.replace("ensemble.member=4").ensemble)
    assert not np.array_equal(draw.ball_offset, other.ball_offset)
    assert np.all(np.linalg.norm(draw.ball_offset, axis=1) <= 0.5)
    # the number of members does not change a member's draw
    wider = member_perturbation(load_config(ensemble(16, seed=7), ["ensemble.member=5"]).ensemble)
    assert np.array_equal(draw.wear_factor, wider.wear_factor)


def test_switching_one_perturbation_leaves_the_others_draws():
    a = member_perturbation(load_config(ensemble(4, perturb={**PERTURB, "ball_offset": 0.0}),
                                        ["ensemble.member=2"]).ensemble)
    b = member_perturbation(load_config(ensemble(4), ["ensemble.member=2"]).ensemble)
    assert a.crank_phase_rad == b.crank_phase_rad
    assert np.array_equal(a.wear_factor, b.wear_factor)


def test_lognormal_wear_factor_has_mean_one_and_the_cv():
    factors = np.array([member_perturbation(load_config(
        ensemble(4000, seed=3, perturb={"wear_coefficient_cv": 0.3}),
        [f"ensemble.member={i}"]).ensemble).wear_factor for i in range(0, 4000, 4)]).ravel()
    assert factors.mean() == pytest.approx(1.0, abs=0.03)
    assert factors.std() / factors.mean() == pytest.approx(0.3, abs=0.03)


def test_perturbed_start_is_no_deeper_than_the_seated_one():
    from clearsweep.params import perturbed_offset

    rng = np.random.default_rng(5)
    c, seat = 2.5e-4, np.array([0.0, 0.0, -2.6e-4])
    for _ in range(200):
        shift = rng.uniform(-1.0, 1.0, 3)
        shift *= rng.random() / np.linalg.norm(shift)
        d = perturbed_offset(seat, shift, c)
        assert np.linalg.norm(d) <= np.linalg.norm(seat) * (1 + 1e-12)
        # centred start: the shift as it is (inside the clearance)
        assert np.array_equal(perturbed_offset(np.zeros(3), shift, c), c * shift)


def test_member_zero_without_perturbation_is_the_nominal_case_bit_for_bit():
    nominal = load_config(BASE)
    zero = load_config(ensemble(4, seed=11, perturb={}))
    materials = resolve_materials(nominal)
    a, b = pack(nominal, materials), pack(zero, materials)
    for name in ("p", "jp", "y0"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    ds_a, ds_b = simulate(nominal), simulate(zero)
    for name in ds_a.data_vars:
        if name != "wall_time":
            xr.testing.assert_identical(ds_a[name], ds_b[name])


# ---------------------------------------------------------------------------- sweeps

def test_ensemble_adds_a_member_dimension_last():
    plan = expand(sweep_doc(4))
    assert plan.dims == {"B_coating": 2, "member": 4}
    members = [c.config.ensemble.member for c in plan.cases]
    assert members == [0, 1, 2, 3] * 2
    assert len({c.hash for c in plan.cases}) == 8


def test_a_sweep_cannot_vary_the_member_index():
    doc = sweep_doc(2)
    doc["sweep"]["grid"]["ensemble.member"] = [0, 1]
    with pytest.raises(ConfigError, match="ensemble.member"):
        expand(doc)


def test_same_seed_is_bit_identical_on_one_and_two_workers(tmp_path, process_pool):
    one = run_sweep(sweep_doc(3), tmp_path / "one.nc", workers=1, progress=False)
    two = run_sweep(sweep_doc(3), tmp_path / "two.nc", client=process_pool, progress=False)
    with one, two:
        xr.testing.assert_identical(drop_timing(one).load(), drop_timing(two).load())
        assert list(one["members_ok"].values) == [3, 3]
        for suffix in ("_mean", "_std", "_ci_low", "_ci_high"):
            var = one["slider_acceleration_rms" + suffix]
            assert var.dims == ("B_coating",) and var.attrs["units"] == "m s-2"
            volume = one["wear_volume" + suffix]
            assert volume.dims == ("B_coating", "joint") and volume.attrs["units"] == "m3"
        np.testing.assert_array_equal(one["wear_volume_mean"].values,
                                      one["wear_volume"].mean("member").values)
        assert "Student t" in one["slider_acceleration_rms_ci_low"].attrs["ci_method"]
        assert one.attrs["ensemble_confidence_level"] == CONFIDENCE_LEVEL


@pytest.mark.slow
def test_another_seed_gives_other_members(tmp_path):
    a = run_sweep(sweep_doc(3, seed=1), workers=1, progress=False)
    b = run_sweep(sweep_doc(3, seed=2), workers=1, progress=False)
    assert not np.array_equal(a["slider_acceleration_rms"].values, b["slider_acceleration_rms"].values)


def test_failed_members_are_counted_not_averaged():
    def fake(cfg):
        # member 1 of the PTFE design stops; the others run
        from clearsweep.simulation import simulate as real

        ds = real(cfg)
        if cfg.ensemble.member == 1 and cfg.joints.B.coating == "PTFE":
            ds["status"] = ((), "penetration")
        return ds

    with pytest.warns(CasesFailedWarning, match="1 of 6 cases failed"):
        ds = run_sweep(sweep_doc(3), workers=1, progress=False, _simulate=fake)
    assert list(ds["members_ok"].values) == [3, 2]
    ok = ds["slider_acceleration_rms"].sel(B_coating="PTFE", member=[0, 2]).values
    assert float(ds["slider_acceleration_rms_mean"].sel(B_coating="PTFE")) == pytest.approx(ok.mean())


# ---------------------------------------------------------------------------- statistics

def synthetic(values: np.ndarray, status: np.ndarray) -> xr.Dataset:
    return xr.Dataset({
        "status": (("design", "member"), status),
        "slider_acceleration_rms": (("design", "member"), values, {"units": "m s-2",
                                                                 "long_name": "RMS"}),
    })


def test_confidence_interval_is_student_t():
    rng = np.random.default_rng(0)
    values = rng.normal(10.0, 2.0, (3, 6))
    status = np.full((3, 6), "ok", dtype=object)
    status[1, 2] = "penetration"
    values[1, 2] = np.nan
    out = ensemble_statistics(synthetic(values, status))
    for d in range(3):
        sample = values[d][status[d] == "ok"]
        low, high = stats.t.interval(0.95, len(sample) - 1, loc=sample.mean(), scale=stats.sem(sample))
        assert float(out["slider_acceleration_rms_mean"][d]) == pytest.approx(sample.mean(), rel=1e-12)
        assert float(out["slider_acceleration_rms_std"][d]) == pytest.approx(sample.std(ddof=1), rel=1e-12)
        assert float(out["slider_acceleration_rms_ci_low"][d]) == pytest.approx(low, rel=1e-12)
        assert float(out["slider_acceleration_rms_ci_high"][d]) == pytest.approx(high, rel=1e-12)
    assert list(out["members_ok"].values) == [6, 5, 6]
    assert out["slider_acceleration_rms_mean"].attrs["units"] == "m s-2"


def test_one_member_gives_no_interval():
    out = ensemble_statistics(synthetic(np.array([[1.0, 2.0]]), np.array([["ok", "error"]], dtype=object)))
    assert float(out["slider_acceleration_rms_mean"][0]) == 1.0
    assert np.isnan(float(out["slider_acceleration_rms_ci_low"][0]))


def test_welch_interval_matches_scipy():
    rng = np.random.default_rng(1)
    a, b = rng.normal(1.0, 1.0, 8), rng.normal(1.5, 2.0, 5)
    diff, low, high = welch_interval(a.mean(), a.std(ddof=1), 8, b.mean(), b.std(ddof=1), 5)
    ci = stats.ttest_ind(b, a, equal_var=False).confidence_interval(0.95)
    assert (low, high) == pytest.approx((ci.low, ci.high), rel=1e-10)
    assert diff == pytest.approx(b.mean() - a.mean())
    assert distinguishable(low, high) is (not (low <= 0 <= high))
    assert welch_interval(1.0, 0.0, 4, 1.0, 0.0, 4)[1:] == (0.0, 0.0)
    assert distinguishable(0.0, 0.0) is False
    assert distinguishable(np.nan, 1.0) is None


# ---------------------------------------------------------------------------- report, run, plot

def synthetic_ensemble() -> xr.Dataset:
    """Three coatings x 6 members of a wear depth at joint B: none and MoS2 overlap, PTFE
    wears far more; one MoS2 member failed."""
    rng = np.random.default_rng(4)
    centre = np.array([1.0, 1.05, 3.0])[:, None] * 1e-9
    depth = np.zeros((3, 6, 2))
    depth[:, :, 1] = centre * (1.0 + 0.2 * rng.standard_normal((3, 6)))
    status = np.full((3, 6), "ok", dtype=object)
    status[1, 0] = "penetration"
    depth[1, 0] = np.nan
    ds = xr.Dataset({
        "status": (("B_coating", "member"), status),
        "wear_depth_max_final": (("B_coating", "member", "joint"), depth,
                                 {"units": "m", "long_name": "maximum wear depth"}),
    }, coords={"B_coating": ["none", "MoS2", "PTFE"], "member": np.arange(6), "joint": ["A", "B"]})
    return xr.merge([ds, ensemble_statistics(ds)], combine_attrs="override")


def test_report_prints_intervals_and_verdicts():
    from clearsweep.analysis import format_ensemble_report

    text = format_ensemble_report(synthetic_ensemble())
    assert "+- 95% CI" in text and "Members ok" in text
    assert "1 member(s) stopped" in text
    lines = {line.split()[1]: line for line in text.splitlines() if line.startswith("B_coating:")}
    assert lines["MoS2"].endswith("not distinguishable")
    assert lines["PTFE"].endswith(" distinguishable") and "not" not in lines["PTFE"]
    # the ideal joint A (no wear, no spread) is not compared
    assert not any(" A " in line for line in lines.values())


def test_report_reference_picks_the_compared_design():
    from clearsweep.analysis import ensemble_comparisons

    groups = ensemble_comparisons(synthetic_ensemble(), ["B_coating=PTFE"])
    assert [r["compared"] for r in groups[0].rows] == ["B_coating: none vs PTFE",
                                                     "B_coating: MoS2 vs PTFE"]


def test_cli_run_of_an_ensemble_runs_every_member(tmp_path):
    from click.testing import CliRunner

    from clearsweep.cli import main, report_command

    config = tmp_path / "c.yaml"
    import yaml

    config.write_text(yaml.safe_dump(ensemble(3)))
    out = tmp_path / "c.nc"
    result = CliRunner().invoke(main, ["run", str(config), "-o", str(out), "--workers", "1"],
                                catch_exceptions=False)
    assert result.exit_code == 0, result.output
    assert "Ensemble statistics over 3 members" in result.output
    # the worn volume beside the largest depth
    depth = result.output.index("wear_depth_max_final: ")
    assert result.output.index("wear_volume: ") > depth
    with xr.open_dataset(out) as ds:
        assert ds.sizes["member"] == 3 and "slider_acceleration_rms_ci_high" in ds
    report = CliRunner().invoke(report_command, [str(out)], catch_exceptions=False)
    assert report.exit_code == 0 and "+- 95% CI" in report.output


def test_sweep_plot_of_an_ensemble_draws_error_bars(tmp_path):
    from clearsweep.plotting import figure

    fig = figure(synthetic_ensemble(), "sweep", metric="wear_depth_max_final")
    ax = fig.axes[0]
    assert len(ax.containers) == 1          # joint B; the ideal joint A (all 0) is left out
    assert "confidence interval" in fig.texts[0].get_text()
    assert "not drawn: joint A, all 0" in fig.get_suptitle()


ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]


def test_shipped_coating_ensemble_expands_to_192_members():
    plan = expand(ROOT / "configs" / "coating_ensemble.yaml")
    assert plan.dims == {"B_coating": 4, "B_clearance": 3, "member": 16}
    assert len(plan.runnable()) == 192 and plan.store == "summary"


@pytest.mark.slow
def test_shipped_coating_ensemble_report_says_not_distinguishable(tmp_path, process_pool):
    from click.testing import CliRunner

    from clearsweep.cli import report_command

    out = tmp_path / "coating_ensemble.nc"
    # shortened to 8 members of 0.1 s: the verdicts come from the spread, not from the length
    run_sweep(ROOT / "configs" / "coating_ensemble.yaml", out, client=process_pool, progress=False,
              overrides=["solver.duration=0.1", "ensemble.members=8"]).close()
    report = CliRunner().invoke(report_command, [str(out), "--full"], catch_exceptions=False)
    assert "+- 95% CI" in report.output and " not distinguishable" in report.output


def test_report_leaves_out_designs_that_the_sweep_skipped():
    from clearsweep.analysis import format_ensemble_table

    ds = synthetic_ensemble()
    ds["status"] = ds["status"].where(ds["B_coating"] != "MoS2", "skipped")
    text = format_ensemble_table(ds)
    assert "MoS2" not in text and "PTFE" in text


# ---------------------------------------------------------------------------- run of an ensemble: parts

def _run_cli(config, out, *options):
    from click.testing import CliRunner

    from clearsweep.cli import main

    return CliRunner().invoke(main, ["run", str(config), "-o", str(out), "-q", "--workers", "1",
                                     *options])


def _ensemble_config(tmp_path, members=3, **extra):
    import yaml

    config = tmp_path / "ens.yaml"
    config.write_text(yaml.safe_dump(ensemble(members, **extra)))
    return config


def test_run_of_an_ensemble_refuses_parts_of_another_sweep(tmp_path):
    """Once, `run` of an ensemble deleted every part in OUT.parts (overwrite=True)."""
    from clearsweep.sweeping import parts_dir_for

    out = tmp_path / "ce.nc"
    other = sweep_doc(2)
    other["name"] = "other"
    run_sweep(other, out, workers=1, progress=False, keep_parts=True).close()
    out.unlink()
    parts = parts_dir_for(out)
    kept = sorted(p.name for p in parts.glob("*.nc"))
    assert len(kept) == 4
    config = _ensemble_config(tmp_path)
    for options in ([], ["--resume"]):
        result = _run_cli(config, out, *options)
        assert result.exit_code == 2, result.output
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("clearsweep: error: ")
        assert "'other'" in lines[0] and "--discard-parts" in lines[0]
        assert sorted(p.name for p in parts.glob("*.nc")) == kept and not out.exists()
    result = _run_cli(config, out, "--discard-parts")
    assert result.exit_code == 0, result.output
    with xr.open_dataset(out) as ds:
        assert ds.sizes["member"] == 3 and int(ds["members_ok"]) == 3


def test_run_of_an_ensemble_refuses_its_own_earlier_parts_without_resume(tmp_path, monkeypatch):
    from clearsweep import simulation
    from clearsweep.sweeping import expand, parts_dir_for

    config = _ensemble_config(tmp_path)
    doc = {"name": "ens", "base": load_config(config).to_dict()}
    first = next(iter(expand(doc).runnable()))
    full = tmp_path / "full.nc"
    run_sweep(doc, full, workers=1, progress=False, keep_parts=True).close()
    # one finished member, as an interrupted run leaves it
    out = tmp_path / "e.nc"
    parts = parts_dir_for(out)
    parts.mkdir()
    (parts / f"{first}.nc").write_bytes((parts_dir_for(full) / f"{first}.nc").read_bytes())
    stamp = (parts / f"{first}.nc").stat().st_mtime_ns
    result = _run_cli(config, out)
    assert result.exit_code == 2, result.output
    assert "--resume" in result.stderr and "--overwrite" in result.stderr
    assert (parts / f"{first}.nc").stat().st_mtime_ns == stamp and not out.exists()
    ran = []
    real = simulation.simulate
    monkeypatch.setattr(simulation, "simulate",
                        lambda cfg, **kw: ran.append(cfg.ensemble.member) or real(cfg, **kw))
    result = _run_cli(config, out, "--resume")
    assert result.exit_code == 0, result.output
    assert ran == [1, 2]                        # the kept member 0 did not run again
    with xr.open_dataset(out) as ds, xr.open_dataset(full) as ref:
        xr.testing.assert_identical(drop_timing(ds.load()), drop_timing(ref.load()))


def test_two_runs_of_an_ensemble_on_one_output_refuse_in_one_line(tmp_path):
    """The second of two concurrent runs raised an uncaught StoreError."""
    from clearsweep.sweeping import PartStore, parts_dir_for

    config = _ensemble_config(tmp_path)
    out = tmp_path / "e.nc"
    with PartStore(parts_dir_for(out)) as first:       # another run holds the folder
        first.open()
        result = _run_cli(config, out)
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: ") and "in use" in lines[0]
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert not out.exists()


@pytest.mark.slow
def test_sigint_stops_a_run_of_an_ensemble_with_130_and_the_resume_command(tmp_path):
    """Ctrl-C printed "Aborted!" and exited 1, and the next run recomputed every member."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from clearsweep.sweeping import PartStore, parts_dir_for

    config = _ensemble_config(tmp_path, members=4, solver={"duration": 0.4})
    out = tmp_path / "e.nc"
    parts = parts_dir_for(out)
    command = [sys.executable, "-m", "clearsweep.cli", "run", str(config), "-o", str(out), "-q",
               "--workers", "1"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    process = subprocess.Popen(command, stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=env)
    end = time.monotonic() + 120
    while not (parts.is_dir() and list(parts.glob("*.nc"))):
        if process.poll() is not None or time.monotonic() > end:
            pytest.fail(f"no part written: {process.communicate()}")
        time.sleep(0.01)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    # run as `python -m clearsweep.cli` from outside the interpreter's tree: said so again
    assert f"continue with: python -m clearsweep.cli run {config} -o {out} --resume" in err
    with PartStore(parts) as store:
        kept = store.finished()
    assert 1 <= len(kept) < 4 and not out.exists()
    resumed = subprocess.run([*command, "--resume"], capture_output=True, text=True, cwd=tmp_path,
                             env=env, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    with xr.open_dataset(out) as ds:
        assert int(ds["members_ok"]) == 4
