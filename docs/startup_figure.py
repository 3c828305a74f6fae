"""Start-up of the two-clearance mechanism: seated vs centred balls, against the ideal mechanism.

Run from the repository root (about 3 s once the kernel is compiled):

    .venv/bin/python docs/startup_figure.py

It simulates ``configs/two_clearances.yaml`` with ``initial.joints=seated`` (the default) and
``initial.joints=centred``, and ``configs/ideal.yaml``, draws the slider acceleration and the
normal contact forces against time (the first 0.1 s, and the settled window t >= 0.05 s) to
``docs/figures/startup/startup_seated_vs_centred.png``, and prints the table of docs/startup.md.

Every number in the table is an every-step statistic of the kernel (docs/physics.md section 8),
never a maximum over the saved rows:

- whole run and settled (t >= metrics.settle_time = 0.05 s): the 1 s run's variables
  ``*_peak`` and ``*_peak_settled``;
- first 0.05 s: the whole-run statistics of the same case run for 0.05 s only;
- t >= 0.5 s: the settled statistics of the 1 s run with ``metrics.settle_time=0.5``.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from clearsweep import simulate  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "figures" / "startup" / "startup_seated_vs_centred.png"
CASES = {  # label: (config, overrides)
    "ideal joints": ("ideal", []),
    "two clearances, seated": ("two_clearances", ["initial.joints=seated"]),
    "two clearances, centred": ("two_clearances", ["initial.joints=centred"]),
}
STYLE = {"ideal joints": ("k", "-"), "two clearances, seated": ("tab:blue", "-"),
         "two clearances, centred": ("tab:red", "-")}


def run(config: str, overrides: list[str]):
    ds = simulate(ROOT / "configs" / f"{config}.yaml", overrides)
    if str(ds.status.values) != "ok":
        raise RuntimeError(f"{config} {overrides}: status {ds.status.values}")
    return ds


def joint_text(ds, name: str, fmt: str) -> str:
    values = [float(ds[name].sel(joint=j)) for j in ("A", "B")]
    if all(v != v for v in values):  # NaN: ideal joints have no contact law
        return "n/a"
    return " / ".join(format(v, fmt) for v in values)


def main() -> None:
    rows = []
    full = {}
    for label, (config, extra) in CASES.items():
        ds = run(config, extra)
        first = run(config, extra + ["solver.duration=0.05"])
        late = run(config, extra + ["metrics.settle_time=0.5"])
        full[label] = ds
        impacts_all = joint_text(ds, "impact_count", ".0f")
        impacts_settled = joint_text(ds, "impact_count_settled", ".0f")
        rows.append((
            label,
            f"{float(ds.slider_acceleration_peak):.3g}",
            f"{float(first.slider_acceleration_peak):.4g}",
            f"{float(ds.slider_acceleration_peak_settled):.3g}",
            f"{float(late.slider_acceleration_peak_settled):.3g}",
            joint_text(first, "normal_force_peak", ".4g"),
            joint_text(ds, "normal_force_peak_settled", ".4g"),
            "n/a" if config == "ideal" else f"{impacts_all} ({impacts_settled})",
        ))
    print("| case | peak slider acc., whole run [m/s^2] | peak, first 0.05 s | "
          "peak, settled t >= 0.05 s | peak, t >= 0.5 s | peak F_N A / B, first 0.05 s [N] | "
          "peak F_N A / B, settled [N] | impacts A / B (settled) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for row in rows:
        print("| " + " | ".join(row) + " |")

    fig, axes = plt.subplots(3, 2, figsize=(11, 9), sharex="col", constrained_layout=True)
    windows = ((0.0, 0.1, "start-up, t < 0.1 s"), (0.05, 1.0, "settled window, t >= 0.05 s"))
    for col, (t0, t1, title) in enumerate(windows):
        for label, ds in full.items():
            color, ls = STYLE[label]
            part = ds.sel(time=slice(t0, t1))
            axes[0, col].plot(part.time, part.slider_acceleration, color=color, ls=ls, lw=0.8,
                              label=label)
            if "seated" in label or "centred" in label:
                for row, joint in ((1, "A"), (2, "B")):
                    axes[row, col].plot(part.time, part.normal_force.sel(joint=joint),
                                        color=color, ls=ls, lw=0.8, label=label)
        axes[0, col].set_title(title)
        axes[0, col].set_ylabel("slider acceleration [m s-2]")
        axes[1, col].set_ylabel("normal force at A [N]")
        axes[2, col].set_ylabel("normal force at B [N]")
        axes[2, col].set_xlabel("time [s]")
        for ax in axes[:, col]:
            ax.axvline(0.05, color="0.5", lw=0.6, ls=":")
    axes[0, 0].legend(loc="lower right", fontsize=8)     # clear of the lines (issue 45 item 6)
    fig.suptitle("configs/two_clearances.yaml, seated vs centred start; configs/ideal.yaml "
                 "(saved rows, every 1e-4 s)", fontsize=10)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=110)
    print(f"wrote {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
