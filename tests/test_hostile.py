"""Hostile input across every command, one table grown by every hardening round: each row
is a command line, the exit code it must end with and a substring of its one
``clearsweep: error:`` line; no row may print a traceback or leave an output file.

Rows of round 3b (issue 22, items 3 and 4) and of the fresh round on the reliability and
life sections, sampling sweeps, sensitivity, the CUDA backend's options and results files
of older versions (issue 20, item 6); round 4's resume integrity and the user's files
(issue 33, items 1 and 2: ``ROUND4_INTEGRITY``), its messages (items 4-6:
``ROUND4_MESSAGES``) and its fresh fuzz round (``ROUND4_FUZZ``); round 5's output paths
and messages of ``--kind bifurcation`` (issue 40, item 10: ``ROUND5_OUTPUTS``,
``ROUND5_BIFURCATION``), its lengths in crank revolutions (``REVOLUTIONS``) and its fresh
fuzz round (item 11: ``ROUND5_FUZZ``). Before, the rows marked
"was:" ended as said there.
Every row is refused before any simulation, or reads a small results file built once.
"""

from __future__ import annotations

import errno
import os
import subprocess
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
    sweep, a two-speed sweep, Saltelli designs that match their data or not, and
    older-version copies."""
    d = tmp_path_factory.mktemp("inputs")
    # the shipped reliability sweep cut to one coating, two members and one short block
    text = (CONFIGS / "reliability.yaml").read_text()
    (d / "rel.yaml").write_text(text.replace("[none, MoS2, lead, PTFE]", "[MoS2]")
                                .replace("map: [36, 72]", "map: [6, 12]"))
    for argv in (["run", ONE, "--set", "solver.duration=0.002", "-q", "-o", d / "run.nc"],
                 ["life", LIFE, *SHORT_LIFE, "-q", "-o", d / "life.nc"],
                 ["sweep", d / "rel.yaml", "--set", "reliability.members=2", *SHORT_LIFE,
                  "--set", "life.max_blocks=1", "--no-progress", "--workers", "1",
                  "-o", d / "rel.nc"],
                 ["sweep", speed_sweep(d), "--no-progress", "--workers", "1", "-q",
                  "-o", d / "bif.nc"],
                 ["sweep", unlabelled_zip(d), "--no-progress", "--workers", "1", "-q",
                  "-o", d / "zip.nc"],
                 ["sweep", clearance_sweep(d), "--no-progress", "--workers", "1", "-q",
                  "-o", d / "clr.nc"]):
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


def speed_sweep(tmp: Path) -> Path:
    """configs/bifurcation.yaml's zip group (labels ``speed``, ``mechanism.speed_rpm``) over
    60 and 600 r/min, 2 ms a case: shorter than a revolution, no Poincaré section."""
    path = tmp / "bif.yaml"
    path.write_text("name: bif\nstore: summary\nbase: {joints: {B: {clearance: 2.5e-4}}, "
                    "solver: {duration: 0.002}, wear: {map: [6, 12]}}\n"
                    "sweep: {zip: [{name: speed, labels: [60, 600], "
                    "mechanism.speed_rpm: [60.0, 600.0]}]}\n")
    return path


def unlabelled_zip(tmp: Path) -> Path:
    """A zip group ``g`` without labels (speed and revolutions together), 0.02 revolutions a
    case: a sweep dimension with no coordinate to select by."""
    path = tmp / "zip.yaml"
    path.write_text("name: zip\nstore: summary\nbase: {joints: {B: {clearance: 2.5e-4}}, "
                    "wear: {map: [6, 12]}}\nsweep: {zip: [{name: g, mechanism.speed_rpm: "
                    "[300.0, 600.0], solver.revolutions: [0.01, 0.02]}]}\n")
    return path


def clearance_sweep(tmp: Path) -> Path:
    """B's clearance at 0.1 and 0.25 mm, 2 ms a case: a swept coordinate in m."""
    path = tmp / "clr.yaml"
    path.write_text("name: clr\nstore: summary\nbase: {solver: {duration: 0.002}, "
                    "wear: {map: [6, 12]}}\nsweep: {grid: {joints.B.clearance: [1.0e-4, 2.5e-4]}}\n")
    return path


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
    ("sensitivity -o under a file (was: OSError; round 4: exit 1 after the analysis)",
     lambda t, f: ["sensitivity", f / "samp.nc", "--metric", "y", "-o", f / "afile" / "out.png"],
     2, "afile is a file, not a folder"),
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
    ("--backend cuda under numba-cuda 0.30.4 and numpy 2.5 (was: every case failed with "
     "numpy's AttributeError)",
     lambda t, f: ["sweep", CONFIGS / "sensitivity.yaml", "--backend", "cuda", "-o", t / "out.nc"],
     2, "numba-cuda 0.30.4 does not compile the kernel with numpy 2.5.0: install numpy below 2.5"),
    ("--backend cuda with CLEARSWEEP_HOST_MEMORY=12x (was: not read, the window 16 GiB at most)",
     lambda t, f: ["sweep", CONFIGS / "sensitivity.yaml", "--backend", "cuda", "-o", t / "out.nc"],
     2, "environment: CLEARSWEEP_HOST_MEMORY: got '12x'; expected a whole number of bytes > 0"),
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


def parts_made_with(tmp: Path, section: str, key: str, value) -> Path:
    """A two-case sweep file whose parts folder ``res.nc.parts`` holds the part of its first
    case as made with ``section.key = value`` in its identity (``run_identity``): other
    materials values or another clearsweep version. Returns the sweep file."""
    from clearsweep.sweeping import expand
    from clearsweep.sweeping.parts import case_hash, part_identity, with_identity, write_part

    path = sweep_file(tmp, "sweep:\n  grid:\n    joints.B.clearance: [1.0e-4, 2.0e-4]\n")
    identity = part_identity(next(iter(expand(path).runnable().values())), "summary")
    if section in ("version", "store"):
        identity[section] = value
    else:
        identity[section]["steel"][key] = value
    (tmp / "res.nc.parts").mkdir()
    write_part(tmp / "res.nc.parts", case_hash(identity),
               with_identity(xr.Dataset({"status": ((), "ok")}), identity))
    return Path(path)


def checkpoint_made_with(tmp: Path, wear_coefficient: float) -> Path:
    """A life checkpoint ``res.nc.life-checkpoint`` of LIFE (SHORT_LIFE) after one block, as
    made with another MoS2 wear coefficient; returns the checkpoint."""
    import json

    from clearsweep.config import load_config
    from clearsweep.service_life import LifeState, checkpoint_path_for, save_checkpoint

    cfg = load_config(LIFE, [o for o in SHORT_LIFE if o != "--set"])
    path = save_checkpoint(checkpoint_path_for(tmp / "res.nc"), cfg,
                           LifeState(np.zeros((2, 6, 12)), np.zeros(2), 1.0, [{"cycle": 1.0}]), 0.0)
    with np.load(path) as data:
        saved = {k: data[k] for k in data.files}
    materials = json.loads(str(saved["materials"]))
    materials["MoS2"]["wear_coefficient_m2_per_N"] = wear_coefficient
    saved["materials"] = np.array(json.dumps(materials))
    with open(path, "wb") as f:
        np.savez(f, **saved)
    return path


def checkpoint_with_status(tmp: Path, status: str) -> Path:
    """A life checkpoint ``res.nc.life-checkpoint`` of LIFE (SHORT_LIFE) of its own inputs and
    layout after one block whose status reads ``status``; returns the checkpoint."""
    from clearsweep.config import load_config
    from clearsweep.service_life import LifeState, checkpoint_path_for, save_checkpoint
    from clearsweep.variables import JOINTS

    cfg = load_config(LIFE, [o for o in SHORT_LIFE if o != "--set"])
    wmap, volumes = np.zeros((len(JOINTS), *cfg.wear.map)), np.zeros(len(JOINTS))
    state = LifeState(wmap, volumes, 1.0, [{"cycle": 1.0, "block_status": status}],
                      snapshots=[(1.0, wmap)], block_volumes=[volumes])
    return save_checkpoint(checkpoint_path_for(tmp / "res.nc"), cfg, state, 0.0)


def users_part_in_ledger(tmp: Path) -> Path:
    """``res.nc.parts`` holding a user's netCDF file named like a part and a ledger whose
    ``done`` line names it (without the content hash clearsweep records)."""
    parts = tmp / "res.nc.parts"
    parts.mkdir()
    xr.Dataset({"x": ("i", [1.0, 2.0])}).to_netcdf(parts / "fedcba9876543210.nc")
    (parts / "sweep.log").write_text('{"event": "done", "hash": "fedcba9876543210"}\n')
    return parts


def copied(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes())
    return dst


# Round 4, items 1 and 2 (issue 33): a resume never mixes results of different inputs;
# nothing of the user's is deleted. Outputs are named res.nc here: a refused row leaves the
# user's folder or file at that name, which the table's "no out* file" check would count.
# The file-system scenarios (an edited materials file between Ctrl-C and --resume, swapped
# parts) are in tests/test_resume_integrity.py.
ROUND4_INTEGRITY = [
    ("sweep --resume over parts of other materials values (was: parts reused, exit 0, a "
     "file of two inputs)",
     lambda t, f: ["sweep", parts_made_with(t, "materials", "wear_coefficient_m2_per_N", 1e-13),
                   "--resume", "-o", t / "res.nc"],
     2, "made with other inputs (materials steel.wear_coefficient_m2_per_N: 1e-13 there, "
        "8e-14 here)"),
    ("sweep --resume over parts of another version (was: parts reused, exit 0)",
     lambda t, f: ["sweep", parts_made_with(t, "version", "", "0.0.1"), "--resume",
                   "-o", t / "res.nc"],
     2, "clearsweep version: '0.0.1' there"),
    ("sweep --resume of a summary sweep over parts of a full one (issue 40, item 2; was: "
     "parts reused, exit 0, a file missing the full store's variables)",
     lambda t, f: ["sweep", parts_made_with(t, "store", "", "full"), "--resume",
                   "-o", t / "res.nc"],
     2, "store: 'full' there, 'summary' here"),
    ("life --resume over a checkpoint of other materials values (was: continued, exit 0)",
     lambda t, f: checkpoint_made_with(t, 1e-13) and
     ["life", LIFE, *SHORT_LIFE, "--resume", "-o", t / "res.nc"],
     2, "of other inputs (materials MoS2.wear_coefficient_m2_per_N: 1e-13 there"),
    ("life --resume over a checkpoint with a hand-edited block status (issue 40, item 8; was: "
     "read as it stood, here a KeyError traceback)",
     lambda t, f: checkpoint_with_status(t, "garbage") and
     ["life", LIFE, *SHORT_LIFE, "--resume", "-o", t / "res.nc"],
     2, "row block_status holds 'garbage', not one of"),
    ("life over the user's file at OUT.life-checkpoint.lock (issue 40, item 3; was: deleted "
     "it, exit 0)",
     lambda t, f: (t / "res.nc.life-checkpoint.lock").write_text("my notes\n") and
     ["life", LIFE, *SHORT_LIFE, "-o", t / "res.nc"],
     2, "res.nc.life-checkpoint.lock is not a lock file clearsweep wrote"),
    ("sweep over an empty .lock of the user's in OUT.parts (issue 40, item 3; was: deleted "
     "it, exit 0)",
     lambda t, f: (t / "res.nc.parts").mkdir() or (t / "res.nc.parts" / ".lock").touch() or
     ["sweep", sweep_file(t, "sweep:\n  grid:\n    joints.B.clearance: [1.0e-4, 2.0e-4]\n"),
      "-o", t / "res.nc"],
     2, "res.nc.parts holds 1 file(s) that clearsweep did not write (.lock)"),
    ("sweep over a user's file in OUT.parts named like a part temporary (issue 40, item 3; "
     "was: deleted it, exit 0)",
     lambda t, f: (t / "res.nc.parts").mkdir() or
     (t / "res.nc.parts" / ".thesis.nc.v2.tmp").write_text("draft\n") and
     ["sweep", sweep_file(t, "sweep:\n  grid:\n    joints.B.clearance: [1.0e-4, 2.0e-4]\n"),
      "-o", t / "res.nc"],
     2, "res.nc.parts holds 1 file(s) that clearsweep did not write (.thesis.nc.v2.tmp)"),
    ("sweep --overwrite over a user's netCDF named like a part and named in a ledger line "
     "(issue 40, item 3; was: deleted it, exit 0)",
     lambda t, f: users_part_in_ledger(t) and
     ["sweep", sweep_file(t, "sweep:\n  grid:\n    joints.B.clearance: [1.0e-4, 2.0e-4]\n"),
      "--overwrite", "-o", t / "res.nc"],
     2, "res.nc.parts holds 1 file(s) that clearsweep did not write (fedcba9876543210.nc)"),
    ("life --discard-checkpoint over the user's file at OUT.life-checkpoint (was: deleted it, "
     "exit 0)",
     lambda t, f: (t / "res.nc.life-checkpoint").write_text("my notes\n") and
     ["life", LIFE, *SHORT_LIFE, "--discard-checkpoint", "-o", t / "res.nc"],
     2, "not a checkpoint archive: empty, truncated or another file); clearsweep deletes only "
        "its own files: move it away"),
    ("sweep into OUT.parts holding the user's files (was: deleted them, exit 0)",
     lambda t, f: (t / "res.nc.parts").mkdir() or (t / "res.nc.parts" / "thesis.tex").write_text("x")
     and ["sweep", sweep_file(t, "sweep:\n  grid:\n    joints.B.clearance: [1.0e-4]\n"),
          "-o", t / "res.nc"],
     2, "res.nc.parts holds 1 file(s) that clearsweep did not write (thesis.tex)"),
    ("sweep --overwrite into OUT.parts holding the user's files (was: deleted them, exit 0)",
     lambda t, f: (t / "res.nc.parts").mkdir() or (t / "res.nc.parts" / "notes.txt").write_text("x")
     and ["sweep", sweep_file(t, "sweep:\n  grid:\n    joints.B.clearance: [1.0e-4]\n"),
          "--overwrite", "-o", t / "res.nc"],
     2, "res.nc.parts holds 1 file(s) that clearsweep did not write (notes.txt)"),
    ("-o a symbolic link that loops (was: the link replaced by the results file, exit 0)",
     lambda t, f: (t / "res.nc").symlink_to("res.nc") or
     ["run", ONE, "--set", "solver.duration=0.002", "-o", t / "res.nc"],
     2, "res.nc is a symbolic link that never reaches a file"),
    ("run over a life run's results file (was: replaced, exit 0)",
     lambda t, f: ["run", ONE, "--set", "solver.duration=0.002",
                   "-o", copied(f / "life.nc", t / "res.nc")],
     2, "res.nc is the results file of a life run, and this command writes a run; pass --overwrite"),
    ("life over a run's results file (was: replaced, exit 0)",
     lambda t, f: ["life", LIFE, *SHORT_LIFE, "-o", copied(f / "run.nc", t / "res.nc")],
     2, "res.nc is the results file of a run, and this command writes a life run"),
    ("sweep over a reliability sweep's results file (was: replaced, exit 0)",
     lambda t, f: ["sweep", sweep_file(t, "sweep:\n  grid:\n    joints.B.clearance: [1.0e-4]\n"),
                   "-o", copied(f / "rel.nc", t / "res.nc")],
     2, "is the results file of a reliability sweep, and this command writes a sweep"),
]
ROWS += ROUND4_INTEGRITY
# --- round 4 (issue 33, items 4-6): one line instead of a traceback, rules that do not
# depend on luck, messages that say what happened. "was:" how main ended before.
REL = str(CONFIGS / "reliability.yaml")
BIG = "1" * 400                 # an integer no float64 holds
LONG = "a" * 300                # a name longer than any file system's 255 bytes
NEAR = "b" * 240                # fits, but OUT.parts' and OUT.life-checkpoint's names do not


