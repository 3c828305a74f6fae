"""A resume never mixes results of different inputs, and nothing of the user's is deleted
(issue 33, items 1 and 2): the file-system scenarios behind the hostile-input rows.

Finished work (a sweep's parts, an ensemble's or a reliability sweep's members, a life
run's checkpoint) belongs to a run exactly when its identity does: the resolved config, the
materials values it reads (not the file's path) and the clearsweep version
(``clearsweep.params.run_identity``). Each test says how the main branch ended before.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from clearsweep import params
from clearsweep.cli import main
from clearsweep.config import load_config
from clearsweep.service_life import LifeInterrupted, checkpoint_path_for, life
from clearsweep.sweeping import assemble as A
from clearsweep.sweeping import parts as P
from clearsweep.sweeping import run_sweep
from clearsweep.sweeping.parts import PartStore, StoreError, parts_dir_for

ROOT = Path(__file__).resolve().parents[1]
#: A user materials file: MoS2's wear coefficient, edited between the runs below.
MATERIALS = 'MoS2:\n  wear_coefficient_m2_per_N: {value: K, source: "a pin-on-disc test"}\n'
CASE = """name: case
materials_file: mats.yaml
mechanism: {preset: realistic, speed_rpm: 60.0}
joints:
  A: {clearance: 0.0}
  B: {clearance: 2.5e-4, coating: MoS2, coating_thickness: 1.0e-4}
solver: {dt: 1.0e-5, duration: 0.004}
"""
SWEEP = """name: sw
store: summary
base: case.yaml
sweep:
  grid:
    joints.B.clearance: [1.0e-4, 2.0e-4]
"""
#: A quick life run (as tests/test_life_checkpoint.py): 0.2 s blocks on a small map.
QUICK = ["wear.map=[12,24]", "wear.interpolate=true", "solver.energy_tolerance=0.5",
         "mechanism.speed_rpm=300", "wear.amplification=1000", "life.cycles=30",
         "life.jump_clearance_fraction=0.05", "life.max_blocks=3"]


def sets(overrides) -> list[str]:
    return [a for o in overrides for a in ("--set", o)]


def invoke(*args) -> object:
    return CliRunner().invoke(main, [str(a) for a in args])


def one_error_line(result, code: int, *words: str) -> str:
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    assert result.exit_code == code, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: "), result.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A folder with the materials file (k = 1e-13), a case config that reads it and a
    two-case sweep over it; the tests run in it."""
    (tmp_path / "mats.yaml").write_text(MATERIALS.replace("K", "1.0e-13"))
    (tmp_path / "case.yaml").write_text(CASE)
    (tmp_path / "sw.yaml").write_text(SWEEP)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def edit_materials(folder: Path, k: str = "9.0e-13") -> None:
    (folder / "mats.yaml").write_text(MATERIALS.replace("K", k))


def sweep(*extra):
    return invoke("sweep", "sw.yaml", "-o", "sw.nc", "--workers", "1", "--no-progress", "-q",
                  *extra)


def volumes(path) -> np.ndarray:
    with xr.open_dataset(path) as ds:
        return ds["wear_volume"].sel(joint="B").values.copy()


# ---------------------------------------------------------------------------- item 1: sweeps

def test_a_sweep_resumed_after_the_materials_file_changed_is_refused(folder):
    """Was: the parts of the old values were kept, the missing case ran with the new ones,
    exit 0: wear_volume at B [4.40e-16, 4.77e-17] m^3 where a fresh run gives [4.40e-16,
    4.29e-16] (the second case 9 times too small)."""
    assert sweep("--keep-parts").exit_code == 0
    parts = parts_dir_for(folder / "sw.nc")
    (folder / "sw.nc").unlink()
    first = sorted(parts.glob("*.nc"))
    first[0].unlink()                                   # as if Ctrl-C came before that case
    edit_materials(folder)
    line = one_error_line(sweep("--resume"), 2, "made with other inputs",
                          "materials MoS2.wear_coefficient_m2_per_N: 1e-13 there, 9e-13 here",
                          "--discard-parts")
    assert "resuming would mix" in line
    assert sorted(parts.glob("*.nc")) == first[1:] and not (folder / "sw.nc").exists()
    # asked for, the old parts go and the file is that of the new values alone
    assert sweep("--resume", "--discard-parts").exit_code == 0
    resumed = volumes("sw.nc")
    (folder / "sw.nc").rename("resumed.nc")
    assert sweep().exit_code == 0
    np.testing.assert_array_equal(resumed, volumes("sw.nc"))
    assert resumed[1] > 5 * 4.77e-17                    # not the old value of the second case


