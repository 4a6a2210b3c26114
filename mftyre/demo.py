"""The main job on bundled data: ``mftyre demo [--out DIR]``.

1. Evaluate the bundled MF 6.1 car tyre (tir_files/car_205_60R15_mf61.tir, installed as mftyre.tir_files): lateral
   force and aligning moment against slip angle at three inflation pressures -> ``characteristics.png``.
2. Run a synthetic test-trailer programme on it (loads, pressures, cambers, pure and combined slip, free rolling,
   load-deflection; measurement noise) -> ``trailer.tdx`` (TYDEX).
3. Fit a .tir to those data from generic start values, pressure terms included -> ``fitted.tir`` and
   ``fit_report/`` (Markdown report with the fit errors and the lower/upper-bound comparison, plots), and check
   the fitted model against the noise-free tyre on a grid it was not fitted on.
4. Gap finder: hand it the fitted model with one physical effect switched off (pressure on cornering stiffness,
   PPY1 = PPY2 = 0) and the same data; it locates the structured residual, names the missing effect, adds it and
   shows the held-out error shrink -> ``gaps/`` (report.md, plots, gaps.json) and ``improved.tir``.

Everything is written below ``DIR`` (default ``out/``). A ``DIR`` that exists and is not empty is refused unless
``--overwrite`` is given (then the demo's files there are replaced and nothing else is touched): the output rule
of :mod:`mftyre.files`. The run takes about 20 s of CPU time with one BLAS thread (``OPENBLAS_NUM_THREADS=1``);
with more BLAS threads the small least-squares problems of the fit take about twice the CPU time.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["run_demo", "register"]

BUNDLED_TIR = "car_205_60R15_mf61.tir"


def run_demo(out_dir="out", tir=None, *, seed: int = 1, echo=print, overwrite: bool = False) -> dict:
    """Run the demonstration on ``tir`` (default: the bundled sample ``car_205_60R15_mf61.tir``); returns the paths
    written and the key figures. A non-empty ``out_dir`` needs ``overwrite=True`` (:class:`mftyre.files.OutputError`
    otherwise)."""
    from matplotlib.figure import Figure

    from mftyre.errors import spelled
    from mftyre.files import check_outputs, make_output_folder, sample_tir, write_figure

    import mftyre
    from mftyre.data import read_tydex, trailer_programme, write_tydex
    from mftyre.fit import fit_tir
    from mftyre.gaps import find_gaps, neutralise

    tir = sample_tir(BUNDLED_TIR) if tir is None else Path(tir)
    out = Path(out_dir)
    check_outputs({}, {"tyre": tir}, folders={"--out": out}, overwrite=overwrite,
                  option=spelled("overwrite=True", "--overwrite"))
    make_output_folder(out, "--out")
    truth = mftyre.load_tir(tir)
    prm = truth.params
    echo(f"1/3 evaluate {Path(tir).name} (FITTYP {prm.fittyp}, FNOMIN {prm.FNOMIN:.0f} N, "
         f"NOMPRES {prm.NOMPRES / 1e5:.2f} bar)")
    alpha = np.radians(np.linspace(-12.0, 12.0, 97))
    pressures = np.array([prm.PRESMIN, prm.NOMPRES, prm.PRESMAX])  # the file's pressure range and nominal
    res = truth.evaluate(prm.FNOMIN, 0.0, alpha[None, :], p=pressures[:, None])
    pressures = res.p[:, 0]  # the pressures used: the labels say what was evaluated
    fig = Figure(figsize=(6, 6), dpi=90)
    ax_fy, ax_mz = fig.subplots(2, 1, sharex=True)
    for p, fy, mz in zip(pressures, res.fy, res.mz):
        ax_fy.plot(np.degrees(alpha), fy, label=f"{p / 1e5:.2f} bar")
        ax_mz.plot(np.degrees(alpha), mz)
    ax_fy.set(ylabel="Fy [N]", title=f"{Path(tir).name}, Fz = {prm.FNOMIN:.0f} N")
    ax_mz.set(xlabel="slip angle [deg]", ylabel="Mz [N m]")
    for ax in (ax_fy, ax_mz):
        ax.grid(True)
    ax_fy.legend()
    fig.tight_layout()
    characteristics = out / "characteristics.png"
    write_figure(fig, characteristics)
    for p, fy, kya in zip(pressures, res.fy, res.kya[:, 0]):
        echo(f"    {p / 1e5:.2f} bar: peak |Fy| {np.max(np.abs(fy)):7.0f} N, cornering stiffness {kya:8.0f} N/rad")
    echo(f"    wrote {characteristics}")

    echo("2/4 synthetic trailer programme with measurement noise")
    data = trailer_programme(truth, noise=1.0, seed=seed)
    tdx = write_tydex(data, out / "trailer.tdx", overwrite=True)
    data = read_tydex(tdx)
    echo(f"    {len(data.frame)} points -> wrote {tdx}")

    echo("3/4 staged fit from generic start values, pressure terms included")
    seen = set()

    def progress(stage, label, evaluations, chisqr):
        if (stage, label) not in seen:
            seen.add((stage, label))
            echo(f"    fitting {stage} ({label})")

    result = fit_tir(data, progress=progress)
    fitted = result.write_tir(out / "fitted.tir", overwrite=True)
    report = result.save_report(out / "fit_report" / "report.md")
    check = _check_grid(truth, result.model, prm)
    for channel, error in check.items():
        echo(f"    {channel}: {error:.2f} % normalised RMS against the noise-free tyre (check grid)")
    echo(f"    wrote {fitted} and {report}")

    hidden = "pressure_cornering_stiffness"
    echo(f"4/4 gap finder on the fitted model with '{hidden}' switched off")
    gaps = find_gaps(data, neutralise(result.model, hidden), progress=lambda text: echo(f"    {text}"))
    gaps.save(out / "gaps")
    improved = gaps.write_tir(out / "improved.tir", overwrite=True)
    for channel, before in gaps.error_before.items():
        echo(f"    {channel}: held-out error {before:.2f} % -> {gaps.error_after[channel]:.2f} %")
    echo(f"    wrote {out / 'gaps'} and {improved}")
    return {"characteristics": characteristics, "trailer": tdx, "fitted": fitted, "report": report,
            "check_error": check, "gaps": gaps, "improved": improved}


def _check_grid(truth, fitted, prm) -> dict:
    """Normalised RMS (Schmeitz et al. 2005) of the fitted model against the noise-free tyre on a grid of
    loads, pressures, cambers and slips that the programme did not measure."""
    from mftyre.fit import normalised_rms

    fz = np.array([0.6, 0.9, 1.2, 1.4])[:, None, None, None] * prm.FNOMIN
    p = np.array([0.9, 1.1])[None, :, None, None] * prm.NOMPRES
    gamma = np.radians([-2.0, 1.0])[None, None, :, None]
    alpha = np.radians(np.linspace(-10, 10, 21))[None, None, None, :]
    kappa = np.linspace(-0.2, 0.2, 21)[None, None, None, :]
    lateral_true, lateral_fit = (m.evaluate(fz, 0.0, alpha, gamma, p=p) for m in (truth, fitted))
    long_true, long_fit = (m.evaluate(fz, kappa, 0.0, gamma, p=p) for m in (truth, fitted))
    return {"FX": normalised_rms(long_fit.fx.ravel(), long_true.fx.ravel()),
            "FY": normalised_rms(lateral_fit.fy.ravel(), lateral_true.fy.ravel()),
            "MZ": normalised_rms(lateral_fit.mz.ravel(), lateral_true.mz.ravel())}


def register(subparsers) -> None:
    from mftyre.arguments import closing_options, command_parser, number_type

    p = command_parser(subparsers, "demo", _run, help="run the main job on the bundled tyre: evaluate, synthetic "
                                                      "trailer data, fit", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="out", help="output folder (default: out)")
    p.add_argument("--seed", type=number_type(0, integer=True), default=1,
                   help="seed of the measurement noise (default 1)")
    closing_options(p, overwrite="write into an output folder that is not empty")


def _run(args) -> int:
    from mftyre.arguments import command_error
    from mftyre.errors import MFTyreError

    try:
        run_demo(args.out, seed=args.seed, overwrite=args.overwrite)
    except MFTyreError as exc:
        return command_error("demo", f"error: {exc}")
    return 0
