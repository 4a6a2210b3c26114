"""Hidden-effect cases of the dynamic gap finder: the pass table (and the time per case).

    python benchmarks/bench_dynamic_gaps.py [--tir FILE] [--duration 2.0] [--cases NAME,...] [--quick] [--workers N]

Each case generates runs from the file with ONE parameter changed (the truth), with noise, a causal 4th-order
anti-alias filter at 150 Hz and a 5 ms delay, and gives the finder the unchanged file and the whole catalogue.
Cleat cases: 12 runs (10, 40, 70 km/h x 1.8, 2.6 bar x 3, 5 kN), ``--duration`` s each at 1 kHz (2 s: the
issue's speed case). Steer cases: 4 step-steer runs (2 deg; 20-80 km/h). Relaxed-wheel cases (model kind relaxed,
truth and finder): 4 step steers and 6 braking steps (-5 % slip; 20, 50, 80 km/h x 2 loads), on the TNO file (MF 6.2:
relaxation lengths K/C) and on the public MF 5.2 file of MFeval (PTX*/PTY*). A case passes when the finder adds exactly
the changed effect (control: nothing) and every channel whose held-out RMS error was above 1.5 x the noise floor
ends within 1.3 x of it; a change that leaves every channel within 1.1 x the noise floor is reported "invisible"
(no run shows it). A changed file must pass verify_tir like the base file (else the case is not a tyre). Time: CPU seconds of this process plus its children (the C compiler), i.e. on one core.
Default file: ../shared/reference/tir/TNO_car205_60R15.tir, else tir_files/car_205_60R15_mf62_swift.tir.
``--workers N``: the simulations on a local cluster of N worker processes (mftyre.runner), started before the first
case; CPU then counts the workers too. Serial and parallel side by side in one run:
``for w in 0 2; do python benchmarks/bench_dynamic_gaps.py --cases "sidewall over pressure" --workers $w; done``.

    python benchmarks/bench_dynamic_gaps.py --rig [--duration 0.6] [--cases NAME,...] [--seed 12 --chain-offset 20]

The rig suite (issue 33; :data:`RIG_CASES`): cases the finder was not tuned to, on two property files (the TNO
file and the sample SWIFT file), each with its own measurement chain drawn from the rig ranges of the issue (a
causal 4th-order anti-alias filter at 90-300 Hz below Nyquist, 3.5-12 ms delay, 500 Hz-2 kHz sampling, AR(1)
sensor noise, load-cell gains off by 1-2 %, a slow offset drift), obstacles beyond cleats (trapezoid, step up,
pothole) and manoeuvres (step steer, braking step), one and two effects at a time, and controls. The finder gets
the unchanged file and the whole catalogue; the pass rule is the one above, with "named" meaning exactly the
changed effects (in any order).
"""
from __future__ import annotations

import argparse
import resource
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import mftyre  # noqa: E402
from mftyre.fit.verify import verify_tir  # noqa: E402
from mftyre.gaps.dynamic import find_dynamic_gaps  # noqa: E402
from mftyre.gaps.dynamic_runs import synthetic_runs  # noqa: E402

CLEAT = dict(speeds=(10.0, 40.0, 70.0), pressures=(1.8e5, 2.6e5), loads=(3000.0, 5000.0), steer_speeds=())
STEER = dict(speeds=(), steer_speeds=(20.0, 40.0, 60.0, 80.0))
RELAXED = dict(speeds=(), steer_speeds=(20.0, 40.0, 60.0, 80.0), brake_speeds=(20.0, 50.0, 80.0), model_kind="relaxed")
MF52 = ROOT.parent / "shared" / "reference" / "mfeval" / "MagicFormula52_Parameters.tir"
#: name -> (setting, {parameter: factor of its value, or ("=", value)}, the effect's catalogue parameter)
CASES = {
    "control (cleat)": (CLEAT, {}, None),
    "sidewall over pressure": (CLEAT, {"SWIFT_PSTIFF": ("=", 1.4)}, "SWIFT_PSTIFF"),
    "contact length": (CLEAT, {"Q_RA1": 1.2}, "Q_RA1"),
    "in-plane damping": (CLEAT, {"DAMP_LONG": 2.0}, "DAMP_LONG"),
    "rolling radius variation": (CLEAT, {"SWIFT_REVAR": ("=", 0.4)}, "SWIFT_REVAR"),
    "in-plane stiffness": (CLEAT, {"FREQ_LONG": 0.88}, "FREQ_LONG"),
    "vertical stiffness over pressure": (CLEAT, {"PFZ1": 1.2}, "PFZ1"),
    "control (steer)": (STEER, {}, None),
    "lateral relaxation": (STEER, {"LATERAL_STIFFNESS": 0.7}, "LATERAL_STIFFNESS"),
    "yaw stiffness": (STEER, {"YAW_STIFFNESS": 0.7}, "YAW_STIFFNESS"),
    "relaxed: control": (dict(RELAXED, loads=(3000.0, 5000.0)), {}, None),
    "relaxed: lateral relaxation": (dict(RELAXED, loads=(3000.0, 5000.0)), {"LATERAL_STIFFNESS": 0.7},
                                    "LATERAL_STIFFNESS"),
    "relaxed: longitudinal relaxation": (dict(RELAXED, loads=(3000.0, 5000.0)), {"LONGITUDINAL_STIFFNESS": 1.4},
                                         "LONGITUDINAL_STIFFNESS"),
    "relaxed MF 5.2: control": (dict(RELAXED, loads=(6000.0, 9000.0), tir=MF52), {}, None),
    "relaxed MF 5.2: PTY1": (dict(RELAXED, loads=(6000.0, 9000.0), tir=MF52), {"PTY1": 0.75}, "PTY1"),
    "relaxed MF 5.2: PTX1": (dict(RELAXED, loads=(6000.0, 9000.0), tir=MF52), {"PTX1": 1.4}, "PTX1"),
}