def test_the_materials_files_path_is_not_part_of_the_key(folder):
    """The values decide the results, not where the file lies: moved, the parts are kept."""
    assert sweep("--keep-parts").exit_code == 0
    (folder / "sw.nc").unlink()
    (folder / "mats.yaml").rename(folder / "moved.yaml")
    (folder / "case.yaml").write_text(CASE.replace("mats.yaml", "moved.yaml"))
    result = invoke("sweep", "sw.yaml", "-o", "sw.nc", "--workers", "1", "--no-progress",
                    "--resume")
    assert result.exit_code == 0, result.output
    assert "2 finished before, kept" in result.stderr


@pytest.mark.parametrize("before", ["0.0.1", "0.1.0"])
def test_parts_of_another_clearsweep_version_are_refused(folder, monkeypatch, before):
    """Was: a part's name was the hash of the config alone; another version's parts were
    resumed as this version's. "0.1.0": the parts of the same package version before its
    results' revision (joint P's walls read bilinearly, their track depth), which
    would have been mixed with this revision's results."""
    version = params.IDENTITY_VERSION
    monkeypatch.setattr(params, "IDENTITY_VERSION", before)
    assert sweep("--keep-parts").exit_code == 0
    monkeypatch.setattr(params, "IDENTITY_VERSION", version)
    (folder / "sw.nc").unlink()
    one_error_line(sweep("--resume"), 2, "made with other inputs",
                   f"clearsweep version: '{before}' there, '{version}' here")


def test_an_ensemble_resumed_after_the_materials_file_changed_is_refused(folder):
    """``run`` of an ensemble keeps its members as a sweep's parts: the same key."""
    (folder / "ens.yaml").write_text(CASE + "ensemble: {members: 2, seed: 1, perturb: "
                                            "{ball_offset: 0.1}}\n")
    cfg = load_config("ens.yaml")
    plan_doc = {"name": "ens", "base": cfg.to_dict()}
    run_sweep(plan_doc, folder / "ens.nc", workers=1, progress=False, keep_parts=True).close()
    (folder / "ens.nc").unlink()
    edit_materials(folder)
    result = invoke("run", "ens.yaml", "-o", "ens.nc", "--workers", "1", "-q", "--resume")
    one_error_line(result, 2, "made with other inputs", "materials MoS2.wear_coefficient")
    assert not (folder / "ens.nc").exists()


def test_reliability_members_resumed_after_the_materials_file_changed_are_refused(folder):
    text = (ROOT / "configs" / "reliability.yaml").read_text()
    (folder / "rel.yaml").write_text(
        text.replace("[none, MoS2, lead, PTFE]", "[MoS2]").replace("map: [36, 72]", "map: [6, 12]"))
    args = ["--set", "reliability.members=2", "--set", "mechanism.speed_rpm=600",
            "--set", "life.max_blocks=1", "--set", f"materials_file={folder / 'mats.yaml'}"]
    result = invoke("sweep", "rel.yaml", "-o", "rel.nc", "--workers", "1", "--no-progress", "-q",
                    "--keep-parts", *args)
    assert result.exit_code == 0, result.output
    (folder / "rel.nc").unlink()
    edit_materials(folder)
    result = invoke("sweep", "rel.yaml", "-o", "rel.nc", "--workers", "1", "--no-progress", "-q",
                    "--resume", *args)
    one_error_line(result, 2, "made with other inputs", "materials MoS2.wear_coefficient")


# ---------------------------------------------------------------------------- item 1: parts

def test_swapped_and_truncated_parts_run_again_and_the_file_is_the_uninterrupted_one(folder):
    """Was: two parts swapped by name were assembled under each other's case, exit 0
    (wear_volume at B [4.77e-17, 4.89e-17] m^3 instead of [4.89e-17, 4.77e-17])."""
    assert sweep("--keep-parts").exit_code == 0
    reference = volumes("sw.nc")
    (folder / "sw.nc").unlink()
    a, b = sorted(parts_dir_for(folder / "sw.nc").glob("*.nc"))
    a.rename(folder / "tmp.nc")
    b.rename(a)
    (folder / "tmp.nc").rename(b)
    assert sweep("--resume", "--keep-parts").exit_code == 0
    np.testing.assert_array_equal(volumes("sw.nc"), reference)
    (folder / "sw.nc").unlink()
    a.write_bytes(a.read_bytes()[:200])                 # truncated
    # no longer provably clearsweep's (no readable mark, not the content the ledger hashed,
    # issue 40 item 3): refused and left alone; once moved away, its case runs again
    one_error_line(sweep("--resume"), 2, f"did not write ({a.name})")
    assert len(a.read_bytes()) == 200
    a.unlink()
    assert sweep("--resume").exit_code == 0
    np.testing.assert_array_equal(volumes("sw.nc"), reference)
    assert not parts_dir_for(folder / "sw.nc").exists()    # the folder went after the sweep


