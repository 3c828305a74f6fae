"""Uncoated vs PTFE-coated socket at B, and the break-even coating wear coefficient.

Run: ``python docs/wear_study.py`` (about 20 s warm). For each shipped clearance config it
runs B's socket uncoated and PTFE-coated with steel's wear coefficient (the materials
file's flagged assumption), then finds by bisection the PTFE wear coefficient k* below
which the coating lowers B's maximum wear depth. Wear depth is very nearly linear in k
(the worn map's feedback on the contact is small), so the first bracket is found from
one run and confirmed by running on both sides of it.
"""

from __future__ import annotations

from pathlib import Path

from clearsweep.simulation import simulate

ROOT = Path(__file__).resolve().parents[1]
K_STEEL = 8e-14  # m^2/N, Jing & Liu 2023 Table 3


def max_depth(config: Path, coating: str, k: float | None = None) -> tuple[float, float]:
    """(max map depth at B [m], max per-axis paper projection at B [m])."""
    overrides = [f"joints.B.coating={coating}"]
    if k is not None:
        overrides.append(f"joints.B.wear_coefficient={k!r}")
    ds = simulate(config, overrides)
    if str(ds.status.values) != "ok":
        raise RuntimeError(f"{config.name} {coating}: {ds.status.values}")
    b = ds.sel(joint="B")
    return float(b.wear_map.max()), float(b.wear_projection.max())


def main() -> None:
    rows = []
    for name in ("one_clearance", "two_clearances"):
        config = ROOT / "configs" / f"{name}.yaml"
        none_map, none_proj = max_depth(config, "none")
        ptfe_map, ptfe_proj = max_depth(config, "PTFE", K_STEEL)
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
        rows.append((name, none_map, ptfe_map, none_proj, ptfe_proj, lo, hi, below and above))
    print("| config | B max wear depth, uncoated [m] | B max wear depth, PTFE with steel's k [m] "
          "| ratio PTFE / uncoated | paper projection max, uncoated / PTFE [m] "
          "| break-even PTFE k* [m^2/N] |")
    print("|---|---|---|---|---|---|")
    for name, nm, pm, npj, ppj, lo, hi, ok in rows:
        k_text = f"{lo:.3g} .. {hi:.3g}" if ok else "not bracketed"
        print(f"| {name} | {nm:.3e} | {pm:.3e} | {pm / nm:.2f} | {npj:.3e} / {ppj:.3e} | {k_text} |")


if __name__ == "__main__":
    main()
