"""Hostile input across every command, one table grown by every hardening round: each row
is a command line, the exit code it must end with and a substring of its one
``clearsweep: error:`` line; no row may print a traceback or leave an output file.

Rows of round 3b (issue 22, items 3 and 4) and of the fresh round on the reliability and
life sections, sampling sweeps, sensitivity, the CUDA backend's options and results files
of older versions (issue 20, item 6). Before, the rows marked "was:" ended as said there.
Every row is refused before any simulation, or reads a small results file built once.
"""

from __future__ import annotations

import errno
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.sweeping.plan import sample_points

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = ROOT / "configs"
ONE = str(CONFIGS / "one_clearance.yaml")
LIFE = str(CONFIGS / "life.yaml")
#: a life run of two short blocks (0.1 s each) on a coarse map
SHORT_LIFE = ("--set", "mechanism.speed_rpm=600", "--set", "life.max_blocks=2",
              "--set", "wear.map=[6,12]")
RANGES = {"x1": [0.0, 1.0], "x2": [0.0, 1.0]}


def saltelli_file(path: Path, sweep_config: str | None = None, n: int = 4) -> Path:
    """A Saltelli sampling sweep file of y = x1 + 0.5 x2 (no simulation), its design in
    ``sweep_config`` unless given."""
    points = sample_points("saltelli", n, RANGES, seed=1)
    spec = {"sweep": {"sample": {"method": "saltelli", "n": n, "seed": 1, "ranges": RANGES}}}
    ds = xr.Dataset({"y": ("sample", points @ np.array([1.0, 0.5])),
                     "status": ("sample", ["ok"] * len(points))},
                    attrs={"sweep_config": yaml.safe_dump(spec) if sweep_config is None
                           else sweep_config})
    ds.to_netcdf(path)
    return path