def _edited(f: Path, src: str, name: str, edit) -> Path:
    """A copy of results file ``src`` in ``f`` changed by ``edit`` (made once per module)."""
    path = f / name
    if not path.exists():
        with xr.open_dataset(f / src) as ds:
            ds = edit(ds.load())
        for var in ds.variables.values():
            var.encoding = {}
        ds.to_netcdf(path)
    return path


def _replaced(name: str, value):
    def edit(ds):
        ds[name] = value(ds) if callable(value) else value
        return ds
    return edit


def _checkpoint(f: Path, t: Path, **arrays) -> Path:
    """A life checkpoint of SHORT_LIFE (2 blocks, made once per module) with ``arrays``
    replaced, where ``life ... -o t/out.nc --resume`` reads it."""
    from clearsweep.config import load_config
    from clearsweep.service_life import checkpoint_path_for, life

    good = f / "good.life-checkpoint"
    if not good.exists():
        made = checkpoint_path_for(f / "ckpt.nc")
        life(load_config(LIFE, [a for a in SHORT_LIFE if a != "--set"]), checkpoint=made)
        made.rename(good)
    with np.load(good) as data:
        saved = {k: data[k] for k in data.files}
    saved.update(arrays)
    path = t / "out.nc.life-checkpoint"
    with open(path, "wb") as out:
        np.savez(out, **saved)
    return path


def _constant_sample(f: Path) -> Path:
    """A Saltelli sampling file whose output ``y`` is 3.0 at every point."""
    path = f / "samp_constant.nc"
    if not path.exists():
        with xr.open_dataset(saltelli_file(f / "samp_c_src.nc")) as ds:
            ds = ds.load()
        ds["y"] = xr.full_like(ds["y"], 3.0)
        ds.to_netcdf(path)
    return path


def _sweep_text(t: Path, sweep: str, store: str = "summary") -> str:
    return sweep_file(t, f"sweep: {sweep}\n", store=store)


ROUND4_MESSAGES = [
    # --- item 4: integers too large for a float
    ("run ensemble.members of 400 digits (was: OverflowError)",
     lambda t, f: ["run", ONE, "--set", f"ensemble.members={BIG}", "-o", t / "out.nc"],
     2, "ensemble.members: got 111111111111... (an integer of 400 digits) (from --set)"),
    ("run ensemble.seed of 400 digits (was: OverflowError)",
     lambda t, f: ["run", ONE, "--set", f"ensemble.seed={BIG}", "-o", t / "out.nc"],
     2, "ensemble.seed: got 111111111111... (an integer of 400 digits)"),
    ("reliability tolerance of 400 digits (was: OverflowError)",
     lambda t, f: ["sweep", REL, "--set", f"reliability.clearance_tolerance={BIG}", "-o", t / "out.nc"],
     2, "reliability.clearance_tolerance: got 111111111111..."),
    ("life cycles of 400 digits (was: OverflowError)",
     lambda t, f: ["life", LIFE, "--set", f"life.cycles={BIG}", "-o", t / "out.nc"],
     2, "life.cycles: got 111111111111... (an integer of 400 digits)"),
    ("run duration of -400 digits (was: OverflowError)",
     lambda t, f: ["run", ONE, "--set", f"solver.duration=-{BIG}", "-o", t / "out.nc"],
     2, "integers of at most 2^63 - 1 in magnitude (a larger number is written as a float"),
    ("sweep grid value of 400 digits (was: OverflowError)",
     lambda t, f: ["sweep", _sweep_text(t, f"{{grid: {{solver.duration: [0.002, {BIG}]}}}}"),
                   "-o", t / "out.nc"],
     2, "sweep.grid.solver.duration: got 111111111111... (an integer of 400 digits)"),
    ("sample range of 400 digits (was: OverflowError)",
     lambda t, f: ["sweep", _sweep_text(t, f"{{sample: {{method: lhs, n: 4, ranges: "
                                           f"{{joints.B.clearance: [0, {BIG}]}}}}}}"),
                   "-o", t / "out.nc"],
     2, "sweep.sample.ranges.joints.B.clearance: got 111111111111..."),
    # --- item 4: output names too long for the file system
    ("run -o a name of 300 bytes (was: OSError 'File name too long')",
     lambda t, f: ["run", ONE, "-o", t / f"{LONG}.nc"],
     2, "the name is 303 bytes long"),
    ("run -o under a folder name of 300 bytes (was: OSError 'File name too long')",
     lambda t, f: ["run", ONE, "-o", t / LONG / "out.nc"],
     2, "is 300 bytes long; the file system admits 255"),
    ("sweep -o a name of 243 bytes (was: every case ran, then 'cannot write .NAME.PID.tmp')",
     lambda t, f: ["sweep", two_case_sweep(t), "-o", t / f"{NEAR}.nc"],
     2, "the names written beside it (OUT.parts and temporary files) 28 bytes more"),
    ("life -o a name of 243 bytes (was: after the compile, exit 1 'cannot write OUT.life-checkpoint')",
     lambda t, f: ["life", LIFE, *SHORT_LIFE, "-o", t / f"{NEAR}.nc"],
     2, "(OUT.life-checkpoint.lock and temporary files) 43 bytes more"),
    ("plot -o a name of 300 bytes (was: OSError 'File name too long')",
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "-o", t / f"{LONG}.png"],
     2, "choose a name of at most 233 bytes"),
    # --- item 4: a malformed --scheduler address, before the plan and the compile
    ("--scheduler without a port (was: ValueError after the compile)",
     lambda t, f: ["sweep", two_case_sweep(t), "--scheduler", "::bad::", "-o", t / "out.nc"],
     2, "invalid value for '--scheduler': '::bad::': a port of 1 to 65535 after the host"),
    ("--scheduler port not a number (was: ValueError after the compile)",
     lambda t, f: ["sweep", two_case_sweep(t), "--scheduler", "tcp://host:port", "-o", t / "out.nc"],
     2, "not 'port'; expected [SCHEME://]HOST:PORT"),
    ("--scheduler unknown scheme (was: ValueError after the compile)",
     lambda t, f: ["sweep", two_case_sweep(t), "--scheduler", "foo://1.2.3.4:1", "-o", t / "out.nc"],
     2, "unknown scheme 'foo'"),
    ("--scheduler empty (was: ValueError after the compile)",
     lambda t, f: ["sweep", two_case_sweep(t), "--scheduler", "", "-o", t / "out.nc"],
     2, "'--scheduler': '': no address"),
    ("--scheduler port 99999 (was: 30 s to time out, exit 1)",
     lambda t, f: ["sweep", two_case_sweep(t), "--scheduler", "tcp://127.0.0.1:99999", "-o", t / "out.nc"],
     2, "a port of 1 to 65535 after the host, not '99999'"),
    # --- item 4: results files whose arrays have other shapes, dims or dtypes, or none
    ("report a life file with an empty cycle (was: IndexError)",
     lambda t, f: ["report", _edited(f, "life.nc", "life_empty.nc", lambda ds: ds.isel(cycle=slice(0, 0)))],
     2, "its dimension 'cycle' is empty"),
    ("plot a life file with an empty cycle (was: a blank figure, exit 0)",
     lambda t, f: ["plot", _edited(f, "life.nc", "life_empty.nc", lambda ds: ds.isel(cycle=slice(0, 0))),
                   "--kind", "life", "-o", t / "out.png"],
     2, "its dimension 'cycle' is empty"),
    ("report a reliability file whose b10 is text (was: exit 0)",
     lambda t, f: ["report", _edited(f, "rel.nc", "rel_b10_text.nc",
                                     _replaced("b10", lambda ds: ds["b10"].astype(str)))],
     2, "its variable 'b10' holds <U"),
    ("plot a reliability file whose R(N) lost its limit dim (was: exit 0)",
     lambda t, f: ["plot", _edited(f, "rel.nc", "rel_r_2d.nc", _replaced(
         "reliability", lambda ds: ds["reliability"].isel(limit=0, drop=True))),
                   "--kind", "reliability", "-o", t / "out.png"],
     2, "its variable 'reliability' has dims"),
    ("report a run whose status is a number (was: exit 0, status '3')",
     lambda t, f: ["report", _edited(f, "run.nc", "run_status_number.nc",
                                     _replaced("status", xr.DataArray(3.0)))],
     2, "its variable 'status' holds float64 values, not text"),
    ("plot a run whose wear map lost a dim (was: KeyError traceback)",
     lambda t, f: ["plot", _edited(f, "run.nc", "run_wear_map_2d.nc", _replaced(
         "wear_map", lambda ds: ds["wear_map"].isel(azimuth=0, drop=True))),
                   "--kind", "wear-map", "-o", t / "out.png"],
     2, "its variable 'wear_map' has dims ('joint', 'polar')"),
    ("report a sweep with a variable on a stray dim (was: exit 0, the dim unread)",
     lambda t, f: ["report", _edited(f, "rel.nc", "rel_stray_dim.nc", _replaced(
         "wall_time", lambda ds: ds["wall_time"].expand_dims(extra=2)))],
     2, "its variable 'wall_time' has dims ('extra', 'B_coating', 'member')"),
    ("life --resume from a checkpoint of another map shape (was: ValueError traceback)",
     lambda t, f: _checkpoint(f, t, wmap=np.zeros((2, 3, 12))) and
     ["life", LIFE, *SHORT_LIFE, "--resume", "-o", t / "out.nc"],
     2, "(wmap has shape (2, 3, 12), expected (4, 6, 12)); pass --discard-checkpoint"),
    ("life --resume from a checkpoint of ragged rows (was: exit 0, a block lost)",
     lambda t, f: _checkpoint(f, t, row_cycle=np.array([1.0])) and
     ["life", LIFE, *SHORT_LIFE, "--resume", "-o", t / "out.nc"],
     2, "block rows of lengths [1, 2]"),
    ("life --resume from a checkpoint whose cycles is text (was: ValueError traceback)",
     lambda t, f: _checkpoint(f, t, cycles=np.array("many")) and
     ["life", LIFE, *SHORT_LIFE, "--resume", "-o", t / "out.nc"],
     2, "cycles holds <U4 values, not numbers"),
    # --- item 5: rules that do not depend on the draws
    ("tolerance band past the largest clearance (was: accepted with seed 1, refused with 0, 2, 3)",
     lambda t, f: ["validate", REL, "--set", "joints.B.clearance=7.4e-3", "--set",
                   "reliability.clearance_tolerance=2e-4", "--set", "reliability.members=2",
                   "--set", "reliability.seed=1"],
     2, "expected a number <= 0.0001, so that the band joints.B.clearance -+ tolerance"),
    ("wear-through only with an uncoated design (was: no word on running the others)",
     lambda t, f: ["validate", REL, "--set", "life.max_clearance_growth=null", "--set",
                   "life.max_motion_error=null", "--set", "life.stop_at_wear_through=true"],
     2, "to run the other designs, skip this one (sweep: skip: [{B_coating: none}])"),
    # --- item 6: an output under a file, refused before any work
    ("run -o under a file (was: the whole run, then 'File exists')",
     lambda t, f: ["run", ONE, "-o", f / "afile" / "out.nc"], 2, "afile is a file, not a folder"),
    ("sweep -o under a file (was: exit 1, 'cannot write OUT.parts: Not a directory')",
     lambda t, f: ["sweep", two_case_sweep(t), "-o", f / "afile" / "out.nc"],
     2, "afile is a file, not a folder"),
    ("life -o under a file (was: after the compile, 'cannot write OUT.life-checkpoint.lock')",
     lambda t, f: ["life", LIFE, *SHORT_LIFE, "-o", f / "afile" / "out.nc"],
     2, "afile is a file, not a folder"),
    ("plot -o under a file (was: the figure drawn, then 'File exists')",
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "-o", f / "afile" / "out.png"],
     2, "afile is a file, not a folder"),
    # --- item 6: sensitivity of an output that never varies
    ("sensitivity of a constant output (was: 0.000 +- 0.000, a SALib RuntimeWarning, exit 0)",
     lambda t, f: ["sensitivity", _constant_sample(f), "--metric", "y"],
     2, "y does not vary over the 16 sample points (every one is 3)"),
]


