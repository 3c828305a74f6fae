"""Parts folder, atomic writes and the one-case-at-a-time sweep writer (clearsweep.sweeping.parts and .assemble)."""

from __future__ import annotations

import netCDF4
import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from clearsweep.dataset import open_results, write_netcdf_atomic
from clearsweep.sweeping import assemble as A
from clearsweep.sweeping import parts as P


def _part(status="ok", n_time=5, dt=0.1, offset=0.0, with_series=True) -> xr.Dataset:
    """A small part: time series, a joint array, an int and a bool scalar."""
    ds = xr.Dataset(
        {
            "status": ((), status, P.STATUS_ATTRS),
            "message": ((), "" if status == "ok" else f"stopped: {status}", P.MESSAGE_ATTRS),
            "peak": (("joint",), np.array([1.0, 2.0]) + offset, {"units": "N", "long_name": "peak"}),
            "steps": ((), np.int64(7 + offset), {"long_name": "steps"}),
            "contact": ((), True, {"long_name": "contact seen"}),
            "wall_time": ((), 0.5, {"units": "s", "long_name": "wall time"}),
        },
        coords={"joint": ("joint", ["A", "B"], {"long_name": "joint"})},
    )
    if with_series:
        t = np.arange(n_time) * dt
        ds["x"] = (("time", "joint"), np.stack([t, -t], axis=1) + offset, {"units": "m", "long_name": "x"})
        ds = ds.assign_coords(time=("time", t, {"units": "s", "long_name": "time"}))
    return ds


@pytest.fixture
def parts(tmp_path):
    with P.PartStore(tmp_path / "out.nc.parts") as store:
        store.open()
        yield store


def test_case_hash_is_canonical():
    a = {"solver": {"dt": 1e-5, "duration": 1.0}, "name": "x"}
    b = {"name": "x", "solver": {"duration": 1.0, "dt": 1e-5}}
    assert P.case_hash(a) == P.case_hash(b)
    assert len(P.case_hash(a)) == P.HASH_LENGTH and int(P.case_hash(a), 16) >= 0
    assert P.case_hash(a) != P.case_hash({**a, "name": "y"})


def test_parts_dir_beside_output(tmp_path):
    assert P.parts_dir_for(tmp_path / "r.nc") == tmp_path / "r.nc.parts"


def test_refuses_earlier_parts_unless_resume_or_overwrite(tmp_path):
    d = tmp_path / "o.nc.parts"
    with P.PartStore(d) as store:
        store.open()
        store.write("aaaa", _part())
    with pytest.raises(P.StoreError, match="--resume"):
        P.PartStore(d).open()
    with P.PartStore(d) as store:
        assert store.open(resume=True) == {"aaaa"}
    with P.PartStore(d) as store:
        assert store.open(overwrite=True) == set()
        assert store.finished() == set()
    with pytest.raises(P.StoreError, match="exclude"):
        P.PartStore(d).open(resume=True, overwrite=True)


def test_lock_keeps_a_second_sweep_out(parts):
    with pytest.raises(P.StoreError, match="in use"):
        P.PartStore(parts.directory).open(resume=True)


def test_part_write_is_atomic(parts, monkeypatch):
    """A write that fails half-way leaves neither the part nor its temporary file."""
    real = xr.Dataset.dump_to_store         # what dataset.write_netcdf_atomic writes through

    def crash(self, store, *args, **kwargs):
        real(self, store, *args, **kwargs)      # the bytes are on disk, under the temporary name
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "dump_to_store", crash)
    with pytest.raises(OSError, match="disk full"):
        parts.write("bbbb", _part())
    assert sorted(p.name for p in parts.directory.iterdir()) == [".lock", P.LOG_NAME]


