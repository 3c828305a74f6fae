"""Max wear depth of every shipped config at its wear map and at twice the resolution.

Run from the repository root: ``.venv/bin/python docs/map_convergence.py`` (add ``--short``
for the short runs of the fast test, ``--only NAME`` for one config, ``--set KEY=VALUE`` for
an override of both runs, e.g. another map; ``--json`` adds, for a life run, each joint's
ratio of depths and of worn volumes). A map's largest bin
depth (``wear_depth_max_final``, a life run's ``wear_depth_max`` at its end) converges from
below as the map is refined (docs/physics.md section 5): a bin wider than the contact cap
spreads the cap's volume over the bin. For each config that reports a max depth it runs
every case at the config's ``wear.map`` [npolar, nazim] and at [2 npolar, 2 nazim], and
prints, over every case and clearance joint, the largest depth at each map and the worst
(lowest) ratio of a case's depth at the map to its depth at twice the resolution.
``tests/test_map_convergence.py`` pins the table: a shipped config's depth is within
:data:`TOLERANCE` of the finer map's. ``ideal`` (no clearance) has no wear.

Short runs (``--short``) use ``solver.duration`` 0.25 s (a quarter revolution at 60 r/min),
a life run of 3 blocks, and ensembles of 4 members; the full runs take the configs as
shipped but for life runs, which stop after ``life.max_blocks=12`` blocks.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: A shipped config's depth may be at most this much below the depth at twice its map.
TOLERANCE = 0.10

#: Shipped configs that report a max wear depth: (file, kind, overrides of the short run,
#: overrides of the full run).
CONFIGS = {
    "one_clearance": ("one_clearance.yaml", "case", ["solver.duration=0.25"], []),
    "two_clearances": ("two_clearances.yaml", "case", ["solver.duration=0.25"], []),
    "paper_case": ("paper_case.yaml", "case", ["solver.duration=0.25"], []),
    "coating_clearance": ("coating_clearance.yaml", "sweep", ["solver.duration=0.25"], []),
    "paper": ("paper.yaml", "sweep", ["solver.duration=0.25"], []),
    "contact_laws": ("contact_laws.yaml", "sweep", ["solver.duration=0.25"], []),
    "revolute_clearance": ("revolute_clearance.yaml", "sweep", ["solver.duration=0.25"], []),
    "coating_ensemble": ("coating_ensemble.yaml", "sweep", ["ensemble.members=4", "solver.duration=0.25"],
                         []),
    "life": ("life.yaml", "life", ["life.max_blocks=3"], ["life.max_blocks=12"]),
    # a reliability sweep's members are life runs of its base: member 0's, unperturbed
    "reliability": ("reliability.yaml", "reliability", ["life.max_blocks=3"], ["life.max_blocks=12"]),
    # all four joints clear: the guide's walls hold the corners' track depth (physics.md 5.7)
    "reliability_joints": ("reliability_joints.yaml", "reliability", ["life.max_blocks=3"],
                           ["life.max_blocks=12"]),
    # the slider-crank benchmark (5 revolutions at 5000 r/min) and its life run
    "slider_crank": ("slider_crank.yaml", "case", ["solver.revolutions=1"], []),
    "slider_crank_life": ("slider_crank_life.yaml", "life", ["life.max_blocks=3"],
                          ["life.max_blocks=12"]),
}


def _depths(name: str, kind: str, overrides: list[str], workers: int,
            client=None) -> tuple[list[int], np.ndarray, np.ndarray | None]:
    """The config's wear map, the max depth [m] of every case and clearance joint (NaN
    where the joint is ideal or nothing wore) and, for a life run, each joint's worn volume
    [m^3] (None otherwise); a sweep runs on ``workers`` processes, or on ``client`` (an
    executor of warm workers, see ``run_sweep``) where given."""
    from clearsweep.config import load_config

    path = ROOT / "configs" / CONFIGS[name][0]
    volume = None
    if kind == "case":
        from clearsweep.simulation import simulate

        ds = simulate(path, overrides)
        shape, depth = load_config(path, overrides).wear.map, ds.wear_map.max(("polar", "azimuth"))
    elif kind in ("life", "reliability"):
        from clearsweep.service_life import life

        cfg = load_config(path, overrides) if kind == "life" else _sweep_base(path, overrides)
        ds = life(cfg)
        shape, depth = cfg.wear.map, ds.wear_depth_max.isel(cycle=-1)
        volume = ds.wear_volume.isel(cycle=-1).values
    else:
        import yaml

        from clearsweep.sweeping import run_sweep

        # the summary store holds the same wear_depth_max_final as the full one, without
        # writing every case's series and maps (the sweep file's folder holds no includes)
        spec = yaml.safe_load(path.read_text())
        if spec.get("store", "full") == "full":
            spec["store"] = "summary"
        ds = run_sweep(spec, workers=workers, client=client, overrides=overrides, progress=False)
        depth = (ds["wear_depth_max_final_mean"] if "wear_depth_max_final_mean" in ds
                 else ds["wear_depth_max_final"])
        base = yaml.safe_load(ds.attrs["sweep_config"])["base"]
        shape = base["wear"]["map"]
    values = np.asarray(depth.values, dtype=float).ravel()
    return list(shape), np.where(values > 0.0, values, np.nan), volume


def _sweep_base(path: Path, overrides: list[str]):
    """The resolved base case of a sweep file, with ``overrides``."""
    from clearsweep.sweeping import expand

    return expand(path).base.replace(*overrides)


def measure(name: str, short: bool, workers: int = 1, client=None,
            extra: tuple[str, ...] = ()) -> dict:
    """One row of the table for config ``name`` (``workers``, ``client``: see :func:`_depths`),
    ``extra`` overrides on both maps' runs (``wear.map=[n, m]``: that map and its double)."""
    _, kind, short_overrides, full_overrides = CONFIGS[name]
    overrides = [*(short_overrides if short else full_overrides), *extra]
    shape, coarse, volume = _depths(name, kind, overrides, workers, client)
    fine_shape = [2 * shape[0], 2 * shape[1]]
    _, fine, fine_volume = _depths(name, kind, [*overrides, f"wear.map={fine_shape}"], workers,
                                   client)
    with np.errstate(invalid="ignore"):
        ratio = coarse / fine
    row = {"config": name, "map": shape, "fine_map": fine_shape,
           "depth_max": float(np.nanmax(coarse)), "fine_depth_max": float(np.nanmax(fine)),
           "worst_ratio": float(np.nanmin(ratio)), "short": short}
    if volume is not None:
        # a life run's joints: each one's depth ratio and worn volume ratio (NaN: ideal)
        from clearsweep.core.joints import JOINTS

        with np.errstate(invalid="ignore", divide="ignore"):
            vratio = np.where(volume > 0.0, volume / fine_volume, np.nan)
        row["joint_depth_ratio"] = {j.name: float(r) for j, r in zip(JOINTS, ratio)}
        row["joint_volume_ratio"] = {j.name: float(r) for j, r in zip(JOINTS, vratio)}
    return row


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", action="store_true", help="the short runs of the fast test")
    parser.add_argument("--only", action="append", choices=list(CONFIGS), help="one config")
    parser.add_argument("--workers", type=int, default=1, help="worker processes of the sweeps")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON lines")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="an override of both runs, e.g. 'wear.map=[36, 72]'")
    args = parser.parse_args(argv)
    print("| config | map | max depth [m] | map x 2 | max depth [m] | worst case ratio | within "
          f"{TOLERANCE:.0%} |")
    print("|---|---|---|---|---|---|---|")
    for name in args.only or CONFIGS:
        row = measure(name, args.short, args.workers, extra=tuple(args.set))
        if args.json:
            print(json.dumps(row))
            continue
        ok = row["worst_ratio"] >= 1.0 - TOLERANCE
        print(f"| {name} | {row['map'][0]} x {row['map'][1]} | {row['depth_max']:.3e} | "
              f"{row['fine_map'][0]} x {row['fine_map'][1]} | {row['fine_depth_max']:.3e} | "
              f"{row['worst_ratio']:.3f} | {'yes' if ok else 'no'} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
