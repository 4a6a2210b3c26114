"""``mftyre sweep FILE.tir --model swift|steady|transient --vary NAME=DIST ... --road ROAD ... --speed V -n N -o
OUT.csv``: Monte-Carlo and grid studies of one tyre, the runs in batches on :mod:`mftyre.runner`.

Conditions: every combination (outer product) of the ``--road`` values (SWIFT and transient), the ``--speed``
values and the grid variables (``--vary NAME=grid(LO, HI, COUNT)`` or ``NAME=values(V1, V2, ...)``); each
condition is run ``-n`` times with the random variables (``NAME=normal(MEAN, SD)``, ``NAME=uniform(LO, HI)``) drawn
from NumPy's generator seeded by ``--seed`` (all draws made here, before any run, in the order of the options: the
table records the seed and every drawn value, and does not depend on the number of workers or the batches). A
NAME is an input (``fz`` [N], ``p`` [Pa]; steady and transient also ``alpha``, ``kappa``, ``gamma`` [rad, -]) or
a .tir parameter (``LMUY``, ``PKY1``...: :meth:`mftyre.MFModel.with_params`, values checked as the reader checks
them). Without a random variable each condition runs once.

The models (no tyre logic here; the existing entry points):

* ``swift``: the run of ``mftyre swift`` (:func:`mftyre.swift_command.roll`): the SWIFT tyre rolling freely over
  the road, axle height held at the loaded radius of fz (or ``--axle load``), over ``--distance`` from the start;
* ``transient``: the relaxed wheel of :mod:`mftyre.transient` (kind "transient", axle height held at the loaded
  radius of fz over the road height under the wheel centre), rolling freely at the speed until t = 0, then at the
  condition's slip angle alpha and slip kappa (a step), over ``--distance``;
* ``steady``: :meth:`mftyre.MFModel.evaluate` at the condition.

Each run gives the peaks ``fz_max`` [N] and ``fx_peak``, ``fy_peak`` [N] (the value of largest magnitude, with
its sign) and ``error`` (empty, or why the run could not be made: a sampled value no tyre can have). The table
(one row per run; ``.csv`` or ``.parquet``) and ``--plot`` (distribution of the three peaks per condition) are
written at the end; ``<OUT>.tasks/`` keeps every finished batch (``--resume``).
"""
from __future__ import annotations

import functools
import itertools
import math
import re
from pathlib import Path

import numpy as np

from .errors import ModelInputError
from .lazy import LazyModule

pd = LazyModule("pandas")  # imported when first used: the command line starts without it

__all__ = ["register", "run", "parse_distribution", "sweep_runs", "run_batch", "sweep", "MODELS", "INPUTS"]

MODELS = ("swift", "transient", "steady")
#: Condition inputs per model (SI).
INPUTS = {"swift": ("fz", "p"), "transient": ("fz", "p", "alpha", "kappa", "gamma"),
          "steady": ("fz", "p", "alpha", "kappa", "gamma")}
_DISTRIBUTIONS = {"normal": 2, "uniform": 2, "grid": 3, "values": None}
_PEAKS = ("fz_max", "fx_peak", "fy_peak")


