"""Reliability over service life (docs/reliability.md): member draws, censoring, the
Kaplan-Meier estimate against a closed form, determinism, bad input, the motion error."""

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner
from scipy import stats

from clearsweep.cli import main
from clearsweep.config import ConfigError, load_config
from clearsweep.reliability import (
    estimate_limit,
    member_config,
    member_draws,
    reliability_case,
    reliability_summary,
    revolution_grid,
)
from clearsweep.service_life import life, settled_motion_error
from clearsweep.simulation import prepare_kernel, run_kernel, simulate
from clearsweep.sweeping import drop_timing, expand, run_sweep

CASE = "configs/one_clearance.yaml"
#: Short life runs: 300 r/min (0.2 s blocks) at the step configs/reliability.yaml takes
#: (2e-5 s), a small map read bilinearly, wear x300, jumps of 0.1 c, to 70 um of wear: about
#: 4 blocks and a few hundred revolutions a member.
TINY = ["mechanism.speed_rpm=300", "metrics.settle_time=0.02", "wear.map=[8,16]",
        "solver.dt=2e-5", "wear.interpolate=true", "solver.energy_tolerance=0.5", "wear.amplification=300",
        "life.cycles=1e5", "life.jump_clearance_fraction=0.1", "life.max_clearance_growth=7e-5"]
#: The wear coefficient's coefficient of variation in the closed-form tests.
K_CV = 0.5


def _tiny(*extra):
    return load_config(CASE, [*TINY, *extra])


def _members(cfg, n):
    """Revolutions to the first limit and censoring flags of members 0..n-1."""
    out = [reliability_summary(reliability_case(cfg.replace(f"reliability.member={m}")))
           for m in range(n)]
    return (np.array([float(s.revolutions_to_limit.sel(limit="any")) for s in out]),
            np.array([bool(s.censored.sel(limit="any")) for s in out]))


def _closed_form(n, nominal, cv):
    """R(N) when N = nominal / f, f lognormal of mean 1 and coefficient of variation cv."""
    sigma = math.sqrt(math.log1p(cv ** 2))
    return stats.norm.cdf((np.log(nominal / n) + 0.5 * sigma ** 2) / sigma)


@pytest.fixture(scope="module")
def nominal():
    """Revolutions to the limit without scatter (the wear factor 1)."""
    ds = life(_tiny())
    value = float(ds.cycles_to_clearance_growth)
    assert math.isfinite(value)
    return value


# ---------------------------------------------------------------------------- draws

def test_draws_depend_on_seed_and_member_only_and_one_scatter_leaves_the_others():
    cfg = _tiny("reliability.wear_coefficient_cv=0.3", "reliability.clearance_tolerance=2e-5",
                "reliability.member=5")
    a, b = member_draws(cfg), member_draws(cfg.replace("reliability.members=99"))
    assert np.array_equal(a.wear_factor, b.wear_factor) and np.array_equal(a.clearance, b.clearance)
    other = member_draws(cfg.replace("reliability.member=6"))
    assert not np.array_equal(a.wear_factor, other.wear_factor)
    no_tolerance = member_draws(cfg.replace("reliability.clearance_tolerance=0"))
    assert np.array_equal(a.wear_factor, no_tolerance.wear_factor)
    assert a.clearance[0] == 0.0 and abs(a.clearance[1] - 2.5e-4) <= 2e-5
    assert a.clearance[1] != 2.5e-4 and no_tolerance.clearance[1] == 2.5e-4
    normal = member_draws(cfg.replace("reliability.clearance_distribution=normal"))
    assert abs(normal.clearance[1] - 2.5e-4) <= 2e-5


def test_member_config_sets_the_draws_and_none_without_scatter():
    cfg = _tiny("reliability.wear_coefficient_cv=0.3", "reliability.speed_cv=0.05",
                "joints.B.coating=MoS2", "reliability.coating_thickness_cv=0.1")
    assert member_config(_tiny()) is _tiny() or member_config(_tiny()) == _tiny()
    drawn = member_config(cfg)
    draws = member_draws(cfg)
    assert drawn.joints.B.wear_coefficient == pytest.approx(8e-14 * draws.wear_factor[1])
    assert drawn.joints.B.coating_thickness == pytest.approx(1e-4 * draws.coating_factor[1])
    assert drawn.mechanism.speed_rpm == pytest.approx(300.0 * draws.speed_factor)
    assert drawn.joints.A == cfg.joints.A      # the ideal joint is left alone


# ---------------------------------------------------------------------------- determinism

