"""Start values: a neutral parameter set sized to the tyre, and first estimates from the data.

:func:`start_parameters` builds the parameter set a fit starts from when no start ``.tir`` is given: every
parameter at its schema default (:data:`mftyre.params.PARAMETERS`), the tyre's FNOMIN, NOMPRES, INFLPRES,
LONGVL, UNLOADED_RADIUS, WIDTH from the data's constants (TYDEX ``FNOMIN``, ``NOMPRES``, ``RFREE``,
``NOMWIDTH``, ``LONGVEL``) or estimated from the data (median load level, middle pressure level, median speed,
loaded radius extrapolated to zero load), the validity ranges set to the data's ranges, and the vertical
stiffness from the load-deflection data. :func:`estimate_stage` then replaces the leading coefficients of a
stage by values read off the data: peak friction (D), slope at zero slip (K, hence B), shifts, trail.
"""
from __future__ import annotations

import math

import numpy as np

from pathlib import Path

from ..data import TyreData
from ..errors import DataError
from ..geometry import find_size, tyre_size
from ..params import TyreParameters
from ..programme import cluster_levels
from .stages import level_labels

__all__ = ["start_parameters", "estimate_stage"]


def _level_centres(x):
    """Level centres (:func:`mftyre.programme.cluster_levels`); the median when no value is on a level."""
    x = np.asarray(x, dtype=float)
    centres = cluster_levels(x)[1]
    return centres if centres.size else np.array([float(np.median(x))])


