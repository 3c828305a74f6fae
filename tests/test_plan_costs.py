"""The plans' clocks (issue 45, item 2): a step is priced by the joints that have clearance,
from the constants benchmarks/calibrate_plan.py measured (clearsweep/data/plan_costs.yaml);
a life or reliability plan by its blocks and their jumps; the compile estimate from the same
file. No timing here: the plans are checked against measured runs in benchmarks/README.md
("Plans against measured times"), never in a unit test."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from clearsweep import budget
from clearsweep.budget import (
    PLAN_COSTS_FILE,
    case_seconds,
    clearance_joints,
    life_seconds,
    plan_costs,
    read_plan_costs,
    step_seconds,
)
from clearsweep.cli import main
from clearsweep.config import load_config
from clearsweep.schema import read_yaml
from clearsweep.service_life import block_steps, forecast_blocks, life_time_text
from clearsweep.sweeping.plan import expand

ROOT = Path(__file__).resolve().parents[1]
IDEAL = ["joints.B.clearance=0", "joints.A.clearance=0"]
GUIDE = [*IDEAL, "joints.P.clearance_y=1e-4", "joints.P.clearance_z=1e-4"]
#: A costs file whose every constant is a round number no measurement gives.
ROUND = """\
measured: {date: test, machine: none, load_average: [0, 0]}
step_s: 1.0e-3
joint_step_s: {O: 2.0e-3, A: 4.0e-3, B: 8.0e-3, P: 16.0e-3}
row_s: 1.0e-4
case_s: 5.0
map_bin_s: 1.0e-6
block_s: 7.0
run_start_s: 3.0
sweep_start_s: 11.0
assemble_case_s: 0.5
assemble_row_s: 1.0e-5
compile_s: 123
"""


@pytest.fixture
def round_costs(tmp_path, monkeypatch):
    path = tmp_path / "costs.yaml"
    path.write_text(ROUND)
    monkeypatch.setenv("CLEARSWEEP_PLAN_COSTS", str(path))
    read_plan_costs.cache_clear()
    yield path
    read_plan_costs.cache_clear()


def seconds_of(text: str) -> float:
    value, unit = re.search(r"about ([0-9.e+]+) (s|min|h|d)\b", text).groups()
    return float(value) * {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}[unit]


def test_the_shipped_file_says_where_and_when_it_was_measured():
    doc = read_yaml(PLAN_COSTS_FILE)
    assert {"date", "machine", "load_average", "kernel_cache"} <= set(doc["measured"])
    costs = plan_costs()
    assert set(costs.joint_step_s) == set("OABP")
    assert all(v >= 0 for v in costs.joint_step_s.values())
    assert costs.step_s > 0 and costs.compile_s > 0
    # the wear pace a life plan walks to life.cycles with, and the run it was fitted to
    assert costs.wear_pace is not None and "configs/life.yaml" in costs.wear_pace.reference


def test_the_shipped_costs_price_the_guide_s_faces():
    """The shipped file was measured on the guide's faces (an elastic foundation over each of
    P's faces with their edge lines), whose step costs an order of magnitude more than the
    ideal one: 25.2 us beyond a 2.02 us ideal step on 9001c94 (12.4x). The file measured on
    the corners' law said 5.83 us beyond 2.06 (2.8x), and the mixed-clearance study's plan
    came out 2.3x short (benchmarks/README.md, "Plans priced by joint set"). A life block's
    cost beyond its steps is measured, not a clipped difference (0 where P's steps were
    priced above what a later block's cost)."""
    costs = plan_costs()
    assert costs.joint_step_s["P"] > 5.0 * costs.step_s
    assert costs.joint_step_s["P"] > 5.0 * max(costs.joint_step_s[j] for j in "OAB")
    assert costs.block_s > 0.0


def test_the_joints_with_clearance():
    assert clearance_joints(load_config({}, IDEAL)) == ""
    assert clearance_joints(load_config({}, GUIDE)) == "P"
    assert clearance_joints(load_config({}, ["joints.O.clearance=1e-4", "joints.A.clearance=2.5e-4",
                                             "joints.B.clearance=2.5e-4"])) == "OAB"


def test_a_guide_case_costs_more_per_step_than_an_ideal_case():
    """The shipped constants: P's 16 corner-wall pairs make its step several times the ideal
    one (benchmarks/README.md measured 3-7x), and the same steps plan longer."""
    ideal, guide = load_config({}, IDEAL), load_config({}, GUIDE)
    assert step_seconds(guide) > 2.0 * step_seconds(ideal)
    assert case_seconds(guide) > 2.0 * case_seconds(ideal) > 0.0
    runner = CliRunner()
    texts = [runner.invoke(main, ["run", str(ROOT / "configs" / "ideal.yaml"), *sets,
                                  "--dry-run"]).stdout
             for sets in ([], ["--set", "joints.P.clearance_y=1e-4", "--set",
                               "joints.P.clearance_z=1e-4"])]
    assert "100,000 RK4 steps" in texts[0] and "100,000 RK4 steps" in texts[1]
    per_step = [float(re.search(r"at ([0-9.e+]+) us per step \((ideal|P)\)", t).group(1))
                for t in texts]
    assert per_step[1] > 2.0 * per_step[0], texts
    assert seconds_of(texts[1]) > seconds_of(texts[0]) + 100_000 * (per_step[1] - per_step[0]) \
        * 1e-6 * 0.99


def test_the_file_s_constants_are_the_plan_s(round_costs):
    """Every constant of the costs file reaches the plans as written."""
    cfg = load_config({"solver": {"duration": 0.01, "dt": 1e-5, "save_every": 10},
                       "wear": {"map": [10, 20]}},
                      ["joints.O.clearance=1e-4", "joints.B.clearance=2.5e-4"])
    assert step_seconds(cfg) == pytest.approx(1e-3 + 2e-3 + 8e-3)
    # 1000 steps, 101 rows, 4 maps of 200 bins
    assert case_seconds(cfg, keeps_series=False) == pytest.approx(5.0 + 1000 * 11e-3)
    kept = 101 * 1e-4 + 800 * 1e-6
    assert case_seconds(cfg) == pytest.approx(5.0 + 1000 * 11e-3 + kept)
    assert budget.assembly_seconds(cfg, False) == pytest.approx(0.5)
    assert budget.assembly_seconds(cfg, True) == pytest.approx(0.5 + 101 * 1e-5)
    assert life_seconds(cfg, 4, 1000) == pytest.approx(5.0 + 4 * (1000 * 11e-3 + 7.0))
    assert budget.sweep_seconds([10.0, 20.0, 30.0], workers=2) == pytest.approx(11.0 + 30.0)
    assert budget.sweep_seconds([10.0, 20.0, 30.0], 2, assembly=1.5) == pytest.approx(42.5)
    # the longest case bounds a sweep from below however many workers share it
    assert budget.sweep_seconds([100.0, 1.0], workers=2) == pytest.approx(11.0 + 100.0)
    text = budget.time_text(cfg)
    assert seconds_of(text) == pytest.approx(3.0 + 5.0 + 11.0 + kept, rel=0.01)
    assert "at 1.1e+04 us per step (OB)" in text


def test_a_sweep_plan_prices_each_case_by_its_joints(round_costs):
    """The mixed study: 16 subsets of {O, A, B, P}; the plan is the sum of its cases, each
    priced by its own joints, shared by the workers, after the start."""
    plan = expand(ROOT / "configs" / "mixed_clearances.yaml")
    cases = plan.runnable()
    expected = (11.0 + sum(case_seconds(c, keeps_series=False) for c in cases.values()) / 2
                + 0.5 * len(cases))
    assert seconds_of(plan.describe(2)) == pytest.approx(expected, rel=0.01)
    # with every case priced as the ideal one the plan would be far shorter
    flat = 11.0 + sum(5.0 + budget.estimate(c).steps * 1e-3 for c in cases.values()) / 2
    assert expected > 5 * flat


def test_a_life_plan_prices_its_blocks_and_jumps(round_costs):
    """configs/reliability_joints.yaml's member: all four joints clear; its expected time is
    the forecast blocks, each its steps at the four joints' price and its jump."""
    cfg = load_config(read_yaml(ROOT / "configs" / "reliability_joints.yaml")["base"])
    assert clearance_joints(cfg) == "OABP"
    steps, blocks = block_steps(cfg), forecast_blocks(cfg).blocks
    per_step = 1e-3 + 2e-3 + 4e-3 + 8e-3 + 16e-3
    text = life_time_text(cfg, steps)
    expected = text.split("expected ")[1]
    assert seconds_of(expected) == pytest.approx(3.0 + 5.0 + blocks * (steps * per_step + 7.0),
                                                 rel=0.01)
    plan = expand(ROOT / "configs" / "reliability_joints.yaml")
    members = plan.runnable().values()
    want = 11.0 + sum(5.0 + forecast_blocks(c, every_limit=True).blocks
                      * (block_steps(c) * per_step + 7.0) for c in members) / 2 \
        + 0.5 * len(members)
    assert seconds_of(plan.describe(2).split("expected ")[1]) == pytest.approx(want, rel=0.01)


def test_the_compile_estimate_is_the_file_s(round_costs, monkeypatch):
    from clearsweep import cli, simulation
    from clearsweep.config import DEFAULTS

    monkeypatch.setattr(simulation, "kernel_needs_compiling", lambda method, build: True)
    monkeypatch.setattr(simulation, "prepare_kernel", lambda method, build: 0.0)
    said = []
    monkeypatch.setattr(cli.click, "echo", lambda text, err=False: said.append(text))
    cli.announce_compile(False, [DEFAULTS])
    assert "about 123 s" in said[0] and "allows clearance at O,P" in said[0], said


#: The later costs, round: the spectrum's import, an ensemble's statistics, and the
#: slider-crank's ideal step and impacts per revolution of each joint.
LATER = ("spectrum_s: 13.0\nensemble_s: 17.0\nslider_crank: {step_s: 0.5e-3, "
         "joint_revolution_s: {O: 1.0, A: 2.0, B: 3.0}}\n")
SLIDER_CRANK = ROOT / "configs" / "slider_crank.yaml"


@pytest.fixture
def later_costs(round_costs):
    round_costs.write_text(ROUND + LATER)
    read_plan_costs.cache_clear()
    yield round_costs


def test_the_shipped_file_prices_the_slider_crank_s_impacts():
    """The slider-crank's cases are impact-driven (configs/slider_crank.yaml: 0.5 mm at B,
    5000 r/min, up to 16 sub-steps a step): its B costs 0.0227 s a revolution beyond the
    4,800 ideal steps' 0.0066 s (calibrate_plan.py --slider-crank, 2026-12-06), where the
    RSSP's per-step share priced it at 0.0008 s and the sweep and the ensemble ran 1.7-2.6x
    their plans (benchmarks/README.md, "Plans against measured times")."""
    costs = plan_costs()
    assert costs.slider_crank_step_s is not None and costs.slider_crank_step_s > 0.0
    per_revolution = 60.0 / (5000.0 * 2.5e-6)
    for joint in "AB":
        assert costs.joint_revolution_s[joint] > 2.0 * per_revolution * costs.slider_crank_step_s
    assert costs.spectrum_s > 0.0 and costs.ensemble_s > 0.0


def test_the_slider_crank_s_impacts_go_with_its_revolutions_not_its_steps(later_costs):
    """The impacts' sub-steps are taken at the contact's own time scale, about a fixed
    number a revolution: 5 revolutions cost the same impacts at 1000 r/min (120,000 steps)
    as at 5000 (24,000); the steps are priced at the slider-crank's ideal step and the
    joints' shares. The RSSP is priced as before."""
    fast = load_config(SLIDER_CRANK)
    slow = load_config(SLIDER_CRANK, ["mechanism.speed_rpm=1000"])
    for cfg, steps in ((fast, 24_000), (slow, 120_000)):
        assert budget.estimate(cfg).steps == steps
        assert case_seconds(cfg, keeps_series=False) == pytest.approx(
            5.0 + steps * (0.5e-3 + 8e-3) + 5 * 3.0)
    both = load_config(SLIDER_CRANK, ["joints.O.clearance=1e-4", "joints.A.clearance=5e-4",
                                      "joints.A.socket_radius=0.01"])
    assert clearance_joints(both) == "OAB"
    assert case_seconds(both, keeps_series=False) == pytest.approx(
        5.0 + 24_000 * (0.5e-3 + 2e-3 + 4e-3 + 8e-3) + 5 * (1.0 + 2.0 + 3.0))
    rssp = load_config({}, ["joints.O.clearance=1e-4", "joints.B.clearance=2.5e-4"])
    assert step_seconds(rssp) == pytest.approx(1e-3 + 2e-3 + 8e-3)


def test_a_slider_crank_life_plan_charges_the_impacts_to_its_first_block(later_costs):
    """A life run's later blocks run in the worn bearing: configs/slider_crank_life.yaml's
    blocks 3-8 took 0.036 s each, less than their steps' price without the impacts; the
    first block is priced with them (2 revolutions, 3.0 s each here)."""
    cfg = load_config(ROOT / "configs" / "slider_crank_life.yaml")
    steps = block_steps(cfg)
    assert steps == 9_600
    assert life_seconds(cfg, 4, steps) == pytest.approx(
        5.0 + 4 * (steps * (0.5e-3 + 8e-3) + 7.0) + 2 * 3.0)


def test_a_sweep_plan_charges_the_spectrum_once_and_an_ensemble_s_statistics(later_costs):
    """A worker imports the spectrum's scipy.signal with its first case whose settled window
    holds 2 revolutions (each worker once, side by side: once in the wall time), and an
    ensemble's driver computes its statistics after the cases."""
    cases = {}
    for name, ensemble in (("slider_crank_clearance_sweep", 0.0), ("slider_crank_ensemble", 17.0)):
        plan = expand(ROOT / "configs" / f"{name}.yaml")
        cases[name] = list(plan.runnable().values())
        work = sum(case_seconds(c, keeps_series=False) for c in cases[name])
        expected = 11.0 + 13.0 + work / 2 + 0.5 * len(cases[name]) + ensemble
        assert seconds_of(plan.describe(2)) == pytest.approx(expected, rel=0.01)
    # a settled window of 1 revolution holds no spectrum: nothing to import
    short = load_config(SLIDER_CRANK, ["solver.revolutions=2"])
    assert budget.spectrum_seconds([short]) == 0.0
    assert budget.spectrum_seconds([load_config(SLIDER_CRANK)]) == 13.0
    assert budget.ensemble_seconds(cases["slider_crank_clearance_sweep"]) == 0.0


#: A wear pace whose numbers are round: r0 2.5e-11 m a revolution at 0.25 mm of clearance,
#: and a K so large that the rate stays r0 at any depth (K / (K / r0 + h)).
PACE = ("wear_pace: {reference: test, first_rate_m: 2.5e-11, growth_m2: 1.0, "
        "clearance_m: 2.5e-4, wear_coefficient_m2_per_N: 8.0e-14}\n")


@pytest.mark.parametrize("text", ["step_s: 1\n", ROUND.replace("P: 16.0e-3", "P: fast"),
                                  ROUND.replace("case_s: 5.0", "case_s: -5.0"),
                                  ROUND + PACE.replace("1.0,", "fast,"),
                                  ROUND + PACE.replace("1.0,", "0,"),
                                  ROUND + "wear_pace: {first_rate_m: 1.0e-6}\n",
                                  ROUND + LATER.replace("B: 3.0}", "}"),
                                  ROUND + LATER.replace("13.0", "-13.0")],
                         ids=["keys missing", "not a number", "negative", "pace not a number",
                              "pace of zero", "pace keys missing", "slider-crank joint missing",
                              "negative spectrum"])
def test_a_broken_costs_file_is_refused_in_one_line(tmp_path, monkeypatch, text):
    path = tmp_path / "costs.yaml"
    path.write_text(text)
    monkeypatch.setenv("CLEARSWEEP_PLAN_COSTS", str(path))
    read_plan_costs.cache_clear()
    try:
        result = CliRunner().invoke(main, ["run", str(ROOT / "configs" / "ideal.yaml"), "--dry-run"])
    finally:
        read_plan_costs.cache_clear()
    assert result.exit_code == 2, result.output
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"clearsweep: error: {path}:") and "plan-costs file" in line