def test_member_0_without_scatter_is_the_plain_life_run_bit_for_bit():
    cfg = _tiny()
    plain = life(cfg)
    member = reliability_case(cfg)
    extra = ["wall_time", "status", *[n for n in member.data_vars if str(n).startswith("member_")]]
    # (the history line's timestamp is the second each run was written)
    for ds in (member, plain):
        ds.attrs.pop("history", None)
    xr.testing.assert_identical(member.drop_vars(extra), plain.drop_vars("wall_time"))


#: A reliability sweep of one design, three members: clearance and wear coefficient scattered.
SMALL_SWEEP = {"store": "reliability", "base": {**_tiny().to_dict(), "reliability": {
    "members": 3, "seed": 2, "wear_coefficient_cv": 0.3, "clearance_tolerance": 2e-5}}}


@pytest.fixture(scope="module")
def small_sweep(tmp_path_factory):
    path = tmp_path_factory.mktemp("rel") / "one.nc"
    run_sweep(SMALL_SWEEP, path, workers=1, progress=False).close()
    return path


@pytest.mark.slow
def test_a_reliability_sweep_is_bit_identical_on_one_and_two_workers(tmp_path, small_sweep,
                                                                     process_pool):
    with xr.open_dataset(small_sweep) as one, \
            run_sweep(SMALL_SWEEP, tmp_path / "two.nc", client=process_pool, progress=False) as two:
        xr.testing.assert_identical(drop_timing(one), drop_timing(two))
        assert one.sizes["member"] == 3 and "b10" in one and "reliability" in one
        assert int(one.members_counted.sel(limit="any")) == 3
        assert one["reliability"].dims == ("limit", "revolutions")
        assert one["revolutions_to_limit"].dims == ("member", "limit")
        assert one["b10"].attrs["units"] == "1" and "long_name" in one["b10_ci_low"].attrs


def test_report_ranks_by_b10_and_plot_draws_r_and_b10(tmp_path, small_sweep):
    runner = CliRunner()
    result = runner.invoke(main, ["report", str(small_sweep)])
    assert result.exit_code == 0, result.output
    assert "ranked by B10" in result.output and "what decides it" in result.output
    for extra in ([], ["--b10"]):
        out = tmp_path / f"r{len(extra)}.png"
        result = runner.invoke(main, ["plot", str(small_sweep), "--kind", "reliability", *extra,
                                      "-o", str(out)])
        assert result.exit_code == 0, result.output
        assert out.stat().st_size > 10_000
    result = runner.invoke(main, ["plot", str(small_sweep), "--kind", "sweep", "--b10", "-o",
                                  str(tmp_path / "x.png")])
    assert result.exit_code == 2 and "--b10" in result.output


# ---------------------------------------------------------------------------- closed form

@pytest.mark.slow
def test_kaplan_meier_of_64_members_matches_the_lognormal_closed_form(nominal):
    """k lognormal (CV 0.5), nothing else scattered: N = N0 / f up to the jump
    discretisation, so R(N) = Phi((ln(N0 / N) + sigma^2 / 2) / sigma)."""
    from lifelines import LogNormalFitter

    revolutions, censored = _members(_tiny(f"reliability.wear_coefficient_cv={K_CV}",
                                           "reliability.members=64", "reliability.seed=1"), 64)
    assert not censored.any()
    grid = revolution_grid(revolutions.min(), revolutions.max(), 40)
    est = estimate_limit(revolutions, censored, grid)
    exact = _closed_form(grid, nominal, K_CV)
    inside = (est.reliability_low <= exact) & (exact <= est.reliability_high)
    assert inside.mean() >= 0.9
    median = nominal * math.exp(0.5 * math.log1p(K_CV ** 2))
    assert est.b50[1] <= median <= est.b50[2]
    fit = LogNormalFitter().fit(revolutions, ~censored)
    low, high = np.exp(fit.summary.loc["mu_", ["coef lower 95%", "coef upper 95%"]].to_numpy(float))
    assert low <= median <= high


