"""Resumable life runs: a checkpoint after every block, --resume bit-identical to an
uninterrupted run, at most one block lost to a SIGKILL, foreign checkpoints refused."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from clearsweep import service_life
from clearsweep.cli import main
from clearsweep.config import load_config
from clearsweep.dataset import write_netcdf_atomic
from clearsweep.service_life import (
    CheckpointError,
    LifeInterrupted,
    checkpoint_blocks,
    checkpoint_path_for,
    life,
)

ROOT = Path(__file__).resolve().parents[1]
CASE = str(ROOT / "configs" / "one_clearance.yaml")
#: A quick life run: 300 r/min (0.2 s blocks), small map, MoS2 that wears through, ten blocks.
QUICK = ["wear.map=[12,24]", "wear.interpolate=true", "solver.energy_tolerance=0.5",
         "mechanism.speed_rpm=300", "wear.amplification=1000", "life.cycles=30",
         "life.jump_clearance_fraction=0.05", "joints.B.coating=MoS2",
         "joints.B.coating_thickness=1e-6", "life.max_blocks=10"]


def sets(overrides) -> list[str]:
    return [a for o in overrides for a in ("--set", o)]


@pytest.fixture(scope="module")
def reference():
    """The uninterrupted run, without a checkpoint."""
    return life(CASE, QUICK)


def same_run(a: xr.Dataset, b: xr.Dataset) -> None:
    """Identical but for when and how they were made (wall time, history)."""
    a, b = a.drop_vars("wall_time"), b.drop_vars("wall_time")
    a.attrs.pop("history", None)
    b.attrs.pop("history", None)
    xr.testing.assert_identical(a, b)


def _interrupt_at_block(n: int):
    seen = []

    def progress(row):
        seen.append(row["cycle"])
        if len(seen) == n:
            raise KeyboardInterrupt
    return progress


def test_resumed_run_is_bit_identical_to_an_uninterrupted_one(tmp_path, reference):
    assert reference.sizes["cycle"] == 10 and float(reference.jump_revolutions.sum()) > 0
    checkpoint = tmp_path / "l.nc.life-checkpoint"
    with pytest.raises(LifeInterrupted) as stopped:
        life(CASE, QUICK, checkpoint=checkpoint, progress=_interrupt_at_block(5))
    # the fifth block was running when it stopped: four are kept
    assert stopped.value.blocks == 4 == checkpoint_blocks(checkpoint)
    states = []
    resumed = life(CASE, QUICK, checkpoint=checkpoint, resume=True,
                   resumed=lambda state: states.append(len(state.rows)))
    assert states == [4]
    same_run(reference, resumed)
    # the wear-through found before the interrupt survives it
    assert np.isfinite(resumed.wear_through_cycle.sel(joint="B"))


def test_an_existing_checkpoint_is_never_deleted_silently(tmp_path):
    checkpoint = tmp_path / "l.nc.life-checkpoint"
    with pytest.raises(LifeInterrupted):
        life(CASE, QUICK, checkpoint=checkpoint, progress=_interrupt_at_block(3))
    stamp = checkpoint.stat().st_mtime_ns
    with pytest.raises(CheckpointError, match="--resume.*--discard-checkpoint"):
        life(CASE, QUICK, checkpoint=checkpoint)
    other = [*QUICK, "wear.amplification=500"]
    with pytest.raises(CheckpointError, match=r"another config \(wear.amplification: 1000.0 there, "
                                              r"500.0 here\).*--discard-checkpoint"):
        life(CASE, other, checkpoint=checkpoint, resume=True)
    assert checkpoint.stat().st_mtime_ns == stamp
    # asked for, it goes: the run starts at block 0
    ds = life(CASE, [*other, "life.max_blocks=2"], checkpoint=checkpoint, resume=True,
              discard_checkpoint=True)
    assert ds.sizes["cycle"] == 2


def _cli(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_cli_refuses_foreign_and_unreadable_checkpoints_in_one_line(tmp_path):
    out = tmp_path / "l.nc"
    checkpoint = checkpoint_path_for(out)
    with pytest.raises(LifeInterrupted):
        life(CASE, QUICK, checkpoint=checkpoint, progress=_interrupt_at_block(2))
    for extra in (["--set", "life.max_blocks=9"], ["--resume", "--set", "life.max_blocks=9"], []):
        result = _cli("life", CASE, "-o", out, "-q", *sets(QUICK), *extra)
        assert result.exit_code == 2, result.output
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("clearsweep: error: "), result.stderr
        assert str(checkpoint) in lines[0] and "--discard-checkpoint" in lines[0]
        assert checkpoint_blocks(checkpoint) == 1 and not out.exists()
    checkpoint.write_bytes(b"not a checkpoint")
    result = _cli("life", CASE, "-o", out, "-q", "--resume", *sets(QUICK))
    assert result.exit_code == 2 and "not a readable life checkpoint" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_cli_interrupt_exits_130_with_the_resume_command(tmp_path, monkeypatch):
    saved = []
    real = service_life.save_checkpoint

    def save_then_stop(*args, **kwargs):
        path = real(*args, **kwargs)
        saved.append(path)
        if len(saved) == 2:
            raise KeyboardInterrupt
        return path

    monkeypatch.setattr(service_life, "save_checkpoint", save_then_stop)
    out = tmp_path / "my life.nc"
    result = _cli("life", CASE, "-o", out, "-q", *sets(QUICK))
    assert result.exit_code == 130, result.output
    assert "interrupted: 2 finished blocks are kept in" in result.stderr
    assert f"continue with: clearsweep life {CASE} -o '{out}' --resume --set" in result.stderr
    assert checkpoint_blocks(checkpoint_path_for(out)) == 2 and not out.exists()


@pytest.mark.slow
def test_sigkill_midway_loses_at_most_one_block_and_resume_finishes_the_run(tmp_path, reference):
    out = tmp_path / "k.nc"
    checkpoint = checkpoint_path_for(out)
    command = [sys.executable, "-m", "clearsweep.cli", "life", CASE, "-o", str(out), *sets(QUICK)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)})
    end = time.monotonic() + 120
    while checkpoint_blocks(checkpoint) < 3:
        if process.poll() is not None or time.monotonic() > end:
            pytest.fail(f"no checkpoint of 3 blocks: {process.communicate()}")
        time.sleep(0.01)
    process.send_signal(signal.SIGKILL)
    _, err = process.communicate()
    assert process.returncode == -signal.SIGKILL and not out.exists()
    finished = err.count("block at")            # blocks the killed run reported as finished
    kept = checkpoint_blocks(checkpoint)
    assert 3 <= kept < 10 and kept >= finished - 1

    result = _cli("life", CASE, "-o", out, *sets(QUICK))     # no --resume: refused, kept
    assert result.exit_code == 2 and "--resume" in result.stderr
    assert checkpoint_blocks(checkpoint) == kept

    result = _cli("life", CASE, "-o", out, "--resume", *sets(QUICK))
    assert result.exit_code == 0, result.output
    assert f"resuming from {checkpoint}: {kept} blocks" in result.stderr
    assert result.stderr.count("block at") == 10 - kept     # no finished block runs again
    assert not checkpoint.exists()
    write_netcdf_atomic(reference, tmp_path / "reference.nc")
    with xr.open_dataset(out) as ds, xr.open_dataset(tmp_path / "reference.nc") as ref:
        same_run(ref.load(), ds.load())


def test_the_checkpoint_belongs_to_the_resolved_config():
    """--set values are part of the identity, as they are of a sweep case's hash."""
    a = service_life._config_json(load_config(CASE, QUICK))
    b = service_life._config_json(load_config(CASE, [*QUICK, "life.max_blocks=11"]))
    assert a != b and a == service_life._config_json(load_config(CASE, QUICK))