# --- round 4, a fresh fuzz round: 203 probes on surfaces the rows above do not cover, every
# command and option (odd YAML types, NaN and inf, empty lists, unicode and duplicate keys,
# booleans where numbers go, deep nesting, dates, tags, materials files, the group itself).
# 195 ended as they do now; the 8 marked "was:" did not (2 tracebacks, 2 exit 0 with
# nothing to run or a foreign file read as a sweep, 4 lines that named the wrong thing).


def _w(t, name, text):
    p = Path(t) / name
    p.write_text(text)
    return p


def _bytes(t, name, data):
    p = Path(t) / name
    p.write_bytes(data)
    return p


def _case(t, text):
    return _w(t, "c.yaml", text)


def _swp(t, body, store="summary",
         base="{joints: {B: {clearance: 2.5e-4}}, solver: {duration: 0.002}}"):
    return _w(t, "s.yaml", f"name: s\nstore: {store}\nbase: {base}\n{body}")


def _foreign(f: Path) -> Path:
    """A netCDF file of another program: no clearsweep source, no status."""
    path = f / "foreign.nc"
    if not path.exists():
        xr.Dataset({"a": ("x", [1.0, 2.0])}, attrs={"source": "elsewhere"}).to_netcdf(path)
    return path


def _setv(cmd, cfg, *kv):
    argv = [cmd, cfg]
    for item in kv:
        argv += ["--set", item]
    return argv


def _run(*kv):
    return lambda t, f: _setv("run", ONE, *kv) + ["-o", Path(t) / "out.nc"]


def _val(*kv):
    return lambda t, f: _setv("validate", ONE, *kv)


def _life(*kv):
    return lambda t, f: _setv("life", LIFE, *kv) + ["-o", Path(t) / "out.nc"]


def _rel(*kv):
    return lambda t, f: _setv("validate", REL, *kv)



