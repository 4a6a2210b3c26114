"""A realistic synthetic test-rig run: what a flat-belt or trailer rig records, sampled in time.

:func:`rig_programme` drives a tyre model (:class:`mftyre.MFModel`) through a test programme as a rig does and
records every channel at ``sample_rate`` (100 Hz by default), with what real rigs show and the idealised
:func:`mftyre.data.trailer_programme` leaves out:

* **time series**: slip angle and slip ratio are swept continuously (0 -> +max -> -max -> 0) at a constant rate,
  conditions change by ramps between the tests (rows marked ``TEST = "transition"``);
* **relaxation**: the tyre responds to a slip that lags the commanded (recorded) one by the first-order
  relaxation of the contact, d(alpha_t)/ds = (alpha - alpha_t) / sigma_alpha (Pacejka 2012, eq. 7.8 in the
  distance s = Vx t), with the model's relaxation lengths (outputs ``sigmay``, ``sigmax`` at the condition):
  up and down sweeps differ (hysteresis) by about 2 K sigma rate / V;
* **friction drift**: the friction scaling LMUX, LMUY follows the tread temperature over the day of testing
  (a warm-up and a slow decline, ``friction_drift`` peak-to-peak fraction), constant within a sweep;
* **load scatter**: the load control holds Fz within a few percent (``load_scatter``, a slowly varying AR(1)
  factor, correlation time 0.5 s); the tyre sees the actual load, the rig records it with sensor noise;
* **levels that are not round numbers**: every load, pressure and camber level is jittered (+-3 % of the
  load and pressure, +-0.15 deg of camber) from the fractions given;
* **autocorrelated measurement noise**: AR(1) in every recorded channel, standard deviation ``noise`` x
  :data:`mftyre.data.NOISE` (forces relative to FNOMIN, moments to FNOMIN x R0), correlation time
  ``noise_time`` (30 ms: about 0.7 lag-one correlation at 100 Hz);
* **free-rolling speed sweeps** from 1 to 40 m/s (My, Re, RL, OMEGA) and **vertical load sweeps** up and down
  (0.1 ... 2 FNOMIN at 1 m/s with RL and RHO).

The run is deterministic for a given ``seed``. Recorded channels: TIME [s], TEST and the canonical channels of
:data:`mftyre.data.CHANNELS` (no SWEEP: finding the sweeps is :func:`mftyre.programme.recognise`'s job).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from .data import CHANNELS, NOISE, TyreData, noise_scales, record_outputs, synthetic_data
from .inputs import hard_limits
from .timeseries import relaxed_slip

__all__ = ["rig_programme", "formula_student_tyre", "write_ttc_mat"]

_SLOW_SPEED = 1.0  # m/s, rolling speed of the vertical load sweeps


class _Path:
    """Commanded channels sampled in time: ramps and holds from the current state."""

    def __init__(self, dt, **state):
        self.dt, self.state, self.parts = dt, dict(state), []

    def move(self, duration, test, **targets):
        n = max(int(round(duration / self.dt)), 1)
        w = np.arange(1, n + 1) / n
        part = {k: v + (targets.get(k, v) - v) * w for k, v in self.state.items()}
        part["TEST"] = np.full(n, test)
        self.parts.append(part)
        self.state.update(targets)

    def frame(self):
        return pd.DataFrame({k: np.concatenate([p[k] for p in self.parts]) for k in self.parts[0]})


def _ar1(rng, n, phi):
    """Unit-variance AR(1) series with lag-one correlation ``phi``."""
    from scipy.signal import lfilter

    w = rng.normal(0.0, math.sqrt(1.0 - phi**2), n)
    w[0] = rng.normal()
    return lfilter([1.0], [1.0, -phi], w)


def rig_programme(model, *, loads=(0.45, 0.8, 1.15, 1.5), pressures=(0.86, 1.0, 1.14), cambers_deg=(-3.0, 0.0, 3.0),
                  speed: float | None = None, alpha_max_deg: float = 12.0, kappa_max: float = 0.2,
                  combined_alpha_deg=(3.0, 6.0), slip_angle_rate_deg: float = 6.0, slip_ratio_rate: float = 0.1,
                  sample_rate: float = 100.0, speed_range=None, speed_ramp: float = 5.0,
                  vertical_range=(0.1, 2.0), noise: float = 1.0, noise_time: float = 0.03,
                  load_scatter: float = 0.02, friction_drift: float = 0.03, relaxation: bool = True,
                  longitudinal: bool = True, lateral: bool = True, free_rolling: bool = True,
                  vertical_sweeps: bool = True, seed=0) -> TyreData:
    """A day of rig testing of ``model`` sampled at ``sample_rate`` [Hz] (see the module text for what it holds).

    Per pressure (fractions of NOMPRES) and load (fractions of FNOMIN), levels jittered: slip-angle sweeps at
    every camber; when ``longitudinal``, slip-ratio sweeps at camber 0 and at each angle of
    ``combined_alpha_deg``; a free-rolling speed sweep ``speed_range`` [m/s] (default 1 m/s to 40 m/s or 0.8 x the
    speed limits of :func:`mftyre.inputs.hard_limits`, the lower) at camber 0 (accelerating at
    ``speed_ramp`` m/s^2). Per pressure: one vertical load sweep up and down, ``vertical_range`` x FNOMIN.
    Slip tests run at ``speed`` (default LONGVL). ``relaxation=False`` removes the slip lag (no hysteresis).
    ``lateral=False`` leaves out the slip-angle sweeps, ``free_rolling=False`` the speed sweeps,
    ``vertical_sweeps=False`` the load sweeps (a drive/brake run: ``lateral=False`` with ``combined_alpha_deg``
    of one sign, as the slip-ratio sweeps of the TTC runs at three slip angles).
    """
    for name, value in (("sample_rate", sample_rate), ("slip_angle_rate_deg", slip_angle_rate_deg),
                        ("slip_ratio_rate", slip_ratio_rate), ("speed_ramp", speed_ramp)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"rig_programme: {name} must be a positive number, got {value!r}")
    for name, value in (("noise", noise), ("noise_time", noise_time), ("load_scatter", load_scatter),
                        ("friction_drift", friction_drift)):
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"rig_programme: {name} must be a number >= 0, got {value!r}")
    rng = np.random.default_rng(seed)
    prm = model.params
    fz0, p0 = prm.FNOMIN, prm.NOMPRES
    vx0 = prm.LONGVL if speed is None else float(speed)
    if speed_range is None:  # as a lab would: up to 40 m/s, not beyond what the tyre's own file makes of a speed
        limits = hard_limits(prm)
        speed_range = (1.0, min(40.0, 0.8 * limits["vx"][0], 0.8 * limits["rim"][0]))
    dt = 1.0 / float(sample_rate)
    load_levels = [f * fz0 * (1 + rng.uniform(-0.03, 0.03)) for f in loads]
    press_levels = [f * p0 * (1 + rng.uniform(-0.03, 0.03)) for f in pressures]
    camber_levels = [math.radians(g + (rng.uniform(-0.15, 0.15) if g else 0.0)) for g in cambers_deg]
    a_max, a_rate = math.radians(alpha_max_deg), math.radians(slip_angle_rate_deg)
    path = _Path(dt, FZ=load_levels[0], P=press_levels[0], IA=0.0, SA=0.0, SL=0.0, VX=vx0)

    def sweep(channel, amplitude, rate, test):
        t = amplitude / rate
        path.move(t, test, **{channel: amplitude})
        path.move(2 * t, test, **{channel: -amplitude})
        path.move(t, test, **{channel: 0.0})

    for p in press_levels:
        path.move(2.0, "transition", P=p, FZ=0.6 * fz0, SA=0.0, SL=0.0, IA=0.0,
                  VX=_SLOW_SPEED if vertical_sweeps else vx0)
        if vertical_sweeps:
            path.move(1.0, "transition", FZ=vertical_range[0] * fz0)
            path.move(2 * (vertical_range[1] - vertical_range[0]), "vertical", FZ=vertical_range[1] * fz0)
            path.move(2 * (vertical_range[1] - vertical_range[0]), "vertical", FZ=vertical_range[0] * fz0)
        for fz in load_levels:
            path.move(1.5, "transition", FZ=fz, IA=0.0, VX=vx0, SA=0.0, SL=0.0)
            for g in camber_levels if lateral else ():
                path.move(1.0, "transition", IA=g)
                path.move(0.5, "transition")
                sweep("SA", a_max, a_rate, "pure_lateral")
            path.move(1.0, "transition", IA=0.0)
            if longitudinal:
                for a in (*((0.0,) if 0.0 not in combined_alpha_deg else ()), *combined_alpha_deg):
                    path.move(1.0, "transition", SA=math.radians(a))
                    path.move(0.5, "transition")
                    sweep("SL", kappa_max, slip_ratio_rate, "pure_longitudinal" if a == 0.0 else "combined")
                path.move(1.0, "transition", SA=0.0)
            if free_rolling:
                path.move(2.0, "transition", VX=speed_range[0])
                path.move((speed_range[1] - speed_range[0]) / speed_ramp, "free_rolling", VX=speed_range[1])
                path.move(2.0, "transition", VX=vx0)
    frame = path.frame()
    n = len(frame)
    time = np.arange(n) * dt
    # what the tyre sees: the actual load (scatter), the lagging slip, the drifting friction
    fz_true = frame["FZ"].to_numpy() * (1.0 + load_scatter * _ar1(rng, n, math.exp(-dt / 0.5)))
    fz_true = np.maximum(fz_true, 0.0)
    vx, p, gamma = frame["VX"].to_numpy(), frame["P"].to_numpy(), frame["IA"].to_numpy()
    alpha_cmd, kappa_cmd = frame["SA"].to_numpy(), frame["SL"].to_numpy()
    if relaxation:
        relax = model.evaluate(fz_true, 0.0, 0.0, gamma, 0.0, vx, p)
        alpha_t = relaxed_slip(alpha_cmd, vx * dt, np.asarray(relax.sigmay, float))
        kappa_t = relaxed_slip(kappa_cmd, vx * dt, np.asarray(relax.sigmax, float))
    else:
        alpha_t, kappa_t = alpha_cmd, kappa_cmd
    total = max(time[-1], dt)
    # tread temperature over the day: warm-up over the first tenth, then a slow decline (wear, heat soak)
    day = time / total
    mu_factor = 1.0 + friction_drift * (0.5 * (1.0 - np.exp(-day / 0.1)) - day + 0.25)
    tests = frame["TEST"].to_numpy()
    block = np.concatenate([[0], np.cumsum(tests[1:] != tests[:-1])])
    out = {k: np.empty(n) for k in ("fx", "fy", "mx", "my", "mz", "omega", "rl", "rho", "re")}
    for b in np.unique(block):
        sel = block == b
        mu = float(np.mean(mu_factor[sel]))
        tyre = model.with_params(LMUX=prm.LMUX * mu, LMUY=prm.LMUY * mu) if friction_drift else model
        res = tyre.evaluate(fz_true[sel], kappa_t[sel], alpha_t[sel], gamma[sel], 0.0, vx[sel], p[sel])
        for k in out:
            out[k][sel] = np.asarray(res[k], float)
    rec = pd.DataFrame({"TIME": time, "TEST": tests})
    rec["FZ"] = fz_true
    record_outputs(rec, out)
    rec["SL"], rec["SA"], rec["IA"], rec["PHIT"], rec["VX"], rec["P"] = kappa_cmd, alpha_cmd, gamma, 0.0, vx, p
    if noise:
        phi = math.exp(-dt / noise_time) if noise_time > 0 else 0.0
        scale = noise_scales(prm)
        for ch, sd in NOISE.items():
            rec[ch] = rec[ch] + noise * sd * scale[ch] * _ar1(rng, n, phi)
        # the rig's own inputs are measured too, with small white noise
        for ch, sd in (("SA", math.radians(0.02)), ("SL", 5e-4), ("IA", math.radians(0.01)), ("VX", 0.02),
                       ("P", 200.0)):
            rec[ch] = rec[ch] + noise * rng.normal(0.0, sd, n)
    order = ["TIME", "TEST", *[c for c in CHANNELS if c in rec.columns]]
    note = (f"rig_programme: {n} samples at {sample_rate:g} Hz, loads {[round(x) for x in load_levels]} N, pressures "
            f"{[round(x) for x in press_levels]} Pa, cambers {[round(math.degrees(g), 2) for g in camber_levels]} deg, "
            f"noise {noise:g} (AR(1), {noise_time * 1e3:g} ms), load scatter {load_scatter:g}, friction drift "
            f"{friction_drift:g}, relaxation {relaxation}, seed {seed}")
    return synthetic_data(rec[order], prm, vx0, "rig_programme", note)


def formula_student_tyre(size: str = "16x7.5-10", *, fnomin: float = 1100.0, nompres: float = 0.83e5,
                         longvl: float = 40 / 3.6, vertical_stiffness: float = 1.1e5):
    """A Formula Student tyre (an :class:`mftyre.MFModel`) of the tyre ``size`` (:func:`mftyre.geometry.tyre_size`,
    default a 16x7.5-10 on a 10-inch rim: R0 0.2032 m, rim radius 0.127 m): the sample car tyre's Magic Formula
    coefficients (dimensionless, normalised by FNOMIN and R0) on the small tyre's geometry, nominal load and
    pressure, vertical stiffness, mass and inertias. A stand-in for the small tyres of the TTC runs, for tests and
    examples; not a measured tyre."""
    from .files import sample_tir
    from .geometry import tyre_size
    from .model import load_tir

    car = load_tir(sample_tir("car_205_60R15_mf61.tir"))
    geo = tyre_size(size)
    mass = 4.5 * (geo.width / 0.1905) * (geo.unloaded_radius / 0.2032) ** 2
    return car.with_params(**geo.parameters(), FNOMIN=fnomin, NOMPRES=nompres, INFLPRES=nompres, LONGVL=longvl,
                           VERTICAL_STIFFNESS=vertical_stiffness, BOTTOM_STIFF=10 * vertical_stiffness,
                           FZMIN=0.0, FZMAX=3.0 * fnomin, PRESMIN=0.5 * nompres, PRESMAX=1.5 * nompres,
                           MASS=mass, IYY=0.6 * mass * geo.unloaded_radius**2, BELT_MASS=0.75 * mass,
                           BELT_IYY=0.5 * mass * geo.unloaded_radius**2,
                           LONGITUDINAL_STIFFNESS=0.35 * car.params.LONGITUDINAL_STIFFNESS * fnomin / car.params.FNOMIN,
                           LATERAL_STIFFNESS=car.params.LATERAL_STIFFNESS * fnomin / car.params.FNOMIN)


#: The channels of a metric TTC run in the order written by :func:`write_ttc_mat`, with their units.
TTC_LAYOUT = (("ET", "s"), ("V", "kph"), ("N", "rpm"), ("SA", "deg"), ("IA", "deg"), ("RL", "cm"), ("RE", "cm"),
              ("P", "kPa"), ("FX", "N"), ("FY", "N"), ("FZ", "N"), ("MX", "N-m"), ("MZ", "N-m"), ("NFX", "none"),
              ("NFY", "none"), ("SL", "none"), ("TSTC", "degC"))


def write_ttc_mat(data: TyreData, path, *, tireid: str = "", dead_spin: bool = False, seed=0,
                  overwrite: bool = False):
    """Write ``data`` (a :func:`rig_programme` run) as the Calspan tyre test consortium delivers its runs: a MATLAB
    ``.mat`` file of vectors ET V N SA IA RL RE P FX FY FZ MX MZ NFX NFY SL TSTC in metric units and SAE axes (FY,
    FZ, MZ and SA turned half a turn about x), a ``channel`` struct array with each name and unit, and the
    ``tireid`` (the tyre description, e.g. ``"Hoosier 43075 16x7.5-10 R25B, 7 in rim"``). ``dead_spin``: the wheel
    spin sensor reads about 0 rpm (|N| < 1 rpm, noise), so the RE the rig computes from it, V / N, is garbage (as in
    a real cornering run). Refuses to replace an existing file without ``overwrite``."""
    import io

    import scipy.io

    from .errors import DataError
    from .files import write_atomically

    path = Path(path)
    if path.exists() and not overwrite:
        raise DataError(f"{path}: file exists: pass overwrite=True to replace it")
    f = data.frame
    n = len(f)
    omega = f["OMEGA"].to_numpy(float)
    vx = f["VX"].to_numpy(float)
    re = f["RE"].to_numpy(float) if "RE" in f else vx / np.maximum(omega, 1e-9)
    if dead_spin:
        rng = np.random.default_rng(seed)
        omega = np.abs(rng.normal(0.0, 0.5, n)) * 2 * math.pi / 60 + 1e-4  # < 1 rpm
        re = vx / omega
    fz = -f["FZ"].to_numpy(float)  # SAE: z down
    cols = {"ET": f["TIME"].to_numpy(float) if "TIME" in f else np.arange(n) * 0.01, "V": vx * 3.6,
            "N": omega * 60 / (2 * math.pi), "SA": -np.degrees(f["SA"].to_numpy(float)),
            "IA": np.degrees(f["IA"].to_numpy(float)), "RL": 100 * f["RL"].to_numpy(float), "RE": 100 * re,
            "P": f["P"].to_numpy(float) / 1e3, "FX": f["FX"].to_numpy(float), "FY": -f["FY"].to_numpy(float),
            "FZ": fz, "MX": f["MX"].to_numpy(float), "MZ": -f["MZ"].to_numpy(float),
            "SL": f["SL"].to_numpy(float), "TSTC": np.full(n, 55.0)}
    cols["NFX"], cols["NFY"] = cols["FX"] / fz, cols["FY"] / fz
    channel = np.array([(name, unit) for name, unit in TTC_LAYOUT], dtype=[("name", object), ("units", object)])
    buffer = io.BytesIO()
    scipy.io.savemat(buffer, {name: np.asarray(cols[name], float) for name, _ in TTC_LAYOUT}
                     | {"channel": channel, "tireid": tireid, "testid": "Drive/Brake/Combined" if np.ptp(cols["SL"]) > 0.02 else
                        "Cornering"})
    return write_atomically(path, buffer.getvalue())