def test_assembly_refuses_a_part_filed_under_another_case(tmp_path):
    """A part renamed while the sweep runs is caught when the file is assembled."""
    status = xr.Dataset({"status": ((), "ok", P.STATUS_ATTRS), "message": ((), "", P.MESSAGE_ATTRS),
                         "peak": ((), 1.0)})
    with PartStore(tmp_path / "o.nc.parts") as store:
        store.open()
        store.write("aaaa", status)
        store.write("bbbb", status.assign(peak=2.0))
        store.path("aaaa").unlink()
        store.path("bbbb").rename(store.path("aaaa"))
        with pytest.raises(StoreError, match=r"holds the case bbbb, not the case aaaa it is filed "
                                             r"under"):
            A.write_sweep_netcdf(tmp_path / "o.nc", sweep_dims={"x": 1}, sweep_coords={},
                                 slots=[A.SweepSlot("aaaa", "")], store=store)
    assert not (tmp_path / "o.nc").exists()


def test_each_part_records_its_case_key_and_identity(folder):
    assert sweep("--keep-parts").exit_code == 0
    for path in parts_dir_for(folder / "sw.nc").glob("*.nc"):
        key, identity = P.read_mark(path)
        assert key == path.stem and P.case_hash(identity) == key
        assert identity["materials"]["MoS2"]["wear_coefficient_m2_per_N"] == 1e-13


# ---------------------------------------------------------------------------- item 1: life

def test_a_life_run_resumed_after_the_materials_file_changed_is_refused(folder):
    """Was: the checkpoint's blocks, made with k = 1e-13, were continued with k = 9e-13, exit 0."""
    out = folder / "l.nc"
    checkpoint = checkpoint_path_for(out)
    seen = []

    def stop_at_second(row):
        seen.append(row)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(LifeInterrupted):
        life("case.yaml", QUICK, checkpoint=checkpoint, progress=stop_at_second)
    before = checkpoint.read_bytes()
    edit_materials(folder)
    result = invoke("life", "case.yaml", "-o", out, "-q", "--resume", *sets(QUICK))
    one_error_line(result, 2, str(checkpoint), "of other inputs",
                   "materials MoS2.wear_coefficient_m2_per_N: 1e-13 there, 9e-13 here",
                   "--discard-checkpoint")
    assert checkpoint.read_bytes() == before and not out.exists()
    # moved, with the same values, the checkpoint is continued
    edit_materials(folder, "1.0e-13")
    (folder / "mats.yaml").rename(folder / "moved.yaml")
    (folder / "case.yaml").write_text(CASE.replace("mats.yaml", "moved.yaml"))
    result = invoke("life", "case.yaml", "-o", out, "--resume", *sets(QUICK))
    assert result.exit_code == 0, result.output
    assert f"resuming from {checkpoint}" in result.stderr


# ---------------------------------------------------------------------------- item 2: parts folder

def test_a_parts_folder_with_the_users_files_is_refused_and_left_alone(folder):
    """Was: `sweep -o sw.nc` deleted sw.nc.parts/ with thesis.tex and notes.txt in it, exit 0.
    A netCDF file named like a part, without the mark and not in a ledger, is not ours either."""
    parts = parts_dir_for(folder / "sw.nc")
    parts.mkdir()
    (parts / "thesis.tex").write_text("chapter 1\n")
    (parts / "notes.txt").write_text("notes\n")
    mine = ["notes.txt", "thesis.tex"]
    for extra in ([], ["--overwrite"], ["--resume"], ["--discard-parts"], ["--keep-parts"]):
        if extra == ["--resume"]:
            (parts / "0123456789abcdef.nc").write_bytes(b"CDF\x01 not ours")
            mine.insert(0, "0123456789abcdef.nc")
        one_error_line(sweep(*extra), 2, f"sw.nc.parts holds {len(mine)} file(s) that "
                       f"clearsweep did not write ({', '.join(mine)})")
        assert sorted(p.name for p in parts.iterdir()) == mine
    assert not (folder / "sw.nc").exists()