def parse_distribution(text: str):
    """``NAME=normal(MEAN, SD)``, ``uniform(LO, HI)``, ``grid(LO, HI, COUNT)``, ``values(V1, ...)`` or a number:
    (name, kind, arguments); ModelInputError naming what was expected."""
    name, sep, spec = text.partition("=")
    name, spec = name.strip(), spec.strip()
    expected = ("expected NAME=normal(MEAN, SD), NAME=uniform(LO, HI), NAME=grid(LO, HI, COUNT), "
                "NAME=values(V1, V2, ...) or NAME=VALUE (SI units)")
    if not sep or not name or not spec:
        raise ModelInputError(f"--vary {text!r}: {expected}")
    m = re.fullmatch(r"([a-z]+)\s*\((.*)\)", spec)
    kind, body = (m.group(1), m.group(2)) if m else ("values", spec)
    if kind not in _DISTRIBUTIONS:
        raise ModelInputError(f"--vary {text!r}: unknown distribution {kind!r}; {expected}")
    try:
        args = [float(a) for a in body.split(",")]
    except ValueError:
        raise ModelInputError(f"--vary {text!r}: the arguments must be numbers; {expected}") from None
    count = _DISTRIBUTIONS[kind]
    if (count is not None and len(args) != count) or not all(math.isfinite(a) for a in args):
        raise ModelInputError(f"--vary {text!r}: {kind} takes {count} finite numbers; {expected}")
    if kind == "normal" and not args[1] >= 0 or kind == "uniform" and not args[1] >= args[0]:
        raise ModelInputError(f"--vary {text!r}: expected SD >= 0 (normal) or HI >= LO (uniform)")
    if kind == "grid":
        if not (args[2] >= 2 and args[2] == int(args[2])):
            raise ModelInputError(f"--vary {text!r}: COUNT must be an integer >= 2")
        kind, args = "values", list(np.linspace(args[0], args[1], int(args[2])))
    return name, kind, args


def sweep_runs(model_kind: str, variables: list, roads, speeds, n: int, seed: int, parameter_names) -> pd.DataFrame:
    """One row per run: ``run``, ``condition``, ``sample``, ``seed``, ``road``, ``speed`` and every variable's
    value (see the module notes). ``variables``: (name, kind, arguments) from :func:`parse_distribution`."""
    names = [v[0] for v in variables]
    for name in names:
        if name not in INPUTS[model_kind] and name not in parameter_names:
            raise ModelInputError(f"--vary {name}: neither an input of the {model_kind} model "
                                  f"({', '.join(INPUTS[model_kind])}) nor a parameter of the .tir file")
    if len(set(names)) != len(names):
        raise ModelInputError(f"--vary: a name given twice among {', '.join(names)}")
    grid = [(name, args) for name, kind, args in variables if kind == "values"]
    random = [(name, kind, args) for name, kind, args in variables if kind != "values"]
    if not random and n != 1:
        raise ModelInputError(f"-n {n}: the number of Monte-Carlo samples needs a random --vary (normal, uniform)")
    conditions = list(itertools.product(roads, speeds, *(args for _, args in grid)))
    rng = np.random.default_rng(seed)
    draws = {}
    for name, kind, (a, b) in random:  # in the order of the options: one draw of (conditions, n) each
        size = (len(conditions), n)
        draws[name] = rng.normal(a, b, size) if kind == "normal" else rng.uniform(a, b, size)
    rows = []
    for c, (road, speed, *values) in enumerate(conditions):
        for s in range(n):
            row = {"run": len(rows), "condition": c, "sample": s, "seed": seed, "road": road, "speed": speed}
            row.update({name: value for (name, _), value in zip(grid, values)})
            row.update({name: float(draws[name][c, s]) for name, _, _ in random})
            rows.append(row)
    return pd.DataFrame(rows)


@functools.lru_cache(maxsize=8)
def _model(tir_text: str, source: str):
    """The model of a .tir text, built once per worker process."""
    from .model import MFModel
    from .tir import parse_tir

    return MFModel(parse_tir(tir_text, source))


def run_batch(model_kind: str, tir_text: str, source: str, runs: pd.DataFrame, options: dict) -> list:
    """One task: the runs (rows of :func:`sweep_runs`) of one batch, where it lands; one dict of peaks per run."""
    import warnings

    from .errors import MFTyreError

    base = _model(tir_text, source)
    out = []
    inputs = INPUTS[model_kind]
    for row in runs.to_dict("records"):
        changes = {k: v for k, v in row.items() if k in base.params and k not in inputs}
        given = {k: float(v) for k, v in row.items() if k in inputs}
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # said once per file by the caller, not once per run
                model = base.with_params(**changes) if changes else base
                peaks = _RUNS[model_kind](model, row["road"], float(row["speed"]), given, options)
            out.append({"run": int(row["run"]), **peaks, "error": ""})
        except MFTyreError as exc:
            out.append({"run": int(row["run"]), **dict.fromkeys(_PEAKS, math.nan), "error": str(exc)})
    return out