def test_written_files_have_ordinary_permissions(tmp_path, parts):
    """Parts and the sweep file are readable as any new file is (umask), not owner-only."""
    import os

    mask = os.umask(0)
    os.umask(mask)
    parts.write("a", _part())
    out, _ = _assemble(tmp_path, parts, [A.SweepSlot("a")], {"coating": 1},
                       {"coating": ("coating", np.array(["none"], dtype=object), {})})
    for path in (parts.path("a"), out):
        assert path.stat().st_mode & 0o777 == 0o666 & ~mask


def test_open_removes_temporaries_of_a_killed_run(tmp_path):
    d = tmp_path / "o.nc.parts"
    d.mkdir()
    # replaced_on_success's name for a case key, begun as netCDF4 (HDF5) begins a file
    (d / ".cccccccccccccccc.nc.123.x1y2.tmp").write_bytes(b"\x89HDF\r\n\x1a\nhalf a file")
    with P.PartStore(d) as store:
        assert store.open() == set()
    assert not list(d.glob("*.tmp"))


def test_log_records_events_with_run_id(parts):
    parts.log("done", hash="aaaa", status="ok")
    parts.log("done", hash="bbbb", status="error")
    (parts.directory / P.LOG_NAME).open("a").write('{"event": "done", "cut sh')   # a killed write
    done = parts.events("done")
    assert [r["hash"] for r in done] == ["aaaa", "bbbb"]
    assert {r["run"] for r in done} == {parts.run_id}


def _assemble(tmp_path, parts, slots, dims, coords):
    out = tmp_path / "sweep.nc"
    counts = A.write_sweep_netcdf(out, sweep_dims=dims, sweep_coords=coords, slots=slots,
                                  store=parts, attrs={"title": "t"})
    return out, counts


def test_assembly_layout_fill_and_outer_join(tmp_path, parts):
    parts.write("a", _part())
    parts.write("b", _part(n_time=3, offset=10.0))       # a shorter run: time is a prefix
    parts.write("c", xr.Dataset({"status": ((), "unstable_step"), "message": ((), "too stiff"),
                                 "wall_time": ((), 0.1)}))
    slots = [A.SweepSlot("a"), A.SweepSlot("b"), A.SweepSlot("c"),
             A.SweepSlot(None, "excluded by sweep.skip[0]")]
    dims = {"coating": 2, "clearance": 2}
    coords = {"coating": ("coating", np.array(["none", "PTFE"], dtype=object), {}),
              "clearance": ("clearance", np.array([1e-4, 2e-4]), {"units": "m"}),
              "label": ("clearance", np.array(["small", "large"], dtype=object), {})}
    out, counts = _assemble(tmp_path, parts, slots, dims, coords)
    assert counts == {"cases": 4, "failed": 1, "skipped": 1}

    for engine in ("netcdf4", "h5netcdf"):
        with open_results(out, engine=engine) as ds:
            assert ds.attrs["sweep_failed"] == 1 and ds.attrs["title"] == "t"
            assert "label" in ds.coords and ds["label"].dims == ("clearance",)
            assert ds["status"].values.tolist() == [["ok", "ok"], ["unstable_step", "skipped"]]
            assert ds["message"].values[1, 1] == "excluded by sweep.skip[0]"
            x = ds["x"].sel(coating="none", clearance=2e-4, joint="A").values
            np.testing.assert_allclose(x[:3], 10.0 + np.arange(3) * 0.1)
            assert np.isnan(x[3:]).all()
            assert np.isnan(ds["peak"].sel(coating="PTFE")).all()
            # Integers with missing cases decode as floats with NaN; booleans as flags.
            np.testing.assert_array_equal(ds["steps"].values, [[7.0, 17.0], [np.nan, np.nan]])
            assert ds["contact"].attrs["flag_meanings"] == "false true"
            assert ds["time"].dtype == np.float64 and ds["time"].attrs["units"] == "s"
            assert ds["coating"].values.tolist() == ["none", "PTFE"]

    with netCDF4.Dataset(out) as nc:
        x = nc["x"]
        assert x.chunking() == [1, 1, 5, 2]            # one case per chunk
        assert x.filters()["zlib"]
        assert nc["peak"].chunking() == [1, 1, 2]


