"""Part-file formats: milliseconds per part to write and to read back, and bytes per part.

Run: ``python benchmarks/bench_parts.py [--parts 30] [--repeats 3]``; prints markdown.

One case of the main job (``configs/coating_clearance.yaml``'s first case, its own
duration) is simulated once, and its part is built as a sweep worker builds it for the
summary store and for the full store. Each format then writes ``--parts`` copies of that
part through ``dataset.write_netcdf_atomic`` (temporary file and rename, as parts are
written) and reads each back as assembly does (``dataset.open_results``, then ``load``).
The formats alternate within each repeat; the best repeat of each is printed, so that a
busy machine slows every format alike. The formats: netCDF4 with zlib level 1 and shuffle
in one chunk per variable (the parts' format before this benchmark), the same without
compression, h5netcdf with gzip level 1 and shuffle, and h5netcdf without compression.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _chunked(ds, compression: dict) -> dict:
    return {str(name): {**compression, "chunksizes": var.shape}
            for name, var in ds.variables.items()
            if var.ndim and var.dtype.kind in "biuf" and all(var.shape)}


#: name -> (engine, encoding of a dataset)
FORMATS = {
    "netcdf4, zlib 1 + shuffle": ("netcdf4", lambda ds: _chunked(
        ds, {"zlib": True, "complevel": 1, "shuffle": True})),
    "netcdf4, uncompressed": ("netcdf4", lambda ds: {}),
    "h5netcdf, gzip 1 + shuffle": ("h5netcdf", lambda ds: _chunked(
        ds, {"compression": "gzip", "compression_opts": 1, "shuffle": True})),
    "h5netcdf, uncompressed": ("h5netcdf", lambda ds: {}),
}


def parts() -> dict:
    """The main job's first case as a summary part and as a full part."""
    import yaml

    from clearsweep.sweeping import expand
    from clearsweep.sweeping.worker import _run_case

    doc = yaml.safe_load((ROOT / "configs" / "coating_clearance.yaml").read_text())
    doc["base"] = str(ROOT / "configs" / doc["base"]) if isinstance(doc.get("base"), str) \
        else doc.get("base")
    plan = expand(doc, [], max_cases=None)
    cfg = next(c.config for c in plan.cases if c.config is not None)
    return {store: _run_case((cfg, store, None, None)) for store in ("summary", "full")}


def time_format(part, engine: str, encoding: dict, n: int, folder: Path) -> tuple[float, float, int]:
    """Seconds per part to write and to read back n parts; bytes per part."""
    from clearsweep.dataset import open_results, write_netcdf_atomic

    paths = [folder / f"{k}.nc" for k in range(n)]
    start = time.perf_counter()
    for path in paths:
        write_netcdf_atomic(part, path, encoding=encoding, engine=engine)
    written = time.perf_counter()
    for path in paths:
        with open_results(path, engine=engine) as ds:
            ds.load()
    read = time.perf_counter()
    size = paths[0].stat().st_size
    for path in paths:
        path.unlink()
    return (written - start) / n, (read - written) / n, size


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
                    w, r, size = time_format(part, engine, encoding(part), args.parts, Path(tmp))
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