def test_after_a_sweep_only_its_own_files_are_deleted(tmp_path):
    """A file put into the folder while the sweep runs stays, and the folder with it."""
    status = xr.Dataset({"status": ((), "ok", P.STATUS_ATTRS)})
    store = PartStore(tmp_path / "o.nc.parts")
    store.open()
    store.write("aaaa", status)
    store.log("done", hash="aaaa", status="ok")
    (store.directory / "notes.txt").write_text("mine\n")
    (store.directory / ".notes.txt.swp.tmp").write_text("mine too\n")
    store.remove()
    assert sorted(p.name for p in store.directory.iterdir()) == [".notes.txt.swp.tmp", "notes.txt"]


def test_a_part_named_in_the_ledger_with_its_content_hash_is_clearsweeps_even_unreadable(
        tmp_path):
    """A part whose name and content hash the ledger records is clearsweep's to delete with
    --overwrite, even without a readable mark."""
    d = tmp_path / "o.nc.parts"
    with PartStore(d) as store:
        store.open()
        (d / "0123456789abcdef.nc").write_bytes(b"cut short")
        store.log("done", hash="0123456789abcdef", status="ok",
                  sha256=P.file_sha256(d / "0123456789abcdef.nc"))
    with PartStore(d) as store:
        assert store.strangers() == []
        assert store.open(overwrite=True) == set()
    assert not (d / "0123456789abcdef.nc").exists()


def test_a_users_file_named_like_a_part_and_in_a_ledger_line_is_left_alone(folder):
    """Was: a user's netCDF file named like a part, plus a ledger line naming it, was taken
    for a part and deleted by --overwrite, exit 0. A ledger line proves a file clearsweep's
    only with the content hash of what it wrote."""
    assert sweep("--keep-parts").exit_code == 0
    parts = parts_dir_for(folder / "sw.nc")
    mine = parts / "fedcba9876543210.nc"
    xr.Dataset({"x": ("i", [1.0, 2.0])}).to_netcdf(mine)
    with open(parts / P.LOG_NAME, "a") as log:
        log.write('{"event": "done", "hash": "fedcba9876543210", "status": "ok"}\n')
    before = mine.read_bytes()
    one_error_line(sweep("--overwrite"), 2, "holds 1 file(s) that clearsweep did not write "
                   "(fedcba9876543210.nc)")
    assert mine.read_bytes() == before


def test_each_ledger_line_records_its_parts_content_hash(folder):
    assert sweep("--keep-parts").exit_code == 0
    store = PartStore(parts_dir_for(folder / "sw.nc"))
    done = store.events("done")
    assert len(done) == 2
    for line in done:
        assert line["sha256"] == P.file_sha256(store.path(line["hash"]))


# ---------------------------------------------------------------------------- item 2: -o

def test_o_a_symbolic_link_writes_its_target_and_the_link_stays(folder):
    """Was: the link (dangling or not) was replaced by the results file, exit 0."""
    (folder / "dangling.nc").symlink_to("results/target.nc")
    result = invoke("run", "case.yaml", "-q", "-o", "dangling.nc")
    assert result.exit_code == 0, result.output
    assert (folder / "dangling.nc").is_symlink() and (folder / "results" / "target.nc").is_file()
    (folder / "live.nc").symlink_to("results/target.nc")
    stamp = (folder / "results" / "target.nc").stat().st_ino
    assert invoke("run", "case.yaml", "-q", "-o", "live.nc").exit_code == 0
    assert (folder / "live.nc").is_symlink()
    assert (folder / "results" / "target.nc").stat().st_ino != stamp    # replaced, atomically
    (folder / "loop.nc").symlink_to("loop.nc")
    one_error_line(invoke("run", "case.yaml", "-q", "-o", "loop.nc"), 2,
                   "loop.nc is a symbolic link that never reaches a file")
    assert (folder / "loop.nc").is_symlink()