def start_parameters(data: TyreData, fittyp: int = 61, *, size: str | None = None, sources: dict | None = None,
                     **given) -> TyreParameters:
    """A neutral MF 6.1 (or 6.2) parameter set for the tyre measured in ``data``; ``given`` overrides. ``size``: the
    tyre size designation (``"16x7.5-10"``, :func:`mftyre.geometry.tyre_size`; default: one found in the data's tyre
    description or file name). ``sources``: a dict filled with parameter -> where its value comes from (the
    provenance the fitted .tir states)."""
    sources = {} if sources is None else sources
    c = data.constants
    fz_levels = _level_centres(data.array("FZ"))
    p_levels = _level_centres(data.array("P"))
    values = dict(
        FNOMIN=float(c.get("FNOMIN") or round(float(np.median(fz_levels)), -1)),
        NOMPRES=float(c.get("NOMPRES") or p_levels[len(p_levels) // 2]),
        LONGVL=float(c.get("LONGVEL") or np.median(data.array("VX"))),
    )
    sources.update(FNOMIN="the data's constants" if c.get("FNOMIN") else "estimated from the data (median load level)",
                   NOMPRES="the data's constants" if c.get("NOMPRES") else "estimated from the data (middle pressure "
                                                                             "level)",
                   LONGVL="the data's constants" if c.get("LONGVEL") else "estimated from the data (median speed)")
    geo = tyre_size(size) if size else find_size(data.tyre, Path(data.source or "").name)
    where = "given (--size)" if size else f"the tyre size {geo.text!r} in the data's description" if geo else ""
    if geo is not None:
        values.update(RIM_RADIUS=geo.rim_radius, WIDTH=geo.width, ASPECT_RATIO=geo.aspect_ratio)
        sources.update(dict.fromkeys(("RIM_RADIUS", "WIDTH", "ASPECT_RATIO"), f"from {where}"))
    if isinstance(c.get("NOMWIDTH"), float):
        values["WIDTH"] = c["NOMWIDTH"]
        sources["WIDTH"] = "the data's constants (NOMWIDTH)"
    r0 = c.get("RFREE")
    sources["UNLOADED_RADIUS"] = "the data's constants (RFREE)"
    if not isinstance(r0, float):
        r0, sources["UNLOADED_RADIUS"] = _free_radius_from_data(data, geo)
    values["UNLOADED_RADIUS"] = r0
    values["INFLPRES"] = values["NOMPRES"]
    sources["INFLPRES"] = "= NOMPRES"
    ranges, said = _ranges(data)
    values.update(ranges)
    sources.update(said)
    cz = _vertical_stiffness(data, values["FNOMIN"], values["NOMPRES"])
    if cz:
        values["VERTICAL_STIFFNESS"] = cz
        sources["VERTICAL_STIFFNESS"] = "estimated from the data (Fz / deflection at the nominal load)"
    given = {k.upper(): v for k, v in given.items()}
    values.update(given)
    sources.update(dict.fromkeys(given, "given"))
    if "RIM_RADIUS" not in values:
        values["RIM_RADIUS"] = _RIM_RATIO * values["UNLOADED_RADIUS"]
        sources["RIM_RADIUS"] = (f"estimated as {_RIM_RATIO:g} x UNLOADED_RADIUS (no tyre size in the data: give "
                                 "--size or --set RIM_RADIUS=...)")
    values.update(_bottoming(data, values, sources))
    return TyreParameters.from_defaults(fittyp=fittyp, **values)


#: RIM_RADIUS / UNLOADED_RADIUS of the tyres that are measured when the size is not known (car 205/60R15 0.61,
#: Formula Student 16x7.5-10 0.63): a stated estimate, never a silent car value.
_RIM_RATIO = 0.62


def _bottoming(data: TyreData, values: dict, sources: dict) -> dict:
    """BOTTOM_OFFST such that bottoming starts below the smallest loaded radius measured (RL at load); DataError
    when the rim radius itself lies above it (a rim of another tyre)."""
    from ..params import PARAMETERS

    if not data.has("RL"):
        return {}
    rl, fz = data.array("RL"), data.array("FZ")
    ok = np.isfinite(rl) & (fz > 0)
    if not ok.any():
        return {}
    rl_min = float(np.quantile(rl[ok], 0.001))
    rim = float(values["RIM_RADIUS"])
    offset = float(values.get("BOTTOM_OFFST", PARAMETERS["BOTTOM_OFFST"].default))
    if rim >= rl_min:
        raise DataError(f"{data.source or 'the data'}: RIM_RADIUS {rim:.4g} m ({sources.get('RIM_RADIUS', 'default')})"
                        f" lies above the smallest loaded radius measured, {rl_min:.4g} m: the rim would be in the "
                        "road; give the tyre's size (--size, e.g. 16x7.5-10) or --set RIM_RADIUS=...")
    if rim + offset < 0.98 * rl_min:
        return {}
    sources["BOTTOM_OFFST"] = (f"lowered from {offset:g} m so that bottoming starts below the smallest loaded radius "
                               f"measured ({rl_min:.4g} m)")
    return {"BOTTOM_OFFST": 0.5 * (rl_min - rim)}


def _free_radius_from_data(data: TyreData, geo=None):
    if data.has("RL"):
        rl, fz = data.array("RL"), data.array("FZ")
        ok = np.isfinite(rl)
        low = ok & (fz <= np.quantile(fz[ok], 0.3))
        if low.sum() >= 2 and np.ptp(fz[low]) > 0:
            slope, intercept = np.polyfit(fz[low], rl[low], 1)
            return float(intercept), "estimated from the data (loaded radius extrapolated to zero load)"
    if geo is not None:
        return geo.unloaded_radius, f"from the tyre size {geo.text!r}"
    if data.has("RE"):
        return float(np.nanmax(data.array("RE")) * 1.03), "estimated from the data (1.03 x the largest RE)"
    raise DataError(f"{data.source}: the unloaded radius is unknown: no RFREE constant, no RL/RE channel; give "
                    "UNLOADED_RADIUS (e.g. fit_tir(..., start=start_parameters(data, UNLOADED_RADIUS=0.31)))")


def _ranges(data: TyreData) -> tuple[dict, dict]:
    """(ranges, sources): the declared ranges where the model is verified: the data's, padded by 2 % of the span.
    A slip measured with one sign only (slip angle beyond 1 deg, slip ratio beyond 0.01 on one side) gives a
    one-sided range (the other bound just across 0); a slip not measured keeps a placeholder range of +-0.05, said
    so."""
    def span(x, pad, floor):
        lo, hi = float(np.min(x)), float(np.max(x))
        w = max(hi - lo, floor)
        return lo - pad * w, hi + pad * w

    out, said = {}, {}
    for ch, lo_name, hi_name, small, what in (("SL", "KPUMIN", "KPUMAX", 0.01, "slip ratio"),
                                             ("SA", "ALPMIN", "ALPMAX", math.radians(1.0), "slip angle")):
        x = data.array(ch)
        lo, hi = span(x, 0.02, 0.1)
        neg, pos = float(np.min(x)) < -small, float(np.max(x)) > small
        if neg and pos:
            out[lo_name], out[hi_name] = min(lo, -0.05), max(hi, 0.05)
            said[lo_name] = said[hi_name] = f"the data's {what} range"
        elif neg or pos:
            out[lo_name], out[hi_name] = (lo, 0.5 * small) if neg else (-0.5 * small, hi)
            said[lo_name] = said[hi_name] = (f"the data's {what} range, ONE-SIDED: the data have {what}s of one sign "
                                             "only; the model is not verified for the other sign")
        else:
            out[lo_name], out[hi_name] = -0.05, 0.05
            said[lo_name] = said[hi_name] = f"placeholder: no {what} in the data"
    gmin, gmax = span(data.array("IA"), 0.02, 0.1)
    pmin, pmax = span(data.array("P"), 0.01, 0.1 * float(np.max(data.array("P"))))
    fz = data.array("FZ")
    out.update(CAMMIN=min(gmin, -0.05), CAMMAX=max(gmax, 0.05), PRESMIN=pmin, PRESMAX=pmax, FZMIN=0.0,
               FZMAX=float(1.1 * np.max(fz)))
    said.update(dict.fromkeys(("CAMMIN", "CAMMAX", "PRESMIN", "PRESMAX"), "the data's range"),
                FZMAX="1.1 x the largest load in the data")
    return out, said


def _vertical_stiffness(data: TyreData, fz0: float, p0: float) -> float | None:
    """Cz0: secant stiffness Fz/rho at the nominal load and pressure, from RHO (or RL)."""
    if data.has("RHO"):
        rho = data.array("RHO")
    else:
        return None
    fz, p = data.array("FZ"), data.array("P")
    ok = np.isfinite(rho) & (rho > 0) & (np.abs(p - p0) <= 0.02 * p0) & (np.abs(fz - fz0) <= 0.3 * fz0)
    if ok.sum() < 2:
        return None
    return float(np.median(fz[ok] / rho[ok]))


def _linear(x, y):
    """(intercept, slope) of the least-squares line; slope 0 for a single distinct x."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.size >= 2 and np.ptp(x) > 0:
        slope, intercept = np.polyfit(x, y, 1)
        return float(intercept), float(slope)
    return float(np.mean(y)), 0.0


def estimate_stage(stage_name: str, prm: TyreParameters, data: TyreData) -> dict:
    """First estimates of a stage's leading parameters from its data (at zero camber, nominal pressure
    where available); {} for stages that start from the neutral values."""
    if len(data) == 0:
        return {}
    fz0, p0 = prm.FNOMIN * prm.LFZO, prm.NOMPRES
    g, p = data.array("IA"), data.array("P")
    ref = (np.abs(g) < math.radians(0.25)) & (np.abs(p - p0) <= 0.02 * p0)
    if ref.sum() < 5:
        ref = np.abs(g) < math.radians(0.25)
    if ref.sum() < 5:
        ref = np.ones(len(data), bool)
    fz = data.array("FZ")[ref]
    groups = level_labels(data, "FZ")[ref]
    if np.all(groups < 0):  # no load level (e.g. a load sweep): one group
        groups = np.zeros_like(groups)
    if stage_name in ("pure_fx", "pure_fy"):
        lateral = stage_name == "pure_fy"
        slip = data.array("SA" if lateral else "SL")[ref]
        force = data.array("FY" if lateral else "FX")[ref]
        small = math.radians(2.0) if lateral else 0.02
        dfz, mu, stiff, shift = [], [], [], []
        for k in np.unique(groups[groups >= 0]):
            sel = groups == k
            fz_k = float(np.mean(fz[sel]))
            dfz.append((fz_k - fz0) / fz0)
            mu.append(float(np.max(np.abs(force[sel]))) / fz_k)
            lin = sel & (np.abs(slip) <= small)
            if lin.sum() >= 3:
                intercept, slope = _linear(slip[lin], force[lin])
            else:
                intercept, slope = 0.0, (-1.0 if lateral else 1.0) * 15.0 * fz_k
            stiff.append(slope)
            shift.append(intercept / slope if slope else 0.0)
        dfz, mu, stiff = np.array(dfz), np.array(mu), np.array(stiff)
        d1, d2 = _linear(dfz, mu)
        if lateral:
            pky1, pky2 = _cornering_stiffness_fit(1.0 + dfz, stiff / fz0)
            out = dict(PDY1=max(d1, 0.1), PKY1=pky1, PHY1=float(np.median(shift)), PCY1=1.3)
            if len(dfz) >= 2:
                out.update(PDY2=d2, PKY2=pky2)
            return out
        k1, k2 = _linear(dfz, stiff / (fz0 * (1.0 + dfz)))
        out = dict(PDX1=max(d1, 0.1), PKX1=max(k1, 1.0), PHX1=float(np.median(shift)), PCX1=1.65)
        if len(dfz) >= 2:
            out.update(PDX2=d2, PKX2=k2)
        return out
    if stage_name == "mz":
        sa, fy, mz = data.array("SA")[ref], data.array("FY")[ref], data.array("MZ")[ref]
        r0 = prm.UNLOADED_RADIUS
        dfz, q = [], []
        for k in np.unique(groups[groups >= 0]):
            sel = (groups == k) & (np.abs(sa) >= math.radians(0.5)) & (np.abs(sa) <= math.radians(2.5))
            if sel.sum() < 2:
                continue
            fz_k = float(np.mean(fz[groups == k]))
            trail = float(np.median(-mz[sel] / fy[sel]))
            dfz.append((fz_k - fz0) / fz0)
            q.append(trail * fz0 / (r0 * fz_k))  # Dt = (QDZ1 + QDZ2 dfz) Fz R0 / Fz0 (paper A60)
        if not q:
            return {}
        q1, q2 = _linear(np.array(dfz), np.array(q))
        out = dict(QDZ1=float(np.clip(q1, 0.01, 0.5)))
        if len(q) >= 2:
            out["QDZ2"] = q2
        return out
    if stage_name == "vertical":
        # the force terms enter squared, (Q_FCY Fy/Fz0)^2: at 0 the data's gradient vanishes and a fit cannot
        # leave it; a small value (1 % less stiffness at |Fy| = Fz0) lets the data decide size and sign
        return dict(Q_FCX=0.1, Q_FCY=0.1)
    if stage_name == "combined_fy":
        # kappa-induced side force (4.E66, 4.E67): typical shape values, the amplitude from the data at alpha = 0
        sl, sa, fy = data.array("SL"), data.array("SA"), data.array("FY")
        zero = np.abs(sa) <= math.radians(0.25)
        if zero.sum() >= 5:
            amplitude = float(np.percentile(np.abs(fy[zero] - np.median(fy[zero & (np.abs(sl) < 0.01)]))
                                            if np.any(zero & (np.abs(sl) < 0.01)) else np.abs(fy[zero]), 90))
            rvy1 = amplitude / (prm.PDY1 * float(np.mean(data.array("FZ")[zero])))
            return dict(RVY1=float(np.clip(rvy1, 0.0, 0.2)), RVY4=20.0, RVY5=1.9, RVY6=10.0)
        return {}
    return {}


def _cornering_stiffness_fit(x, k_per_fz0):
    """PKY1, PKY2 of K_ya/Fz0 = PKY1 sin(2 atan(x / PKY2)) (4.E25 with PKY4 = 2, no camber or pressure) by a
    scan over PKY2 with PKY1 solved linearly; x = Fz/Fz0."""
    best = (float("inf"), -15.0, 1.5)
    for pky2 in np.linspace(0.4, 6.0, 113):
        basis = np.sin(2.0 * np.arctan(x / pky2))
        pky1 = float(basis @ k_per_fz0 / (basis @ basis))
        err = float(np.sum((pky1 * basis - k_per_fz0) ** 2))
        if err < best[0]:
            best = (err, pky1, float(pky2))
    return min(best[1], -0.5), best[2]
