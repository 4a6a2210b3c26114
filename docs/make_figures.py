"""The figures of README.md and docs/, drawn from the model itself: ``python docs/make_figures.py`` (writes
``docs/fy_alpha.png``; an existing figure is replaced)."""
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


if __name__ == "__main__":
    print(fy_alpha())