def without(src: Path, dst: Path, *names: str) -> Path:
    """A copy of results file ``src`` without the variables ``names``: as an older version
    of the tool wrote it."""
    with xr.open_dataset(src) as ds:
        ds.load().drop_vars(list(names)).to_netcdf(dst)
    return dst


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Results files the rows read: a short run, a short life run, a small reliability
    sweep, Saltelli designs that match their data or not, and older-version copies."""
    d = tmp_path_factory.mktemp("inputs")
    # the shipped reliability sweep cut to one coating, two members and one short block
    text = (CONFIGS / "reliability.yaml").read_text()
    (d / "rel.yaml").write_text(text.replace("[none, MoS2, lead, PTFE]", "[MoS2]")
                                .replace("map: [36, 72]", "map: [6, 12]"))
    for argv in (["run", ONE, "--set", "solver.duration=0.002", "-q", "-o", d / "run.nc"],
                 ["life", LIFE, *SHORT_LIFE, "-q", "-o", d / "life.nc"],
                 ["sweep", d / "rel.yaml", "--set", "reliability.members=2", *SHORT_LIFE,
                  "--set", "life.max_blocks=1", "--no-progress", "--workers", "1",
                  "-o", d / "rel.nc"]):
        result = CliRunner().invoke(main, [str(a) for a in argv])
        assert result.exit_code == 0, result.output
    saltelli_file(d / "samp.nc")
    saltelli_file(d / "samp_bad_yaml.nc", "sweep: {sample: [unclosed\n  x: {")
    saltelli_file(d / "samp_list.nc", "- 1\n- 2\n")
    saltelli_file(d / "samp_n8.nc", yaml.safe_dump(
        {"sweep": {"sample": {"method": "saltelli", "n": 8, "seed": 1, "ranges": RANGES}}}))
    saltelli_file(d / "samp_3_inputs.nc", yaml.safe_dump(
        {"sweep": {"sample": {"method": "saltelli", "n": 4, "seed": 1,
                              "ranges": {**RANGES, "x3": [0.0, 1.0]}}}}))
    saltelli_file(d / "samp_ranges_list.nc", yaml.safe_dump(
        {"sweep": {"sample": {"method": "saltelli", "n": 4, "ranges": [1, 2]}}}))
    without(d / "life.nc", d / "old_life.nc", "stop_reason")
    without(d / "run.nc", d / "old_run.nc", "status")
    with xr.open_dataset(d / "rel.nc") as ds:
        b10 = [str(v) for v in ds.data_vars if str(v).startswith("b10")]
    without(d / "rel.nc", d / "old_rel.nc", *b10)
    (d / "afile").write_text("a file, not a folder\n")
    return d


def sweep_file(tmp: Path, body: str, base: str = ONE, store: str = "summary") -> str:
    path = tmp / "s.yaml"
    path.write_text(f"name: s\nstore: {store}\nbase: {base}\n{body}")
    return str(path)


def sample_file(tmp: Path, section: str) -> str:
    return sweep_file(tmp, f"sweep:\n  sample: {section}\n")


# (id, argv(tmp, files), exit code, words of the error line). "was:" what main did before.
ROWS = [
    # --- round 3b, item 3: tracebacks instead of one line
    ("dopri5 max_step 1e-300 (was: OverflowError)",
     lambda t, f: ["run", ONE, "--set", "solver.method=dopri5", "--set", "solver.max_step=1e-300",
                   "--set", "solver.duration=0.002", "-o", t / "out.nc"],
     2, "solver.max_step: got 1e-300"),
    ("validate dopri5 max_step 1e-300 (was: accepted)",
     lambda t, f: ["validate", ONE, "--set", "solver.method=dopri5", "--set", "solver.max_step=1e-300"],
     2, "solver.max_step: got 1e-300"),
    ("dopri5 max_step 1e-12 (was: unstable_step, no hint)",
     lambda t, f: ["run", ONE, "--set", "solver.method=dopri5", "--set", "solver.max_step=1e-12",
                   "--set", "solver.duration=0.002", "-o", t / "out.nc"],
     2, "solver.dt / 2^solver.max_substep_level"),
    ("sensitivity --metric status (was: ValueError)",
     lambda t, f: ["sensitivity", f / "samp.nc", "--metric", "status"],
     2, "output 'status' is text, not a number; choose from: y"),
    ("sensitivity -o under a file (was: OSError)",
     lambda t, f: ["sensitivity", f / "samp.nc", "--metric", "y", "-o", f / "afile" / "out.png"],
     1, "cannot write"),
    ("sensitivity malformed sweep_config (was: ParserError)",
     lambda t, f: ["sensitivity", f / "samp_bad_yaml.nc", "--metric", "y"],
     2, "sweep_config attribute is not readable YAML"),
    ("sensitivity design of 3 inputs, data of 2 (was: SALib RuntimeError)",
     lambda t, f: ["sensitivity", f / "samp_3_inputs.nc", "--metric", "y"],
     2, "(n = 4 base points over 3 inputs: 20 points) does not match the 16 samples"),
    ("sensitivity design n 8, data of n 4 (was: exit 0, n = 8 reported)",
     lambda t, f: ["sensitivity", f / "samp_n8.nc", "--metric", "y"],
     2, "does not match the 16 samples"),
    ("sensitivity sweep_config a list (was: AttributeError)",
     lambda t, f: ["sensitivity", f / "samp_list.nc", "--metric", "y"],
     2, "not a sampling sweep"),
    ("sensitivity ranges a list (was: AttributeError)",
     lambda t, f: ["sensitivity", f / "samp_ranges_list.nc", "--metric", "y"],
     2, "holds no readable Saltelli design"),
    # --- round 3b, item 4: dead ends and wrong words
    ("plot life wear-map --select cycle (was: asks for snapshot)",
     lambda t, f: ["plot", f / "life.nc", "--kind", "wear-map", "--select", "cycle=1",
                   "-o", t / "out.png"],
     2, "--select snapshot=K, K one of 0 ("),
    ("plot life wear-map --select snapshot=99 (was: unknown sweep dimension)",
     lambda t, f: ["plot", f / "life.nc", "--kind", "wear-map", "--select", "snapshot=99",
                   "-o", t / "out.png"],
     2, "--select snapshot=K"),
    ("life block_revolutions 1e6 (was: names solver.duration)",
     lambda t, f: ["life", LIFE, "--set", "life.block_revolutions=1000000", "-o", t / "out.nc"],
     2, "life.block_revolutions: got 1000000"),
    ("life sweep block_revolutions 1e6 (was: accepted, every case fails)",
     lambda t, f: ["sweep", CONFIGS / "life_sweep.yaml", "--set", "life.block_revolutions=1000000",
                   "-o", t / "out.nc"],
     2, "life.block_revolutions: got 1000000"),
    ("life ensemble.members 2 (was: member 0 alone, exit 0)",
     lambda t, f: ["life", LIFE, "--set", "ensemble.members=2", "-o", t / "out.nc"],
     2, "ensemble.members: got 2; expected 1 with `clearsweep life`"),
    ("run members 1 with a perturbation (was: one perturbed case, exit 0)",
     lambda t, f: ["run", ONE, "--set", "ensemble.perturb.ball_offset=0.5", "-o", t / "out.nc"],
     2, "ensemble.perturb.ball_offset: got 0.5"),
    ("life members 1 with a perturbation (was: exit 0)",
     lambda t, f: ["life", LIFE, "--set", "ensemble.perturb.crank_phase_deg=10", "-o", t / "out.nc"],
     2, "ensemble.perturb.crank_phase_deg: got 10"),
    # --- fresh round: reliability and life sections
    ("reliability sweep without limits (was: names joints.B.coating)",
     lambda t, f: ["sweep", CONFIGS / "reliability.yaml", "--set", "life.max_clearance_growth=null",
                   "--set", "life.max_motion_error=null", "-o", t / "out.nc"],
     2, "reliability.yaml: life: got no limit set"),
    ("reliability block_revolutions 1e6 (was: accepted, every member fails)",
     lambda t, f: ["sweep", CONFIGS / "reliability.yaml", "--set", "life.block_revolutions=1000000",
                   "-o", t / "out.nc"],
     2, "life.block_revolutions: got 1000000"),
    ("life dopri5 max_step 1e-300 (was: block unstable_step, exit 0)",
     lambda t, f: ["life", LIFE, "--set", "solver.method=dopri5", "--set", "solver.max_step=1e-300",
                   "-o", t / "out.nc"],
     2, "solver.max_step: got 1e-300"),
    ("life cycles inf", lambda t, f: ["life", LIFE, "--set", "life.cycles=.inf", "-o", t / "out.nc"],
     2, "life.cycles: got inf"),
    ("reliability members 1",
     lambda t, f: ["sweep", CONFIGS / "reliability.yaml", "--set", "reliability.members=1",
                   "-o", t / "out.nc"],
     2, "reliability.members: got 1"),
    ("life checkpoint path a folder (was: 'holds the finished blocks of an earlier run')",
     lambda t, f: (t / "out.nc.life-checkpoint").mkdir() or
     ["life", LIFE, *SHORT_LIFE, "-o", t / "out.nc"],
     2, "is where this run keeps its checkpoint, and it is not a file"),
    ("life --resume from a text file (was: numpy's 'pickled data' advice)",
     lambda t, f: (t / "out.nc.life-checkpoint").write_text("garbage\n") and
     ["life", LIFE, *SHORT_LIFE, "--resume", "-o", t / "out.nc"],
     2, "not a checkpoint archive"),
    # --- fresh round: sampling sweeps
    ("sample range beyond the key's values (was: by the luck of the draw)",
     lambda t, f: ["sweep", sample_file(t, "{method: lhs, n: 4, ranges: {joints.B.clearance: "
                                           "[-1.0e-4, 4.0e-4]}}"), "-o", t / "out.nc"],
     2, "at -0.0001, joints.B.clearance expected a number >= 0"),
    ("sample range of an integer key (was: names the first point drawn)",
     lambda t, f: ["sweep", sample_file(t, "{method: lhs, n: 4, ranges: {solver.save_every: [1, 10]}}"),
                   "-o", t / "out.nc"],
     2, "sweep.sample.ranges.solver.save_every: got [1, 10]"),
    ("sample second_order with lhs (was: silently ignored)",
     lambda t, f: ["sweep", sample_file(t, "{method: lhs, n: 4, second_order: true, ranges: "
                                           "{joints.B.clearance: [1.0e-4, 4.0e-4]}}"), "-o", t / "out.nc"],
     2, "sweep.sample.second_order: got True; expected false with method lhs"),
    ("sample n a string",
     lambda t, f: ["sweep", sample_file(t, "{method: lhs, n: many, ranges: {joints.B.clearance: "
                                           "[1.0e-4, 4.0e-4]}}"), "-o", t / "out.nc"],
     2, "sweep.sample.n: got 'many'"),
    # --- fresh round: CUDA backend options (this process has no device, or it is hidden)
    ("--backend cuda without a device",
     lambda t, f: ["sweep", CONFIGS / "sensitivity.yaml", "--backend", "cuda", "-o", t / "out.nc"],
     2, "no CUDA device: use --backend processes"),
    ("--keep-series beyond the cases (was: names keep_series in <sweep>)",
     lambda t, f: ["sweep", sample_file(t, "{method: lhs, n: 4, ranges: {joints.B.clearance: "
                                           "[1.0e-4, 4.0e-4]}}"), "--backend", "cuda",
                   "--keep-series", "99", "-o", t / "out.nc"],
     2, "s.yaml: --keep-series: got 99"),
    ("--keep-series with processes",
     lambda t, f: ["sweep", ONE, "--keep-series", "all", "-o", t / "out.nc"],
     2, "--keep-series selects the cases of --backend cuda"),
    # --- fresh round: results files of older versions
    ("report a life file without stop_reason (was: KeyError)",
     lambda t, f: ["report", f / "old_life.nc"], 2, "has no 'stop_reason'"),
    ("plot --kind life without stop_reason (was: KeyError)",
     lambda t, f: ["plot", f / "old_life.nc", "--kind", "life", "-o", t / "out.png"],
     2, "needs stop_reason"),
    ("report a reliability file without b10 (was: KeyError)",
     lambda t, f: ["report", f / "old_rel.nc"], 2, "has no 'b10'"),
    ("report a life run --format json (was: text, exit 0)",
     lambda t, f: ["report", f / "life.nc", "--format", "json"], 2,
     "--format json: "),
    ("report a reliability sweep --full (was: ignored)",
     lambda t, f: ["report", f / "rel.nc", "--full"], 2, "is a reliability sweep, which report prints as text only"),
    ("report a run without status (was: KeyError)",
     lambda t, f: ["report", f / "old_run.nc"], 2, "has no 'status'"),
]


def fifo(tmp: Path, name: str) -> Path:
    """A FIFO that nothing writes to: reading it would wait for ever. So that a reader that
    waits fails the row instead of hanging the suite, from 3 s to 20 s after it is made a
    line of text and an end of file are written to whoever waits on it."""
    path = tmp / name
    os.mkfifo(path)

    def release() -> None:
        time.sleep(3.0)
        end = time.monotonic() + 17.0
        while time.monotonic() < end:
            try:
                fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK)     # ENXIO: no reader waits
            except OSError:
                time.sleep(0.2)
                continue
            try:
                os.write(fd, b"still waiting: 1\n")
            except OSError:
                pass
            os.close(fd)

    threading.Thread(target=release, daemon=True).start()
    return path


def declared_rows(tmp: Path, rows: int = 2_000_000_000) -> Path:
    """A results file of a few kilobytes whose metadata declares ``rows`` time rows of two
    float64 variables (chunked and never written: nothing of them is stored)."""
    import netCDF4

    path = tmp / "declared.nc"
    with netCDF4.Dataset(path, "w") as nc:
        nc.createDimension("time", rows)
        for name in ("time", "slider_acceleration"):
            nc.createVariable(name, "f8", ("time",), chunksizes=(1024,))
        nc.createVariable("status", str, ())
    return path


# --- round 4 (issue 33, item 3): every size and every wait bounded before it is taken
ROUND4_BOUNDS = [
    ("validate a FIFO (was: waits for a writer for ever)",
     lambda t, f: ["validate", fifo(t, "in.yaml")], 2, "in.yaml' (a FIFO, not a regular file)"),
    ("sweep --dry-run a FIFO (was: waits for ever)",
     lambda t, f: ["sweep", fifo(t, "in.yaml"), "--dry-run"], 2, "(a FIFO, not a regular file)"),
    ("run a FIFO (was: waits for ever)",
     lambda t, f: ["run", fifo(t, "in.yaml"), "-o", t / "out.nc"], 2, "(a FIFO, not a regular file)"),
    ("materials -m a FIFO (was: waits for ever)",
     lambda t, f: ["materials", "-m", fifo(t, "m.yaml")], 2, "m.yaml' (a FIFO, not a regular file)"),
    ("validate /dev/zero (was: read 1 MiB of zeros, 'more than 1048576 bytes')",
     lambda t, f: ["validate", "/dev/zero"], 2, "'/dev/zero' (a character device, not a regular file)"),
    ("report a FIFO (was: waits for ever)",
     lambda t, f: ["report", fifo(t, "in.nc")], 2, "in.nc' is a FIFO, not a results file"),
    ("plot a FIFO (was: waits for ever)",
     lambda t, f: ["plot", fifo(t, "in.nc"), "--kind", "slider", "-o", t / "out.png"], 2,
     "is a FIFO, not a results file"),
    ("sensitivity a FIFO (was: waits for ever)",
     lambda t, f: ["sensitivity", fifo(t, "in.nc"), "--metric", "y"], 2,
     "is a FIFO, not a results file"),
    ("report a device (was: 'no netCDF reader can open it')",
     lambda t, f: ["report", "/dev/null"], 2, "'/dev/null' is a character device"),
    ("report 2e9 declared time rows (was: allocates 15 GiB, _ArrayMemoryError)",
     lambda t, f: ["report", declared_rows(t)], 2,
     "declares a variable 'time' of 2,000,000,000 time values (14.9 GiB); this command reads "
     "whole variables, of at most 4 GiB"),
    ("plot 2e9 declared time rows (was: allocates 15 GiB)",
     lambda t, f: ["plot", declared_rows(t), "--kind", "slider", "-o", t / "out.png"], 2,
     "'time' of 2,000,000,000 time values"),
    ("sensitivity 2e9 declared time rows (was: allocates 15 GiB)",
     lambda t, f: ["sensitivity", declared_rows(t), "--metric", "slider_acceleration"], 2,
     "'time' of 2,000,000,000 time values"),
    ("life snapshots 1e4 of a 1000 x 2000 map (was: dry run 'memory up to 41 MiB'; the run "
     "died at 3.6 GB with a traceback)",
     lambda t, f: ["life", LIFE, "--set", "life.snapshots=10000", "--set", "wear.map=[1000,2000]",
                   "--dry-run"], 2,
     "life.snapshots: got 10000 (201 snapshots kept of a 1000 x 2000 wear map of 2 joints, "
     "30.5 MiB each: 18.2 GiB in all"),
    ("life sweep snapshots 1e4 of a 1000 x 2000 map (was: accepted)",
     lambda t, f: ["sweep", CONFIGS / "life_sweep.yaml", "--set", "life.snapshots=10000",
                   "--set", "wear.map=[1000,2000]", "--dry-run"], 2,
     "life.snapshots: got 10000 (201 snapshots kept"),
    ("life max_blocks 1e6 (was: accepted, a checkpoint rewritten after each of 1e6 blocks)",
     lambda t, f: ["life", LIFE, "--set", "life.max_blocks=1000000", "--dry-run"], 2,
     "life.max_blocks: got 1000000 (from --set); expected an integer with 1 <= x <= 10000"),
    ("run --allow-large beyond the machine's memory (was: MemoryError traceback)",
     lambda t, f: ["run", ONE, "--set", "solver.duration=1e6", "--allow-large", "-o", t / "out.nc"],
     2, "expected a case whose arrays fit in this machine's memory"),
]
ROWS += ROUND4_BOUNDS


@pytest.fixture
def device(monkeypatch):
    """The CUDA device as the row needs it: none for ``--backend cuda``, a stand-in for
    ``--keep-series`` (refused before any batch is made)."""
    import clearsweep.gpu as gpu

    def none():
        raise gpu.NoCudaDevice()

    return lambda present: monkeypatch.setattr(gpu, "device_name",
                                               (lambda: "stand-in") if present else none)


@pytest.mark.parametrize("name, argv, code, words", ROWS, ids=[r[0] for r in ROWS])
def test_hostile_input_is_one_error_line(tmp_path, files, device, name, argv, code, words):
    device("--keep-series beyond" in name)
    result = CliRunner().invoke(main, [str(a) for a in argv(tmp_path, files)])
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        f"{type(result.exception).__name__}: {result.exception}"
    assert "Traceback" not in result.stderr
    assert result.exit_code == code, result.output
    lines = result.stderr.strip().splitlines()
    assert lines and lines[-1].startswith("clearsweep: error: ") and words in lines[-1], result.stderr
    assert [line for line in lines if "error" in line] == [lines[-1]]      # one error line
    left = [p for p in tmp_path.glob("out*") if not p.name.endswith(".life-checkpoint")]
    assert not left and not list(files.glob("out*"))


def two_case_sweep(tmp: Path) -> str:
    path = tmp / "two.yaml"
    path.write_text("name: two\nstore: summary\nbase: {joints: {B: {clearance: 2.5e-4}}, "
                    "solver: {duration: 0.002}, wear: {map: [6, 12]}}\n"
                    "sweep: {grid: {joints.B.coating: [none, PTFE]}}\n")
    return str(path)


def test_a_full_disk_during_a_sweep_says_so_and_keeps_the_finished_parts(tmp_path, monkeypatch):
    """Before: "the serial backend failed (OSError: [Errno 28] ...)", no word of the disk."""
    from clearsweep.sweeping.parts import PartStore

    real, calls = PartStore.write, []

    def second_write_fills_the_disk(self, h, part):
        calls.append(h)
        if len(calls) > 1:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, h, part)

    monkeypatch.setattr(PartStore, "write", second_write_fills_the_disk)
    out = tmp_path / "out.nc"
    result = CliRunner().invoke(main, ["sweep", two_case_sweep(tmp_path), "-o", str(out),
                                       "--workers", "1", "--no-progress"])
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    line = result.stderr.strip().splitlines()[-1]
    assert line.startswith("clearsweep: error: the disk is full: cannot write in ")
    assert "1 of the 2 cases are finished and kept there: make room and run again with --resume" in line
    assert not out.exists() and len(list((tmp_path / "out.nc.parts").glob("*.nc"))) == 1


def test_the_resume_banner_counts_only_the_cases_left(tmp_path):
    """Before: "2 cases, 2 to simulate" when both were kept."""
    config, out = two_case_sweep(tmp_path), str(tmp_path / "two.nc")
    first = CliRunner().invoke(main, ["sweep", config, "-o", out, "--keep-parts", "--workers", "1",
                                      "--no-progress"])
    assert first.exit_code == 0 and "2 cases, 2 to simulate, 400 RK4 steps" in first.stderr
    again = CliRunner().invoke(main, ["sweep", config, "-o", out, "--resume", "--workers", "1",
                                      "--no-progress"])
    assert again.exit_code == 0, again.output
    assert "2 cases, 0 to simulate (2 finished before, kept), 0 RK4 steps" in again.stderr
    size = first.stderr.split("results up to ")[1]
    assert again.stderr.split("results up to ")[1].split("\n")[0] == size.split("\n")[0]


@pytest.mark.parametrize("select, title", [((), "Socket wear depth"),
                                           (("--select", "snapshot=1"),
                                            "Socket wear depth, snapshot 1 at ")])
def test_a_life_runs_wear_map_is_drawn_whole_or_by_snapshot(tmp_path, files, select, title):
    """Before: --kind wear-map on a life file asked for --select on snapshot, then refused it."""
    import clearsweep.plotting as plotting

    figures = []
    real = plotting.figure

    def keep(*args, **kwargs):
        figures.append(real(*args, **kwargs))
        return figures[-1]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(plotting, "figure", keep)
        result = CliRunner().invoke(main, ["plot", str(files / "life.nc"), "--kind", "wear-map",
                                           *select, "-o", str(tmp_path / "w.png")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "w.png").stat().st_size > 0
    suptitle = figures[0].get_suptitle()
    assert suptitle.startswith(title) and ("snapshot" in suptitle) == bool(select)


def test_a_reliability_sweeps_b10_is_a_metric(files):
    """Before: "unknown metric 'b10'; choose from: status, wear_depth_max_final, wall_time"."""
    result = CliRunner().invoke(main, ["report", str(files / "rel.nc"), "--metric", "b10"])
    assert result.exit_code == 0, result.output
    header = result.stdout.splitlines()[2].split()
    assert header[:2] == ["B_coating", "limit"] and "member" not in header
    with xr.open_dataset(files / "rel.nc") as ds:     # a row per design and limit
        assert len(result.stdout.strip().splitlines()) == 3 + ds["b10"].size


@pytest.mark.parametrize("command", ["run", "life"])
def test_a_full_disk_while_writing_the_results_says_the_disk_is_full(tmp_path, monkeypatch, command):
    """Before: "cannot write OUT: No space left on device", no word of the disk."""
    import clearsweep.dataset as dataset

    def full(ds, path, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(dataset, "write_netcdf_atomic", full)
    out = tmp_path / "out.nc"
    argv = (["run", ONE, "--set", "solver.duration=0.002"] if command == "run"
            else ["life", LIFE, *SHORT_LIFE, "--set", "life.max_blocks=1"])
    result = CliRunner().invoke(main, [*argv, "-q", "-o", str(out)])
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    assert result.stderr.strip().splitlines()[-1] == (
        f"clearsweep: error: cannot write {out}: the disk is full (No space left on device)")
    assert not out.exists()
