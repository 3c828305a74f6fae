"""The slider-crank benchmark's figures of docs/mechanisms.md.

Run from the repository root (about a minute once the kernel is compiled):

    .venv/bin/python docs/mechanisms_figures.py

It simulates ``configs/slider_crank.yaml`` (0.5 mm radial clearance at the rod-slider joint
B, 5000 r/min, 5 crank revolutions) and draws to ``docs/figures/mechanisms/``:

- ``slider_acceleration.png``: the slider's velocity and acceleration over the 2nd and 3rd
  revolutions against the ideal mechanism's closed form
  (``params.slider_crank_kinematics``, which the ideal slider-crank's kernel run matches to
  2e-12 relative);
- ``orbit.png``: the pin centre's path in its bearing (B's offset in the mechanism's plane,
  y along the guide and z across it), revolutions 1 to 5;
- ``contact_force.png``: B's normal contact force over revolutions 2 to 5;
- ``poincare.png``: the pin centre once a revolution (at crank angle 0) over 100
  revolutions, at 0.5 mm and at 0.1 mm of clearance (``--set solver.revolutions=100``,
  ``--set joints.B.clearance=1e-4``), against an unworn bearing (``--set
  wear.feedback=false``, as configs/bifurcation.yaml: the clearance's dynamics alone; with
  the wear fed back both runs end ok too); the pins stay in the mechanism's plane
  (docs/mechanisms.md, "In the plane"), and the script prints the largest offset across it.

It prints the numbers the page quotes.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from clearsweep import simulate  # noqa: E402
from clearsweep.config import load_config  # noqa: E402
from clearsweep.params import PRESETS, slider_crank_kinematics  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "slider_crank.yaml"
OUT = ROOT / "docs" / "figures" / "mechanisms"


def run(overrides: list[str]):
    ds = simulate(CONFIG, overrides)
    if str(ds.status.values) != "ok":
        raise RuntimeError(f"{overrides}: status {ds.status.values}")
    return ds


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    cfg = load_config(CONFIG)
    preset = PRESETS[cfg.mechanism.preset]
    omega = cfg.mechanism.speed_rpm * 2.0 * math.pi / 60.0
    period = 60.0 / cfg.mechanism.speed_rpm
    ds = run([])
    t = ds.time.values
    theta = ds.crank_angle.values
    _, v_ideal, a_ideal = slider_crank_kinematics(theta, omega, preset.crank_length_m,
                                                  preset.rod_length_m, preset.slider_height_m)
    offset = ds.ball_offset.sel(joint="B")
    force = ds.normal_force.sel(joint="B").values
    print(f"peak slider acceleration: ideal {np.abs(a_ideal).max():.4g} m/s^2, with clearance "
          f"{float(ds.slider_acceleration_peak):.4g} (settled {float(ds.slider_acceleration_peak_settled):.4g})")
    print(f"peak normal force at B {float(ds.normal_force_peak.sel(joint='B')):.4g} N; impacts "
          f"{int(ds.impact_count.sel(joint='B'))} ({int(ds.impact_count_settled.sel(joint='B'))} "
          f"settled); contact fraction {float(ds.contact_fraction.sel(joint='B')):.3f}; largest "
          f"penetration {float(ds.penetration_peak.sel(joint='B')) * 1e6:.1f} um; largest offset "
          f"across the plane {float(np.abs(offset.sel(axis='x')).max()):.2g} m")
    print(f"largest slider velocity: ideal {np.abs(v_ideal).max():.4g} m/s, with clearance "
          f"{float(np.abs(ds.slider_velocity).max()):.4g} m/s")

    # slider velocity and acceleration, revolutions 2 and 3
    window = (t >= period) & (t <= 3.0 * period)
    deg = np.degrees(theta[window])
    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, constrained_layout=True)
    for ax, name, ideal, unit in ((axes[0], "slider_velocity", v_ideal, "m s-1"),
                                  (axes[1], "slider_acceleration", a_ideal, "m s-2")):
        ax.plot(deg, ds[name].values[window], color="tab:red", lw=0.7, label="0.5 mm clearance at B")
        ax.plot(deg, ideal[window], color="k", lw=1.0, label="ideal joints (closed form)")
        ax.set_ylabel(f"{name.replace('_', ' ')} [{unit}]")
        ax.grid(alpha=0.3)
    axes[1].set_xlabel("crank angle theta [degree] (TDC at 90 + 360 k)")
    axes[0].legend(loc="upper right", fontsize=8)
    fig.suptitle("Slider-crank benchmark, 5000 r/min: the slider along its guide "
                 "(configs/slider_crank.yaml, revolutions 2-3)", fontsize=10)
    fig.savefig(OUT / "slider_acceleration.png", dpi=110)
    plt.close(fig)

    # the pin centre's orbit in its bearing
    c = cfg.joints.B.clearance
    fig, ax = plt.subplots(figsize=(5.5, 5.5), constrained_layout=True)
    ring = np.linspace(0.0, 2.0 * math.pi, 361)
    ax.plot(c * 1e3 * np.cos(ring), c * 1e3 * np.sin(ring), "k--", lw=0.8, label="clearance circle")
    ax.plot(offset.sel(axis="y") * 1e3, offset.sel(axis="z") * 1e3, color="tab:red", lw=0.5,
            label="pin centre")
    ax.plot(0.0, 0.0, "k+", ms=8)
    ax.set_aspect("equal")
    ax.set_xlabel("d_y (along the guide) [mm]")
    ax.set_ylabel("d_z (across the guide) [mm]")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title("Pin centre in its bearing, joint B, revolutions 1-5", fontsize=10)
    fig.savefig(OUT / "orbit.png", dpi=110)
    plt.close(fig)

    # B's normal contact force, revolutions 2 to 5
    window = t >= period
    fig, ax = plt.subplots(figsize=(9, 3.5), constrained_layout=True)
    ax.plot(np.degrees(theta[window]), force[window] * 1e-3, color="tab:red", lw=0.6)
    ax.set_xlabel("crank angle theta [degree] (TDC at 90 + 360 k)")
    ax.set_ylabel("normal contact force at B [kN]")
    ax.grid(alpha=0.3)
    ax.set_title("Contact force in the rod-slider joint B, revolutions 2-5", fontsize=10)
    fig.savefig(OUT / "contact_force.png", dpi=110)
    plt.close(fig)

    # Poincare sections over 100 revolutions at two clearances
    fig, axes = plt.subplots(1, 2, figsize=(10, 5), constrained_layout=True)
    for ax, clearance in zip(axes, (5e-4, 1e-4)):
        long = run(["solver.revolutions=100", f"joints.B.clearance={clearance}",
                    "solver.save_every=400", "wear.feedback=false"])
        sec = long.poincare_offset.sel(joint="B")
        held = sec.sel(axis="y").notnull().values
        y, z = sec.sel(axis="y").values, sec.sel(axis="z").values
        # the pin's offset across the plane at the sections, from the bodies' attachments (a
        # pin's ball_offset has no axial part: its bearing's gap drops it)
        across = float(np.nanmax(np.abs(sec.sel(axis="x").values))) * clearance
        print(f"clearance {clearance * 1e3:g} mm: {int(held.sum())} sections; largest offset "
              f"across the plane {across:.2g} m; settled impacts "
              f"{int(long.impact_count_settled.sel(joint='B'))}, contact fraction "
              f"{float(long.contact_fraction_settled.sel(joint='B')):.3f}")
        ax.plot(np.cos(ring), np.sin(ring), "k--", lw=0.8)
        ax.plot(y[held], z[held], "o", color="tab:red", ms=4, label="pin centre at theta = 0")
        ax.set_aspect("equal")
        ax.set_xlim(-1.1, 1.1)
        ax.set_ylim(-1.1, 1.1)
        ax.set_xlabel("d_y / c")
        ax.set_ylabel("d_z / c")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower left", fontsize=8)
        ax.set_title(f"c = {clearance * 1e3:g} mm, 100 revolutions", fontsize=10)
    fig.suptitle("Poincare sections of the pin centre at B, once a revolution (theta = 0), "
                 "5000 r/min", fontsize=10)
    fig.savefig(OUT / "poincare.png", dpi=110)
    plt.close(fig)
    print(f"wrote {OUT.relative_to(ROOT)}/{{slider_acceleration,orbit,contact_force,poincare}}.png")


if __name__ == "__main__":
    main()
