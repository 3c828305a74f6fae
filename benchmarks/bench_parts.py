"""Part-file formats: milliseconds per part to write and to read back, and bytes per part.

Run: ``python benchmarks/bench_parts.py [--parts 30] [--repeats 3]``; prints markdown.

One case of the main job (``configs/coating_clearance.yaml``'s first case, its own
duration) is simulated once, and its part is built as a sweep worker builds it for the
summary store and for the full store. Each format then writes ``--parts`` copies of that
part through ``dataset.write_netcdf_atomic`` (temporary file and rename, as parts are
written) and reads each back as assembly does (``dataset.open_results``, then ``load``).
The formats alternate within each repeat; the best repeat of each is printed, so that a
busy machine slows every format alike. The formats: netCDF4 with zlib level 1 and shuffle
in one chunk per variable (the parts' format before this benchmark), the same with small
arrays as they are, the same file written by ``parts.write_part`` (netCDF4 defines it;
the large arrays' chunks, deflated by zlib or by ISA-L (the parts now), are written as
bytes), npz, netCDF4 without compression, h5netcdf with gzip level 1 and shuffle, and
h5netcdf without compression.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import time
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _chunked(ds, compression: dict) -> dict:
    return {str(name): {**compression, "chunksizes": var.shape}
            for name, var in ds.variables.items()
            if var.ndim and var.dtype.kind in "biuf" and all(var.shape)}


def _parts_encoding(ds) -> dict:
    from clearsweep.sweeping.parts import _encoding

    return _encoding(ds)


#: name -> (engine, encoding of a dataset); engine "npz": numpy.savez + JSON attributes;
#: engine "part": ``parts.write_part``, the parts' own writer (its own encoding)
FORMATS = {
    "netcdf4, zlib 1 + shuffle": ("netcdf4", lambda ds: _chunked(
        ds, {"zlib": True, "complevel": 1, "shuffle": True})),
    "netcdf4, zlib 1 + shuffle, small arrays contiguous": ("netcdf4", _parts_encoding),
    "parts.write_part, chunks deflated by zlib (netCDF4 alone: every variable defined, then "
    "the values; the chunks written as bytes)": ("part-zlib", lambda ds: {}),
    "parts.write_part, chunks deflated by ISA-L (the parts now)": ("part", lambda ds: {}),
    "npz + JSON attributes": ("npz", lambda ds: {}),
    "netcdf4, uncompressed": ("netcdf4", lambda ds: {}),
    "h5netcdf, gzip 1 + shuffle": ("h5netcdf", lambda ds: _chunked(
        ds, {"compression": "gzip", "compression_opts": 1, "shuffle": True})),
    "h5netcdf, uncompressed": ("h5netcdf", lambda ds: {}),
}


def parts() -> dict:
    """The main job's first case as a summary part and as a full part."""
    import yaml

    from clearsweep.sweeping import expand
    from clearsweep.sweeping.worker import CaseTask, _run_case

    doc = yaml.safe_load((ROOT / "configs" / "coating_clearance.yaml").read_text())
    doc["base"] = str(ROOT / "configs" / doc["base"]) if isinstance(doc.get("base"), str) \
        else doc.get("base")
    plan = expand(doc, [], max_cases=None)
    cfg = next(c.config for c in plan.cases if c.config is not None)
    return {store: _run_case(CaseTask(cfg, store)) for store in ("summary", "full")}


def _write_npz(part, path: Path) -> None:
    """The values as one .npz (strings as unicode arrays) and the attributes as JSON, each
    written to a temporary file and renamed."""
    import numpy as np

    values = {name: np.asarray(var.values, dtype=str) if var.dtype.kind == "O" else var.values
              for name, var in part.variables.items()}
    meta = {"attrs": {k: str(v) for k, v in part.attrs.items()},
            "variables": {name: {"dims": list(var.dims), "attrs": {k: str(v) for k, v in
                                                                   var.attrs.items()}}
                          for name, var in part.variables.items()}}
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "wb") as f:
        np.savez(f, **values)
    os.replace(tmp, path)
    json_path = path.with_suffix(".json")
    json_path.with_name(f".{json_path.name}.tmp").write_text(json.dumps(meta))
    os.replace(json_path.with_name(f".{json_path.name}.tmp"), json_path)


def _read_npz(path: Path):
    import numpy as np
    import xarray as xr

    meta = json.loads(path.with_suffix(".json").read_text())
    with np.load(path, allow_pickle=False) as z:
        return xr.Dataset({name: (v["dims"], z[name], v["attrs"])
                           for name, v in meta["variables"].items()}, attrs=meta["attrs"])


def time_format(part, engine: str, encoding: dict, n: int, folder: Path) -> tuple[float, float, int]:
    """Seconds per part to write and to read back n parts; bytes per part."""
    from clearsweep.dataset import open_results, write_netcdf_atomic
    from clearsweep.sweeping.parts import write_part

    paths = [folder / f"{k}.nc" for k in range(n)]
    start = time.perf_counter()
    for path in paths:
        if engine == "npz":
            _write_npz(part, path)
        elif engine.startswith("part"):
            write_part(folder, path.stem, part)
        else:
            write_netcdf_atomic(part, path, encoding=encoding, engine=engine)
    written = time.perf_counter()
    for path in paths:
        if engine == "npz":
            _read_npz(path)
            continue
        with open_results(path, engine="netcdf4" if engine.startswith("part") else engine) as ds:
            ds.load()
    read = time.perf_counter()
    size = paths[0].stat().st_size + (paths[0].with_suffix(".json").stat().st_size
                                      if engine == "npz" else 0)
    for path in paths:
        path.unlink()
        path.with_suffix(".json").unlink(missing_ok=True)
    return (written - start) / n, (read - written) / n, size


@contextlib.contextmanager
def _deflate(compress):
    """``parts.write_part`` deflating its chunks with ``compress`` (None: its own, ISA-L)."""
    from clearsweep.sweeping import parts as P

    own = P._compress
    P._compress = compress or own
    try:
        yield
    finally:
        P._compress = own


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--parts", type=int, default=30, help="parts written per format and repeat")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    built = parts()
    for store, part in built.items():
        best: dict[str, tuple[float, float, int]] = {}
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(args.repeats):
                for name, (engine, encoding) in FORMATS.items():
                    with _deflate(zlib.compress if engine == "part-zlib" else None):
                        w, r, size = time_format(part, engine, encoding(part), args.parts,
                                                 Path(tmp))
                    old = best.get(name)
                    best[name] = (min(w, old[0]), min(r, old[1]), size) if old else (w, r, size)
        print(f"\n{store} store: {len(part.data_vars)} variables, "
              f"{sum(v.nbytes for v in part.data_vars.values()) / 1e3:,.0f} kB in memory; "
              f"best of {args.repeats} x {args.parts} parts\n")
        print("| format | write [ms/part] | read [ms/part] | file [kB] |")
        print("|---|---|---|---|")
        for name, (w, r, size) in best.items():
            print(f"| {name} | {1e3 * w:.1f} | {1e3 * r:.1f} | {size / 1e3:,.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