@pytest.mark.slow
def test_censored_members_are_not_failures(nominal):
    """life.cycles below most members' lives: those members are censored at it. Counted
    as failures there (the naive estimate), R(life.cycles) would be the fraction that
    failed before, far below the closed form; censored, R stays in its band."""
    median = nominal * math.exp(0.5 * math.log1p(K_CV ** 2))
    horizon = round(0.8 * median)
    revolutions, censored = _members(_tiny(f"reliability.wear_coefficient_cv={K_CV}",
                                           "reliability.members=24", "reliability.seed=4",
                                           f"life.cycles={horizon}"), 24)
    assert censored.sum() >= 12
    assert np.allclose(revolutions[censored], horizon, rtol=1e-9)
    grid = np.array([0.99 * horizon])
    est = estimate_limit(revolutions, censored, grid)
    exact = _closed_form(grid, nominal, K_CV)[0]
    assert est.reliability_low[0] <= exact <= est.reliability_high[0]
    naive = estimate_limit(revolutions, np.zeros_like(censored), np.array([1.01 * horizon]))
    assert naive.reliability[0] == 0.0
    assert not naive.reliability_low[0] <= exact <= naive.reliability_high[0]
    assert math.isinf(est.b50[0])               # the median life lies beyond the horizon
    assert est.weibull_scale[0] > horizon       # the Weibull fit extrapolates past it


# ---------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("override, key", [
    ("reliability.clearance_tolerance=-1e-6", "reliability.clearance_tolerance"),
    ("reliability.clearance_tolerance=3e-4", "reliability.clearance_tolerance"),
    ("reliability.wear_coefficient_cv=-0.1", "reliability.wear_coefficient_cv"),
    ("reliability.speed_cv=-0.1", "reliability.speed_cv"),
    ("reliability.members=1", "reliability.members"),
    ("life.max_motion_error=0", "life.max_motion_error"),
])
def test_bad_reliability_value_names_the_key(override, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        load_config(CASE, [override])


@pytest.mark.parametrize("overrides, key", [
    (["life.max_clearance_growth=null"], "life"),
    (["joints.B.clearance=0", "life.max_motion_error=1e-4", "life.max_clearance_growth=null"],
     "life.max_motion_error"),
    (["life.stop_at_wear_through=true"], "life.stop_at_wear_through"),
    (["ensemble.members=2"], "ensemble.members"),
])
def test_a_limit_that_can_never_be_reached_is_refused_before_anything_runs(tmp_path, overrides, key):
    sweep = {"store": "reliability", "base": _tiny(*overrides).to_dict()}
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        expand(sweep)


def test_cli_bad_reliability_input_is_one_line_and_exit_2(tmp_path):
    path = tmp_path / "rel.yaml"
    path.write_text(f"store: reliability\nbase: {(tmp_path / 'base.yaml').name}\n")
    (tmp_path / "base.yaml").write_text(open(CASE).read() + "reliability: {wear_coefficient_cv: -1}\n")
    result = CliRunner().invoke(main, ["sweep", str(path), "-o", str(tmp_path / "out.nc")])
    assert result.exit_code == 2
    assert result.output.count("\n") == 1 and "clearsweep: error:" in result.output
    assert "reliability.wear_coefficient_cv" in result.output
    assert not (tmp_path / "out.nc").exists()


# ---------------------------------------------------------------------------- motion error

@pytest.mark.slow
def test_motion_error_is_zero_for_the_ideal_mechanism_and_read_from_the_settled_rows():
    from clearsweep.config import resolve_materials
    from clearsweep.params import PRESETS, ideal_slider_x, pack

    prepare_kernel()
    errors = []
    for extra in (["joints.B.clearance=0"], []):
        cfg = load_config(CASE, ["solver.duration=0.2", *extra])
        errors.append(settled_motion_error(cfg, run_kernel(pack(cfg, resolve_materials(cfg)))))
    assert errors[0] < 1e-9
    # the slider leads or lags by about the clearance of its one clearance joint (0.25 mm)
    assert 0.2 * 2.5e-4 < errors[1] < 3 * 2.5e-4
    ds = simulate(CASE, ["solver.duration=0.2"]).where(lambda d: d.time >= 0.05, drop=True)
    p = PRESETS["realistic"]
    ideal = ideal_slider_x(ds.crank_angle.values, p.crank_length_m, p.rod_length_m, p.slider_height_m)
    assert errors[1] == np.max(np.abs(ds.slider_position.values - ideal))


def test_the_plan_of_a_reliability_sweep_counts_every_block_of_every_member():
    """Each member is a life run of up to life.max_blocks blocks: the plan's steps and time
    are those of the blocks (the estimate counted one block per member, 16 s for the shipped
    example that runs minutes)."""
    config = Path(__file__).resolve().parent.parent / "configs" / "reliability.yaml"
    plan = expand(str(config))
    cfg = next(iter(plan.runnable().values()))
    per_block = cfg.life.block_revolutions * 60.0 / cfg.mechanism.speed_rpm / cfg.solver.dt
    steps = len(plan.runnable()) * cfg.life.max_blocks * per_block
    text = plan.describe(2)
    assert "life runs" in text and f"at most {steps:.3g} RK4 steps" in text, text