ROUND4_FUZZ = [
    # --- run / validate: odd YAML types in --set values
    ('run solver.dt true', _run("solver.dt=true"),
     2, 'solver.dt: got True (from --set); expected a number > 0'),
    ('run solver.dt string', _run("solver.dt=fast"),
     2, "solver.dt: got 'fast' (from --set); expected a number > 0"),
    ('run solver.dt list', _run("solver.dt=[1e-5]"),
     2, 'solver.dt: got [1e-05] (from --set); expected a number > 0'),
    ('run solver.dt mapping', _run("solver.dt={a: 1}"),
     2, "solver.dt: got {'a': 1} (from --set); expected a number > 0"),
    ('run solver.dt null', _run("solver.dt=null"),
     2, 'solver.dt: got None (from --set); expected a number > 0'),
    ('run solver.dt .nan', _run("solver.dt=.nan"),
     2, 'solver.dt: got nan (from --set); expected a number > 0'),
    ('run solver.dt -.inf', _run("solver.dt=-.inf"),
     2, 'solver.dt: got -inf (from --set); expected a number > 0'),
    ("run solver.dt empty (was: 'got None')", _run("solver.dt="),
     2, "solver.dt: got an empty value (from --set); expected a value after '=' (null for"),
    ("run solver.dt date (was: 'got datetime.date(2020, 1, 1)')", _run("solver.dt=2020-01-01"),
     2, "solver.dt: got '2020-01-01' (from --set); expected a number > 0"),
    ('run solver.dt hex', _run("solver.dt=0x10"),
     2, 'solver.dt: got 16.0 (from --set); expected a number <= solver.duration (1.0)'),
    ('run solver.save_every 1.5', _run("solver.save_every=1.5"),
     2, 'solver.save_every: got 1.5 (from --set); expected an integer >= 1'),
    ('run solver.save_every true', _run("solver.save_every=true"),
     2, 'solver.save_every: got True (from --set); expected an integer >= 1'),
    ('run solver.save_every 1e3 float', _run("solver.save_every=1e3"),
     2, 'solver.save_every: got 1000.0 (from --set); expected an integer >= 1'),
    ('run solver.baumgarte empty list', _run("solver.baumgarte=[]"),
     2, 'solver.baumgarte: got [] (from --set); expected a list of 2 numbers >= 0'),
    ('run solver.baumgarte nested', _run("solver.baumgarte=[[5, 5], [5, 5]]"),
     2, 'solver.baumgarte: got [[5, 5], [5, 5]] (from --set); expected a list of 2 number'),
    ('run solver.baumgarte three', _run("solver.baumgarte=[5, 5, 5]"),
     2, 'solver.baumgarte: got [5, 5, 5] (from --set); expected a list of 2 numbers >= 0'),
    ('run solver.baumgarte nan', _run("solver.baumgarte=[.nan, 5]"),
     2, 'solver.baumgarte: got [nan, 5] (from --set); expected a list of 2 numbers >= 0'),
    ('run solver.method unknown', _run("solver.method=euler"),
     2, "solver.method: got 'euler' (from --set); expected one of 'rk4', 'dopri5'"),
    ('run solver.method number', _run("solver.method=4"),
     2, "solver.method: got 4 (from --set); expected one of 'rk4', 'dopri5'"),
    ('run solver.max_substep_level 17', _run("solver.max_substep_level=17"),
     2, 'solver.max_substep_level: got 17 (from --set); expected an integer with 0 <= x <'),
    ('run solver.max_substep_level -1', _run("solver.max_substep_level=-1"),
     2, 'solver.max_substep_level: got -1 (from --set); expected an integer with 0 <= x <'),
    ('run solver.stability_limit 2.8', _run("solver.stability_limit=2.8"),
     2, 'solver.stability_limit: got 2.8 (from --set); expected a number with 0 < x < 2.8'),
    ('run solver.rtol 0', _run("solver.rtol=0"),
     2, 'solver.rtol: got 0 (from --set); expected a number with 0 < x <= 1'),
    ('run mechanism.gravity scalar', _run("mechanism.gravity=9.81"),
     2, 'mechanism.gravity: got 9.81 (from --set); expected a list of 3 numbers'),
    ('run mechanism.gravity strings', _run("mechanism.gravity=[a, b, c]"),
     2, "mechanism.gravity: got ['a', 'b', 'c'] (from --set); expected a list of 3 number"),
    ('run mechanism.gravity inf', _run("mechanism.gravity=[0, 0, .inf]"),
     2, 'mechanism.gravity: got [0, 0, inf] (from --set); expected a list of 3 numbers'),
    ('run mechanism.speed_rpm 0', _run("mechanism.speed_rpm=0"),
     2, 'mechanism.speed_rpm: got 0 (from --set); expected a number > 0'),
    ('run mechanism.speed_rpm negative', _run("mechanism.speed_rpm=-60"),
     2, 'mechanism.speed_rpm: got -60 (from --set); expected a number > 0'),
    ('run mechanism.speed_rpm bool', _run("mechanism.speed_rpm=false"),
     2, 'mechanism.speed_rpm: got False (from --set); expected a number > 0'),
    ('run mechanism.theta0 inf', _run("mechanism.theta0=.inf"),
     2, 'mechanism.theta0: got inf (from --set); expected a number'),
    ('run mechanism.preset unknown', _run("mechanism.preset=paperr"),
     2, "mechanism.preset: got 'paperr' (from --set); expected one of 'realistic', 'paper"),
    ('run mechanism a value', _run("mechanism=1"),
     2, 'mechanism: got 1 (from --set); expected a mapping with keys kind, preset, speed_rpm, g'),
    ('run joints.B.coating number', _run("joints.B.coating=1"),
     2, 'joints.B.coating: got 1 (from --set); expected a string'),
    ('run joints.B.coating unknown', _run("joints.B.coating=PTFEE"),
     2, "joints.B.coating: got 'PTFEE' (from --set); expected 'none' or a known material"),
    ('run joints.B.coating unicode', _run("joints.B.coating=PTFÉ"),
     2, "joints.B.coating: got 'PTFÉ' (from --set); expected 'none' or a known material ("),
    ('run joints.B.clearance negative', _run("joints.B.clearance=-1e-4"),
     2, 'joints.B.clearance: got -0.0001 (from --set); expected a number >= 0'),
    ('run joints.B.clearance huge', _run("joints.B.clearance=1"),
     2, 'joints.B.clearance: got 1.0 (from --set); expected a number <= 0.5 * joints.B.so'),
    ('run joints.C', _run("joints.C.clearance=1e-4"),
     2, "joints.C: got {'clearance': 0.0001} (from --set); expected one of the keys of jo"),
    ('run joints.B.unicode key', _run("joints.B.clearancé=1e-4"),
     2, 'joints.B.clearancé: got 0.0001 (from --set); expected one of the keys of joints.'),
    ('run joints.B.wear_coefficient negative', _run("joints.B.wear_coefficient=-1"),
     2, 'joints.B.wear_coefficient: got -1 (from --set); expected null or a number >= 0'),
    ('run joints.B.coating_thickness 0', _run("joints.B.coating_thickness=0"),
     2, 'joints.B.coating_thickness: got 0 (from --set); expected a number > 0'),
    ('run contact.restitution 0', _run("contact.restitution=0"),
     2, 'contact.restitution: got 0 (from --set); expected a number with 0 < x <= 1'),
    ('run contact.restitution 1.5', _run("contact.restitution=1.5"),
     2, 'contact.restitution: got 1.5 (from --set); expected a number with 0 < x <= 1'),
    ('run contact.layer_rule unknown', _run("contact.layer_rule=parallel"),
     2, "contact.layer_rule: got 'parallel' (from --set); expected one of 'series', 'pape"),
    ('run friction.enabled string', _run("friction.enabled=yes please"),
     2, "friction.enabled: got 'yes please' (from --set); expected true or false"),
    ('run friction.enabled number', _run("friction.enabled=1"),
     2, 'friction.enabled: got 1 (from --set); expected true or false'),
    ('run friction.v1 below v0', _run("friction.v1=1e-5"),
     2, 'friction.v1: got 1e-05 (from --set); expected a number > friction.v0 (0.0001)'),
    ('run wear.map one int', _run("wear.map=12"),
     2, 'wear.map: got 12 (from --set); expected a list of 2 integers >= 1'),
    ('run wear.map zero', _run("wear.map=[0, 12]"),
     2, 'wear.map: got [0, 12] (from --set); expected a list of 2 integers >= 1'),
    ('run wear.map floats', _run("wear.map=[6.5, 12]"),
     2, 'wear.map: got [6.5, 12] (from --set); expected a list of 2 integers >= 1'),
    ('run wear.amplification -1', _run("wear.amplification=-1"),
     2, 'wear.amplification: got -1 (from --set); expected a number >= 0'),
    ('run metrics.settle_time -1', _run("metrics.settle_time=-1"),
     2, 'metrics.settle_time: got -1 (from --set); expected a number >= 0'),
    ('run initial.joints unknown', _run("initial.joints=floating"),
     2, "initial.joints: got 'floating' (from --set); expected one of 'seated', 'centred'"),
    ('run name list', _run("name=[a, b]"),
     2, "name: got ['a', 'b'] (from --set); expected a string"),
    ('run materials_file missing', _run("materials_file=nowhere.yaml"),
     2, "materials_file: got 'nowhere.yaml' (from --set); expected an existing YAML file"),
    ('run materials_file number', _run("materials_file=5"),
     2, 'materials_file: got 5 (from --set); expected null or a string'),
    ('run --set no equals', _run("solver.dt"),
     2, "got 'solver.dt'; expected an override KEY=VALUE with a dotted key, e.g. joints.B"),
    ('run --set empty key', _run("=1"),
     2, "got '=1'; expected an override KEY=VALUE with a dotted key, e.g. joints.B.coatin"),
    ('run --set trailing dot', _run("solver.=1"),
     2, "got 'solver.=1'; expected an override KEY=VALUE with a dotted key, e.g. joints.B"),
    ('run --set double dot', _run("solver..dt=1"),
     2, "got 'solver..dt=1'; expected an override KEY=VALUE with a dotted key, e.g. joint"),
    ('run --set unknown top', _run("solvr.dt=1e-5"),
     2, "solvr: got {'dt': 1e-05} (from --set); expected one of the top-level keys (name,"),
    ('run --set value into section', _run("solver.dt.x=1"),
     2, 'solver.dt.x: got 1 (from --set); expected a key inside a section, but solver.dt'),
    ('run --set bad YAML', _run("solver.dt=[1, 2"),
     2, "solver.dt: got '[1, 2'; expected valid YAML (expected ',' or ']', but got '<stre"),
    ('run --set tag', _run("solver.dt=!!python/object:os.system x"),
     2, "solver.dt: got '!!python/object:os.system x'; expected valid YAML (could not det"),
    ('run --set alias', _run("solver.dt=*a"),
     2, "solver.dt: got '*a'; expected valid YAML (found undefined alias 'a')"),
    ('run ensemble.members 0', _run("ensemble.members=0"),
     2, 'ensemble.members: got 0 (from --set); expected an integer with 1 <= x <= 100000'),
    ('run ensemble.seed -1', _run("ensemble.seed=-1"),
     2, 'ensemble.seed: got -1 (from --set); expected an integer >= 0'),
    ('run ensemble.perturb.ball_offset 2', _run("ensemble.members=2", "ensemble.perturb.ball_offset=2"),
     2, 'ensemble.perturb.ball_offset: got 2 (from --set); expected a number with 0 <= x'),
    ('run ensemble.member >= members', _run("ensemble.members=2", "ensemble.member=2"),
     2, 'ensemble.member: got 2 (from --set); expected a number < ensemble.members (2)'),
    ('validate solver.duration below dt', _val("solver.duration=1e-6"),
     2, 'solver.dt: got 1e-05; expected a number <= solver.duration (1e-06)'),
    ('validate life.snapshots 1', _val("life.snapshots=1"),
     2, 'life.snapshots: got 1 (from --set); expected an integer with 2 <= x <= 10000'),
    ('validate reliability.member 99', _val("reliability.member=99"),
     2, 'reliability.member: got 99 (from --set); expected a number < reliability.members'),
    # --- config files: odd YAML documents
    ('validate empty file', lambda t, f: ["validate", _case(t, "")],
     2, 'got an empty file; expected a mapping with keys name, materials_file, mechanism,'),
    ('validate comments only', lambda t, f: ["validate", _case(t, "# nothing\n")],
     2, 'got an empty file; expected a mapping with keys name, materials_file, mechanism,'),
    ('validate top-level list', lambda t, f: ["validate", _case(t, "- 1\n- 2\n")],
     2, 'got [1, 2]; expected a mapping with keys name, materials_file, mechanism, initia'),
    ('validate top-level scalar', lambda t, f: ["validate", _case(t, "42\n")],
     2, 'got 42; expected a mapping with keys name, materials_file, mechanism, initial, j'),
    ('validate duplicate key', lambda t, f: ["validate", _case(t, "solver: {dt: 1.0e-5}\nsolver: {dt: 2.0e-5}\n")],
     2, "line 2: got the key 'solver' a second time (first on line 1); expected each key"),
    ('validate duplicate nested key', lambda t, f: ["validate", _case(t, "solver: {dt: 1.0e-5, dt: 2.0e-5}\n")],
     2, "line 1: got the key 'dt' a second time (first on line 1); expected each key once"),
    ('validate unicode top key', lambda t, f: ["validate", _case(t, "sölver: {dt: 1.0e-5}\n")],
     2, "sölver: got {'dt': 1e-05}; expected one of the top-level keys (name, materials_f"),
    ('validate integer key', lambda t, f: ["validate", _case(t, "1: 2\n")],
     2, '1: got 2; expected one of the top-level keys (name, materials_file, mechanism, i'),
    ('validate null key', lambda t, f: ["validate", _case(t, "~: 2\n")],
     2, 'None: got 2; expected one of the top-level keys (name, materials_file, mechanism'),
    ('validate bool key', lambda t, f: ["validate", _case(t, "true: 2\n")],
     2, 'True: got 2; expected one of the top-level keys (name, materials_file, mechanism'),
    ('validate list key', lambda t, f: ["validate", _case(t, "? [a, b]\n: 1\n")],
     2, "line 1: got '? [a, b]'; expected valid YAML (found unhashable key)"),
    ('validate deep nesting', lambda t, f: ["validate", _case(t, "solver: " + "[" * 40 + "]" * 40 + "\n")],
     2, 'line 1: got mappings and lists nested more than 32 deep; expected at most 32 lev'),
    ('validate tab indentation', lambda t, f: ["validate", _case(t, "solver:\n\tdt: 1.0e-5\n")],
     2, "line 2: got 'dt: 1.0e-5'; expected valid YAML (found character '\\t' that cannot"),
    ('validate python tag', lambda t, f: ["validate", _case(t, "solver: !!python/object/apply:os.system [ls]\n")],
     2, "line 1: got 'solver: !!python/object/apply:os.system [ls]'; expected valid YAML"),
    ('validate binary value', lambda t, f: ["validate", _case(t, "name: !!binary aGVsbG8=\n")],
     2, "name: got b'hello'; expected a string"),
    ('validate not utf-8', lambda t, f: ["validate", _bytes(t, "c.yaml", b"name: \xff\xfe\n")],
     2, "('utf-8' codec can't decode byte 0xff in position 6: invalid start byte); expect"),
    ('validate section a list', lambda t, f: ["validate", _case(t, "solver: [1, 2]\n")],
     2, 'solver: got [1, 2]; expected a mapping with keys dt, duration, revolutions, save_every'),
    ('validate section a string', lambda t, f: ["validate", _case(t, "solver: fast\n")],
     2, "solver: got 'fast'; expected a mapping with keys dt, duration, revolutions, save_every"),
    ('validate 400-digit integer in the file (was: OverflowError)',
     lambda t, f: ["validate", _case(t, f"solver: {{duration: {BIG}}}\n")],
     2, 'solver.duration: got 111111111111... (an integer of 400 digits); expected a numb'),
    ('validate a folder', lambda t, f: ["validate", t],
     2, 'is a directory'),
    ('validate missing file', lambda t, f: ["validate", Path(t) / "none.yaml"],
     2, '(No such file or directory); expected a readable YAML file'),
    ('validate .nan in file', lambda t, f: ["validate", _case(t, "solver: {dt: .nan}\n")],
     2, 'solver.dt: got nan; expected a number > 0'),
    ('validate merge key', lambda t, f: ["validate", _case(t, "a: &a {dt: 1.0e-5}\nsolver: {<<: *a}\n")],
     2, "a: got {'dt': 1e-05}; expected one of the top-level keys (name, materials_file,"),
    # --- sweep files
    ('sweep grid empty list',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: []}}\n"), "-o", Path(t) / "out.nc"],
     2, 'sweep.grid.joints.B.coating: got []; expected a non-empty list of values'),
    ('sweep grid value not a list',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: PTFE}}\n"), "-o", Path(t) / "out.nc"],
     2, "sweep.grid.joints.B.coating: got 'PTFE'; expected a non-empty list of values"),
    ('sweep grid a list', lambda t, f: ["sweep", _swp(t, "sweep: {grid: [1, 2]}\n"), "-o", Path(t) / "out.nc"],
     2, 'sweep.grid: got [1, 2]; expected a mapping of dotted config keys to lists of val'),
    ('sweep grid unknown key',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coatin: [none]}}\n"), "-o", Path(t) / "out.nc"],
     2, 'sweep.grid.joints.B.coatin: got no such config key; expected one of the keys of'),
    ('sweep grid duplicate values',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none, none]}}\n"), "-o", Path(t) / "out.nc"],
     2, "sweep.grid.joints.B.coating: got 'none' twice; expected distinct values (they la"),
    ('sweep grid nan value',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.clearance: [.nan, 1.0e-4]}}\n"), "-o", Path(t) / "out.nc"],
     2, 'joints.B.clearance: got nan; expected a number >= 0 (in the sweep case B_clearan'),
    ('sweep grid bool for number',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.clearance: [true, false]}}\n"), "-o", Path(t) / "out.nc"],
     2, 'joints.B.clearance: got True; expected a number >= 0 (in the sweep case B_cleara'),
    ('sweep grid unicode key',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {jöints.B.clearance: [1.0e-4]}}\n"), "-o", Path(t) / "out.nc"],
     2, 'sweep.grid.jöints.B.clearance: got no such config key; expected one of the top-l'),
    ('sweep grid mixed types',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none, 1, [2]]}}\n"), "-o", Path(t) / "out.nc"],
     2, 'joints.B.coating: got 1; expected a string (in the sweep case B_coating=1)'),
    ('sweep zip unequal',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {zip: [{joints.A.clearance: [0.0, 1.0e-4], joints.B.clearance: [1.0e-4]}]}\n"), "-o",
                   Path(t) / "out.nc"],
     2, 'sweep.zip[0].joints.B.clearance: got 1 values; expected a list of 2 values (as l'),
    ('sweep zip not a list',
     lambda t, f: ["sweep", _swp(t, "sweep: {zip: {joints.A.clearance: [0.0]}}\n"), "-o", Path(t) / "out.nc"],
     2, "sweep.zip: got {'joints.A.clearance': [0.0]}; expected a list of groups (mapping"),
    ('sweep skip unknown coordinate',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none, PTFE]}, skip: [{B_coatin: none}]}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.skip[0].B_coatin: got an unknown coordinate; expected a sweep coordinate ('),
    ('sweep skip value not swept',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none, PTFE]}, skip: [{B_coating: lead}]}\n"),
                   "-o", Path(t) / "out.nc"],
     2, "sweep.skip[0].B_coating: got 'lead'; expected one of the swept values ['none', '"),
    ('sweep skip every case (was: a file of 1 skipped case, exit 0)',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}, skip: [{B_coating: none}]}\n"), "-o",
                   Path(t) / "out.nc"],
     2, 'sweep.skip: got rules that skip all 1 cases; expected rules that leave at least'),
    ('sweep store unknown',
     lambda t, f: ["sweep", _swp(t, "sweep: {}\n", store="everything"), "-o", Path(t) / "out.nc"],
     2, "store: got 'everything'; expected full or summary or life or reliability"),
    ('sweep name empty',
     lambda t, f: ["sweep", _w(t, "s.yaml", "name: ''\nbase: {}\nsweep: {grid: {joints.B.coating: [none]}}\n"), "-o",
                   Path(t) / "out.nc"],
     2, "name: got ''; expected a non-empty string"),
    ('sweep name a list',
     lambda t, f: ["sweep", _w(t, "s.yaml", "name: [a]\nbase: {}\nsweep: {grid: {joints.B.coating: [none]}}\n"), "-o",
                   Path(t) / "out.nc"],
     2, "name: got ['a']; expected a non-empty string"),
    ('sweep base missing file',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n", base="nowhere.yaml"), "-o",
                   Path(t) / "out.nc"],
     2, "base: got 'nowhere.yaml'; expected an inline case config or the path of a case Y"),
    ("sweep base itself (was: 'run a sweep file with `clearsweep sweep S.yaml: base s.yaml`')",
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n", base="s.yaml"), "-o",
                   Path(t) / "out.nc"],
     2, "base: got 's.yaml', a sweep file; expected the path of a case config (a sweep's"),
    ('sweep base a list',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n", base="[1, 2]"), "-o",
                   Path(t) / "out.nc"],
     2, 'base: got [1, 2]; expected an inline case config (a mapping) or the path of a ca'),
    ('sweep unknown sweep key',
     lambda t, f: ["sweep", _swp(t, "sweep: {gird: {joints.B.coating: [none]}}\n"), "-o", Path(t) / "out.nc"],
     2, 'sweep.gird: got an unknown key; expected one of the keys grid, zip, sample, skip'),
    ('sweep sample and grid of one key',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {grid: {joints.B.clearance: [1.0e-4]}, sample: {method: lhs, n: 4, "
                           "ranges: {joints.B.clearance: [1.0e-4, 2.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.joints.B.clearance: got a key swept twice; expected each key in one grid e'),
    ('sweep sample range reversed',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: lhs, n: 4, ranges: {joints.B.clearance: [2.0e-4, 1.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.ranges.joints.B.clearance: got [0.0002, 0.0001]; expected [low, hig'),
    ('sweep sample n 0',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: lhs, n: 0, ranges: {joints.B.clearance: [1.0e-4, 2.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.n: got 0; expected an integer >= 1 (points, or base points of salte'),
    ('sweep sample n 1.5',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: lhs, n: 1.5, ranges: {joints.B.clearance: [1.0e-4, 2.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.n: got 1.5; expected an integer >= 1 (points, or base points of sal'),
    ('sweep sample n true',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: lhs, n: true, ranges: {joints.B.clearance: [1.0e-4, 2.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.n: got True; expected an integer >= 1 (points, or base points of sa'),
    ('sweep sample seed -1',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: lhs, n: 4, seed: -1, "
                           "ranges: {joints.B.clearance: [1.0e-4, 2.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.seed: got -1; expected an integer >= 0'),
    ('sweep sample method null',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: null, n: 4, ranges: {joints.B.clearance: [1.0e-4, 2.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.method: got None; expected sobol or lhs or saltelli'),
    ('sweep sample ranges empty',
     lambda t, f: ["sweep", _swp(t, "sweep: {sample: {method: lhs, n: 4, ranges: {}}}\n"), "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.ranges: got {}; expected a mapping of dotted config keys to [low, h'),
    ('sweep sample range nan',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: lhs, n: 4, ranges: {joints.B.clearance: [.nan, 2.0e-4]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.ranges.joints.B.clearance: got [nan, 0.0002]; expected [low, high],'),
    ('sweep sample range inf',
     lambda t, f: ["sweep",
                   _swp(t, "sweep: {sample: {method: lhs, n: 4, ranges: {joints.B.clearance: [1.0e-4, .inf]}}}\n"),
                   "-o", Path(t) / "out.nc"],
     2, 'sweep.sample.ranges.joints.B.clearance: got [0.0001, inf]; expected a range of v'),
    ('sweep sample range of a text key',
     lambda t, f: ["sweep", _swp(t, "sweep: {sample: {method: lhs, n: 4, ranges: {joints.B.coating: [1, 2]}}}\n"), "-o",
                   Path(t) / "out.nc"],
     2, 'sweep.sample.ranges.joints.B.coating: got [1, 2]; expected a range of values joi'),
    ('sweep a case config', lambda t, f: ["sweep", ONE, "-o", Path(t) / "out.nc"],
     2, 'got a case config (top-level keys name, mechanism, joints, solver); expected a s'),
    ('sweep --workers 0',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "--workers", "0", "-o",
                   Path(t) / "out.nc"],
     2, "invalid value for '--workers': 0 is not in the range x>=1"),
    ('sweep --dask-local 0',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "--dask-local", "0", "-o",
                   Path(t) / "out.nc"],
     2, "invalid value for '--dask-local': 0 is not in the range x>=1"),
    ('sweep --backend unknown',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "--backend", "tpu", "-o",
                   Path(t) / "out.nc"],
     2, "invalid value for '--backend': 'tpu' is not one of 'processes', 'cuda'"),
    ('sweep --resume --overwrite',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "--resume", "--overwrite", "-o",
                   Path(t) / "out.nc"],
     2, '--resume keeps the finished cases and --overwrite deletes them; give one'),
    ('sweep --set a swept key',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "--set", "joints.B.coating=PTFE",
                   "-o", Path(t) / "out.nc"],
     2, "--set: joints.B.coating: got 'joints.B.coating=PTFE'; expected a key that the sw"),
    ('sweep -o a folder', lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "-o", t],
     2, 'is a directory'),
    ('sweep -o the sweep file',
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "-o", Path(t) / "s.yaml"],
     2, 'which this command reads; an output never replaces an input: choose another outp'),
    # --- life and reliability sections
    ('life cycles 0', _life("life.cycles=0"),
     2, 'life.cycles: got 0 (from --set); expected a number > 0'),
    ('life cycles nan', _life("life.cycles=.nan"),
     2, 'life.cycles: got nan (from --set); expected a number > 0'),
    ('life cycles string', _life("life.cycles=many"),
     2, "life.cycles: got 'many' (from --set); expected a number > 0"),
    ('life cycles bool', _life("life.cycles=true"),
     2, 'life.cycles: got True (from --set); expected a number > 0'),
    ('life block_revolutions 0', _life("life.block_revolutions=0"),
     2, 'life.block_revolutions: got 0 (from --set); expected an integer >= 1'),
    ('life block_revolutions 1.5', _life("life.block_revolutions=1.5"),
     2, 'life.block_revolutions: got 1.5 (from --set); expected an integer >= 1'),
    ('life jump_clearance_fraction 0', _life("life.jump_clearance_fraction=0"),
     2, 'life.jump_clearance_fraction: got 0 (from --set); expected a number with 0 < x <'),
    ('life jump_coating_fraction 1.5', _life("life.jump_coating_fraction=1.5"),
     2, 'life.jump_coating_fraction: got 1.5 (from --set); expected a number with 0 < x <'),
    ('life snapshots huge', _life("life.snapshots=100000"),
     2, 'life.snapshots: got 100000 (from --set); expected an integer with 2 <= x <= 1000'),
    ('life max_blocks 0', _life("life.max_blocks=0"),
     2, 'life.max_blocks: got 0 (from --set); expected an integer with 1 <= x <= 10000'),
    ('life max_normal_force 0', _life("life.max_normal_force=0"),
     2, 'life.max_normal_force: got 0 (from --set); expected null or a number > 0'),
    ('life max_motion_error -1', _life("life.max_motion_error=-1"),
     2, 'life.max_motion_error: got -1 (from --set); expected null or a number > 0'),
    ('life stop_at_wear_through string', _life("life.stop_at_wear_through=maybe"),
     2, "life.stop_at_wear_through: got 'maybe' (from --set); expected true or false"),
    ('life a sweep file',
     lambda t, f: ["life", _swp(t, "sweep: {grid: {joints.B.coating: [none]}}\n"), "-o", Path(t) / "out.nc"],
     2, 'got a sweep file (top-level keys name, store, base, sweep); expected a case conf'),
    ('reliability members 0', _rel("reliability.members=0"),
     2, 'base: reliability.members: got 0 (from --set); expected an integer with 2 <= x <'),
    ('reliability members over the cap', _rel("reliability.members=100000000"),
     2, 'base: reliability.members: got 100000000 (from --set); expected an integer with'),
    ('reliability distribution unknown', _rel("reliability.clearance_distribution=lognormal"),
     2, "base: reliability.clearance_distribution: got 'lognormal' (from --set); expected"),
    ('reliability wear cv negative', _rel("reliability.wear_coefficient_cv=-0.1"),
     2, 'base: reliability.wear_coefficient_cv: got -0.1 (from --set); expected a number'),
    ('reliability speed cv nan', _rel("reliability.speed_cv=.nan"),
     2, 'base: reliability.speed_cv: got nan (from --set); expected a number with 0 <= x'),
    ('reliability coating cv 2', _rel("reliability.coating_thickness_cv=2"),
     2, 'base: reliability.coating_thickness_cv: got 2 (from --set); expected a number wi'),
    ('reliability tolerance negative', _rel("reliability.clearance_tolerance=-1e-6"),
     2, 'base: reliability.clearance_tolerance: got -1e-06 (from --set); expected a numbe'),
    ('reliability tolerance equal to clearance', _rel("reliability.clearance_tolerance=2.5e-4"),
     2, 'base: reliability.clearance_tolerance: got 0.00025 (from --set); expected a numb'),
    ('reliability seed bool', _rel("reliability.seed=true"),
     2, 'base: reliability.seed: got True (from --set); expected an integer >= 0'),
    ('reliability with an ensemble', _rel("ensemble.members=2"),
     2, 'ensemble.members: got 2; expected 1 with store: reliability (its members are rel'),
    # --- report, plot, sensitivity on odd inputs
    ('report missing file', lambda t, f: ["report", Path(t) / "none.nc"],
     2, 'does not exist'),
    ('report a folder', lambda t, f: ["report", t],
     2, 'is a directory'),
    ('report a YAML file', lambda t, f: ["report", ONE],
     2, 'is not a results file (no netCDF reader can open it)'),
    ('report an empty file', lambda t, f: ["report", _w(t, "e.nc", "")],
     2, 'is not a results file (no netCDF reader can open it)'),
    ('report a netCDF of another program (was: read as a sweep of 2 cases, exit 0)',
     lambda t, f: ["report", _foreign(f)],
     2, "not a clearsweep results file (its source attribute is 'elsewhere', not 'clearsweep')"),
    ('report --format unknown', lambda t, f: ["report", f / "run.nc", "--format", "xml"],
     2, "invalid value for '--format': 'xml' is not one of 'text', 'markdown', 'csv', 'js"),
    ('report --metric unknown', lambda t, f: ["report", f / "run.nc", "--metric", "bogus"],
     2, "unknown metric 'bogus'"),
    ('report --reference no equals', lambda t, f: ["report", f / "run.nc", "--reference", "joint"],
     2, "expected DIM=VALUE, got 'joint'"),
    ('report --reference and --metric',
     lambda t, f: ["report", f / "run.nc", "--reference", "joint=B", "--metric", "x"],
     2, '--reference and --metric print different tables; give one of them'),
    ('plot --kind unknown', lambda t, f: ["plot", f / "run.nc", "--kind", "pie", "-o", Path(t) / "out.png"],
     2, "invalid value for '--kind': 'pie' is not one of 'slider', 'forces', 'wear-map',"),
    ('plot -o .txt', lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "-o", Path(t) / "out.txt"],
     2, 'the suffix must be one of .png, .pdf, .svg'),
    ('plot -o without suffix', lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "-o", Path(t) / "out"],
     2, 'the suffix must be one of .png, .pdf, .svg'),
    ('plot --dpi 0', lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "--dpi", "0", "-o", Path(t) / "out.png"],
     2, "invalid value for '--dpi': 0 is not in the range 10<=x<=1200"),
    ('plot --dpi huge',
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "--dpi", "100000", "-o", Path(t) / "out.png"],
     2, "invalid value for '--dpi': 100000 is not in the range 10<=x<=1200"),
    ('plot --x unknown',
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "--x", "space", "-o", Path(t) / "out.png"],
     2, "invalid value for '--x': 'space' is not one of 'angle', 'time'"),
    ('plot --select no equals',
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "--select", "joint", "-o", Path(t) / "out.png"],
     2, "expected DIM=VALUE, got 'joint'"),
    ('plot --select unknown dim',
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "--select", "planet=mars", "-o", Path(t) / "out.png"],
     2, "unknown sweep dimension 'planet'"),
    ('plot --kind sweep of a run', lambda t, f: ["plot", f / "run.nc", "--kind", "sweep", "-o", Path(t) / "out.png"],
     2, "--kind sweep draws a metric across a sweep's designs;"),
    ('plot --kind life of a run', lambda t, f: ["plot", f / "run.nc", "--kind", "life", "-o", Path(t) / "out.png"],
     2, '--kind life draws a life run (`clearsweep life CONFIG` writes one);'),
    ('plot --kind reliability of a run',
     lambda t, f: ["plot", f / "run.nc", "--kind", "reliability", "-o", Path(t) / "out.png"],
     2, '--kind reliability needs reliability, reliability_ci_low, reliability_ci_high, b'),
    ('plot --b10 with --kind slider',
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "--b10", "-o", Path(t) / "out.png"],
     2, '--b10 applies to --kind reliability only'),
    ("plot a netCDF of another program (was: 'needs slider_position ... a summary-only sweep')",
     lambda t, f: ["plot", _foreign(f), "--kind", "slider", "-o", Path(t) / "out.png"],
     2, "not a clearsweep results file (its source attribute is 'elsewhere', not 'clearsweep')"),
    ('plot -o the results file', lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "-o", f / "run.nc"],
     2, 'the suffix must be one of .png, .pdf, .svg'),
    ('sensitivity a run file', lambda t, f: ["sensitivity", f / "run.nc", "--metric", "slider_acceleration_peak"],
     2, "not a sampling sweep: Sobol' indices need a sweep with 'sweep: sample: method: s"),
    ('sensitivity --metric unknown', lambda t, f: ["sensitivity", f / "samp.nc", "--metric", "bogus"],
     2, "unknown output 'bogus'"),
    ('sensitivity --select on a 1-d output',
     lambda t, f: ["sensitivity", f / "samp.nc", "--metric", "y", "--select", "joint=B"],
     2, "unknown dimension 'joint'"),
    ('sensitivity -o .txt', lambda t, f: ["sensitivity", f / "samp.nc", "--metric", "y", "-o", Path(t) / "out.txt"],
     2, 'the suffix must be one of .png, .pdf, .svg'),
    ('sensitivity --overwrite without -o', lambda t, f: ["sensitivity", f / "samp.nc", "--metric", "y", "--overwrite"],
     2, '--overwrite acts on the -o/--out figure; give -o'),
    # --- materials files
    ('materials missing file', lambda t, f: ["materials", "-m", Path(t) / "none.yaml"],
     2, '(No such file or directory); expected a readable YAML file'),
    ('materials a folder', lambda t, f: ["materials", "-m", t],
     2, 'is a directory'),
    ('materials empty file', lambda t, f: ["materials", "-m", _w(t, "m.yaml", "")],
     2, 'got an empty file; expected a mapping of material names to their fields (youngs_'),
    ('materials a list', lambda t, f: ["materials", "-m", _w(t, "m.yaml", "- 1\n")],
     2, 'got [1]; expected a mapping of material names to their fields (youngs_modulus_Pa'),
    ('materials duplicate name', lambda t, f: ["materials", "-m", _w(t, "m.yaml", "X: {}\nX: {}\n")],
     2, "line 2: got the key 'X' a second time (first on line 1); expected each key once"),
    ('materials a material a number', lambda t, f: ["materials", "-m", _w(t, "m.yaml", "X: 5\n")],
     2, 'X: got 5; expected a mapping with the fields youngs_modulus_Pa, poisson_ratio, f'),
    ('materials unknown property', lambda t, f: ["materials", "-m", _w(t, "m.yaml", "X: {colour: red}\n")],
     2, "X.colour: got 'red'; expected one of the fields youngs_modulus_Pa, poisson_ratio"),
    ('materials negative modulus',
     lambda t, f: ["materials", "-m", _w(t, "m.yaml", "X: {youngs_modulus_Pa: {value: -1, source: s}}\n")],
     2, 'X.youngs_modulus_Pa.value: got -1; expected a number > 0'),
    ('materials nan modulus',
     lambda t, f: ["materials", "-m", _w(t, "m.yaml", "X: {youngs_modulus_Pa: {value: .nan, source: s}}\n")],
     2, 'X.youngs_modulus_Pa.value: got nan; expected a number > 0'),
    ('materials 400-digit modulus (was: OverflowError)',
     lambda t, f: ["materials", "-m", _w(t, "m.yaml", f"X: {{youngs_modulus_Pa: {{value: {BIG}, source: s}}}}\n")],
     2, 'X.youngs_modulus_Pa.value: got 111111111111... (an integer of 400 digits); expec'),
    ('materials bool modulus',
     lambda t, f: ["materials", "-m", _w(t, "m.yaml", "X: {youngs_modulus_Pa: {value: true, source: s}}\n")],
     2, 'X.youngs_modulus_Pa.value: got True; expected a number > 0'),
    ('materials unicode name',
     lambda t, f: ["materials", "-m", _w(t, "m.yaml", "Ünï: {youngs_modulus_Pa: {value: 1, source: s}}\n")],
     2, 'Ünï.poisson_ratio: got nothing; expected a value for every field of a new materi'),
    # --- the group itself
    ('unknown command', lambda t, f: ["simulate", ONE],
     2, "no such command 'simulate'"),
    ('run with no argument', lambda t, f: ["run"],
     2, "missing argument 'CONFIG'"),
    ('run two configs', lambda t, f: ["run", ONE, ONE],
     2, 'got unexpected extra argument ('),
    ('run unknown option', lambda t, f: ["run", ONE, "--speed", "60"],
     2, "no such option '--speed'. Did you mean '--set'?"),
]


ROWS += ROUND4_MESSAGES + ROUND4_FUZZ
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
     "life.snapshots: got 10000 (201 snapshots kept of a 1000 x 2000 wear map of 4 joints, "
     "61 MiB each: 36.3 GiB in all"),
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

#: A path of 4.2 kB from / (42 folders of 100 bytes): each name within NAME_MAX, the whole
#: beyond PATH_MAX.
LONG_PATH = "/".join(["b" * 100] * 42)

# --- round 5 (issue 40, item 10): output paths that name no file
ROUND5_OUTPUTS = [
    ("run -o '' (was: wrote the default one_clearance.nc, exit 0)",
     lambda t, f: ["run", ONE, "--set", "solver.duration=0.002", "-o", ""], 2,
     "invalid value for '-o' / '--out': an empty name; give a file name, such as out.nc"),
    ("sweep -o '' (was: wrote the default s.nc in the current folder, exit 0)",
     lambda t, f: ["sweep", sweep_file(t, "sweep: {grid: {joints.B.coating: [none]}}\n"),
                   "--set", "solver.duration=0.002", "--workers", "1", "-o", ""], 2,
     "an empty name"),
    ("plot -o '' (was: refused by the figure-format check, naming no empty name)",
     lambda t, f: ["plot", f / "run.nc", "--kind", "slider", "-o", ""], 2, "an empty name"),
    ("run -o out_new/ (was: wrote the file out_new, exit 0)",
     lambda t, f: ["run", ONE, "--set", "solver.duration=0.002", "-o", f"{t}/out_new/"], 2,
     "out_new/' names a folder; give a file in it, such as "),
    ("life -o existing folder/ (was: click's 'File ... is a directory')",
     lambda t, f: ["life", LIFE, *SHORT_LIFE, "-o", f"{t}/"], 2, "names a folder"),
    ("run -o a 4.2 kB path (was: OSError [Errno 36] traceback)",
     lambda t, f: ["run", ONE, "--set", "solver.duration=0.002", "-o", t / LONG_PATH / "out.nc"],
     2, "bytes long (from /), the names written beside it 28 bytes more, and the system admits "
        "paths of 4095: choose a shorter path"),
    ("sweep -o a 4.2 kB path (was: OSError [Errno 36] traceback)",
     lambda t, f: ["sweep", sweep_file(t, "sweep: {grid: {joints.B.coating: [none]}}\n"),
                   "-o", t / LONG_PATH / "out.nc"], 2, "and the system admits paths of 4095"),
]
ROWS += ROUND5_OUTPUTS


def _bifurcation(*options: str):
    return lambda t, f: ["plot", f / "bif.nc", "--kind", "bifurcation", *options, "-o", t / "out.png"]


# --- round 5 (issue 40, item 10): --kind bifurcation's --select says what its keys must be
ROUND5_BIFURCATION = [
    ("plot bifurcation --select a zip group's key (was: 'unknown sweep dimension', no word "
     "of --x)", _bifurcation("--select", "speed_rpm=60"), 2,
     "a --select key of --kind bifurcation must be a swept dimension, and the key drawn "
     "against is given with --x (one of speed, speed_rpm)"),
    ("plot bifurcation --select a joint (was: 'unknown sweep dimension', no word of --x)",
     _bifurcation("--select", "joint=B"), 2,
     "a --select key of --kind bifurcation must be a swept dimension"),
    ("plot bifurcation --select the swept key (was: 'this file sweeps none')",
     _bifurcation("--select", "speed=60"), 2,
     "--select speed=...: fixes the last swept dimension, and --kind bifurcation draws "
     "against one: leave it out of --select (--x names the key drawn against)"),
    ("plot bifurcation --x speed_rpm --select speed=600 (was: '--x speed_rpm: not a swept "
     "key of this file')", _bifurcation("--x", "speed_rpm", "--select", "speed=600"), 2,
     "--select speed=...: fixes the dimension of --x speed_rpm, which --kind bifurcation "
     "draws against"),
    ("plot bifurcation of runs shorter than a revolution (was: 'a file of an older version "
     "of clearsweep')", _bifurcation(), 2,
     "which this file lacks: its runs ended before their first section (one a crank "
     "revolution: run for solver.duration >= 2 x 60 / mechanism.speed_rpm s)"),
]
ROWS += ROUND5_BIFURCATION


def both_lengths(tmp: Path) -> Path:
    """A case file that gives the run's length in seconds and in crank revolutions."""
    path = tmp / "both.yaml"
    path.write_text("solver: {duration: 2.0, revolutions: 3}\n")
    return path


def speeds_file(tmp: Path, sweep: str) -> Path:
    path = tmp / "speeds.yaml"
    path.write_text("name: speeds\nstore: summary\nbase: {solver: {revolutions: 2}}\n"
                    f"sweep: {sweep}\n")
    return path


#: A length in crank revolutions (issue 41, item 8): one of each pair of keys.
REVOLUTIONS = [
    ("run duration and revolutions both in the file (was: solver.revolutions an unknown key)",
     lambda t, f: ["run", both_lengths(t), "-o", t / "out.nc"], 2,
     "solver.revolutions: got 3; expected null when solver.duration is given (2.0): a length "
     "is given in one of solver.duration [s] and solver.revolutions, not both"),
    ("validate settle_time and settle_revolutions both (was: an unknown key)",
     lambda t, f: ["validate", ONE, "--set", "metrics.settle_time=0.1", "--set",
                   "metrics.settle_revolutions=1"], 2,
     "metrics.settle_revolutions: got 1 (from --set); expected one of metrics.settle_time and "
     "metrics.settle_revolutions, not both"),
    ("sweep zip of duration and revolutions (was: an unknown key)",
     lambda t, f: ["sweep", speeds_file(t, "{zip: [{solver.duration: [1, 2], "
                                            "solver.revolutions: [1, 2]}]}"), "--dry-run"], 2,
     "sweep.solver.revolutions: got both swept; expected one of solver.duration and "
     "solver.revolutions swept, not both"),
    ("sweep of revolutions with --set solver.duration (was: an unknown key)",
     lambda t, f: ["sweep", speeds_file(t, "{grid: {solver.revolutions: [1, 2]}}"),
                   "--set", "solver.duration=3", "--dry-run"], 2,
     "solver.duration: got 'solver.duration=3'; expected a key other than solver.duration: "
     "the sweep gives this length in solver.revolutions"),
]
ROWS += REVOLUTIONS

# --- round 5's fresh fuzz round (issue 40, item 11): lengths in revolutions, -o and input
# paths, selections of a zip group
ROUND5_FUZZ = [
    ("run revolutions shorter than a step (was: 'solver.dt: got 1e-05; expected a number <= "
     "solver.duration (1e-07)', a key never given)",
     lambda t, f: ["run", ONE, "--set", "mechanism.speed_rpm=600", "--set", "solver.revolutions=1e-6",
                   "-o", t / "out.nc"], 2,
     "solver.revolutions: got 1e-06 (from --set); expected a run of at least one step: "
     "solver.revolutions * 60 / mechanism.speed_rpm = 1e-06 * 60 / 600.0 = 1e-07 s, below "
     "solver.dt (1e-05 s)"),
    ("validate revolutions of 5e-324, 0 s (was: 'solver.dt ... <= solver.duration (5e-324)')",
     lambda t, f: ["validate", ONE, "--set", "solver.revolutions=5e-324"], 2,
     "solver.revolutions: got 5e-324 (from --set); expected a run of at least one step"),
    ("sweep case of revolutions shorter than a step (was: 'solver.dt ... <= solver.duration "
     "(1e-08)')",
     lambda t, f: ["sweep", sweep_file(t, "sweep: {grid: {solver.revolutions: [1.0e-7, 0.03]}}",
                                       base="{mechanism: {speed_rpm: 600}}"), "--dry-run"], 2,
     "solver.revolutions: got 1e-07; expected a run of at least one step"),
    ("sweep of speeds where one leaves the revolutions shorter than a step (was: 'solver.dt "
     "... <= solver.duration (1.8e-09)', the swept speed not named)",
     lambda t, f: ["sweep", sweep_file(t, "sweep: {grid: {mechanism.speed_rpm: [600, 1.0e9]}}",
                                       base="{solver: {revolutions: 0.03}}"), "--dry-run"], 2,
     "mechanism.speed_rpm: got 1000000000.0; expected a value with which solver.revolutions = "
     "0.03 is a run of at least one step"),
    ("run revolutions at 1e300 r/min (was: 'solver.dt: got 1e-05; expected a number <= "
     "solver.duration (6e-299)')",
     lambda t, f: ["run", ONE, "--set", "mechanism.speed_rpm=1e300", "--set", "solver.revolutions=1",
                   "-o", t / "out.nc"], 2, "solver.revolutions: got 1.0 (from --set); expected a "
     "run of at least one step: solver.revolutions * 60 / mechanism.speed_rpm = 1.0 * 60 / 1e+300"),
    ("run revolutions at 5e-324 r/min (was: 'solver.revolutions: got 0.03 (... = inf s / "
     "1e-05 s = inf steps)', the speed not named)",
     lambda t, f: ["run", ONE, "--set", "mechanism.speed_rpm=5e-324", "--set",
                   "solver.revolutions=0.03", "-o", t / "out.nc"], 2,
     "mechanism.speed_rpm: got 5e-324 (from --set); expected a speed at which "
     "solver.revolutions (0.03) lasts a finite time"),
    ("validate settle_revolutions at 5e-324 r/min (was: accepted, an infinite settle time)",
     lambda t, f: ["validate", ONE, "--set", "mechanism.speed_rpm=5e-324", "--set",
                   "metrics.settle_revolutions=1"], 2,
     "mechanism.speed_rpm: got 5e-324 (from --set); expected a speed at which "
     "metrics.settle_revolutions (1.0) lasts a finite time"),
    ("validate settle_revolutions of 1.7e308 (was: accepted, an infinite settle time)",
     lambda t, f: ["validate", ONE, "--set", "metrics.settle_revolutions=1.7e308"], 2,
     "metrics.settle_revolutions: got 1.7e+308 (from --set); expected a number of revolutions "
     "that lasts a finite time at mechanism.speed_rpm = 60.0"),
    ("validate revolutions of 1e308 (was: 'solver.duration / solver.dt = inf s / 1e-05 s = inf "
     "steps')", lambda t, f: ["validate", ONE, "--set", "solver.revolutions=1e308"], 2,
     "solver.revolutions: got 1e+308 (from --set); expected a number of revolutions that lasts "
     "a finite time at mechanism.speed_rpm = 60.0 (solver.revolutions * 60 / "
     "mechanism.speed_rpm = inf s)"),
    ("run revolutions at 1e-300 r/min (was: the step count without the speed that made it)",
     lambda t, f: ["run", ONE, "--set", "mechanism.speed_rpm=1e-300", "--set",
                   "solver.revolutions=0.03", "-o", t / "out.nc"], 2,
     "solver.revolutions: got 0.03 (solver.revolutions * 60 / mechanism.speed_rpm = 0.03 * 60 / "
     "1e-300 = 1.8e+300 s, / solver.dt (1e-05 s) = 1.8e+305 steps); expected a run of at most"),
    ("run -o a name with a NUL byte (was: ValueError traceback, 'embedded null byte')",
     lambda t, f: ["run", ONE, "--set", "solver.duration=0.002", "-o", f"{t}/out\0.nc"], 2,
     "invalid value for '-o' / '--out': "),
    ("report a path with a NUL byte (was: ValueError traceback)",
     lambda t, f: ["report", f"{f}/run\0.nc"], 2, "invalid value for 'PATH': "),
    ("run a config path with a NUL byte (was: ValueError traceback)",
     lambda t, f: ["run", "one\0.yaml", "-o", t / "out.nc"], 2, "holds a NUL byte"),
    ("plot --select a zip group without labels (was: \"unknown sweep dimension 'g'; choose "
     "from: none\")", lambda t, f: ["plot", f / "zip.nc", "--kind", "slider", "--select", "g=0",
                                    "-o", t / "out.png"], 2,
     "sweep dimension 'g' has no values to select by (a zip group without labels: give the "
     "group labels in the sweep file)"),
    ("plot bifurcation --select a zip group without labels (was: \"unknown sweep dimension "
     "'g'; choose from: none\")", lambda t, f: ["plot", f / "zip.nc", "--kind", "bifurcation",
                                                "--select", "g=0", "-o", t / "out.png"], 2,
     "sweep dimension 'g' has no values to select by"),
    ("report --reference a zip group without labels (was: \"unknown sweep dimension 'g'; "
     "choose from: none\")", lambda t, f: ["report", f / "zip.nc", "--reference", "g=0"], 2,
     "sweep dimension 'g' has no values to select by"),
]
ROWS += ROUND5_FUZZ
#: Issue 40 item 9: every geometric input of joints O and P bounded against the mechanism.
ROUND5_SIZES = [
    ("O denormal clearance (was: ZeroDivisionError traceback, in validate too)",
     lambda t, f: ["validate", ONE, "--set", "joints.O.clearance=5e-324"], 2,
     "joints.O.clearance: got 5e-324 (from --set); expected 0 (an ideal joint) or a number >= 1e-10 m"),
    ("P denormal clearances (was: ZeroDivisionError traceback, in validate too)",
     lambda t, f: ["validate", ONE, "--set", "joints.P.clearance_y=5e-324",
                   "--set", "joints.P.clearance_z=5e-324"], 2,
     "joints.P.clearance_y: got 5e-324"),
    ("O 1 um bearing (was: ValueError traceback)",
     lambda t, f: ["validate", ONE, "--set", "joints.O.bearing_radius=1e-6"], 2,
     "joints.O.bearing_radius: got 1e-06 (from --set); expected a number with 0.001 <= x <= 0.14 m"),
    ("P 1e-300 m corner radius (was: ValueError traceback)",
     lambda t, f: ["validate", ONE, "--set", "joints.P.corner_radius=1e-300"], 2,
     "joints.P.corner_radius: got 1e-300 (from --set); expected a number >= 1e-05 m"),
    ("O 1 km bearing on a 0.14 m crank (was: accepted and run)",
     lambda t, f: ["run", ONE, "--set", "joints.O.bearing_radius=1000", "-o", t / "out.nc"], 2,
     "joints.O.bearing_radius: got 1000.0 (from --set); expected a number with 0.001 <= x <= 0.14 m "
     "(the crank's length)"),
    ("O 1e300 m bearing length (was: accepted and run)",
     lambda t, f: ["run", ONE, "--set", "joints.O.length=1e300", "-o", t / "out.nc"], 2,
     "joints.O.length: got 1e+300 (from --set); expected a number <= 0.38 m"),
    ("O 1e300 m base (was: accepted and run)",
     lambda t, f: ["validate", ONE, "--set", "joints.O.base_thickness=1e300"], 2,
     "joints.O.base_thickness: got 1e+300"),
    ("P 1e300 m base (was: accepted and run)",
     lambda t, f: ["validate", ONE, "--set", "joints.P.base_thickness=1e300"], 2,
     "joints.P.base_thickness: got 1e+300"),
    ("O 5 cm coating on a 1 cm bearing (was: accepted and run)",
     lambda t, f: ["validate", ONE, "--set", "joints.O.coating_thickness=0.05"], 2,
     "joints.O.coating_thickness: got 0.05 (from --set); expected a number < joints.O.bearing_radius"),
    ("O wear k = 1e300 (was: a 3.7e303 m wear depth at O, status ok)",
     lambda t, f: ["run", ONE, "--set", "joints.O.wear_coefficient=1e300", "-o", t / "out.nc"], 2,
     "joints.O.wear_coefficient: got 1e+300 (from --set); expected null or a number <= 1e-09 m^2/N"),
    ("P wear k = 1e300 (was: accepted and run)",
     lambda t, f: ["validate", ONE, "--set", "joints.P.wear_coefficient=1e300"], 2,
     "joints.P.wear_coefficient: got 1e+300"),
    ("P 1 km block (was: accepted and run)",
     lambda t, f: ["validate", ONE, "--set", "joints.P.block=[1000,0.06,0.06]"], 2,
     "joints.P.block: got [1000"),
]
ROWS += ROUND5_SIZES

# --- issue 42 item 3: the elastic bushing's settings
BUSHING = [
    ("B a bushing with its clearance (was: unknown key joints.B.type)",
     lambda t, f: ["validate", ONE, "--set", "joints.B.type=bushing"], 2,
     "joints.B.clearance: got 0.00025; expected 0 where joints.B.type is bushing (a bushing has no gap)"),
    ("A a bushing with a coating (was: unknown key joints.A.type)",
     lambda t, f: ["run", ONE, "--set", "joints.A.type=bushing", "--set", "joints.A.coating=PTFE",
                   "-o", t / "out.nc"], 2,
     "joints.A.coating: got 'PTFE' (from --set); expected 'none' where joints.A.type is bushing"),
    ("O a bushing on a prismatic's type (was: unknown key joints.O.type)",
     lambda t, f: ["validate", ONE, "--set", "joints.O.type=prismatic"], 2,
     "joints.O.type: got 'prismatic' (from --set); expected one of 'revolute', 'bushing'"),
    ("O a bushing damped beyond the step's reach (was: unknown key joints.O.bushing_damping)",
     lambda t, f: ["run", ONE, "--set", "joints.O.type=bushing", "--set",
                   "joints.O.bushing_damping=[1e8,0]", "-o", t / "out.nc"], 2,
     "solver.dt: got 1e-05; expected a step <="),
    ("B a bushing of stiffness 0 (was: unknown key joints.B.bushing_stiffness)",
     lambda t, f: ["validate", ONE, "--set", "joints.B.bushing_stiffness=[0,1e6]"], 2,
     "joints.B.bushing_stiffness: got [0"),
]
ROWS += BUSHING

# --- issue 44: the mechanism (mechanism.kind) and its presets
ISSUE44_MECHANISM = [
    ("the slider-crank's preset on the RSSP (was: refused as one preset of 'realistic', "
     "'paper')",
     lambda t, f: ["validate", ONE, "--set", "mechanism.preset=flores_benchmark"], 2,
     "mechanism.preset: got 'flores_benchmark' (from --set); expected a preset of "
     "mechanism.kind rssp: one of realistic, paper"),
    ("mechanism.kind slider_crank on the RSSP's preset (was: unknown key mechanism.kind)",
     lambda t, f: ["run", ONE, "--set", "mechanism.kind=slider_crank", "-o", t / "out.nc"], 2,
     "mechanism.preset: got 'realistic'; expected a preset of mechanism.kind slider_crank: "
     "one of flores_benchmark"),
    ("a slider-crank guide's side gap below its gap in the plane (was: refused, any "
     "clearance of the slider-crank's guide: expected 0 where mechanism.kind is slider_crank)",
     lambda t, f: ["run", ONE, "--set", "mechanism.kind=slider_crank", "--set",
                   "mechanism.preset=flores_benchmark", "--set", "joints.P.clearance_y=5e-5",
                   "--set", "joints.P.clearance_z=1e-4", "-o", t / "out.nc"], 2,
     "joints.P.clearance_y: got 5e-05 (from --set); expected a number >= joints.P.clearance_z "
     "(0.0001 m) where mechanism.kind is slider_crank"),
    ("a slider-crank with clearance_z alone in its guide (was: refused, any clearance of the "
     "slider-crank's guide: expected 0 where mechanism.kind is slider_crank)",
     lambda t, f: ["validate", ONE, "--set", "mechanism.kind=slider_crank", "--set",
                   "mechanism.preset=flores_benchmark", "--set", "joints.P.clearance_z=1e-4"], 2,
     "joints.P.clearance_y: got 0.0; expected a number > 0 when the other clearance of joint P "
     "is, or both 0 (an ideal guide)"),
    ("an unknown mechanism.kind (was: unknown key mechanism.kind)",
     lambda t, f: ["run", ONE, "--set", "mechanism.kind=four_bar", "-o", t / "out.nc"], 2,
     "mechanism.kind: got 'four_bar' (from --set); expected one of 'rssp', 'slider_crank'"),
    ("a sweep of mechanism.kind on the RSSP's preset (was: unknown key mechanism.kind)",
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {mechanism.kind: [rssp, slider_crank]}}\n"),
                   "--no-progress", "--workers", "1", "-o", Path(t) / "out.nc"], 2,
     "mechanism.kind: got 'slider_crank'; expected a value with which mechanism.preset = "
     "'realistic' is a preset of mechanism.kind slider_crank"),
]
ROWS += ISSUE44_MECHANISM

SLIDER_CRANK = str(CONFIGS / "slider_crank.yaml")
#: The slider-crank's pins: a bushing at A or B is radial in the plane and runs its axial
#: pair as the radial one, so an axial value given that differs is refused, not replaced.
ISSUE44_PIN_BUSHINGS = [
    ("a slider-crank's B bushing with its own axial stiffness (was: run, its axial 5e5 "
     "N/m replaced by the radial 2e6 without a word)",
     lambda t, f: ["run", SLIDER_CRANK, "--set", "joints.B.clearance=0", "--set",
                   "joints.B.type=bushing", "--set", "joints.B.bushing_stiffness=[2e6,5e5]",
                   "-o", t / "out.nc"], 2,
     "joints.B.bushing_stiffness: got [2000000.0, 500000.0] (from --set); expected (radial, "
     "axial) with the axial value the radial one, [2e+06, 2e+06], where mechanism.kind is "
     "slider_crank (a bushing at B is a pin's"),
    ("a slider-crank's A bushing with its own axial damping in a sweep (was: run, its "
     "axial 100 N s/m replaced by the radial 400)",
     lambda t, f: ["sweep", _swp(t, "sweep: {grid: {joints.A.bushing_damping: "
                                 "[[400.0, 400.0], [400.0, 100.0]]}}\n",
                                 base="{mechanism: {kind: slider_crank, preset: "
                                 "flores_benchmark}, joints: {A: {type: bushing}}}"),
                   "--no-progress", "--workers", "1", "-o", Path(t) / "out.nc"], 2,
     "joints.A.bushing_damping: got [400.0, 100.0]; expected (radial, axial) with the axial "
     "value the radial one, [400, 400]"),
]
ROWS += ISSUE44_PIN_BUSHINGS

ISSUE44_PINS = [
    ("a bearing length at the RSSP's ball joint A (was: unknown key joints.A.length)",
     lambda t, f: ["run", ONE, "--set", "joints.A.length=0.02", "-o", t / "out.nc"], 2,
     "joints.A.length: got 0.02 (from --set); expected null where mechanism.kind is rssp"),
    ("a slider-crank pin's bearing length longer than its rod (was: unknown key "
     "joints.B.length)",
     lambda t, f: ["validate", ONE, "--set", "mechanism.kind=slider_crank", "--set",
                   "mechanism.preset=flores_benchmark", "--set", "joints.B.length=0.5"], 2,
     "joints.B.length: got 0.5 (from --set); expected a number <= 0.12 m, the mechanism's "
     "longest link (the rod)"),
    ("a slider-crank pin's bearing length of 0 (was: unknown key joints.B.length)",
     lambda t, f: ["validate", ONE, "--set", "mechanism.kind=slider_crank", "--set",
                   "mechanism.preset=flores_benchmark", "--set", "joints.B.length=0"], 2,
     "joints.B.length: got 0 (from --set)"),
]
ROWS += ISSUE44_PINS

#: A and B are the mechanism's own type (the RSSP's spherical, the slider-crank's
#: revolute) or a bushing: the other mechanism's type is refused.
ISSUE44_PIN_TYPES = [
    ("a revolute A in the RSSP (was: unknown value revolute, the choices spherical and "
     "bushing)",
     lambda t, f: ["run", ONE, "--set", "joints.A.type=revolute", "-o", t / "out.nc"], 2,
     "joints.A.type: got 'revolute' (from --set); expected spherical or bushing where "
     "mechanism.kind is rssp (its A and B are balls in sockets)"),
    ("a spherical B in the slider-crank (was: run as the revolute pin, the config saying "
     "spherical)",
     lambda t, f: ["run", SLIDER_CRANK, "--set", "joints.B.type=spherical", "-o",
                   t / "out.nc"], 2,
     "joints.B.type: got 'spherical' (from --set); expected revolute or bushing where "
     "mechanism.kind is slider_crank (its A and B are pins in bearings)"),
]
ROWS += ISSUE44_PIN_TYPES


def friction_materials(tmp: Path, mu: str) -> str:
    """A user materials file giving PTFE the friction coefficient ``mu``."""
    path = tmp / "m.yaml"
    path.write_text(f"PTFE: {{friction_coefficient: {{value: {mu}, source: a test}}}}\n")
    return f"materials_file={path}"


# --- round 5 (issue 40, items 9 and 11): layers and materials of the fuzz round's last probes
ROUND5_LAYERS = [
    ("O denormal coating (was: accepted and run as an elastic layer)",
     lambda t, f: ["validate", ONE, "--set", "joints.O.clearance=1e-4", "--set",
                   "joints.O.coating=PTFE", "--set", "joints.O.coating_thickness=5e-324"], 2,
     "joints.O.coating_thickness: got 5e-324 (from --set); expected a number >= 1e-09 m"),
    ("O denormal base under a coating (was: accepted and run)",
     lambda t, f: ["run", ONE, "--set", "joints.O.clearance=1e-4", "--set", "joints.O.coating=PTFE",
                   "--set", "joints.O.base_thickness=5e-324", "-o", t / "out.nc"], 2,
     "joints.O.base_thickness: got 5e-324 (from --set); expected a number >= 1e-09 m"),
    ("P denormal coating (was: accepted and run)",
     lambda t, f: ["validate", ONE, "--set", "joints.P.coating=MoS2", "--set",
                   "joints.P.coating_thickness=5e-324"], 2, "joints.P.coating_thickness: got 5e-324"),
    ("a friction coefficient of 1e300 (was: an overflow warning, then singular_constraints, exit 1)",
     lambda t, f: ["run", ONE, "--set", "joints.O.clearance=1e-4", "--set", "joints.O.coating=PTFE",
                   "--set", friction_materials(t, "1e300"), "-o", t / "out.nc"], 2,
     "PTFE.friction_coefficient.value: got 1e+300; expected a number with 0 <= x <= 2"),
    ("a friction coefficient of 10 (was: unstable_step, exit 1)",
     lambda t, f: ["validate", ONE, "--set", "joints.B.coating=PTFE",
                   "--set", friction_materials(t, "10")], 2,
     "PTFE.friction_coefficient.value: got 10"),
]
ROWS += ROUND5_LAYERS

#: --select and --reference take a value with a unit of its quantity (issue 45 item 6): one
#: that is not is refused naming the key and the units it takes.
SELECT_UNITS = [
    ("plot --select a clearance in furlongs (was: \"unknown value for B_clearance "
     "'0.25furlong'\", no word of units)",
     lambda t, f: ["plot", f / "clr.nc", "--kind", "sweep", "--select", "B_clearance=0.25furlong",
                   "-o", t / "out.png"], 2,
     "unknown unit 'furlong' in B_clearance=0.25furlong (its values are in m: give a "
     "number in m, or one of m, mm, um"),
    ("report --reference a clearance in seconds (was: \"unknown value for B_clearance "
     "'0.1 s'\")",
     lambda t, f: ["report", f / "clr.nc", "--reference", "B_clearance=0.1 s"], 2,
     "unknown unit 's' in B_clearance=0.1 s"),
    ("plot --select a clearance given in mm that is not swept (was: the values in m only)",
     lambda t, f: ["plot", f / "clr.nc", "--kind", "slider", "--select", "B_clearance=0.2mm",
                   "-o", t / "out.png"], 2,
     "unknown value for B_clearance '0.2mm'; choose from: 0.0001, 0.00025 (in m, or with a "
     "unit: m, mm, um"),
]
ROWS += SELECT_UNITS

#: A settled limit whose window lies beyond each life block (issue 44: the slider-crank's
#: 5000 r/min turns a revolution in 12 ms, inside the default 0.05 s of settling) is refused
#: naming the settle key.
SETTLED_WINDOW = [
    ("life max_normal_force with blocks shorter than the settling (was: ran, every block's "
     "settled statistics NaN, the limit 'not reached')",
     lambda t, f: ["life", LIFE, "--set", "mechanism.speed_rpm=3000", "--set",
                   "life.max_normal_force=30", "-o", t / "out.nc"], 2,
     "metrics.settle_time: got 0.05 (the settled window starts 0.05 s into the block); "
     "expected a settled window inside each life block (0.02 s"),
    ("reliability max_motion_error with blocks shorter than the settling (was: ran, every "
     "member censored on it)",
     lambda t, f: ["sweep", CONFIGS / "reliability.yaml", "--set", "mechanism.speed_rpm=3000",
                   "--set", "metrics.settle_revolutions=2", "-o", t / "out.nc"], 2,
     "metrics.settle_revolutions: got 2"),
]
ROWS += SETTLED_WINDOW


@pytest.fixture
def device(monkeypatch):
    """The CUDA device as the row needs it: none for ``--backend cuda``, a stand-in for
    ``--keep-series`` and a bad CLEARSWEEP_HOST_MEMORY (set for its row; both refused before
    any batch is made), the real check under a faked numpy / numba-cuda mismatch for the
    pairing's row."""
    import clearsweep.gpu as gpu

    def none():
        raise gpu.NoCudaDevice()

    def setup(name):
        if "numba-cuda 0.30.4 and numpy 2.5" in name:
            monkeypatch.setattr(gpu, "simulated", lambda: False)
            monkeypatch.setattr(gpu, "installed_versions", lambda: ("2.5.0", "0.30.4"))
            return
        if gpu.HOST_MEMORY_ENV in name:
            monkeypatch.setenv(gpu.HOST_MEMORY_ENV, name.split("=", 1)[1].split()[0])
        present = "--keep-series beyond" in name or gpu.HOST_MEMORY_ENV in name
        monkeypatch.setattr(gpu, "device_name", (lambda: "stand-in") if present else none)

    return setup


@pytest.mark.parametrize("name, argv, code, words", ROWS, ids=[r[0] for r in ROWS])
def test_hostile_input_is_one_error_line(tmp_path, files, device, name, argv, code, words):
    device(name)
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


def drawn(argv: list[str]):
    """``clearsweep ARGV`` and the matplotlib figures it drew."""
    import clearsweep.plotting as plotting

    figures = []
    real = plotting.figure

    def keep(*args, **kwargs):
        figures.append(real(*args, **kwargs))
        return figures[-1]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(plotting, "figure", keep)
        return CliRunner().invoke(main, argv), figures


@pytest.mark.parametrize("select, title", [((), "Socket wear depth"),
                                           (("--select", "snapshot=1"),
                                            "Socket wear depth, snapshot 1 at ")])
def test_a_life_runs_wear_map_is_drawn_whole_or_by_snapshot(tmp_path, files, select, title):
    """Before: --kind wear-map on a life file asked for --select on snapshot, then refused it."""
    result, figures = drawn(["plot", str(files / "life.nc"), "--kind", "wear-map", *select,
                             "-o", str(tmp_path / "w.png")])
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


# --- round 4 (issue 33, items 4-6): what the table's one-line rows cannot show

@pytest.mark.parametrize("limit", ["any", "clearance_growth"])
def test_a_reliability_figure_of_one_limit(tmp_path, files, limit):
    """Before: --select limit=any stopped with "TypeError: iteration over a 0-d array"."""
    result, figures = drawn(["plot", str(files / "rel.nc"), "--kind", "reliability", "--select",
                             f"limit={limit}", "-o", str(tmp_path / "r.png")])
    assert result.exit_code == 0, result.output
    assert [ax.get_title() for ax in figures[0].axes] == [f"limit: {limit}"]


def test_the_tolerance_band_rule_does_not_depend_on_the_seed():
    """Before: with B's clearance 7.4 mm (bound 7.5 mm) and t = 0.2 mm, seed 1 was accepted
    and seeds 0, 2 and 3 refused, by the draws of member 1; a band inside the bounds was
    refused or not by the draws too."""
    lines = set()
    for seed in range(4):
        result = CliRunner().invoke(main, ["validate", REL, "-q", "--set", "joints.B.clearance=7.4e-3",
                                           "--set", "reliability.clearance_tolerance=2e-4", "--set",
                                           "reliability.members=2", "--set", f"reliability.seed={seed}"])
        assert result.exit_code == 2, (seed, result.output)
        lines.add(result.stderr.strip())
    assert len(lines) == 1 and "reliability.clearance_tolerance: got 0.0002" in lines.pop()
    inside = CliRunner().invoke(main, ["validate", REL, "-q", "--set", "joints.B.clearance=7.4e-3",
                                       "--set", "reliability.clearance_tolerance=0.99e-4"])
    assert inside.exit_code == 0, inside.output      # c + t < 7.5 mm: every draw admitted
    # t = 0.2 mm < c = 0.25 mm: every member keeps a clearance. Before, the band was checked
    # again around each member's drawn clearance: seeds 0-3 and 5 refused it, seed 4 not.
    for seed in range(6):
        result = CliRunner().invoke(main, ["validate", REL, "-q", "--set", "reliability.members=4",
                                           "--set", "reliability.clearance_tolerance=2e-4",
                                           "--set", f"reliability.seed={seed}"])
        assert result.exit_code == 0, (seed, result.output)


def test_the_skip_rule_the_wear_through_message_names_runs_the_coated_designs(tmp_path):
    """The rule the refusal names (docs/reliability.md) leaves the other designs valid."""
    limits = ["--set", "life.max_clearance_growth=null", "--set", "life.max_motion_error=null",
              "--set", "life.stop_at_wear_through=true"]
    refused = CliRunner().invoke(main, ["validate", REL, *limits])
    rule = refused.stderr.split("(sweep: skip: ")[1].split(")")[0]
    assert rule == "[{B_coating: none}]"
    text = (CONFIGS / "reliability.yaml").read_text().replace(
        "    joints.B.coating: [none, MoS2, lead, PTFE]\n",
        f"    joints.B.coating: [none, MoS2, lead, PTFE]\n  skip: {rule}\n")
    (tmp_path / "rel.yaml").write_text(text)
    result = CliRunner().invoke(main, ["validate", str(tmp_path / "rel.yaml"), *limits])
    assert result.exit_code == 0, result.output
    assert "64 life runs, 48 to run" in result.stdout      # 16 members of each coated design


def test_a_damaged_part_is_named_and_its_case_runs_again(tmp_path):
    """Before: "cannot write OUT.parts/H.nc: NetCDF: HDF error; ... make room and run again
    with --resume", and every --resume ended the same way. Now --resume names the damaged
    part, counts it as a case to simulate, deletes it and runs its case again. A part damaged
    past its mark is no longer provably clearsweep's (issue 40, item 3: the ledger line holds
    the content hash of what was written): it is refused, named and left alone, and once
    moved away its case runs again."""
    config, out = two_case_sweep(tmp_path), tmp_path / "two.nc"
    argv = ["sweep", config, "-o", str(out), "--workers", "1", "--no-progress"]
    assert CliRunner().invoke(main, [*argv, "--keep-parts"]).exit_code == 0
    with xr.open_dataset(out) as ds:
        reference = ds.load()
    out.unlink()
    part = sorted((tmp_path / "two.nc.parts").glob("*.nc"))[0]
    part.write_bytes(part.read_bytes()[:300])
    result = CliRunner().invoke(main, [*argv, "--resume"])
    assert result.exit_code == 2 and f"did not write ({part.name})" in result.stderr
    assert len(part.read_bytes()) == 300
    part.unlink()
    result = CliRunner().invoke(main, [*argv, "--resume"])
    assert result.exit_code == 0, result.output
    assert "2 cases, 1 to simulate (1 finished before, kept)" in result.stderr
    with xr.open_dataset(out) as ds:
        for name in ("wear_volume", "status"):
            np.testing.assert_array_equal(ds[name].values, reference[name].values)


def test_ctrl_c_counts_the_parts_kept_on_disk(tmp_path, monkeypatch):
    """Before: "1 of 2 cases are finished" while 2 parts were on disk: a worker writes its
    part before the driver hears of it, and --resume keeps every part."""
    import clearsweep.sweeping.run as run
    from clearsweep.sweeping.worker import _run_and_store

    def two_written_one_heard(backend, tasks, on_result, guard):
        tasks = list(tasks)
        receipts = [_run_and_store(payload, backend.parts_dir, h) for h, payload in tasks]
        on_result(tasks[0][0], receipts[0])
        raise KeyboardInterrupt

    monkeypatch.setattr(run, "_drive", two_written_one_heard)
    monkeypatch.setattr(run, "_backend", lambda *a, **k: _Parts(tmp_path / "out.nc.parts"))
    result = CliRunner().invoke(main, ["sweep", two_case_sweep(tmp_path), "-o", str(tmp_path / "out.nc"),
                                       "--workers", "2", "--no-progress"])
    assert result.exit_code == 130, result.output
    assert "2 of 2 cases are finished and kept in" in result.stderr.splitlines()[-1]
    assert len(list((tmp_path / "out.nc.parts").glob("*.nc"))) == 2


class _Parts:
    """A stand-in backend whose ``_drive`` the test replaces: it only names the parts folder."""

    label = "stand-in"

    def __init__(self, parts_dir):
        self.parts_dir = str(parts_dir)

    def close(self, interrupted=False):
        pass


def test_library_warnings_are_one_clearsweep_line(tmp_path, capsys):
    """Before: scipy's and SALib's two raw lines each ("UserWarning: The balance properties
    of Sobol' points require n to be a power of 2" and the source line)."""
    from clearsweep.cli import _show_warning

    config = sample_file(tmp_path, "{method: sobol, n: 5, ranges: {joints.B.clearance: [1.0e-4, 2.0e-4]}}")
    result = CliRunner().invoke(main, ["validate", config, "-q"])
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines() == [
        "clearsweep: warning: sweep.sample.n: 5 is not a power of 2; Sobol' points (method sobol) "
        "are balanced at n = 2^k only: 4 or 8 keeps that balance"]
    _show_warning(RuntimeWarning("invalid value encountered in divide"), RuntimeWarning,
                  "/venv/lib/python3.11/site-packages/SALib/analyze/sobol.py", 140)
    assert capsys.readouterr().err == ("clearsweep: warning: invalid value encountered in divide "
                                       "(RuntimeWarning from SALib)\n")


def under_file_size_limit(tmp: Path, argv: list[str], limit: int) -> subprocess.CompletedProcess:
    """``clearsweep ARGV`` in a process whose files may not grow beyond ``limit`` bytes
    (``ulimit -f``: a write beyond it fails with EFBIG, "NetCDF: HDF error" in netCDF-C)."""
    import resource
    import sys

    def limited() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.getrlimit(resource.RLIMIT_FSIZE)[1]))

    return subprocess.run([sys.executable, "-m", "clearsweep.cli", *map(str, argv)], cwd=tmp,
                          capture_output=True, text=True, timeout=300, preexec_fn=limited)


@pytest.mark.parametrize("workers", ["1", "2"])
def test_a_sweep_whose_parts_pass_the_file_size_limit_says_so_and_counts_what_is_kept(tmp_path,
                                                                                      workers):
    """Before: "the serial backend failed (OSError: [Errno 5] NetCDF: HDF error: ...); 0 of 2
    cases are kept in ...; run again with --resume", which the limit stops again."""
    out = tmp_path / "out.nc"
    result = under_file_size_limit(tmp_path, ["sweep", two_case_sweep(tmp_path), "-o", out,
                                              "--workers", workers, "--no-progress", "-q"],
                                   16 * 1024)
    assert result.returncode == 1, result.stderr[-2000:]
    assert result.stderr.strip().splitlines() == [
        f"clearsweep: error: cannot write in {out}.parts: a file would pass this process's "
        "file-size limit of 16,384 bytes (ulimit -f); 0 of the 2 cases are finished and kept "
        "there: raise the limit (ulimit -f unlimited) and run again with --resume"]
    assert not out.exists()


@pytest.mark.parametrize("what, limit_kib", [("sweep", 64), ("full sweep", 600), ("run", 64)])
def test_a_results_file_beyond_the_file_size_limit_names_the_limit(tmp_path, what, limit_kib):
    """Before: "cannot write OUT: NetCDF: HDF error", for a sweep with "make room and run
    again with --resume"; a full sweep whose time series passed the limit in h5py's copy
    ended in a traceback (RuntimeError: Can't decrement id ref count (... errno = 27 ...))."""
    out = tmp_path / "out.nc"
    if what != "run":     # four parts fit (summary: about 47 kB each), the sweep file not
        config = tmp_path / "four.yaml"
        text = Path(two_case_sweep(tmp_path)).read_text().replace(
            "[none, PTFE]", "[none, PTFE, MoS2, lead]")
        if what == "full sweep":
            text = text.replace("store: summary", "store: full").replace("0.002", "0.05")
        config.write_text(text)
        argv = ["sweep", config, "-o", out, "--workers", "1", "--no-progress", "-q"]
        kept = f"; the 4 finished case(s) are kept in {out}.parts: run again with --resume"
    else:
        argv = ["run", ONE, "--set", "solver.duration=0.05", "-o", out, "-q"]
        kept = ""
    result = under_file_size_limit(tmp_path, argv, limit_kib * 1024)
    assert result.returncode == 1, result.stderr[-2000:]
    assert result.stderr.strip().splitlines() == [
        f"clearsweep: error: cannot write {out}: a file would pass this process's file-size "
        f"limit of {limit_kib * 1024:,} bytes (ulimit -f); raise the limit (ulimit -f "
        f"unlimited){kept}"]
    assert not out.exists()