def test_a_second_life_run_to_the_same_output_is_refused_while_the_first_runs(tmp_path):
    """Two life runs to one output wrote over each other's checkpoint (or the second continued
    the first's with --resume while the first went on); the second is now refused in one line,
    with and without --resume, and the first's checkpoint is left as it was."""
    import fcntl

    from clearsweep.dataset import LOCK_MARK

    out = tmp_path / "l.nc"
    checkpoint = checkpoint_path_for(out)
    with pytest.raises(LifeInterrupted):
        life(CASE, QUICK, checkpoint=checkpoint, progress=_interrupt_at_block(2))
    before = checkpoint.read_bytes()
    lock = checkpoint.with_name(checkpoint.name + ".lock")
    with open(lock, "wb") as held:      # the first run, still going: its lock holds the mark
        held.write(LOCK_MARK)
        held.flush()
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        for extra in ([], ["--resume"], ["--discard-checkpoint"]):
            result = _cli("life", CASE, "-o", out, "-q", *sets(QUICK), *extra)
            assert result.exit_code == 2, result.output
            (line,) = result.stderr.strip().splitlines()
            assert line.startswith("clearsweep: error: ") and "in use by another life run" in line
            assert checkpoint.read_bytes() == before and not out.exists()
    result = _cli("life", CASE, "-o", out, "-q", "--resume", *sets(QUICK))
    assert result.exit_code == 0, result.output
    assert not lock.exists() and not checkpoint.exists() and out.exists()