def test_a_life_plan_walks_to_life_cycles_at_the_file_s_wear_pace(tmp_path, monkeypatch):
    """The wear pace is the file's. Without one a life plan walks to its wear limits alone
    (configs/life.yaml: 101 blocks to 0.25 mm of wear at 2.5 um a jump). With one it also
    walks to life.cycles, each jump the allowance over the pace's rate, cut as the run cuts
    it: at 2.5e-11 m a revolution the jumps are 1e5 revolutions, and 1e6 revolutions take
    11 blocks (the tenth jump cut to 99,989). The rate goes with Archard's k: 4 times k,
    jumps of 2.5e4 revolutions, 41 blocks; and with the clearance, as the allowance does:
    0.1 mm, jumps of 1e5 revolutions again."""
    path = tmp_path / "costs.yaml"
    life_yaml = ROOT / "configs" / "life.yaml"
    cfg = load_config(life_yaml)
    try:
        path.write_text(ROUND)
        monkeypatch.setenv("CLEARSWEEP_PLAN_COSTS", str(path))
        read_plan_costs.cache_clear()
        without = forecast_blocks(cfg)
        path.write_text(ROUND + PACE)
        read_plan_costs.cache_clear()
        paced = forecast_blocks(cfg)
        worn = forecast_blocks(load_config(life_yaml, ["joints.B.wear_coefficient=3.2e-13"]))
        tight = forecast_blocks(load_config(life_yaml, ["joints.B.clearance=1e-4"]))
        text = life_time_text(cfg, block_steps(cfg))
    finally:
        read_plan_costs.cache_clear()
    assert (without.blocks, without.to_cycles) == (101, None)
    assert (paced.blocks, paced.to_limits, paced.to_cycles) == (11, 101, 11)
    assert (worn.blocks, tight.blocks) == (41, 11)
    assert "11 blocks to 1e+06 revolutions at the wear pace of" in text
    assert seconds_of(text.split("expected ")[1]) == pytest.approx(
        3.0 + 5.0 + 11 * (block_steps(cfg) * (1e-3 + 8e-3) + 7.0), rel=0.01)


def test_a_denormal_crank_speed_is_priced(later_costs):
    """speed_rpm * dt / 60 underflows to 0 at 5e-324 r/min: the steps a revolution are then
    infinite, and a step carries no share of the slider-crank's impacts (no division by 0)."""
    rssp = load_config({}, ["mechanism.speed_rpm=5e-324", "joints.B.clearance=2.5e-4"])
    assert step_seconds(rssp) == pytest.approx(1e-3 + 8e-3)
    crank = load_config({"mechanism": {"kind": "slider_crank", "preset": "flores_benchmark",
                                       "speed_rpm": 5e-324},
                         "joints": {"B": {"clearance": 5e-4, "socket_radius": 0.01}},
                         "solver": {"duration": 1e-3}})
    assert clearance_joints(crank) == "B"
    assert step_seconds(crank) == pytest.approx(0.5e-3 + 8e-3)
