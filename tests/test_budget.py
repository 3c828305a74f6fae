"""Bounds on the work and memory a config implies, checked before anything runs."""

import pytest
from click.testing import CliRunner

from clearsweep.budget import MAX_OUTPUT_BYTES, estimate
from clearsweep.cli import main
from clearsweep.config import ConfigError, load_config
from clearsweep.simulation import preflight
from clearsweep.sweeping import expand

BASE = {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.01}}

# (override, key named, words in the message): each passes validation field by field
TOO_LARGE = [
    ("solver.duration=1.0e+3", "solver.duration", "GiB"),              # 10 GiB of saved rows
    ("solver.duration=1.0e+6", "solver.duration", "1e+11 steps"),
    ("solver.dt=1.0e-300", "solver.dt", "1e+298 steps"),
    ("wear.map=[100000, 100000]", "wear.map", "wear maps 298 GiB"),
]


@pytest.fixture
def big_machine(monkeypatch):
    """A machine with memory for any of these (--allow-large is bounded by the real one)."""
    import clearsweep.budget as budget

    monkeypatch.setattr(budget, "machine_memory", lambda: 1 << 62)


@pytest.mark.parametrize("override, key, words", TOO_LARGE, ids=[t[0] for t in TOO_LARGE])
def test_preflight_refuses_a_case_beyond_the_budget(override, key, words, big_machine):
    cfg = load_config(BASE, [override])
    with pytest.raises(ConfigError) as info:
        preflight(cfg)
    assert info.value.key == key and words in str(info.value) and "--allow-large" in str(info.value)
    if override != "solver.dt=1.0e-300":       # 1e298 rows: no machine holds them
        preflight(cfg, allow_large=True)        # lifted on request (nothing is allocated here)


@pytest.mark.parametrize("override, key, words", TOO_LARGE[:2] + TOO_LARGE[3:],
                         ids=[t[0] for t in TOO_LARGE[:2] + TOO_LARGE[3:]])
@pytest.mark.parametrize("command", ["validate", "run"])
def test_cli_refuses_a_case_beyond_the_budget(tmp_path, command, override, key, words,
                                              big_machine):
    path = tmp_path / "c.yaml"
    path.write_text("joints: {B: {clearance: 2.5e-4}}\n")
    out = tmp_path / "o.nc"
    args = [command, str(path), "--set", override] + (["-o", str(out)] if command == "run" else [])
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith(f"clearsweep: error: {path}: {key}: got ") and words in result.stderr
    assert not out.exists()
    if command == "validate":
        assert CliRunner().invoke(main, args + ["--allow-large"]).exit_code == 0


def test_save_every_beyond_the_run_is_refused():
    cfg = load_config(BASE, ["solver.save_every=5000"])          # 0.01 s / 1e-5 s = 1000 steps
    with pytest.raises(ConfigError, match=r"solver\.save_every: got 5000; expected an integer "
                                          r"<= 1000 \(the steps in solver\.duration"):
        preflight(cfg, allow_large=True)
    preflight(load_config(BASE, ["solver.save_every=1000"]))


def test_sweep_expansion_checks_every_case(big_machine):
    sweep = {"base": BASE, "sweep": {"grid": {"wear.map": [[36, 72], [100000, 100000]]}}}
    with pytest.raises(ConfigError, match=r"wear\.map: got \[100000, 100000\].*map=\[100000, 100000\]"):
        expand(sweep)
    assert len(expand(sweep, allow_large=True).cases) == 2


def test_estimate_bounds_the_arrays_of_a_real_case():
    from clearsweep.simulation import simulate

    cfg = load_config(BASE, ["solver.duration=0.02", "solver.save_every=5"])
    est = estimate(cfg)
    assert est.steps == 2000 and est.rows == 401
    ds = simulate(cfg)
    assert ds.sizes["time"] == est.rows
    assert ds.nbytes <= est.output_bytes <= 3 * ds.nbytes
    assert est.output_bytes < MAX_OUTPUT_BYTES


@pytest.mark.parametrize("override, key", [("solver.duration=1.0e+3", "solver.duration"),
                                           ("wear.map=[100000, 100000]", "wear.map")])
def test_allow_large_is_still_bounded_by_the_machines_memory(monkeypatch, override, key):
    """Was: --allow-large took any size, and a case beyond the machine's memory ended in a
    MemoryError traceback (or the out-of-memory killer)."""
    import clearsweep.budget as budget

    monkeypatch.setattr(budget, "machine_memory", lambda: 2 * 2 ** 30)
    with pytest.raises(ConfigError) as info:
        preflight(load_config(BASE, [override]), allow_large=True)
    assert info.value.key == key
    assert "fit in this machine's memory (2 GiB free)" in str(info.value)
    assert "--allow-large lifts the bounds of clearsweep, not those of this machine" in str(info.value)


def test_a_memory_error_during_a_run_is_one_line(tmp_path, monkeypatch):
    """Was: a MemoryError traceback when the arrays did not fit after all."""
    import clearsweep.cli as cli
    import clearsweep.simulation as simulation

    def no_memory(*args, **kwargs):
        raise MemoryError("Unable to allocate 9.97 TiB for an array")

    monkeypatch.setattr(simulation, "simulate", no_memory)
    monkeypatch.setattr(cli, "announce_compile", lambda *a, **k: None)
    path = tmp_path / "c.yaml"
    path.write_text("joints: {B: {clearance: 2.5e-4}}\n")
    result = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "o.nc")])
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    assert "Traceback" not in result.stderr
    assert result.stderr.strip().splitlines()[-1].startswith(
        "clearsweep: error: out of memory: this machine could not hold the arrays of the run")
    assert not (tmp_path / "o.nc").exists()