def test_a_run_stopped_by_max_blocks_ends_on_its_last_block_s_map():
    """The last block's jump was applied before the max_blocks check: the file's final map
    and its last snapshot, labelled with the last block's revolutions, were a jump deeper
    than that block's wear (its row's wear_depth_max)."""
    ds = life(CASE, [*QUICK, "life.max_blocks=3"])
    assert str(ds.stop_reason.values) == "max_blocks" and ds.sizes["cycle"] == 3
    last = ds.isel(cycle=-1)
    for joint in ("B",):
        assert float(ds.wear_map.sel(joint=joint).max()) == float(last.wear_depth_max.sel(joint=joint))
    assert float(ds.snapshot_cycle[-1]) == float(ds.cycle[-1])
    np.testing.assert_array_equal(ds.wear_map_snapshot.isel(snapshot=-1).values, ds.wear_map.values)


def _edited(path, name: str, edit) -> None:
    """Rewrite the checkpoint at ``path`` with ``edit`` applied to its array ``name``."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    arrays[name] = edit(arrays[name])
    with open(path, "wb") as f:
        np.savez(f, **arrays)


#: Hand edits of a checkpoint that keep its layout and break its invariants (issue 40, item
#: 8): (array, edit, the field the refusal names).
EDITS = [
    ("wvol", lambda a: -np.abs(a) - 1e-12, "wvol holds values that are not finite numbers >= 0"),
    ("row_wear_volume", lambda a: a[::-1], "row wear_volume decreases"),
    ("row_cycle", lambda a: a[::-1], "row cycle is not increasing"),
    ("snapshot_cycle", lambda a: a[::-1], "snapshot_cycle is not increasing"),
    ("row_block_status", lambda a: np.array(["garbage"] * len(a)), "row block_status holds "
                                                                  "'garbage'"),
    ("block_volumes", lambda a: a[:-1], "block_volumes has shape"),
    ("block_volumes", lambda a: -np.abs(a) - 1e-18, "block_volumes holds values"),
]


@pytest.mark.parametrize("name, edit, words", EDITS,
                         ids=[f"{e[0]}-{i}" for i, e in enumerate(EDITS)])
def test_a_hand_edited_checkpoint_is_refused_naming_the_field(tmp_path, name, edit, words):
    """Was: a negative worn volume, reversed cycles, garbage block statuses and truncated
    block volumes were resumed, some with exit 0."""
    out = tmp_path / "l.nc"
    checkpoint = checkpoint_path_for(out)
    with pytest.raises(LifeInterrupted):
        life(CASE, QUICK, checkpoint=checkpoint, progress=_interrupt_at_block(4))
    _edited(checkpoint, name, edit)
    before = checkpoint.read_bytes()
    result = _cli("life", CASE, "-o", out, "-q", "--resume", *sets(QUICK))
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: "), result.stderr
    assert words in lines[0] and str(checkpoint) in lines[0], lines[0]
    assert checkpoint.read_bytes() == before and not out.exists()
