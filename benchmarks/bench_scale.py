"""Parallel work on mftyre.runner, every ratio against a baseline measured in the same run:

    python benchmarks/bench_scale.py            # reduced size (a shared machine): 4 tyres, 40 SWIFT runs, 4.2e6 points
    python benchmarks/bench_scale.py --full     # the issue's size: 8 tyres, 1 000 SWIFT runs, 1e8 points
    python benchmarks/bench_scale.py --tyres 8 --runs 100    # any size between
    python benchmarks/bench_scale.py --workers 4 --scheduler tcp://host:8786   # another machine or a cluster

Cases:

* ``campaign``: synthetic trailer programmes of N tyres (the sample MF 6.1 file with LMUX, LMUY, PKX1, PKY1 spread
  by a few per cent per tyre; 3 loads, 1 pressure, 3 cambers, 21 points per sweep, noise 1, seed = tyre index),
  fitted (stages pure_fx, pure_fy, mz; report and plots) by :func:`mftyre.campaign.run_campaign` serially in this
  process and on the workers; speed-up = serial / parallel wall time (target >= 1.7 on 2 cores, 2 workers).
* ``SWIFT Monte-Carlo``: :mod:`mftyre.sweep` runs of the sample SWIFT file over a 10 mm cleat at 10 m/s, 1 m, LMUX
  ~ normal(1, 0.05), fz ~ uniform(3000, 5000) (seed 1), batches of 10 (fewer where a worker would get fewer than 4
  batches): runs per second serially in this process
  (a quarter of the runs, at least 10) and per worker (target: >= 90 % of the serial rate per worker).
* ``evaluation``: :meth:`mftyre.MFModel.evaluate_chunked` (fx, fy, mz; chunks of 2**20 points) on the workers, ns
  per point, against the same compiled kernel in one call and :meth:`mftyre.MFModel.evaluate` (NumPy) on 1e6 of
  the points in this process.

Before any timing the cluster is started and every process that works (this one and each worker) is warmed the
same way: mftyre's fitting, plotting and SWIFT modules imported, one figure drawn, the compiled libraries loaded;
the start-up and the warm-up are printed separately. Both clocks are printed: wall time (what the targets are
about) and CPU time (this process for the serial case; the workers plus this process, which reads the runs,
schedules and writes the outputs, for the parallel one). On a machine shared with others the wall-time ratios are
depressed by the load, which is printed before and after (a process started with ``nice`` gets a small share of
a loaded machine); the CPU times are disturbed far less. ``speed-up from CPU`` = serial CPU / max(the busiest
worker's CPU, all the parallel CPU / workers): the wall-time speed-up of the same work on an idle machine with a
core per worker.
"""
from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import mftyre  # noqa: E402
from mftyre.campaign import run_campaign  # noqa: E402
from mftyre.data import trailer_programme, write_tydex  # noqa: E402
from mftyre.files import make_output_folder, sample_tir  # noqa: E402
from mftyre.runner import Runner  # noqa: E402
from mftyre.sweep import parse_distribution, sweep, sweep_runs  # noqa: E402

SIZES = {"reduced": dict(tyres=4, runs=40, points=4 * 2**20), "full": dict(tyres=8, runs=1000, points=10**8)}
STAGES = ["pure_fx", "pure_fy", "mz"]
SWIFT_OPTIONS = {"axle": "height", "start": 0.0, "distance": 1.0, "dt": 1e-3}


def load() -> str:
    one, five, _ = os.getloadavg()
    return f"load average {one:.1f} (1 min), {five:.1f} (5 min) on {os.cpu_count()} cores"


def campaign(folder: Path, tyres: int) -> Path:
    truth = mftyre.load_tir(sample_tir("car_205_60R15_mf61.tir"))
    prm = truth.params
    for i in range(tyres):
        f = 1.0 + 0.02 * (i - tyres / 2)
        model = truth.with_params(LMUX=f, LMUY=2.0 - f, PKX1=prm.PKX1 * f, PKY1=prm.PKY1 * (2.0 - f))
        data = trailer_programme(model, loads=(0.6, 1.0, 1.4), pressures=(1.0,), cambers_deg=(-3.0, 0.0, 3.0),
                                 points=21, noise=1.0, seed=i)
        write_tydex(data, folder / f"tyre{i:02d}.tdx")
    return folder


def timed(fn):
    t0 = time.perf_counter()
    value = fn()
    return time.perf_counter() - t0, value


def cpu_seconds(client=None) -> dict:
    """CPU time [s] used so far by this process ("here") and by each worker of ``client``."""
    out = {"here": time.process_time()}
    if client is not None:
        out.update(client.run(time.process_time))
    return out