def test_chunk_copy_equals_decoded_copy(tmp_path, parts, monkeypatch):
    """Whole-case arrays copied as compressed bytes read back as the values written."""
    monkeypatch.setattr(P, "SMALL_ARRAY_BYTES", 0)     # these tiny arrays as one chunk each
    parts.write("a", _part(offset=1.0))
    parts.write("b", _part(offset=2.0))
    slots, dims = [A.SweepSlot("a"), A.SweepSlot("b")], {"k": 2}
    coords = {"k": ("k", np.array([0, 1]), {})}
    copied = []
    real = A._copy_chunks
    monkeypatch.setattr(A, "_copy_chunks", lambda path, raw, check: (copied.extend(raw),
                                                                       real(path, raw, check)))
    fast, _ = _assemble(tmp_path, parts, slots, dims, coords)
    assert {n for _, _, names in copied for n in names} == {"x", "peak"}
    monkeypatch.setattr(A, "_chunk_copyable", lambda *args: False)
    slow = tmp_path / "slow.nc"
    A.write_sweep_netcdf(slow, sweep_dims=dims, sweep_coords=coords, slots=slots, store=parts,
                         attrs={"title": "t"})
    with open_results(fast) as a, open_results(slow) as b:
        xr.testing.assert_identical(a.load(), b.load())
        np.testing.assert_array_equal(a["x"].isel(k=1).values, parts.read("b")["x"].values)


def _netcdf_contents(path) -> dict:
    """Everything netCDF says of a file, in order: dimensions, global attributes, and each
    variable's type, dimensions, storage, filters, attributes (``_FillValue`` included) and
    values."""
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_maskandscale(False)
        return {"dims": [(k, len(d)) for k, d in nc.dimensions.items()],
                "attrs": [(k, repr(nc.getncattr(k))) for k in nc.ncattrs()],
                "variables": [(k, str(v.dtype), v.dimensions, v.chunking(), v.filters(),
                               [(a, repr(v.getncattr(a))) for a in v.ncattrs()],
                               repr(np.asarray(v[...]).tolist()))
                              for k, v in nc.variables.items()]}


