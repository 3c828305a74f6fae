"""Uncoated vs PTFE-coated socket at B, and the break-even coating wear coefficient.

Run from the repository root: ``.venv/bin/python docs/wear_study.py`` (about 5 s once the
kernel is compiled). For each shipped clearance config, with the config's defaults (seated
start, 144 x 288 wear map spread by the contact-area rule, wear feedback on; docs/physics.md
sections 1.2 and 5), it runs B's socket uncoated and PTFE-coated with steel's wear
coefficient (the materials file's flagged assumption), then finds by bisection the PTFE
wear coefficient k* below which the coating lowers B's maximum wear depth (the largest bin
of ``wear_map``). Wear depth is very nearly linear in k (the worn map's feedback on the
contact is small), so the first bracket is found from one run and confirmed by running on
both sides of it. It also prints B's worn volume (``wear_volume``), which, unlike a
maximum depth, does not depend on the map's grid.

Extra arguments are config overrides applied to every run, e.g.
``.venv/bin/python docs/wear_study.py initial.joints=centred``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from clearsweep.simulation import simulate

ROOT = Path(__file__).resolve().parents[1]
K_STEEL = 8e-14  # m^2/N, Jing & Liu 2023 Table 3
EXTRA: list[str] = []  # overrides from the command line


def max_depth(config: Path, coating: str, k: float | None = None) -> tuple[float, float, float]:
    """(max map depth at B [m], max per-axis paper projection at B [m], worn volume at B [m^3])."""
    overrides = [*EXTRA, f"joints.B.coating={coating}"]
    if k is not None:
        overrides.append(f"joints.B.wear_coefficient={k!r}")
    ds = simulate(config, overrides)
    if str(ds.status.values) != "ok":
        raise RuntimeError(f"{config.name} {coating}: {ds.status.values}")
    b = ds.sel(joint="B")
    return float(b.wear_map.max()), float(b.wear_projection.max()), float(b.wear_volume)


def main() -> None:
    rows = []
    for name in ("one_clearance", "two_clearances"):
        config = ROOT / "configs" / f"{name}.yaml"
        none_map, none_proj, none_vol = max_depth(config, "none")
        ptfe_map, ptfe_proj, ptfe_vol = max_depth(config, "PTFE", K_STEEL)
        k = K_STEEL * none_map / ptfe_map
        lo, hi = 0.9 * k, 1.1 * k
        below = max_depth(config, "PTFE", lo)[0] < none_map
        above = max_depth(config, "PTFE", hi)[0] > none_map
        for _ in range(6 if below and above else 0):
            mid = 0.5 * (lo + hi)
            if max_depth(config, "PTFE", mid)[0] < none_map:
                lo = mid
            else:
                hi = mid
        rows.append((name, none_map, ptfe_map, none_proj, ptfe_proj, none_vol, ptfe_vol, lo, hi,
                     below and above))
    print("| config | B max wear depth, uncoated [m] | B max wear depth, PTFE with steel's k [m] "
          "| ratio PTFE / uncoated | paper projection max, uncoated / PTFE [m] "
          "| B worn volume, uncoated / PTFE [m^3] | break-even PTFE k* [m^2/N] |")
    print("|---|---|---|---|---|---|---|")
    for name, nm, pm, npj, ppj, nv, pv, lo, hi, ok in rows:
        k_text = f"{lo:.3g} .. {hi:.3g}" if ok else "not bracketed"
        print(f"| {name} | {nm:.3e} | {pm:.3e} | {pm / nm:.2f} | {npj:.3e} / {ppj:.3e} "
              f"| {nv:.3e} / {pv:.3e} | {k_text} |")


if __name__ == "__main__":
    EXTRA.extend(sys.argv[1:])
    main()
