"""Time per co-simulation step of the tyre FMU against a direct Python call of the same model, side by side.

    python benchmarks/bench_fmu.py [--tir FILE.tir] [--steps 20000] [--repeat 3]

One step = set the six vehicle inputs (vx, vy, omega, gamma, Fz_in or z, p), do the step, get the six wheel-centre
loads. Rows, each the time per step (best of --repeat) and its ratio to the baseline, the direct NumPy call:

* ``MFModel.evaluate`` (NumPy), one point, slips computed in Python: the baseline;
* the FMU's computation called directly in Python (``mftyre_fmu_core.SteadyTyre``), compiled C and CasADi VM;
* the FMU through fmpy (``FMU2Slave``: fmi2SetReal, fmi2DoStep, fmi2GetReal), evaluators compiled and casadi,
  vertical input load and position.

The FMU is built into a temporary folder first (its build time is printed).
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import mftyre  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "fmu"))

from build import build_fmu  # noqa: E402
from mftyre_fmu_core import SteadyTyre  # noqa: E402


def best(fn, repeat):
    t = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        t = min(t, time.perf_counter() - t0)
    return t


def inputs(i):
    s = 1e-3 * i
    return 20.0 + math.sin(s), 0.4 * math.sin(3 * s), 68.0 + 2.0 * math.cos(s), 0.01, 4000.0 + 500 * math.sin(7 * s), 2.2e5


def direct_numpy(model, steps):
    re = 0.30

    def run():
        nonlocal re
        for i in range(steps):
            vx, vy, omega, gamma, fz, p = inputs(i)
            kappa = (omega * re - vx) / abs(vx)
            o = model.evaluate(fz, kappa, math.atan2(vy, abs(vx)), gamma, 0.0, vx, p, omega)
            re = float(o.re)
            (float(o.fx), float(o.fy), float(o.fz), float(o.mx), float(o.my), float(o.mz))
    return run


def direct_core(core, steps):
    def run():
        for i in range(steps):
            vx, vy, omega, gamma, fz, p = inputs(i)
            core.step_vehicle(vx, vy, omega, gamma, p, fz=fz)
    return run


class FMUStepper:
    def __init__(self, path, tmp, params):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        unz = extract(path, unzipdir=tempfile.mkdtemp(dir=tmp))
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unz, modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName="tyre")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for k, v in params.items():
            self.fmu.setString([self.vr[k]], [v])
        self.fmu.exitInitializationMode()
        self.position = params.get("vertical_input") == "position"

    def runner(self, steps):
        names = ("vx", "vy", "omega", "gamma", "z" if self.position else "Fz_in", "p")
        set_vr = [self.vr[k] for k in names]
        get_vr = [self.vr[k] for k in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")]
        fmu = self.fmu
        h = 1e-3

        def run():
            t = 0.0
            for i in range(steps):
                values = list(inputs(i))
                if self.position:
                    values[4] = 0.29 + 0.003 * math.sin(7e-3 * i)
                fmu.setReal(set_vr, values)
                fmu.doStep(t, h)
                t += h
                fmu.getReal(get_vr)
        return run

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tir_files" / "car_205_60R15_mf61.tir"))
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(args.tir)
    steps = args.steps
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        path = build_fmu(args.tir, Path(tmp) / "tyre.fmu")
        print(f"{Path(args.tir).name}: FMU built in {time.perf_counter() - t0:.1f} s; {steps} steps per row, "
              f"best of {args.repeat}")
        rows = [("direct: MFModel.evaluate (NumPy), one point", best(direct_numpy(model, max(steps // 20, 200)),
                                                                  args.repeat) / max(steps // 20, 200))]
        for ev in ("compiled", "casadi"):
            core = SteadyTyre(model, ev)
            n = steps if ev == "compiled" else steps // 5
            rows.append((f"direct: FMU computation in Python, {ev}", best(direct_core(core, n), args.repeat) / n))
        for ev, vertical in (("compiled", "load"), ("compiled", "position"), ("casadi", "load")):
            stepper = FMUStepper(path, tmp, {"evaluator": ev, "vertical_input": vertical})
            n = steps if ev == "compiled" else steps // 5
            rows.append((f"FMU via fmpy: set 6 + doStep + get 6, {ev}, {vertical}",
                         best(stepper.runner(n), args.repeat) / n))
            stepper.close()
    base = rows[0][1]
    width = max(len(r[0]) for r in rows)
    print(f"{'':{width}}  {'us/step':>9}  {'vs NumPy':>9}")
    for name, t in rows:
        print(f"{name:{width}}  {t * 1e6:9.1f}  {t / base:9.3f}")


if __name__ == "__main__":
    main()
