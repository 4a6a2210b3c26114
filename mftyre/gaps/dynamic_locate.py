"""Locating a dynamic gap in the terms engineers use, per run (condition) and channel: the level before the
event, peak values, peak-to-peak, the response length (travel over which the signal departs from its level by
more than 10 % of its largest departure), for a steer or braking step the phase lag (time to 63 % of the final
change) and its build-up distance (lag x speed), and the frequency and damping ratio of the free decay after the obstacle
(a damped sine fitted to the tail).

:func:`features` computes them from one signal; :func:`compare` puts measured beside model values with the
uncertainty that the measurement noise gives each feature, and flags the differences beyond 3 of them.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["FEATURES", "features", "compare"]

FEATURES = ("level", "peak", "peak_to_peak", "response_length", "lag", "build_up", "frequency", "damping")
UNITS = {"level": "", "peak": "", "peak_to_peak": "", "response_length": "m", "lag": "ms", "build_up": "m",
         "frequency": "Hz", "damping": "-"}


def _decay(y, dt):
    """(frequency Hz, damping ratio, their standard errors) of a damped sine fitted to ``y`` (nan when none)."""
    from scipy.optimize import curve_fit

    n = y.size
    if n < 30:
        return (math.nan,) * 4
    y = y - np.mean(y[-max(5, n // 5):])
    spec = np.abs(np.fft.rfft(y * np.hanning(n), 8 * n))
    f = np.fft.rfftfreq(8 * n, dt)
    band = (f > 15) & (f < 150)
    if not band.any():
        return (math.nan,) * 4
    f0 = float(f[band][np.argmax(spec[band])])
    t = dt * np.arange(n)

    def model(t, a, zeta, fr, phi, c):
        w = 2 * math.pi * fr
        return a * np.exp(-zeta * w * t) * np.cos(w * math.sqrt(max(1 - zeta**2, 1e-6)) * t + phi) + c

    # the start: amplitude and phase at f0 and damping 0.1 by linear least squares (a phase near pi from 0, with the
    # amplitude kept positive, took thousands of iterations)
    w0, zeta0 = 2 * math.pi * f0, 0.1
    decay0, wd0 = np.exp(-zeta0 * w0 * t), w0 * math.sqrt(1 - zeta0**2)
    basis = np.column_stack([decay0 * np.cos(wd0 * t), decay0 * np.sin(wd0 * t), np.ones_like(t)])
    cos_part, sin_part, c0 = np.linalg.lstsq(basis, y, rcond=None)[0]
    start = (math.hypot(cos_part, sin_part), zeta0, f0, math.atan2(-sin_part, cos_part), c0)
    try:
        p, cov = curve_fit(model, t, y, p0=start,
                           bounds=([0, 0, 5, -10, -np.inf], [np.inf, 0.9, 300, 10, np.inf]), maxfev=2000)
    except (RuntimeError, ValueError):
        return (math.nan,) * 4
    err = np.sqrt(np.clip(np.diag(cov), 0, np.inf))
    return float(p[2]), float(p[1]), float(err[2]), float(err[1])


def features(y, t, x, kind: str, quiet: int, *, decay_from: int | None = None, sigma: float = 0.0) -> dict:
    """Features of signal ``y`` over time ``t`` and axle travel ``x``; ``quiet``: samples before the event;
    ``decay_from``: first sample of the free decay (cleat runs; None: none); ``sigma``: the noise (the response
    length counts departures beyond 4 sigma; frequency and damping only from a decay 10 sigma high, with their
    standard errors ``frequency_se``, ``damping_se``). Samples missing in ``y`` (NaN) are left out; the lag and
    build-up only where the step's change is 10 sigma high (below, noise decides where 63 % of it is reached)."""
    y = np.asarray(y, float)
    dt = float(t[1] - t[0])
    q = max(quiet, 3)
    level = float(np.nanmean(y[:q]))
    dev = y - level
    out = dict(level=level, peak=float(y[np.nanargmax(np.abs(dev))]),
               peak_to_peak=float(np.nanmax(y[q:]) - np.nanmin(y[q:])) if y.size > q else math.nan)
    big = np.flatnonzero(np.abs(dev) > max(0.1 * np.nanmax(np.abs(dev)), 4 * sigma))
    out["response_length"] = float(x[big[-1]] - x[big[0]]) if big.size > 1 else math.nan
    out["lag"] = out["build_up"] = math.nan
    if kind in ("steer", "brake"):
        final = float(np.nanmean(y[-max(10, y.size // 10):]))
        change = final - level
        after = np.flatnonzero(np.sign(change) * (y[q:] - level) >= 0.632 * abs(change))
        if after.size and abs(change) > 10 * sigma:
            out["lag"] = 1e3 * dt * float(after[0])
            out["build_up"] = float(x[q + after[0]] - x[q])
    out["frequency"] = out["damping"] = out["frequency_se"] = out["damping_se"] = math.nan
    if decay_from is not None and y.size - decay_from > 30:
        tail = y[decay_from:decay_from + int(0.15 / dt)]
        if np.all(np.isfinite(tail)) and np.ptp(tail) > 10 * sigma:
            f, z, fe, ze = _decay(tail, dt)
            if fe < 0.2 * f and ze < 0.5:
                out.update(frequency=f, damping=z, frequency_se=fe, damping_se=ze)
    return out


def compare(measured: dict, model: dict, sigma: float, dt: float, speed: float) -> list:
    """Per feature: dict(feature, measured, model, difference, uncertainty, z) with the uncertainty the noise
    ``sigma`` gives the feature (level: sigma/sqrt(quiet samples) is not known here, so 1 sigma; peaks 2 sigma;
    peak-to-peak 3 sigma; lag 2 samples; lengths the travel in 2 samples plus 5 mm; frequency and damping their
    fit's standard errors plus 2 % of the measured value)."""
    unc = dict(level=sigma, peak=2 * sigma, peak_to_peak=3 * sigma, response_length=2 * speed * dt + 0.005,
               lag=2e3 * dt, build_up=2 * speed * dt + 0.005)
    rows = []
    for f in FEATURES:
        m, s = measured.get(f, math.nan), model.get(f, math.nan)
        if not (math.isfinite(m) and math.isfinite(s)):
            continue
        u = unc.get(f) or math.hypot(measured.get(f + "_se", 0.0), model.get(f + "_se", 0.0)) + 0.02 * abs(m)
        rows.append(dict(feature=f, measured=m, model=s, difference=m - s, uncertainty=u, z=(m - s) / u))
    return rows