def _peak(values) -> float:
    values = np.asarray(values, dtype=float)
    return float(values[np.argmax(np.abs(values))])


def _swift(model, road, speed, given, options) -> dict:
    from swift.road import parse_road

    from .swift_command import roll

    res, _ = roll(model, parse_road(road), speed, fz=given.get("fz"), p=given.get("p"), axle=options["axle"],
                  start=options["start"], distance=options["distance"], dt=options["dt"])
    return {"fz_max": float(np.max(res["fz"])), "fx_peak": _peak(res["fx"]), "fy_peak": _peak(res["fy"])}


def _transient(model, road, speed, given, options) -> dict:
    import casadi as ca

    from swift.road import parse_road

    from .transient import wheel_functions

    prm = model.params
    fz, p = given.get("fz", prm.FNOMIN), given.get("p", prm.INFLPRES)
    alpha, kappa, gamma = given.get("alpha", 0.0), given.get("kappa", 0.0), given.get("gamma", 0.0)
    static = model.evaluate(fz=fz, kappa=0.0, alpha=0.0, gamma=gamma, vx=speed, p=p)
    f = wheel_functions(model, "transient", "position")
    dt = options["dt"]
    n = max(int(round(options["distance"] / speed / dt)), 1)
    x = options["start"] + speed * dt * np.arange(n + 1)
    free = dict(vx=speed, vy=0.0, omega=speed / float(static.re), gamma=gamma, road_camber=0.0, p=p, mu_scale=1.0,
                z=float(static.rl), road_z=0.0)
    cols = dict(free, vy=math.tan(alpha) * speed, omega=(1.0 + kappa) * speed / float(static.re))
    u = np.array([np.full(n + 1, cols[k]) for k in f.input_names], dtype=float)
    u[f.input_names.index("road_z")] = parse_road(road).height(x)
    q = np.array(f.parameter_starts, dtype=float)
    x0 = f.init(np.array([free[k] for k in f.input_names]), q)
    xs = f.step.mapaccum(n)(x0, u[:, :-1], ca.repmat(q, 1, n), dt)
    ys = np.asarray(f.out.map(n + 1)(ca.horzcat(x0, xs), u, ca.repmat(q, 1, n + 1)))
    names = list(f.output_names)
    return {"fz_max": float(np.max(ys[names.index("Fz")])), "fx_peak": _peak(ys[names.index("Fx")]),
            "fy_peak": _peak(ys[names.index("Fy")])}


def _steady(model, road, speed, given, options) -> dict:
    out = model.evaluate(fz=given.get("fz", model.params.FNOMIN), kappa=given.get("kappa", 0.0),
                         alpha=given.get("alpha", 0.0), gamma=given.get("gamma", 0.0), vx=speed, p=given.get("p"))
    return {"fz_max": float(out.fz), "fx_peak": float(out.fx), "fy_peak": float(out.fy)}


_RUNS = {"swift": _swift, "transient": _transient, "steady": _steady}


def sweep(tir, model_kind: str, runs: pd.DataFrame, runner, *, options: dict, batch: int = 25, tasks=None,
          resume: bool = False):
    """Run the rows of ``runs`` (:func:`sweep_runs`) for the .tir file ``tir`` on ``runner`` in batches of
    ``batch``; returns (the table: ``runs`` with the peaks and ``error``, list of :class:`mftyre.runner.Failure`).
    ``tasks``: the results folder (``--resume``)."""
    from .tir import read_tir_text

    text = read_tir_text(tir)
    jobs = {f"runs-{i:07d}-{min(i + batch, len(runs)) - 1:07d}":
            {"model_kind": model_kind, "tir_text": text, "source": str(tir), "runs": runs.iloc[i:i + batch],
             "options": options} for i in range(0, len(runs), batch)}
    outcome = runner.run(run_batch, jobs, results=tasks, resume=resume)
    done = pd.DataFrame([row for rows in outcome.results.values() for row in rows],
                        columns=["run", *_PEAKS, "error"])
    table = runs.merge(done, on="run", how="left")
    table["error"] = table["error"].fillna("not run: its batch failed")
    return table, outcome.failures


