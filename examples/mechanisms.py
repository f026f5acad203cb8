"""Figures of docs/mechanisms.md: the cam as a rigid body and the stick-slip oscillator.

- mechanisms_speed_fluctuation.png: the chapter 4 friction rig (preset
  ``sundar2014-friction``, 11.55 Hz) with its cam on a shaft of inertia ``J`` driven by a
  DC motor: (a) over the last two revolutions, the contact's torque on the cam and its
  friction part, and the cam speed less its mean over these revolutions; (b) the coefficient of speed
  fluctuation ``(omega_max - omega_min) / omega_mean`` [-] against the friction
  coefficient at the contact, for three shaft inertias.
- stick_slip_cycle.png: the stick-slip oscillator from rest: (a) the extension ``x`` [mm]
  against time with the sticking intervals shaded; (b) the phase portrait with the
  closed-form limit cycle.

Run: python examples/mechanisms.py [--data FILE]   (about 20 s; ``--data`` writes the
numbers each figure shows)
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camdyn  # noqa: E402
from camdyn.plotting.style import axis_label, legend_below, save_figure, styled, tidy_axis  # noqa: E402
from camdyn.simulation.mechanisms import CamDrive, simulate_driven_cam, simulate_stick_slip  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
#: cam speed [Hz] and the motor's free speed over it [-]
SPEED, FREE_OVER_SPEED = 11.55, 1.2
#: shaft inertias [kg m^2] and contact friction coefficients [-] of panel (b)
INERTIAS = (1e-4, 3e-4, 1e-3)
FRICTIONS = tuple(float(v) for v in np.round(np.linspace(0.0, 0.3, 7), 2))
#: revolutions run, the last two shown
REVOLUTIONS = 12
#: stick-slip oscillator: mass [kg], stiffness [N/m], belt speed [m/s], mu_s, mu_k, damping [N s/m]
STICK_SLIP = dict(mass=1.0, stiffness=400.0, belt_speed=0.1, static_friction=0.5, kinetic_friction=0.3,
                  damping=0.4)


def _drive(system, inertia):
    omega = system.motion.angular_speed
    # stall torque: the motor runs near 1/1.2 of its free speed under the rig's load
    return CamDrive(shaft_inertia=inertia, kind="motor", stall_torque=1.0, free_speed=FREE_OVER_SPEED * omega)


def data_speed_fluctuation() -> dict:
    """Panel (a): time [s], contact torque and its friction part [N m], speed less its mean
    in the window [rad/s] over the last two revolutions (J = 3e-4 kg m^2, mu of the preset); panel (b):
    the coefficient of fluctuation [-] per inertia and friction coefficient."""
    rig = camdyn.load_system("sundar2014-friction").with_values(**{"motion.speed": SPEED})
    ds = simulate_driven_cam(rig, _drive(rig, INERTIAS[1]), revolutions=REVOLUTIONS, sample_rate=20e3)
    last = ds.time.values >= ds.time.values[-1] - 4 * math.pi / ds.attrs["mean_cam_speed"]
    panel_a = {"time": (ds.time.values[last] - ds.time.values[last][0]).tolist(),
               "contact_torque": ds.contact_torque.values[last].tolist(),
               "friction_torque": ds.friction_torque.values[last].tolist(),
               "speed_fluctuation": (ds.cam_speed.values[last] - ds.cam_speed.values[last].mean()).tolist(),
               "mean_speed": ds.attrs["mean_cam_speed"]}
    panel_b = {}
    for inertia in INERTIAS:
        values = []
        for mu in FRICTIONS:
            s = rig.with_values(**{"friction.coefficient": mu})
            run = simulate_driven_cam(s, _drive(s, inertia), revolutions=REVOLUTIONS, sample_rate=5e3)
            keep = run.time.values >= run.time.values[-1] - 4 * math.pi / run.attrs["mean_cam_speed"]
            speed = run.cam_speed.values[keep]
            values.append(float((speed.max() - speed.min()) / speed.mean()))
        panel_b[f"{inertia:g}"] = values
    return {"a": panel_a, "b": {"friction": list(FRICTIONS), "fluctuation": panel_b}}


@styled
def draw_speed_fluctuation(data: dict, path) -> Path:
    """The two panels of mechanisms_speed_fluctuation.png."""
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(9.0, 4.0))
    a = data["a"]
    t = 1e3 * np.asarray(a["time"])
    ax_a.plot(t, a["speed_fluctuation"], color="C0", label=r"$\dot\Theta - \bar\omega$")
    ax_a.set_xlabel(axis_label("time in the last two revolutions $t$", "ms"))
    ax_a.set_ylabel(axis_label(r"cam speed less its mean $\dot\Theta - \bar\omega$", "rad/s"))
    ax_a.set_title(rf"(a) $J$ = 3e-4 kg m², mean {a['mean_speed']:.1f} rad/s")
    tidy_axis(ax_a.xaxis)
    torque = ax_a.twinx()
    torque.grid(False)
    torque.plot(t, 1e3 * np.asarray(a["contact_torque"]), color="C1", label=r"contact torque $T_c$")
    torque.plot(t, 1e3 * np.asarray(a["friction_torque"]), color="C2", ls="--", label=r"its friction part $T_f$")
    torque.set_ylabel(axis_label("torque on the cam", "mN m"))
    for axis in (ax_a, torque):   # room below the curves for the legend
        low, high = axis.get_ylim()
        axis.set_ylim(low - 0.6 * (high - low), high)
    lines = ax_a.get_lines() + torque.get_lines()
    ax_a.legend(lines, [line.get_label() for line in lines], loc="lower left")
    b = data["b"]
    for name, values in b["fluctuation"].items():
        ax_b.plot(b["friction"], values, marker="o", ms=3, label=f"$J$ = {float(name):g} kg m²")
    ax_b.set_xlabel(axis_label(r"friction coefficient at the contact $\mu$", "-"))
    ax_b.set_ylabel(axis_label(r"coefficient of speed fluctuation $C_s$", "-"))
    ax_b.set_title("(b) DC motor drive, last two revolutions")
    tidy_axis(ax_b.xaxis)
    legend_below(fig, ax_b, 3)
    return save_figure(fig, path)


def _closed_form_cycle(p: dict) -> tuple[np.ndarray, np.ndarray]:
    """The undamped limit cycle's slip arc (docs/mechanisms.md): ``x = x_k + R sin(w s + psi)``
    from breakaway at ``x_b`` back to the belt speed; the stick segment closes it."""
    n = p["mass"] * 9.80665
    w = math.sqrt(p["stiffness"] / p["mass"])
    x_k, x_b = p["kinetic_friction"] * n / p["stiffness"], p["static_friction"] * n / p["stiffness"]
    d = x_b - x_k
    r = math.hypot(d, p["belt_speed"] / w)
    psi = math.atan2(d * w, p["belt_speed"])
    phase = np.linspace(psi, 2 * math.pi - psi, 200)
    x = np.r_[x_k + r * np.sin(phase), x_b]
    v = np.r_[w * r * np.cos(phase), p["belt_speed"]]
    return x, v


def data_stick_slip() -> dict:
    """Time [s], extension [m], velocity [m/s] and sticking flag of a run from rest, and the
    undamped closed-form cycle [m, m/s] for comparison."""
    ds = simulate_stick_slip(**STICK_SLIP, duration=1.5, sample_rate=4e3)
    undamped = dict(STICK_SLIP, damping=0.0)
    x, v = _closed_form_cycle(undamped)
    return {"time": ds.time.values.tolist(), "x": ds.x.values.tolist(), "x_dot": ds.x_dot.values.tolist(),
            "sticking": ds.sticking.values.tolist(), "cycle_x": x.tolist(), "cycle_v": v.tolist(),
            "transitions": int(ds.sizes["transition"])}


@styled
def draw_stick_slip(data: dict, path) -> Path:
    """The two panels of stick_slip_cycle.png."""
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(9.0, 4.0))
    t = np.asarray(data["time"])
    x = 1e3 * np.asarray(data["x"])
    ax_a.plot(t, x, color="C0", label="extension $x$")
    sticking = np.asarray(data["sticking"], bool)
    ax_a.fill_between(t, x.min(), x.max(), where=sticking, color="0.88", step="mid", label="sticking")
    ax_a.set_xlabel(axis_label("time $t$", "s"))
    ax_a.set_ylabel(axis_label("extension $x$", "mm"))
    ax_a.set_title("(a) from rest, damped (c = 0.4 N s/m)")
    tidy_axis(ax_a.xaxis)
    ax_b.plot(x, data["x_dot"], color="C0", label="simulated, damped")
    ax_b.plot(1e3 * np.asarray(data["cycle_x"]), data["cycle_v"], color="C3", ls="--",
              label="closed-form cycle, undamped")
    ax_b.set_xlabel(axis_label("extension $x$", "mm"))
    ax_b.set_ylabel(axis_label(r"velocity $\dot x$", "m/s"))
    ax_b.set_title("(b) phase portrait")
    legend_below(fig, ax_b, 3)
    return save_figure(fig, path)


def main(argv=None, out: Path = OUT) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="write the numbers each figure shows to this JSON file")
    args = parser.parse_args(argv)
    out.mkdir(parents=True, exist_ok=True)
    speed = data_speed_fluctuation()
    draw_speed_fluctuation(speed, out / "mechanisms_speed_fluctuation.png")
    slip = data_stick_slip()
    draw_stick_slip(slip, out / "stick_slip_cycle.png")
    for name, values in speed["b"]["fluctuation"].items():
        print(f"J = {name} kg m^2: C_s = " + ", ".join(f"{v:.4f}" for v in values))
    print(f"stick-slip: {slip['transitions']} transitions in 1.5 s")
    if args.data:
        shown = {"mechanisms_speed_fluctuation.png": {"fluctuation": speed["b"]["fluctuation"]},
                 "stick_slip_cycle.png": {"transitions": slip["transitions"]}}
        args.data.write_text(json.dumps(shown, indent=1))


if __name__ == "__main__":
    main()