@pytest.mark.parametrize("first, second, kinds", [
    (["life", "LIFE", *sets(["life.max_blocks=1", "mechanism.speed_rpm=600", "wear.map=[6,12]"])],
     ["run", "LIFE", "--set", "solver.duration=0.002"], ("a life run", "a run")),
    (["run", "case.yaml"], ["sweep", "sw.yaml", "--workers", "1", "--no-progress"],
     ("a run", "a sweep")),
], ids=["run over a life run", "sweep over a run"])
def test_a_results_file_of_another_kind_needs_overwrite(folder, first, second, kinds):
    """Was: `run life.yaml` replaced life.nc, the life run of the same config, exit 0."""
    (folder / "life.yaml").write_text((ROOT / "configs" / "life.yaml").read_text())
    swap = {"LIFE": "life.yaml"}
    result = invoke(*[swap.get(a, a) for a in first], "-q", "-o", "life.nc")
    assert result.exit_code == 0, result.output
    before = (folder / "life.nc").read_bytes()
    command = [swap.get(a, a) for a in second] + ["-q", "-o", "life.nc"]
    one_error_line(invoke(*command), 2, f"life.nc is the results file of {kinds[0]}, and this "
                   f"command writes {kinds[1]}", "--overwrite")
    assert (folder / "life.nc").read_bytes() == before
    assert invoke(*command, "--overwrite").exit_code == 0
    assert invoke(*command).exit_code == 0                 # its own kind: replaced as before


def test_a_users_sweep_log_or_lock_file_is_not_taken_for_clearsweeps(tmp_path):
    """The ledger and the lock are recognised by their content, not their names alone."""
    d = tmp_path / "o.nc.parts"
    d.mkdir()
    (d / "sweep.log").write_text("my own notes on the sweep\n")
    (d / ".lock").write_text("held by my script\n")
    with pytest.raises(StoreError, match=r"holds 2 file\(s\) that clearsweep did not write "
                                         r"\(.lock, sweep.log\)"):
        PartStore(d).open()
    assert (d / "sweep.log").read_text() == "my own notes on the sweep\n"


# ------------------------------------------- issue 40, item 7: every part kept, no output
@pytest.mark.parametrize("config", ["life_sweep.yaml", "reliability.yaml", "mixed_clearances.yaml"])
def test_the_plan_of_a_sweep_with_every_part_kept_says_nothing_is_left_to_run(config):
    """Was: a life or reliability sweep with every part kept ended in `IndexError: list
    index out of range` in the plan's line, before the assembly."""
    from clearsweep.sweeping import expand

    plan = expand(str(ROOT / "configs" / config), ("reliability.members=2",)
                  if config == "reliability.yaml" else ())
    text = plan.describe(2, kept=set(plan.runnable()))
    assert f"0 to {'run' if plan.store in ('life', 'reliability') else 'simulate'}" in text


@pytest.mark.parametrize("quiet", [[], ["-q"]], ids=["", "-q"])
def test_a_reliability_sweep_with_every_part_kept_assembles_on_resume(folder, quiet):
    """Was: `sweep --resume` with every part on disk and no output ended in IndexError."""
    args = ["--set", "reliability.members=2", "--set", "mechanism.speed_rpm=600",
            "--set", "life.max_blocks=1"]
    config = ROOT / "configs" / "reliability.yaml"
    first = invoke("sweep", config, "-o", "rel.nc", "-q", "--keep-parts", *args)
    assert first.exit_code == 0, first.output
    (folder / "rel.nc").rename(folder / "first.nc")
    result = invoke("sweep", config, "-o", "rel.nc", "--resume", *quiet, *args)
    assert result.exit_code == 0, result.output
    with xr.open_dataset(folder / "first.nc") as a, xr.open_dataset(folder / "rel.nc") as b:
        xr.testing.assert_identical(a.drop_attrs(), b.drop_attrs())


# ------------------------------------------------- issue 40, item 2: parts of another store
@pytest.mark.parametrize("first, second", [("full", "summary"), ("summary", "full")])
def test_parts_resumed_under_another_store_are_refused_naming_both(folder, first, second):
    """Was: full parts resumed as summary were accepted (variables missing from the file),
    summary parts resumed as full gave a full sweep file without any time series; exit 0."""
    (folder / "sw.yaml").write_text(SWEEP.replace("store: summary", f"store: {first}"))
    assert sweep("--keep-parts").exit_code == 0
    (folder / "sw.nc").unlink()
    parts = sorted(p.read_bytes() for p in parts_dir_for(folder / "sw.nc").iterdir())
    (folder / "sw.yaml").write_text(SWEEP.replace("store: summary", f"store: {second}"))
    one_error_line(sweep("--resume"), 2, f"store: {first!r} there, {second!r} here")
    assert not (folder / "sw.nc").exists()
    assert sorted(p.read_bytes() for p in parts_dir_for(folder / "sw.nc").iterdir()) == parts


def test_each_part_records_the_store_it_was_made_for(folder):
    assert sweep("--keep-parts").exit_code == 0
    for path in parts_dir_for(folder / "sw.nc").glob("*.nc"):
        assert P.read_mark(path)[1]["store"] == "summary"