@pytest.mark.parametrize("n_time", [5, P.SMALL_ARRAY_BYTES // 8 + 1])
def test_a_part_is_the_file_xarray_writes(tmp_path, n_time):
    """write_part writes parts of numbers and strings with netCDF4 alone (xarray's encoding
    and its writes between definitions were most of a part's cost): the file is the one
    ``to_netcdf`` wrote before, to the attribute order and the fill values, small arrays
    contiguous and large ones compressed."""
    part = _part(n_time=n_time).drop_vars("contact")      # a bool goes through xarray
    part["counts"] = (("joint",), np.array([3, 4], dtype=np.int32), {"long_name": "counts"})
    part["shape_m"] = ((), 0.25, {"units": "m", "range": [0.0, 1.0], "n": np.int64(2)})
    part = P.with_identity(part.assign_attrs(title="t", count=3, ratio=0.5), {"config": {}})
    assert P._plain(part)
    written = P.write_part(tmp_path, "h", part)
    before = tmp_path / "before.nc"
    write_netcdf_atomic(part.assign_attrs({P.KEY_ATTR: "h"}), before, encoding=P._encoding(part))
    assert _netcdf_contents(written) == _netcdf_contents(before)
    with open_results(written) as a, open_results(before) as b:
        xr.testing.assert_identical(a.load(), b.load())


@pytest.mark.parametrize("compress", ["isal", "zlib"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.int64, np.int32, np.int8, ">f8", ">i4"])
def test_a_deflated_chunk_reads_back_through_hdf5(tmp_path, dtype, compress, monkeypatch):
    """A large array's chunk, shuffled and deflated by write_part itself (ISA-L, or zlib
    without it) and written as bytes, is what HDF5's own filters give back: the values, NaN
    and infinities included, under the variable's declared filters, with no filter skipped."""
    import zlib

    import h5py

    if compress == "zlib":
        monkeypatch.setattr(P, "_compress", zlib.compress)
    rng = np.random.default_rng(7)
    shape = (P.SMALL_ARRAY_BYTES // 8 + 3, 4, 3)
    values = (rng.standard_normal(shape) * 1e3 if np.dtype(dtype).kind == "f"
              else rng.integers(-3, 4, shape)).astype(dtype)     # counts: small integers
    if values.dtype.kind == "f":
        values[1, 2, 0], values[5, 0, 1], values[7, 3, 2] = np.nan, np.inf, -np.inf
    part = xr.Dataset({"x": (("time", "joint", "axis"), values)})
    written = P.write_part(tmp_path, "h", part)
    with netCDF4.Dataset(written) as nc:
        nc.set_auto_maskandscale(False)
        assert nc["x"].filters()["zlib"] and nc["x"].filters()["shuffle"]
        assert nc["x"].chunking() == list(values.shape)
        np.testing.assert_array_equal(nc["x"][...], values)
    with h5py.File(written) as h5:
        mask, raw = h5["x"].id.read_direct_chunk((0, 0, 0))
        assert mask == 0 and len(raw) < values.nbytes
        native = values.astype(values.dtype.newbyteorder("="))
        assert zlib.decompress(raw) == np.ascontiguousarray(
            native.reshape(-1).view(np.uint8).reshape(-1, values.itemsize).T).tobytes()


def test_small_arrays_are_contiguous_in_parts_and_chunked_in_the_sweep(tmp_path, parts):
    """A part stores arrays under SMALL_ARRAY_BYTES as they are (an HDF5 chunk and its filters
    cost more than their values); the sweep file compresses them one case per chunk all the same."""
    parts.write("a", _part(n_time=P.SMALL_ARRAY_BYTES // 16 + 1))
    with netCDF4.Dataset(parts.path("a")) as nc:
        assert nc["peak"].chunking() == "contiguous" and not nc["peak"].filters()["zlib"]
        assert nc["x"].chunking() == list(nc["x"].shape) and nc["x"].filters()["zlib"]
    out, _ = _assemble(tmp_path, parts, [A.SweepSlot("a")], {"k": 1},
                       {"k": ("k", np.array([0]), {})})
    with netCDF4.Dataset(out) as nc:
        assert nc["peak"].chunking() == [1, 2] and nc["peak"].filters()["zlib"]
        assert nc["peak"].filters()["shuffle"]


def test_assembly_opens_each_part_once_and_the_same_without_the_scan_cache(tmp_path, parts,
                                                                           monkeypatch):
    """The scan keeps what the copy pass needs of each part (was: every part opened twice by
    netCDF4); past SCAN_CACHE_BYTES parts are opened again, and the file is the same."""
    for k, offset in enumerate((1.0, 2.0, 3.0)):
        parts.write(f"p{k}", _part(offset=offset, n_time=4 + k))
    slots, dims = [A.SweepSlot(f"p{k}") for k in range(3)], {"k": 3}
    coords = {"k": ("k", np.array([0, 1, 2]), {})}
    opened = []
    real = A._open_part
    monkeypatch.setattr(A, "_open_part", lambda path: (opened.append(path), real(path))[1])
    cached, _ = _assemble(tmp_path, parts, slots, dims, coords)
    assert sorted(opened) == sorted(parts.path(f"p{k}") for k in range(3))
    opened.clear()
    monkeypatch.setattr(A, "SCAN_CACHE_BYTES", 0)
    reopened = tmp_path / "reopened.nc"
    A.write_sweep_netcdf(reopened, sweep_dims=dims, sweep_coords=coords, slots=slots, store=parts,
                         attrs={"title": "t"})
    assert len(opened) == 6
    with open_results(cached) as a, open_results(reopened) as b:
        xr.testing.assert_identical(a.load(), b.load())


def test_assembly_refuses_missing_part(tmp_path, parts):
    with pytest.raises(P.StoreError, match="--resume"):
        _assemble(tmp_path, parts, [A.SweepSlot("nope")], {"k": 1},
                  {"k": ("k", np.array([1]), {})})
    assert not (tmp_path / "sweep.nc").exists()
    assert not list(tmp_path.glob(".sweep.nc*"))


def test_assembly_interrupted_leaves_no_file(tmp_path, parts):
    parts.write("a", _part())
    calls = []

    def check():
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        A.write_sweep_netcdf(tmp_path / "s.nc", sweep_dims={"k": 2},
                             sweep_coords={"k": ("k", np.array([0, 1]), {})},
                             slots=[A.SweepSlot("a"), A.SweepSlot("a")], store=parts, check=check)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.nc.parts"]


def test_assembly_reorders_label_coordinates(tmp_path, parts):
    """A part whose labels come in another order lands in the right places."""
    parts.write("a", _part())
    parts.write("b", _part().isel(joint=[1, 0]))
    out, _ = _assemble(tmp_path, parts, [A.SweepSlot("a"), A.SweepSlot("b")], {"k": 2},
                       {"k": ("k", np.array([0, 1]), {})})
    with open_results(out) as ds:
        xr.testing.assert_equal(ds["peak"].isel(k=0, drop=True), ds["peak"].isel(k=1, drop=True))
        assert ds["joint"].values.tolist() == ["A", "B"]


@settings(max_examples=15, deadline=None)
@given(labels=st.lists(st.text(st.characters(min_codepoint=33, max_codepoint=0x2FF), min_size=1,
                               max_size=8), min_size=1, max_size=4, unique=True),
       numbers=st.lists(st.floats(-1e9, 1e9, allow_nan=False, width=64), min_size=1, max_size=3,
                        unique=True))
def test_sweep_coordinates_round_trip(tmp_path_factory, labels, numbers):
    tmp = tmp_path_factory.mktemp("rt")
    with P.PartStore(tmp / "o.nc.parts") as store:
        store.open()
        store.write("a", _part(with_series=False))
        slots = [A.SweepSlot("a")] * (len(labels) * len(numbers))
        out = tmp / "o.nc"
        A.write_sweep_netcdf(out, sweep_dims={"m": len(labels), "v": len(numbers)},
                             sweep_coords={"m": ("m", np.array(labels, dtype=object), {}),
                                           "v": ("v", np.array(numbers), {})},
                             slots=slots, store=store)
    for engine in ("netcdf4", "h5netcdf"):
        with open_results(out, engine=engine) as ds:
            assert ds["m"].values.tolist() == labels
            assert ds["v"].values.tolist() == numbers
            assert ds.sel(m=labels[-1], v=numbers[0])["status"].item() == "ok"


@pytest.mark.parametrize("store", ["full", "summary"])
def test_a_cases_part_is_its_dataset_and_summaries_whatever_their_coordinates(store):
    """The worker's part (bare variables assigned, not DataArrays aligned): the time series
    (full store), every summary with its attributes, an empty message; a summary with a
    coordinate of its own keeps it."""
    from clearsweep.sweeping.worker import _part as case_part

    ds = _part().assign(status=((), "ok"))

    def summarize(d):
        return xr.Dataset({"x_peak": ("joint", d["x"].max("time").values, {"units": "m"}),
                           "y_peak": ("band", [1.0, 2.0])},
                          coords={"joint": d["joint"], "band": ("band", ["lo", "hi"])})

    for summary in (summarize, lambda d: summarize(d).drop_vars(["y_peak", "band"])):
        got = case_part(ds, store, summary)
        expected = (ds if store == "full" else summary(ds)).assign(
            {**summary(ds).data_vars, "message": ((), "", P.MESSAGE_ATTRS)})
        xr.testing.assert_identical(got, expected)
        assert list(got.variables) == list(expected.variables)
