"""Time per co-simulation step of the tyre FMU against a direct Python call of the same model, side by side.

    python benchmarks/bench_fmu.py [--tir FILE.tir] [--steps 20000] [--repeat 3]

One step = set the six vehicle inputs (vx, vy, omega, gamma, Fz_in or z, p), do the step, get the six wheel-centre
loads. Rows, each the time per step (best of --repeat) and its ratio to the baseline, the direct NumPy call:

* ``MFModel.evaluate`` (NumPy), one point, slips computed in Python: the baseline;
* the FMU's computation called directly in Python (``mftyre_fmu_core.SteadyTyre``), compiled C and CasADi VM;
* the FMU through fmpy (``FMU2Slave``: fmi2SetReal, fmi2DoStep, fmi2GetReal), evaluators compiled and casadi,
  vertical input load and position.

Swift mode (``--swift-tir``, default the SWIFT sample tyre; a 1 cm cleat every 5 m, axle height imposed, spin
imposed, 1 ms communication steps), its own baseline: ``SwiftTyre.step`` called directly in a Python loop;
then the FMU's computation (``mftyre_fmu_core.SwiftCore.advance``, which adds the input mapping and the MF at the
contact patch for the extra outputs) and the FMU through fmpy.

The FMUs are built into a temporary folder first (their build times are printed).
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

from timing import best_time  # noqa: E402  (benchmarks/timing.py)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "fmu"))

from build import build_fmu  # noqa: E402
from mftyre_fmu_core import SteadyTyre, SwiftCore  # noqa: E402

SWIFT_ROAD = "+".join(f"cleat(x0={5.0 * k + 3.0}, length=0.05, height=0.01)" for k in range(5))




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

    def runner(self, steps, swift=False):
        if swift:
            return self.swift_runner(steps)
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

    def swift_runner(self, steps):
        set_vr = [self.vr[k] for k in ("vx", "vy", "omega", "gamma", "z", "p")]
        get_vr = [self.vr[k] for k in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")]
        fmu, h = self.fmu, 1e-3

        def run():
            t = 0.0
            for i in range(steps):
                fmu.setReal(set_vr, list(swift_inputs(i)))
                fmu.doStep(t, h)
                t += h
                fmu.getReal(get_vr)
        return run

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def swift_inputs(i):
    """vx, vy, omega, gamma, z, p of step i (swift rows): 10 m/s with small variations."""
    s = 1e-3 * i
    return 10.0 + 0.2 * math.sin(s), 0.1 * math.sin(3 * s), (10.0 + 0.2 * math.sin(s)) / 0.305, 0.01, \
        0.288 + 0.001 * math.sin(7 * s), 2.2e5


def direct_swift_step(tyre, steps):
    """SwiftTyre.step in a Python loop: the swift baseline (the inputs built as StepInputs each step)."""
    from swift import StepInputs

    def run():
        vx, vy, omega, gamma, z, p = swift_inputs(0)
        state = tyre.initial_state(StepInputs(x=0.0, vx=vx, z=z, omega=omega, p=p, vy=vy, gamma=gamma))
        for i in range(steps):
            vx, vy, omega, gamma, z, p = swift_inputs(i)
            state, out = tyre.step(state, StepInputs(x=state[9], vx=vx, z=z, omega=omega, p=p, vy=vy, gamma=gamma),
                                   1e-3)
            (out["fx"], out["fy"], out["fz"], out["mx"], out["my"], out["mz"])
    return run


def direct_swift_core(core, steps):
    names = ("vx", "vy", "omega", "gamma", "z", "p")

    def run():
        u = dict(zip(names, swift_inputs(0)), vz=0.0, road_z=0.0, Fz_in=0.0, torque=0.0)
        core.initialise(u)
        for i in range(steps):
            u.update(zip(names, swift_inputs(i)))
            core.advance(u, 1e-3)
    return run


def swift_rows(tir, tmp, steps, repeat):
    from swift import Cleat, SwiftTyre
    from swift.ring import STATE_NAMES

    assert STATE_NAMES[9] == "xa"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(tir)
        t0 = time.perf_counter()
        path = build_fmu(tir, Path(tmp) / "tyre_swift.fmu", model="swift", vertical_input="position")
        print(f"{Path(tir).name}: swift FMU built in {time.perf_counter() - t0:.1f} s")
        road = Cleat(3.0, 0.05, 0.01)
        for k in range(1, 5):
            road = road + Cleat(5.0 * k + 3.0, 0.05, 0.01)
        tyre = SwiftTyre(model, road, axle="height", rim="speed", x_range=(-1.0, 30.0))
        core = SwiftCore(model, SWIFT_ROAD, vertical="position")
    n = min(steps, 2500)  # 25 m: the road above
    rows = [("swift direct: SwiftTyre.step in a Python loop", best_time(direct_swift_step(tyre, n), repeat) / n),
            ("swift direct: FMU computation (SwiftCore.advance)", best_time(direct_swift_core(core, n), repeat) / n)]
    stepper = FMUStepper(path, tmp, {"road": SWIFT_ROAD})
    rows.append(("swift FMU via fmpy: set 6 + doStep + get 6, position", best_time(stepper.runner(n, swift=True),
                                                                             repeat) / n))
    stepper.close()
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tir", default=str(ROOT / "tir_files" / "car_205_60R15_mf61.tir"))
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--swift-tir", default=str(ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir"))
    ap.add_argument("--no-swift", action="store_true", help="skip the swift-mode rows")
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
        rows = [("direct: MFModel.evaluate (NumPy), one point", best_time(direct_numpy(model, max(steps // 20, 200)),
                                                                  args.repeat) / max(steps // 20, 200))]
        for ev in ("compiled", "casadi"):
            core = SteadyTyre(model, ev)
            n = steps if ev == "compiled" else steps // 5
            rows.append((f"direct: FMU computation in Python, {ev}", best_time(direct_core(core, n), args.repeat) / n))
        for ev, vertical in (("compiled", "load"), ("compiled", "position"), ("casadi", "load")):
            stepper = FMUStepper(path, tmp, {"evaluator": ev, "vertical_input": vertical})
            n = steps if ev == "compiled" else steps // 5
            rows.append((f"FMU via fmpy: set 6 + doStep + get 6, {ev}, {vertical}",
                         best_time(stepper.runner(n), args.repeat) / n))
            stepper.close()
        srows = [] if args.no_swift else swift_rows(args.swift_tir, tmp, steps, args.repeat)
    width = max(len(r[0]) for r in rows + srows)
    for table, label in ((rows, "vs NumPy"), (srows, "vs step")):
        if not table:
            continue
        base = table[0][1]
        print(f"\n{'':{width}}  {'us/step':>9}  {label:>9}")
        for name, t in table:
            print(f"{name:{width}}  {t * 1e6:9.1f}  {t / base:9.3f}")


if __name__ == "__main__":
    main()