def test_assembly_refuses_a_part_made_for_another_store(folder):
    """A part filed under this sweep's key but recording another store (forged, or an older
    clearsweep's) is not assembled: the file would lack what the store needs."""
    assert sweep("--keep-parts").exit_code == 0
    directory = parts_dir_for(folder / "sw.nc")
    path = sorted(directory.glob("*.nc"))[0]
    with xr.open_dataset(path) as ds:
        part = ds.load()
    identity = P.read_mark(path)[1] | {"store": "full"}
    path.unlink()
    P.write_part(directory, path.stem, P.with_identity(part, identity))
    from clearsweep.sweeping import expand

    sw = expand("sw.yaml")
    store = PartStore(directory)
    with pytest.raises(StoreError, match="made for store: full, not for this sweep's store: summary"):
        A.write_sweep_netcdf(folder / "again.nc", sweep_dims=sw.dims, sweep_coords=sw.coords,
                                slots=sw.slots(), store=store, holds=sw.store)
    assert not (folder / "again.nc").exists()


# ------------------------------------------- issue 40, item 3: files named like clearsweep's
def test_an_empty_lock_in_the_parts_folder_is_not_taken_for_clearsweeps(folder):
    """Was: an empty `.lock` in OUT.parts/ was taken for a sweep's lock and deleted, exit 0.
    clearsweep's lock holds its mark (dataset.LOCK_MARK)."""
    parts = parts_dir_for(folder / "sw.nc")
    parts.mkdir()
    (parts / ".lock").write_bytes(b"")
    one_error_line(sweep(), 2, "sw.nc.parts holds 1 file(s) that clearsweep did not write (.lock)")
    assert [p.name for p in parts.iterdir()] == [".lock"] and not (folder / "sw.nc").exists()


def test_a_sweep_lock_holds_clearsweeps_mark_and_goes_after(folder):
    from clearsweep.dataset import LOCK_MARK

    with PartStore(folder / "o.nc.parts") as store:
        store.open()
        assert (store.directory / ".lock").read_bytes() == LOCK_MARK
        assert store.strangers() == []
    store.remove()
    assert not store.directory.exists()


def test_a_users_file_named_like_the_life_checkpoints_lock_is_left_alone(folder):
    """Was: `life -o l.nc` deleted the user's l.nc.life-checkpoint.lock, exit 0."""
    (folder / "l.nc.life-checkpoint.lock").write_text("my notes\n")
    result = invoke("life", "case.yaml", "-o", "l.nc", "-q", *sets(QUICK))
    one_error_line(result, 2, "l.nc.life-checkpoint.lock is not a lock file clearsweep wrote")
    assert (folder / "l.nc.life-checkpoint.lock").read_text() == "my notes\n"
    assert not (folder / "l.nc").exists()


def test_a_users_file_named_like_a_part_temporary_is_left_alone(folder):
    """Was: `.thesis.nc.v2.tmp` in OUT.parts/ was taken for a part's temporary file and
    deleted, exit 0. A temporary is clearsweep's only when named with a case key and begun
    as the netCDF4 file it writes."""
    assert sweep("--keep-parts").exit_code == 0
    (folder / "sw.nc").unlink()
    parts = parts_dir_for(folder / "sw.nc")
    (parts / ".thesis.nc.v2.tmp").write_text("draft\n")
    (parts / ".0123456789abcdef.nc.42.abc_9.tmp").write_text("mine too\n")
    one_error_line(sweep("--resume"), 2, "holds 2 file(s) that clearsweep did not write "
                   "(.0123456789abcdef.nc.42.abc_9.tmp, .thesis.nc.v2.tmp)")
    assert (parts / ".thesis.nc.v2.tmp").read_text() == "draft\n"
    assert (parts / ".0123456789abcdef.nc.42.abc_9.tmp").read_text() == "mine too\n"


def test_a_temporary_a_killed_part_write_left_is_removed_on_resume(folder):
    assert sweep("--keep-parts").exit_code == 0
    (folder / "sw.nc").unlink()
    parts = parts_dir_for(folder / "sw.nc")
    part = sorted(parts.glob("*.nc"))[0]
    left = parts / f".{part.name}.4242.k1lled.tmp"
    left.write_bytes(part.read_bytes()[:2048])        # cut short, as a kill leaves it
    assert sweep("--resume").exit_code == 0
    assert not left.exists() and (folder / "sw.nc").exists()