SAMPLE = ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir"
TNO = ROOT.parent / "shared" / "reference" / "tir" / "TNO_car205_60R15.tir"
#: Obstacles of the rig suite ({x0}: the leading edge).
TRAPEZOID = "trapezoid(x0={x0}, top_length=0.05, height=0.015, ramp=0.03)"
STEP = "step({x0}, 0.012)"
POTHOLE = "cleat(x0={x0}, length=0.12, height=-0.015)"
CLEAT = "cleat(x0={x0}, length=0.02, height=0.01)"
_OBSTACLES = dict(speeds=(20.0, 60.0), pressures=(1.9e5, 2.5e5), steer_speeds=())
_STEERS = dict(speeds=(), steer_speeds=(25.0, 45.0, 65.0, 85.0))
#: name -> (file, runs, {parameter: factor or ("=", value)}, the changed effects' parameters, chain seed)
RIG_CASES = {
    "rig control: trapezoid + pothole (TNO)": (TNO, dict(_OBSTACLES, roads=(TRAPEZOID, POTHOLE)), {}, (), 1),
    "rig control: step + cleat (sample)": (SAMPLE, dict(_OBSTACLES, roads=(STEP, CLEAT)), {}, (), 2),
    "rig control: step steer (sample)": (SAMPLE, _STEERS, {}, (), 3),
    "rig: contact length on trapezoid (sample)": (SAMPLE, dict(_OBSTACLES, roads=(TRAPEZOID, POTHOLE)),
                                                  {"Q_RA1": 1.25}, ("Q_RA1",), 4),
    "rig: sidewall over pressure on a step (TNO)": (TNO, dict(_OBSTACLES, roads=(STEP, CLEAT)),
                                                    {"SWIFT_PSTIFF": ("=", 1.4)}, ("SWIFT_PSTIFF",), 5),
    "rig: in-plane damping on a pothole (TNO)": (TNO, dict(_OBSTACLES, roads=(POTHOLE, CLEAT)),
                                                 {"DAMP_LONG": 2.0}, ("DAMP_LONG",), 6),
    "rig: lateral relaxation on step steer (TNO)": (TNO, _STEERS, {"LATERAL_STIFFNESS": 0.7}, ("LATERAL_STIFFNESS",),
                                                  7),
    "rig: two at once: contact length + damping (TNO)": (TNO, dict(_OBSTACLES, roads=(TRAPEZOID, CLEAT)),
                                                         {"Q_RA1": 1.2, "DAMP_LONG": 2.0}, ("Q_RA1", "DAMP_LONG"), 8),
    "rig relaxed: braking step longitudinal relaxation (sample)": (
        SAMPLE, dict(speeds=(), steer_speeds=(), brake_speeds=(20.0, 50.0, 80.0), loads=(3000.0, 5000.0),
                     model_kind="relaxed"), {"LONGITUDINAL_STIFFNESS": 1.4}, ("LONGITUDINAL_STIFFNESS",), 9),
}


def rig_chain(seed: int) -> dict:
    """A measurement chain drawn from the issue's rig ranges (``synthetic_runs`` settings)."""
    import numpy as np

    rng = np.random.default_rng(1000 + seed)
    rate = float(rng.choice((500.0, 1000.0, 2000.0)))
    cutoff = float(min(rng.uniform(90.0, 300.0), 0.4 * rate))
    gain = {c: 1.0 + float(rng.choice((-1, 1)) * rng.uniform(0.01, 0.02)) for c in ("FX", "FY", "FZ", "MZ")}
    drift = {c: float(rng.uniform(-1, 1)) * (2.0 if c == "MZ" else 60.0) for c in ("FX", "FY", "FZ", "MZ")}
    return dict(dt=1.0 / rate, cutoff=cutoff, delay=float(rng.uniform(3.5e-3, 12e-3)), ar=float(rng.uniform(0.3, 0.8)),
                gain=gain, drift=drift)