def summary_figure(table: pd.DataFrame, title: str):
    """Box plots of fz_max, |fx_peak|, |fy_peak| per condition."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    conditions = sorted(table["condition"].unique())
    labels = []
    for c in conditions:
        row = table[table["condition"] == c].iloc[0]
        extra = [f"{k}={row[k]:.4g}" for k in table.columns
                 if k not in ("run", "condition", "sample", "seed", "road", "speed", *_PEAKS, "error")
                 and table.groupby("condition")[k].nunique().max() == 1 and table[k].nunique() > 1]
        labels.append("\n".join(filter(None, [str(row["road"]) or "flat", f"{row['speed']:g} m/s", *extra])))
    fig = Figure(figsize=(max(6.0, 1.2 * len(conditions) + 2), 7.5), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 1, sharex=True)
    for ax, name, meaning in zip(axes, _PEAKS, ("peak vertical force Fz", "peak |Fx|", "peak |Fy|")):
        data = [np.abs(table.loc[table["condition"] == c, name].dropna().to_numpy()) for c in conditions]
        ax.boxplot(data, showfliers=True)
        ax.set_ylabel(f"{meaning} [N]", fontsize=8)
        ax.grid(True, lw=0.3)
    axes[-1].set_xticks(range(1, len(conditions) + 1), labels, fontsize=6)
    fig.suptitle(title, fontsize=8)
    return fig


# ---------------------------------------------------------------------------------------------- command
def register(subparsers) -> None:
    from .arguments import closing_options, command_parser, number_type
    from .runner import add_runner_options

    p = command_parser(
        subparsers, "sweep", run, help="Monte-Carlo and grid studies (SWIFT, transient, steady) in parallel",
        description="Run the tyre of FILE.tir over every condition (roads x speeds x grid variables), each -n times "
                    "with the random variables drawn from --seed; one row per run (the drawn values, the peaks "
                    "fz_max, fx_peak, fy_peak) in OUT (.csv or .parquet) and a plot of their distribution per "
                    "condition. The runs go in batches to the workers (mftyre.runner).",
        epilog="example: mftyre sweep tyre.tir --model swift --vary LMUX=normal(1,0.05) --vary fz=grid(3000,5000,3) "
               "--road 'cleat(x0=1, length=0.05, height=0.01)' --speed 10,20 -n 100 -o runs.csv --plot runs.png")
    p.add_argument("file", metavar="FILE.tir", help="tyre property file")
    p.add_argument("--model", choices=MODELS, default="swift", help="swift (default), transient or steady")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=DIST",
                   help="normal(MEAN,SD), uniform(LO,HI), grid(LO,HI,COUNT), values(V1,...) or a value; NAME an "
                        "input (fz, p; alpha, kappa, gamma: transient, steady) or a .tir parameter; repeatable")
    p.add_argument("--road", action="append", default=None, metavar="ROAD",
                   help="road (as mftyre swift --road; repeatable: one condition each; default flat)")
    p.add_argument("--speed", type=_speeds, default=None, metavar="V",
                   help="speed(s): a value or comma list, units allowed (default LONGVL)")
    p.add_argument("-n", type=number_type(1, integer=True), default=1, metavar="N",
                   help="Monte-Carlo samples per condition (needs a random --vary; default 1)")
    p.add_argument("--seed", type=number_type(0, integer=True), default=0, help="seed of the draws (default 0)")
    p.add_argument("--axle", choices=("height", "load"), default="height", help="swift: axle height or load held")
    p.add_argument("--start", type=number_type(), default=0.0, metavar="X", help="wheel position at t = 0 [m]")
    p.add_argument("--distance", type=number_type(0, open_low=True), default=3.0, metavar="D",
                   help="distance rolled [m] (swift, transient; default 3)")
    p.add_argument("--dt", type=number_type(1e-5, 0.01), default=1e-3, metavar="DT", help="time step [s] (1e-3)")
    p.add_argument("--batch", type=number_type(1, integer=True), default=25, metavar="K",
                   help="runs per task (default 25; the same K keeps --resume valid)")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="the table: .csv or .parquet")
    p.add_argument("--plot", metavar="OUT.png", help="distribution of the peaks per condition")
    closing_options(p, overwrite="replace existing output files", quiet="no progress output")
    add_runner_options(p)


def _speeds(text: str):
    import argparse

    from .arguments import parse_sweep

    try:
        return [float(v) for v in parse_sweep("vx", text).values]
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def run(args) -> int:
    import sys

    from .arguments import command_error, progress_printer, refused_outputs
    from .errors import MFTyreError
    from .files import write_atomically, write_figure, write_frame_csv
    from .runner import runner_from_args

    out = Path(args.output)
    if out.suffix.lower() not in (".csv", ".parquet"):
        return command_error("sweep", f"-o {out}: expected a .csv or .parquet file")
    if out.suffix.lower() == ".parquet":
        try:
            import pyarrow  # noqa: F401  (pandas writes Parquet through it)
        except ImportError:
            return command_error("sweep", f"-o {out}: writing Parquet needs pyarrow, which is not installed "
                                          "(pip install \"mftyre[parquet]\" or pip install pyarrow); or write .csv")
    if args.model == "steady" and args.road:
        return command_error("sweep", "--road: the steady model has no road; use --model swift or transient")
    tasks = out.with_name(out.name + ".tasks")
    if refused := refused_outputs("sweep", {"-o": out, "--plot": args.plot}, {"FILE.tir": args.file},
                                  folders={"tasks folder": tasks},
                                  overwrite=args.overwrite or args.resume):  # a rerun replaces its own outputs
        return refused
    say = progress_printer(args.quiet)
    try:
        from .model import load_tir

        model = load_tir(args.file)
        speeds = args.speed or [float(model.params.LONGVL)]
        if any(not v > 0 for v in speeds):
            return command_error("sweep", "--speed: expected forward speeds above 0")
        variables = [parse_distribution(v) for v in args.vary]
        runs = sweep_runs(args.model, variables, args.road or [""], speeds, args.n, args.seed, model.params)
        options = {"axle": args.axle, "start": args.start, "distance": args.distance, "dt": args.dt}
        with runner_from_args(args) as runner:
            say(f"{len(runs)} run(s) of the {args.model} model in batches of {args.batch} on {runner.describe()}")
            table, failures = sweep(args.file, args.model, runs, runner, options=options, batch=args.batch,
                                    tasks=tasks, resume=args.resume)
        if out.suffix.lower() == ".parquet":
            import io

            buffer = io.BytesIO()
            table.to_parquet(buffer, index=False)
            write_atomically(out, buffer.getvalue())
        else:
            write_frame_csv(table, out, index=False)
        if args.plot:
            write_figure(summary_figure(table, f"{Path(args.file).name}: {args.model}, {len(runs)} runs, seed "
                                               f"{args.seed}"), args.plot)
    except (MFTyreError, OSError) as exc:
        return command_error("sweep", exc, 1)
    bad = table[table["error"] != ""]
    summary = table.groupby("condition")[list(_PEAKS)].agg(["mean", "std", "min", "max"])
    print(summary.to_string(float_format=lambda v: f"{v:.1f}"))
    print(f"wrote {out} ({len(table)} runs)" + (f" and {args.plot}" if args.plot else ""))
    for failure in failures:
        print(f"mftyre sweep: {failure.summary()}", file=sys.stderr)
    if len(bad):
        print(f"mftyre sweep: {len(bad)} run(s) not made, e.g. run {bad['run'].iloc[0]}: {bad['error'].iloc[0]}",
              file=sys.stderr)
    return 1 if failures or len(bad) else 0