def cpu_timed(fn, client=None):
    """(wall s, {process: CPU s}, value): the CPU time is what a loaded machine disturbs least (time waiting for a
    core is not counted)."""
    c0 = cpu_seconds(client)
    wall, value = timed(fn)
    c1 = cpu_seconds(client)
    return wall, {k: c1[k] - c0[k] for k in c1}, value


def cpu_text(cpu: dict) -> str:
    workers = [v for k, v in cpu.items() if k != "here"]
    if not workers:
        return f"CPU {cpu['here']:.1f} s"
    return (f"CPU {sum(cpu.values()):.1f} s: workers {' + '.join(f'{v:.1f}' for v in workers)}, this process "
            f"{cpu['here']:.1f}")


def busiest(cpu: dict) -> float:
    """The wall time [s] of the work on an idle machine with a core per worker: the busiest worker's CPU time, or
    all the CPU time (this process's too: scheduler, reading, writing) shared by the cores, whichever is longer."""
    workers = [v for k, v in cpu.items() if k != "here"]
    return max(max(workers), sum(cpu.values()) / len(workers))


def warm() -> None:
    """What every working process does once (imports, fonts, compiled libraries); run here and on each worker
    before any timing, so that both sides are timed at their steady rate."""
    import io

    import mftyre.fit.core  # noqa: F401  (lmfit, scipy.stats: seconds of CPU per process)
    from mftyre.fit import report  # noqa: F401
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 1), dpi=50)
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1], ".")
    ax.set_title("warm", fontsize=8)
    fig.savefig(io.BytesIO(), format="png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--full", action="store_true", help="the issue's sizes (8 tyres, 1000 runs, 1e8 points)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the local cluster (2)")
    parser.add_argument("--scheduler", default=None, help="a running scheduler's address instead")
    for name in ("tyres", "runs", "points"):
        parser.add_argument(f"--{name}", type=int, default=None, help=f"number of {name} (overrides the size)")
    args = parser.parse_args()
    size = dict(SIZES["full" if args.full else "reduced"])
    size.update({k: getattr(args, k) for k in size if getattr(args, k) is not None})
    print(f"# bench_scale ({'full' if args.full else 'reduced'} size: {size['tyres']} tyres, {size['runs']} SWIFT "
          f"runs, {size['points']:.2g} points): {load()}")
    tmp = Path(tempfile.mkdtemp(prefix="bench_scale_"))
    try:
        source = campaign(make_output_folder(tmp / "campaign"), size["tyres"])
        swift_file = sample_tir("car_205_60R15_mf62_swift.tir")
        swift_model = mftyre.load_tir(swift_file)
        variables = [parse_distribution("LMUX=normal(1, 0.05)"), parse_distribution("fz=uniform(3000, 5000)")]
        runs = sweep_runs("swift", variables, ["cleat(x0=0.4, length=0.05, height=0.01)"], [10.0], size["runs"], 1,
                          swift_model.params)
        defaults = {"start": None, "stages": STAGES, "weighting": "uniform", "bins": 40, "max_nfev": None,
                    "no_pressure": False}
        serial = Runner(workers=0)
        model = mftyre.load_tir(sample_tir("car_205_60R15_mf61.tir"))
        kernels = ("fx", "fy", "mz")

        def warm_all():  # the same in this process and on each worker (see the notes)
            warm()
            sweep(swift_file, "swift", runs.iloc[:1], serial, options=SWIFT_OPTIONS)
            model.evaluate_chunked(np.full(8, 4000.0), 0.0, 0.0, outputs=kernels)["fx"].compute(
                scheduler="sync")

        t_here, _ = timed(warm_all)
        t_start, cluster = timed(lambda: Runner(workers=args.workers, scheduler=args.scheduler))
        with cluster:
            t_client, client = timed(cluster.client)
            workers = len(client.scheduler_info()["workers"])
            t_warm, _ = timed(lambda: client.run(warm_all))
            print(f"cluster: {cluster.describe()}, {workers} workers; start {t_start + t_client:.1f} s; warm-up "
                  f"(imports, a figure, compiled libraries) {t_here:.1f} s here, {t_warm:.1f} s on the workers")
            rows = []
            t_serial, c_serial, _ = cpu_timed(lambda: run_campaign(source, tmp / "serial", serial, defaults=defaults,
                                                                    say=lambda text: None))
            t_parallel, c_parallel, (summary, failures) = cpu_timed(
                lambda: run_campaign(source, tmp / "parallel", cluster, defaults=defaults, say=lambda text: None),
                client)

            def fitted(folder, i):  # the .tir without its "Fitted by ... in N s" line
                lines = (folder / f"tyre{i:02d}.tir").read_text().splitlines()
                return [line for line in lines if not line.startswith("! Fitted by")]

            same = all(fitted(tmp / "serial", i) == fitted(tmp / "parallel", i) for i in range(size["tyres"]))
            rows.append((f"campaign, {size['tyres']} tyres", f"{t_serial:.1f} s ({cpu_text(c_serial)})",
                         f"{t_parallel:.1f} s ({cpu_text(c_parallel)})",
                         f"speed-up {t_serial / t_parallel:.2f} (target >= 1.7 with 2 workers); speed-up from CPU "
                         f"{c_serial['here'] / busiest(c_parallel):.2f}; CPU serial / parallel "
                         f"{c_serial['here'] / sum(c_parallel.values()):.2f}",
                         f"{'identical' if same else 'DIFFERENT'} .tir files; {len(failures)} failed"))
            n_serial = max(size["runs"] // 4, 10)
            batch = max(1, min(10, len(runs) // (4 * workers)))  # at least 4 tasks per worker: none waits idle
            t_one, c_one, (table_one, _) = cpu_timed(lambda: sweep(swift_file, "swift", runs.iloc[:n_serial],
                                                                    serial, options=SWIFT_OPTIONS, batch=batch))
            t_many, c_many, (table, failed) = cpu_timed(lambda: sweep(swift_file, "swift", runs, cluster,
                                                                      options=SWIFT_OPTIONS, batch=batch), client)
            rate_one, rate_many = n_serial / t_one, len(runs) / t_many / workers
            cpu_one, cpu_many = n_serial / c_one["here"], len(runs) / sum(c_many.values())
            same = table.iloc[:n_serial][table_one.columns].equals(table_one)
            rows.append((f"SWIFT Monte-Carlo, {len(runs)} runs, batches of {batch}",
                         f"{rate_one:.2f} runs/s ({n_serial} runs; {cpu_one:.2f} runs per CPU s)",
                         f"{rate_many:.2f} runs/s per worker ({cpu_many:.2f} runs per CPU s; {cpu_text(c_many)})",
                         f"{100 * rate_many / rate_one:.0f} % of serial per worker (target >= 90 %); per CPU s "
                         f"{100 * cpu_many / cpu_one:.0f} %",
                         f"{'identical' if same else 'DIFFERENT'} peaks; {len(failed)} failed"))
            n = size["points"]
            rng = np.random.default_rng(1)
            m = min(n, 10**6)
            fz, kappa, alpha = rng.uniform(2000, 6000, m), rng.uniform(-0.2, 0.2, m), rng.uniform(-0.2, 0.2, m)
            t_numpy, _ = timed(lambda: model.evaluate(fz, kappa, alpha))
            from mftyre.compiled import compile_model

            kernel = compile_model(model, outputs=kernels)
            t_kernel, _ = timed(lambda: kernel.batch(fz, kappa, alpha, 0.0, 0.0, model.params.LONGVL,
                                                     model.params.INFLPRES))
            import dask
            import dask.array as da

            def big():
                chunk = 2**20  # (a task costs milliseconds of the scheduler's and worker's time: chunks of 1e6)
                out = model.evaluate_chunked(da.random.uniform(2000, 6000, n, chunks=chunk),
                                             da.random.uniform(-0.2, 0.2, n, chunks=chunk),
                                             da.random.uniform(-0.2, 0.2, n, chunks=chunk), outputs=kernels,
                                             chunks=chunk)
                with client.as_current():  # the sums come back, not the 3 x 8e8 bytes
                    return dask.compute(*(v.sum() for v in out.values()))

            t_big, c_big, _ = cpu_timed(big, client)
            rows.append((f"evaluation, {n:.2g} points", f"{1e9 * t_numpy / m:.0f} ns/point NumPy, "
                                                        f"{1e9 * t_kernel / m:.0f} ns/point compiled ({m:.0e})",
                         f"{1e9 * t_big / n:.0f} ns/point ({workers} workers; {cpu_text(c_big)})",
                         f"{t_numpy / m / (t_big / n):.1f}x the NumPy rate, {t_kernel / m / (t_big / n):.2f}x the "
                         "compiled kernel's in one process", "fx, fy, mz; random inputs drawn on the workers"))
        print()
        print("| case | serial (this process) | workers | ratio | notes |")
        print("|---|---|---|---|---|")
        for row in rows:
            print("| " + " | ".join(row) + " |")
        print(f"\n# after: {load()}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
