"""A life or reliability plan gives an expected time beside its upper bound (issue 34 item 3).

Before, ``life --dry-run`` and the plan of a life or reliability sweep printed only the
upper bound, ``life.max_blocks`` blocks for every run: the reliability example's "at most
about 21.3 min" ran in 1 min 55 s. The expected blocks come from the depth walk of
:func:`clearsweep.service_life.forecast_blocks`: a jump grows the bin that limits it by
what ``life.jump_*_fraction`` allows, whatever the wear rate, so the block at which a wear
limit is crossed follows from the config (benchmarks/README.md, "Life and reliability
plans": the estimate against the wall time of the shipped examples).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.config import load_config
from clearsweep.service_life import forecast_blocks, life

ROOT = Path(__file__).resolve().parent.parent
CASE = str(ROOT / "configs/one_clearance.yaml")
#: A life run that wear ends within a few blocks: 300 r/min (0.2 s blocks), a coarse map,
#: wear x300, to 70 um of wear at B (tests/test_figure_layout.py's TINY_LIFE).
TINY_LIFE = ["mechanism.speed_rpm=300", "metrics.settle_time=0.02", "wear.map=[8,16]",
             "wear.interpolate=true", "solver.energy_tolerance=0.5", "wear.amplification=300",
             "life.cycles=1e5", "life.jump_clearance_fraction=0.1",
             "life.max_clearance_growth=7e-5"]

_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}


def _seconds(text: str, before: str) -> float:
    """The duration that follows ``before`` in ``text`` ("at most about 1.33 min") [s]."""
    match = re.search(re.escape(before) + r" ([0-9.e+]+) (s|min|h|d)\b", text)
    assert match, f"no {before!r} in: {text}"
    return float(match.group(1)) * _UNITS[match.group(2)]


@pytest.mark.parametrize("argv", [
    ["life", "configs/life.yaml", "--dry-run"],
    ["sweep", "configs/reliability.yaml", "--dry-run", "--workers", "2"],
    ["sweep", "configs/life_sweep.yaml", "--dry-run", "--workers", "2"],
], ids=lambda a: a[1])
def test_the_plan_gives_an_expected_time_beside_the_bound(argv, monkeypatch):
    monkeypatch.chdir(ROOT)
    result = CliRunner().invoke(main, argv)
    assert result.exit_code == 0, result.output
    bound = _seconds(result.output, "at most about")
    expected = _seconds(result.output, "expected about")
    assert 0.0 < expected <= bound
    assert "blocks" in result.output.split("expected about", 1)[1]


def test_the_reliability_example_is_expected_in_a_fraction_of_its_bound(monkeypatch):
    """Its members reach their wear limit (40 um at jumps of 2 % of 0.25 mm) in 9 blocks of
    the 200 the bound counts: about 1.1 min expected on 2 workers, 21.5 min at most."""
    monkeypatch.chdir(ROOT)
    result = CliRunner().invoke(main, ["sweep", "configs/reliability.yaml", "--dry-run",
                                       "--workers", "2"])
    assert "9 blocks a run to its wear limits (life.max_clearance_growth)" in result.output
    assert _seconds(result.output, "expected about") < 0.1 * _seconds(result.output, "at most about")


def test_the_joint_with_the_smallest_allowance_sets_the_pace():
    """configs/reliability_joints.yaml: 40 um of wear at jumps of 2 % of each joint's
    clearance. A's and B's 0.25 mm allow 5 um a jump (9 blocks); O's and P's 0.1 mm 2 um,
    and either can cut every jump: 21 blocks (its members ran about 24, issue 45)."""
    from clearsweep.schema import read_yaml

    cfg = load_config(read_yaml(ROOT / "configs" / "reliability_joints.yaml")["base"])
    assert forecast_blocks(cfg, every_limit=True).blocks == 21
    only_b = load_config(read_yaml(ROOT / "configs" / "reliability_joints.yaml")["base"],
                         ["joints.O.clearance=0", "joints.A.clearance=0",
                          "joints.P.clearance_y=0", "joints.P.clearance_z=0"])
    assert forecast_blocks(only_b, every_limit=True).blocks == 9


@pytest.mark.parametrize("extra, limit", [
    ([], "clearance_growth"),
    (["joints.B.coating=MoS2", "joints.B.coating_thickness=5e-5",
      "life.stop_at_wear_through=true", "life.max_clearance_growth=null"], "wear_through"),
])
def test_the_forecast_is_the_blocks_a_run_that_wear_ends_takes(extra, limit):
    """Two runs that a wear limit ends: at 2.5e-5 m a jump, 7e-5 m of clearance growth is
    crossed in the fourth block; a 50 um MoS2 coating, with jumps of a quarter of what is
    left of it (and at least a quarter of a quarter of it), wears through in the tenth."""
    cfg = load_config(CASE, TINY_LIFE + extra)
    forecast = forecast_blocks(cfg)
    ds = life(cfg)
    assert str(ds["stop_reason"].values) == limit
    assert forecast.limits == (limit,)
    assert forecast.blocks == ds.sizes["cycle"] == (4 if limit == "clearance_growth" else 10)


#: configs/life.yaml: its run ends at its 10^6 revolutions in 40 blocks (docs/service_life.md)
#: long before its wear limit, 0.25 mm of wear (101 blocks at jumps of 1 % of the clearance).
LIFE = str(ROOT / "configs/life.yaml")


def _kernel_at_the_plan_s_pace(cfg, monkeypatch):
    """Stand in for the kernel in ``life``: each block deepens one bin of each clearance
    joint by the plan's wear pace (service_life.pace_rate at the bin's depth, times the
    block's revolutions) and does nothing else. The run's own loop is left as it is: the
    rates it reads from the block, its jumps, their cut at life.cycles, its limits."""
    import types

    import numpy as np

    from clearsweep import service_life
    from clearsweep.core import layout as L
    from clearsweep.params import joint_configs

    paced = service_life.wear_pace(cfg)
    assert paced is not None
    clear = [j for j, (_, joint) in enumerate(joint_configs(cfg)) if joint.clearance > 0.0]
    revs = cfg.life.block_revolutions

    def run_kernel(packed, wmap, wvol):
        out = wmap.copy()
        for j, (_, coating, *pace) in zip(clear, paced, strict=True):
            out[j, 0, 0] += service_life.pace_rate(float(out[j, 0, 0]), coating, *pace) * revs
        return types.SimpleNamespace(
            wmap=out, wvol=wvol + 1e-12, stats=np.zeros((2, L.N_M)), status="ok",
            residual_max=0.0, ke_peak=0.0, n_saved=0, t=np.zeros(0), y=np.zeros((0, L.N_Y)))

    monkeypatch.setattr(service_life, "run_kernel", run_kernel)
    monkeypatch.setattr(service_life, "prepare_kernel", lambda *args, **kwargs: 0.0)


@pytest.mark.parametrize("overrides, stop", [
    ([], "cycles"),
    (["life.cycles=2e4"], "cycles"),
    (["joints.B.clearance=1e-4", "wear.amplification=10"], "cycles"),
    (["life.max_clearance_growth=2.5e-5"], "clearance_growth"),
    (["joints.B.coating_thickness=2e-5", "life.stop_at_wear_through=true",
      "life.max_clearance_growth=null"], "wear_through"),
    (["life.max_blocks=25"], "max_blocks"),
], ids=["life.yaml", "2e4 revolutions", "0.1 mm, wear x10", "wear limit", "wear-through",
        "max_blocks"])
def test_the_forecast_is_the_blocks_of_a_run_that_wears_at_the_plan_s_pace(
        overrides, stop, monkeypatch):
    """Physics aside, the plan counts blocks by the run's own rule: a run whose wear follows
    the plan's pace takes exactly the blocks forecast, whichever end comes first, life.cycles
    or a wear limit (was: configs/life.yaml forecast 101 blocks, the walk to its wear limit,
    for a run that reaches its 10^6 revolutions in 40)."""
    cfg = load_config(LIFE, overrides)
    _kernel_at_the_plan_s_pace(cfg, monkeypatch)
    ds = life(cfg)
    assert str(ds["stop_reason"].values) == stop
    assert forecast_blocks(cfg).blocks == ds.sizes["cycle"]


def test_the_calibration_gives_back_the_pace_a_run_wore_at(monkeypatch):
    """benchmarks/calibrate_plan.py's fit of the wear pace inverts the plan's walk: on a
    run that wore at the shipped pace it gives that pace back (r0 to rounding, K to 1e-3:
    the fit leaves out the blocks' own wear, about a nanometre a block against the jumps'
    2.5 um)."""
    import importlib.util

    from clearsweep.budget import plan_costs

    spec = importlib.util.spec_from_file_location("calibrate_plan",
                                                  ROOT / "benchmarks" / "calibrate_plan.py")
    assert spec is not None and spec.loader is not None
    calibrate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(calibrate)
    cfg = load_config(LIFE)
    _kernel_at_the_plan_s_pace(cfg, monkeypatch)
    fitted = calibrate.fit_wear_pace(life(cfg), cfg)
    pace = plan_costs().wear_pace
    assert fitted["first_rate_m"] == pytest.approx(pace.first_rate_m, rel=1e-9)
    assert fitted["growth_m2"] == pytest.approx(pace.growth_m2, rel=1e-3)
    assert fitted["clearance_m"] == pace.clearance_m
    assert fitted["wear_coefficient_m2_per_N"] == pace.wear_coefficient_m2_per_N


def test_the_forecast_of_a_short_run_to_life_cycles_is_its_blocks():
    """configs/life.yaml cut to 2e4 revolutions, run: its 10^6 revolutions' pace (fitted
    by benchmarks/calibrate_plan.py to the whole run's 40 blocks) forecasts 6 blocks, and
    the run takes 5 (was: 101, the walk to its wear limit)."""
    cfg = load_config(LIFE, ["life.cycles=2e4"])
    ds = life(cfg)
    assert str(ds["stop_reason"].values) == "cycles"
    assert abs(forecast_blocks(cfg).blocks - ds.sizes["cycle"]) <= 1


def test_the_forecast_never_passes_the_bound():
    life_yaml = str(ROOT / "configs/life.yaml")
    cfg = load_config(life_yaml)
    assert forecast_blocks(cfg).to_limits == 101     # 0.25 mm at 1 % of 0.25 mm a jump
    capped = forecast_blocks(load_config(life_yaml, ["life.max_blocks=30"]))
    assert (capped.blocks, capped.to_limits, capped.to_cycles) == (30, 30, 30)
    # at most the blocks that reach life.cycles without a jump; at the wear pace, one jump
    # to a block short of them and that block
    short = forecast_blocks(load_config(life_yaml, ["life.cycles=20"]))
    assert (short.to_limits, short.to_cycles, short.blocks) == (20, 2, 2)
    # no wear limit watched: life.cycles at the wear pace, said so
    paced = forecast_blocks(load_config(life_yaml, ["life.max_clearance_growth=null",
                                                    "life.max_normal_force=30"]))
    assert (paced.blocks, paced.limits) == (forecast_blocks(cfg).to_cycles, ())
    assert "revolutions at the wear pace of" in paced.describe(cfg)
    # nothing to forecast from (no wear; a bearing with clearance, whose pace no run
    # measured): the bound, said so
    for overrides in (["life.max_clearance_growth=null", "life.max_normal_force=30",
                       "joints.O.clearance=1e-4"], ["wear.enabled=false"]):
        forecast = forecast_blocks(load_config(life_yaml, overrides))
        assert (forecast.blocks, forecast.limits, forecast.to_cycles) == (200, (), None)
        assert "no wear limit watched" in forecast.describe(cfg)
    # a reliability member waits for every limit: the later of the two
    both = load_config(life_yaml, ["joints.B.coating_thickness=5e-5",
                                   "life.stop_at_wear_through=true"])
    first, every = forecast_blocks(both), forecast_blocks(both, every_limit=True)
    assert first.limits == every.limits == ("clearance_growth", "wear_through")
    assert first.blocks < every.blocks <= 200


def test_a_life_names_the_joint_that_reaches_a_limit_first():
    """Each joint against the limit: the first_joint_to_* of a life run is the joint whose
    own series crosses it first (here B, the one with clearance, of A, B, O, P), the report
    names it, and a reliability sweep counts it per design."""
    import numpy as np
    import xarray as xr

    from clearsweep.reliability import _first_joints
    from clearsweep.service_life import crossing_cycle, life_summary_text

    cfg = load_config(CASE, TINY_LIFE)
    ds = life(cfg)
    assert str(ds["stop_reason"].values) == "clearance_growth"
    depth = ds["wear_depth_max"].values
    crossings = [crossing_cycle(ds["cycle"].values, depth[:, j], 7e-5) for j in range(depth.shape[1])]
    first = str(ds["joint"].values[int(np.nanargmin(crossings))])
    assert first == "B" == str(ds["first_joint_to_clearance_growth"].values)
    assert str(ds["first_joint_to_motion_error"].values) == ""     # not set
    assert "revolutions to life.max_clearance_growth: " in life_summary_text(ds)
    assert "(joint B first)" in life_summary_text(ds)
    flat = xr.Dataset({"first_joint": (("design", "member", "limit"),
                                       np.array([[["B", "B"], ["P", "P"], ["B", "B"], ["", ""]]],
                                                dtype=object))},
                      coords={"limit": ["clearance_growth", "any"]})
    rows = [("B_coating=none", flat.isel(design=0).sel(limit="any"))]
    assert _first_joints(flat, "any", rows) == [
        "which joint reaches any first:",
        "  B_coating=none: first to reach it: joint B in 2 members, joint P in 1 member"]