def run_rig_case(name, duration, seed=11, chain_offset=0):
    tir, setting, change, params, chain_seed = RIG_CASES[name]
    chain_seed += chain_offset
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(tir)
    values = {p: (v[1] if isinstance(v, tuple) else model.params[p] * v) for p, v in change.items()}
    truth = model.with_params(**values)
    new_problems = [p for p in verify_tir(truth) if p not in verify_tir(model)]
    if new_problems:
        raise SystemExit(f"case {name!r}: the changed file fails verification: {new_problems[0]}")
    chain = rig_chain(chain_seed)
    runs = synthetic_runs(model, truth=truth, duration=duration, lead=0.3, seed=seed, **setting, **chain)
    t0, w0 = cpu(), time.perf_counter()
    rep = find_dynamic_gaps(runs, model, model_kind=setting.get("model_kind", "auto"), runner=RUNNER)
    seconds, wall = cpu() - t0, time.perf_counter() - w0
    found = sorted(p for c in rep.effects_added for p in c.parameters)
    named = (found == [] if not params else all(any(p in c.parameters for c in rep.effects_added) for p in params)
             and len(rep.effects_added) == len(params))
    shrunk = all(rep.error_after[c] <= 1.3 * rep.noise_floor[c] for c in rep.error_before
                 if rep.error_before[c] > 1.5 * rep.noise_floor[c])
    visible = not params or any(rep.error_before[c] > 1.1 * rep.noise_floor[c] for c in rep.error_before)
    ok = (named and shrunk) if visible else "invisible"
    return dict(case=name, runs=len(runs), named=", ".join(rep.effect_names) or "-", ok=ok, cpu=seconds, wall=wall,
                evaluations=rep.evaluations,
                rig=f"{1 / chain['dt']:.0f} Hz, {chain['cutoff']:.0f} Hz, {1e3 * chain['delay']:.1f} ms, AR "
                    f"{chain['ar']:.2f}, gain " + " ".join(f"{c} {chain['gain'][c]:.3f}" for c in sorted(rep.chain.gain)),
                fitted=f"{1e3 * rep.chain.delay:.1f} ms, "
                       + ("no filter" if rep.chain.cutoff is None else f"{rep.chain.cutoff:.0f} Hz/{rep.chain.order}")
                       + ", gain " + " ".join(f"{c} {g:.3f}" for c, g in rep.chain.gain.items()),
                errors=", ".join(f"{c} {rep.error_before[c]:.3g}->{rep.error_after[c]:.3g} ({rep.noise_floor[c]:.2g})"
                                 for c in rep.error_before))


def cpu() -> float:
    """CPU seconds of this process, its finished children (the C compiler) and its live ones (the runner's worker
    processes and their nannies)."""
    import psutil

    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    live = 0.0
    for child in psutil.Process().children(recursive=True):
        try:
            t = child.cpu_times()
            live += t.user + t.system
        except psutil.Error:
            pass
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime + live


#: The runner of --workers (None: serially in this process).
RUNNER = None


