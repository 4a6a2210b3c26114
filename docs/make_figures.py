"""The figures of README.md and docs/, drawn from the model itself: ``python docs/make_figures.py`` (writes
``docs/fy_alpha.png`` and ``docs/swift_cleat.png``; existing figures are replaced)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import mftyre
from mftyre.files import sample_tir, write_figure

HERE = Path(__file__).resolve().parent


def fy_alpha(path: Path = HERE / "fy_alpha.png") -> Path:
    """Lateral force and aligning torque against slip angle of the bundled 205/60 R15 MF 6.1 tyre at three loads
    and two inflation pressures (pure side slip, no camber)."""
    model = mftyre.load_tir(sample_tir("car_205_60R15_mf61.tir"))
    alpha = np.radians(np.linspace(-15.0, 15.0, 121))
    fig = Figure(figsize=(7.2, 3.2), dpi=100, layout="constrained")
    ax_fy, ax_mz = fig.subplots(1, 2)
    colours = {2000.0: "tab:blue", 4000.0: "tab:orange", 6000.0: "tab:green"}
    for p, style in ((1.9e5, "--"), (2.5e5, "-")):
        for fz, colour in colours.items():
            out = model.evaluate(fz=fz, kappa=0.0, alpha=alpha, p=p)
            label = f"{fz / 1000:g} kN, {p / 1e5:g} bar"
            ax_fy.plot(np.degrees(alpha), out.fy / 1000.0, style, color=colour, lw=1.4, label=label)
            ax_mz.plot(np.degrees(alpha), out.mz, style, color=colour, lw=1.4)
    ax_fy.set(xlabel="slip angle [deg]", ylabel="Fy [kN]")
    ax_mz.set(xlabel="slip angle [deg]", ylabel="Mz [N m]")
    for ax in (ax_fy, ax_mz):
        ax.grid(alpha=0.3)
    fig.legend(*ax_fy.get_legend_handles_labels(), loc="outside lower center", ncol=6, fontsize=7, frameon=False)
    fig.suptitle("mftyre: 205/60 R15, MF 6.1 (tir_files/car_205_60R15_mf61.tir), ISO-W axes", fontsize=9)
    path.unlink(missing_ok=True)  # the figure is regenerated, not kept
    return write_figure(fig, path)


def swift_cleat(path: Path = HERE / "swift_cleat.png") -> Path:
    """The SWIFT tyre (bundled MF 6.2 file, 4 kN, 2.2 bar, axle height held) over a 10 mm x 50 mm cleat at three
    speeds: vertical and longitudinal axle force against the wheel position."""
    from swift import StepInputs, SwiftTyre
    from swift.road import parse_road

    model = mftyre.load_tir(sample_tir("car_205_60R15_mf62_swift.tir"))
    road = parse_road("cleat(x0=0.5, length=0.05, height=0.01)")
    fig = Figure(figsize=(7.2, 3.4), dpi=100, layout="constrained")
    ax_fz, ax_fx = fig.subplots(1, 2, sharex=True)
    tyre = SwiftTyre(model, road, axle="height", rim="speed", x_range=(-1.0, 2.5))
    for kmh in (10.0, 30.0, 60.0):
        v = kmh / 3.6
        static = model.evaluate(fz=4000.0, kappa=0.0, alpha=0.0, vx=v, p=2.2e5)
        rl, re = float(static.rl), float(static.re)
        res = tyre.run(1.5 / v, StepInputs(x=0.0, vx=v, z=rl, load=4000.0, omega=v / re, p=2.2e5), dt=1e-3)
        ax_fz.plot(res.x, np.asarray(res.outputs["fz"]) / 1000.0, lw=1.2, label=f"{kmh:g} km/h")
        ax_fx.plot(res.x, np.asarray(res.outputs["fx"]) / 1000.0, lw=1.2)
    ax_fz.set(xlabel="wheel position [m]", ylabel="Fz [kN]")
    ax_fx.set(xlabel="wheel position [m]", ylabel="Fx [kN]")
    for ax in (ax_fz, ax_fx):
        ax.grid(alpha=0.3)
        ax.axvspan(0.5, 0.55, color="0.85", lw=0)
    fig.legend(*ax_fz.get_legend_handles_labels(), loc="outside lower center", ncol=3, fontsize=7, frameon=False)
    fig.suptitle("SWIFT over a 10 mm x 50 mm cleat (grey), car_205_60R15_mf62_swift.tir, 4 kN, 2.2 bar, axle height "
                 "held", fontsize=9)
    path.unlink(missing_ok=True)
    return write_figure(fig, path)


if __name__ == "__main__":
    print(fy_alpha())
    print(swift_cleat())
