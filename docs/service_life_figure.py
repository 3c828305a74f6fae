"""Figure of docs/service_life.md: final wear depth at B after 10^6 revolutions per coating
and initial clearance, with the shipped wear coefficients and with the what-if of
docs/data/coatings_k_tenth.yaml (each coating's k a tenth of steel's).

Run from the repository root: ``.venv/bin/python docs/service_life_figure.py`` (two life
sweeps of configs/life_sweep.yaml on 2 workers, 49 s and 22 s measured on the 2-core
machine with nothing else running; ``--shipped FILE`` and ``--tenth FILE`` reuse
sweep files made before). Writes docs/figures/service_life/coatings.png and prints each
sweep's wall time and the two ranking tables.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import clearsweep  # noqa: E402
from clearsweep.dataset import open_results  # noqa: E402
from clearsweep.service_life import life_sweep_text  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SWEEP = ROOT / "configs" / "life_sweep.yaml"
TENTH = ROOT / "docs" / "data" / "coatings_k_tenth.yaml"
OUT = ROOT / "docs" / "figures" / "service_life" / "coatings.png"


def sweep_file(given: str | None, path: Path, overrides: list[str]) -> Path:
    if given:
        return Path(given)
    start = time.perf_counter()
    clearsweep.sweep(str(SWEEP), path, workers=2, overrides=overrides, progress=False,
                     overwrite=True).close()
    print(f"{path}: swept in {time.perf_counter() - start:.0f} s on 2 workers")
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shipped")
    ap.add_argument("--tenth")
    args = ap.parse_args()
    files = {
        "wear coefficients as shipped (every coating: steel's 8e-14 m^2/N, assumed)":
            sweep_file(args.shipped, Path("life_sweep.nc"), []),
        "what-if: each coating's k a tenth of steel's":
            sweep_file(args.tenth, Path("life_sweep_k_tenth.nc"), [f"materials_file={TENTH}"]),
    }
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, (title, path) in zip(axes, files.items()):
        with open_results(path) as ds:
            print(title)
            print(life_sweep_text(ds))
            print()
            depth = ds["wear_depth_max_final"].sel(joint="B")
            coatings = [str(c) for c in ds["B_coating"].values]
            x = np.arange(len(coatings))
            for k, clearance in enumerate(ds["B_clearance"].values):
                ax.bar(x + (k - 0.5) * 0.38, 1e6 * depth.sel(B_clearance=clearance).values, 0.38,
                       label=f"initial clearance {1e3 * float(clearance):g} mm")
            thickness = 1e6 * clearsweep.load_config(ROOT / "configs" / "life.yaml").joints.B.coating_thickness
            ax.axhline(thickness, color="k", lw=0.8, ls="--", label="coating thickness")
            ax.set_xticks(x, coatings)
            ax.set_title(title, fontsize=9)
            ax.set_xlabel("coating at B")
    axes[0].set_ylabel("largest wear depth at B after 10^6 revolutions [\u00b5m]")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=120)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