def run_case(model, name, duration, seed=11):
    setting, change, param = CASES[name]
    setting = dict(setting)
    if "tir" in setting:  # a case on another file
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = mftyre.load_tir(setting.pop("tir"))
    values = {p: (v[1] if isinstance(v, tuple) else model.params[p] * v) for p, v in change.items()}
    truth = model.with_params(**values)
    new_problems = [p for p in verify_tir(truth) if p not in verify_tir(model)]
    if new_problems:  # a hidden truth no tyre could have is no test: the finder rightly refuses it
        raise SystemExit(f"case {name!r}: the changed file fails verification: {new_problems[0]}")
    runs = synthetic_runs(model, truth=truth, duration=duration, lead=0.3, seed=seed, **setting)
    t0, w0 = cpu(), time.perf_counter()
    rep = find_dynamic_gaps(runs, model, model_kind=setting.get("model_kind", "auto"), runner=RUNNER)
    seconds, wall = cpu() - t0, time.perf_counter() - w0
    names = rep.effect_names
    named = (names == [] if param is None else len(names) == 1 and f"{param}" in " ".join(
        rep.effects_added[0].parameters))
    shrunk = all(rep.error_after[c] <= 1.3 * rep.noise_floor[c] for c in rep.error_before
                 if rep.error_before[c] > 1.5 * rep.noise_floor[c])
    # a change that leaves no gap beyond the noise in any channel cannot be named from these runs
    visible = param is None or any(rep.error_before[c] > 1.1 * rep.noise_floor[c] for c in rep.error_before)
    ok = (named and shrunk) if visible else "invisible"
    return dict(case=name, runs=len(runs), named=", ".join(names) or "-", ok=ok, named_ok=named,
                shrunk=shrunk, cpu=seconds, wall=wall, evaluations=rep.evaluations,
                errors=", ".join(f"{c} {rep.error_before[c]:.3g}->{rep.error_after[c]:.3g} ({rep.noise_floor[c]:.2g})"
                                 for c in rep.error_before))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir")
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--cases", help="comma-separated case names (default: all)")
    ap.add_argument("--quick", action="store_true", help="0.6 s runs")
    ap.add_argument("--rig", action="store_true", help="the rig suite (RIG_CASES) instead")
    ap.add_argument("--seed", type=int, default=11, help="the rig suite's sensor-noise seed (default 11)")
    ap.add_argument("--chain-offset", type=int, default=0,
                    help="added to every rig case's chain seed: other chains drawn from the same ranges (default 0)")
    ap.add_argument("--workers", type=int, default=0,
                    help="simulate on a local cluster of N worker processes (mftyre.runner; default 0: serially "
                         "in this process); the cluster is started before the first case (its start is printed)")
    a = ap.parse_args(argv)
    global RUNNER
    if a.workers:
        from mftyre.runner import Runner, default_workers

        RUNNER = Runner(workers=a.workers)
        w0 = time.perf_counter()
        RUNNER.run(default_workers, {"start": {}})  # a task that does nothing: the cluster up, its workers ready
        print(f"a local cluster of {a.workers} worker processes started in {time.perf_counter() - w0:.1f} s; CPU "
              "below: this process and every worker")
    try:
        return _main(a)
    finally:
        if RUNNER is not None:
            RUNNER.close()


def _main(a) -> int:
    if a.rig:
        warnings.simplefilter("ignore")
        names = [n.strip() for n in a.cases.split(",")] if a.cases else list(RIG_CASES)
        print(f"rig suite; runs of {a.duration:g} s; noise seed {a.seed}, chain seeds + {a.chain_offset}")
        print("| case | runs | pass | CPU s | wall s | rig chain (rate, cutoff, delay, AR(1), gains) | fitted chain | named | "
              "held-out RMS before -> after (noise) |")
        print("|---|---|---|---|---|---|---|---|---|")
        rows = []
        for n in names:
            r = run_rig_case(n, a.duration, a.seed, a.chain_offset)
            rows.append(r)
            status = r["ok"] if isinstance(r["ok"], str) else ("yes" if r["ok"] else "NO")
            print(f"| {r['case']} | {r['runs']} | {status} | {r['cpu']:.0f} | {r['wall']:.0f} | {r['rig']} | "
                  f"{r['fitted']} | {r['named']} | {r['errors']} |", flush=True)
        seen = [r for r in rows if r["ok"] != "invisible"]
        print(f"passed {sum(r['ok'] is True for r in seen)} of {len(seen)} ({len(rows) - len(seen)} invisible)")
        return 0
    shared = ROOT.parent / "shared" / "reference" / "tir" / "TNO_car205_60R15.tir"
    tir = Path(a.tir) if a.tir else (shared if shared.exists() else ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(tir)
    warnings.simplefilter("ignore")
    names = [n.strip() for n in a.cases.split(",")] if a.cases else list(CASES)
    duration = 0.6 if a.quick else a.duration
    print(f"file {tir.name}; runs of {duration:g} s at 1 kHz")
    print(f"{'case':34s} {'runs':>4s} {'pass':>9s} {'cpu s':>7s} {'wall s':>7s} {'evals':>5s}  named / held-out RMS "
          f"before->after (noise)")
    rows = []
    for n in names:
        r = run_case(model, n, duration)
        rows.append(r)
        status = r["ok"] if isinstance(r["ok"], str) else ("yes" if r["ok"] else "NO")
        print(f"{r['case']:34s} {r['runs']:4d} {status:>9s} {r['cpu']:7.1f} {r['wall']:7.1f} "
              f"{r['evaluations']:5d}  {r['named']} / {r['errors']}", flush=True)
    seen = [r for r in rows if r["ok"] != "invisible"]
    print(f"passed {sum(r['ok'] is True for r in seen)} of {len(seen)} (and {len(rows) - len(seen)} changes that leave "
          f"no gap beyond the noise: not nameable from these runs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
