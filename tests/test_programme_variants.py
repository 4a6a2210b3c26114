"""Programme recognition on rig runs of varied shapes (issue 11): the counts of levels and sweeps a test engineer
planned must be recognised exactly, whatever the rig's habits.

The runs are made here by a small generator of their own (not :mod:`mftyre.rig`): a commanded path of ramps,
holds and steps per channel, sampled at a given rate, with load scatter and drift, pressure drift, measurement
noise, a warm-up header, shuffled test order, dwell points, sweeps that start at a non-zero slip, camber set by
steps, separate files concatenated with time gaps, and point data at 10 Hz without TIME. The forces are a plain
saturating function of the slips: recognition does not look at them.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from mftyre.data import TyreData
from mftyre.programme import recognise

DEG = math.pi / 180.0
V_TEST = 16.0  # m/s, speed of the slip tests


class _Path:
    """Commanded channels: ramps (``go``), holds and instantaneous steps, sampled at ``rate``."""

    def __init__(self, rate, **state):
        self.rate, self.state, self.parts, self.files = rate, dict(state), [], [0]

    def go(self, seconds, **target):
        n = max(1, int(round(seconds * self.rate)))
        w = np.arange(1, n + 1) / n
        self.parts.append({k: v + (target.get(k, v) - v) * w for k, v in self.state.items()})
        self.state.update(target)

    def hold(self, seconds):
        self.go(seconds)

    def step(self, **target):
        self.state.update(target)

    def new_file(self):
        self.files.append(sum(len(p["FZ"]) for p in self.parts))

    def frame(self):
        return pd.DataFrame({k: np.concatenate([p[k] for p in self.parts]) for k in self.state})


def _slip_sweep(path, ch, amp, rate, shape):
    """One sweep of slip channel ``ch`` to +-amp at ``rate`` per second, in one of the shapes rigs use."""
    t = amp / rate
    if shape == "triangle":  # 0 -> +max -> -max -> 0
        path.go(t, **{ch: amp}), path.go(2 * t, **{ch: -amp}), path.go(t, **{ch: 0.0})
    elif shape == "dwell":  # the same with a dwell at either end
        path.go(t, **{ch: amp}), path.hold(1.0), path.go(2 * t, **{ch: -amp}), path.hold(1.0)
        path.go(t, **{ch: 0.0})
    elif shape == "nonzero":  # positioned at -max, one pass to +max, back to zero quickly
        path.go(0.3 * t, **{ch: -amp}), path.hold(0.5), path.go(2 * t, **{ch: amp}), path.go(0.3 * t, **{ch: 0.0})
    elif shape == "jump":  # starts at -max straight away (a step), one pass up, steps back
        path.step(**{ch: -amp}), path.go(2 * t, **{ch: amp}), path.step(**{ch: 0.0}), path.hold(0.5)
    else:
        raise ValueError(shape)


def _run(*, loads=(1620.0, 2230.0, 2790.0), pressures=(0.83e5, 0.97e5), cambers=(-2.0, 0.0, 2.0),
         combined=(0.0, 4.0), rate=100.0, shape="triangle", scatter=0.02, drift=0.0, pressure_drift=0.0,
         shuffle=False, warm_up=False, camber_steps=False, files=False, time=True, speed_sweeps=True,
         vertical=True, seed=0):
    """A rig run and the counts it was planned with."""
    rng = np.random.default_rng(seed)
    path = _Path(rate, FZ=0.0, P=pressures[0], IA=0.0, SA=0.0, SL=0.0, VX=0.0)
    if warm_up:  # roll up to speed and scrub the tread at small slip angles before the programme
        path.go(5.0, VX=V_TEST, FZ=0.8 * loads[0])
        for _ in range(8):
            path.go(1.0, SA=2.5 * DEG), path.go(1.0, SA=-2.5 * DEG)
        path.go(1.0, SA=0.0)
    else:
        path.go(2.0, VX=V_TEST, FZ=loads[0])
    p_order = rng.permutation(len(pressures)) if shuffle else range(len(pressures))
    for ip in p_order:
        if files and path.parts:
            path.new_file()
        path.go(3.0, FZ=0.3 * loads[0], P=pressures[ip], IA=0.0, SA=0.0, SL=0.0)
        path.hold(1.0)
        if vertical:  # load sweep up and down at the test speed
            path.go(4.0, FZ=1.6 * max(loads)), path.go(4.0, FZ=0.3 * loads[0])
        l_order = rng.permutation(len(loads)) if shuffle else range(len(loads))
        for il in l_order:
            path.go(1.5, FZ=loads[il])
            path.hold(1.0)
            for g in (rng.permutation(cambers) if shuffle else cambers):
                if camber_steps:
                    path.step(IA=g * DEG)
                else:
                    path.go(1.0, IA=g * DEG)
                path.hold(0.5)
                _slip_sweep(path, "SA", 12 * DEG, 6 * DEG, shape)
                path.hold(0.5)
            path.go(1.0, IA=0.0) if not camber_steps else path.step(IA=0.0)
            for a in combined:
                path.go(1.0, SA=a * DEG), path.hold(0.5)
                _slip_sweep(path, "SL", 0.2, 0.1, shape)
            path.go(1.0, SA=0.0), path.hold(0.5)
            if speed_sweeps:  # free rolling from 2 to 30 m/s
                path.go(2.0, VX=2.0), path.go(28.0 / 5.0, VX=30.0), path.go(2.0, VX=V_TEST), path.hold(0.5)
    f = path.frame()
    n = len(f)
    level = f["FZ"].to_numpy()
    # load control: AR(1) scatter (0.5 s) and a slow drift over each file; pressure drifting inside its stay
    phi = math.exp(-1.0 / (0.5 * rate))
    ar = np.zeros(n)
    e = rng.normal(0.0, math.sqrt(1 - phi**2), n)
    for k in range(1, n):
        ar[k] = phi * ar[k - 1] + e[k]
    s = np.arange(n) / n
    f["FZ"] = level * (1.0 + scatter * ar + drift * np.sin(2 * math.pi * 3 * s)) + rng.normal(0, 5.0, n)
    f["P"] = f["P"] * (1.0 + pressure_drift * np.sin(2 * math.pi * 7 * s)) + rng.normal(0, 200.0, n)
    f["IA"] += rng.normal(0, 0.01 * DEG, n)
    f["SA"] += rng.normal(0, 0.02 * DEG, n)
    f["SL"] += rng.normal(0, 5e-4, n)
    f["VX"] += rng.normal(0, 0.02, n)
    f["FY"] = -f["FZ"] * np.sin(1.3 * np.arctan(10 * f["SA"]))
    f["FX"] = f["FZ"] * np.sin(1.5 * np.arctan(12 * f["SL"]))
    f["MZ"] = -0.02 * f["FY"]
    if time:
        t = np.arange(n) / rate
        for k, start in enumerate(path.files[1:], 1):  # separate files: the clock jumps, or starts again
            t[start:] = t[start:] - t[start] + (0.0 if k % 2 else t[start - 1] + 600.0)
        f.insert(0, "TIME", t)
    planned = dict(loads=len(loads), pressures=len(pressures), cambers=len(cambers),
                   slip_angle=len(pressures) * len(loads) * len(cambers),
                   slip_ratio=len(pressures) * len(loads) * len(combined),
                   speed=len(pressures) * len(loads) * bool(speed_sweeps), load=len(pressures) * bool(vertical))
    return TyreData(f, source=f"variant {shape}"), planned


VARIANTS = {
    "plain": dict(),
    "one camber": dict(cambers=(0.0,)),
    "lateral only": dict(combined=()),
    "start at non-zero slip": dict(shape="nonzero"),
    "starts with a step": dict(shape="jump"),
    "dwell at the ends": dict(shape="dwell"),
    "load scatter 5 % and drift": dict(scatter=0.05, drift=0.03),
    "pressure drift": dict(pressure_drift=0.02),
    "not sorted by condition": dict(shuffle=True, seed=5),
    "warm-up header": dict(warm_up=True),
    "camber by steps": dict(camber_steps=True),
    "files with time gaps": dict(files=True, pressures=(0.8e5, 0.95e5, 1.1e5)),
    "10 Hz without TIME": dict(rate=10.0, time=False),
    "five loads, close": dict(loads=(1100.0, 1650.0, 2200.0, 2750.0, 3300.0), pressures=(0.9e5,), scatter=0.04),
    "no speed or vertical sweeps": dict(speed_sweeps=False, vertical=False),
}


def _counts(prog):
    return dict(loads=prog.levels["FZ"].size, pressures=prog.levels["P"].size, cambers=prog.levels["IA"].size,
                **{k: prog.count(k) for k in ("slip_angle", "slip_ratio", "speed", "load")})


@pytest.mark.parametrize("name", list(VARIANTS))
def test_recognised_counts_are_the_planned_ones(name):
    data, planned = _run(**VARIANTS[name])
    prog = recognise(data)
    assert _counts(prog) == planned
    # every slip-angle sweep covers the full +-12 deg and the loads are found where they were set
    sa = prog.sweeps[prog.sweeps["kind"] == "slip_angle"]
    lo = [data.array("SA")[a:b].min() for a, b in zip(sa["start"], sa["stop"])]
    hi = [data.array("SA")[a:b].max() for a, b in zip(sa["start"], sa["stop"])]
    np.testing.assert_allclose(np.degrees(lo), -12.0, atol=0.2)
    np.testing.assert_allclose(np.degrees(hi), 12.0, atol=0.2)
    loads = VARIANTS[name].get("loads", (1620.0, 2230.0, 2790.0))
    np.testing.assert_allclose(prog.levels["FZ"], loads, rtol=0.03)
    # the summary says what was planned, in words
    text = prog.summary()
    c = np.round(prog.levels["FZ"])
    assert f"{planned['loads']} loads {c.min():.0f} to {c.max():.0f} N" in text
    assert (f"{planned['pressures']} pressures" if planned["pressures"] > 1 else "1 pressure ") in text
    assert (f"{planned['cambers']} cambers" if planned["cambers"] > 1 else "1 camber ") in text
    for kind, words in (("slip_angle", "slip-angle sweeps"), ("slip_ratio", "slip-ratio sweeps"),
                        ("speed", "speed sweeps"), ("load", "vertical load sweeps")):
        assert (f"{planned[kind]} {words}" if planned[kind] else f"no {words}") in text
    assert ("no longitudinal slip" in text) == (planned["slip_ratio"] == 0)
