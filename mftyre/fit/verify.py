"""Verify a parameter set before it is written: finite and plausible over the domain that matters.

:func:`verification` is the one check used by the fitting stages (:mod:`mftyre.fit.core`) and by the gap finder
(before an improved ``.tir`` is accepted); :func:`verify_tir` returns its ``problems``. It evaluates the model on
grids over two domains (:class:`Domain`):

* the **physical domain** (:func:`physical_domain`): pressures 0.5-1.5 x NOMPRES, loads from max(FZMIN,
  0.05 FNOMIN) up to min(FZMAX, 2.5 FNOMIN), slips and camber up to the declared limits (KPUMIN..KPUMAX,
  ALPMIN..ALPMAX, CAMMIN..CAMMAX), speeds from 1 m/s up to max(1.25 x the data's top speed, 2 LONGVL); every
  range intersected with the file's declared one (PRESMIN..PRESMAX, FZMAX), since the model saturates its inputs
  there anyway (and so the checks never trigger :class:`mftyre.InputClippedWarning`);
* the **checked domain** (:func:`data_domain`): the data's range widened by a stated margin (:data:`MARGINS`),
  intersected with the physical domain. Without data it is the domain of a standard test programme
  (:data:`STANDARD_PROGRAMME`: loads 0.25-1.5 FNOMIN, pressures 0.8-1.2 NOMPRES, the declared slips and camber,
  no margin: it is no measurement to extrapolate from but a generous range already).

A problem in the checked domain is a *problem* (the parameters are rejected) unless the ``baseline`` (the file as
given, the values before a stage) has a problem of the same kind there too: an improvement is not blamed for what
the given file already does. Problems only in the physical domain beyond the data, and problems the baseline
shares, are *warnings* naming the range. Each problem is a :class:`Problem` (a sentence naming the quantity,
where, the value and what was expected; ``.kind`` says which check).

Checks (each a physical property of a pneumatic tyre, not of the data):

* every output finite, and no exception from the model (e.g. the spin fixed point failing to converge);
* free radius growth with speed R_omega / (R0 Q_RE0) - 1 within [-1 %, +5 %] (Q_V1), vertical stiffness
  factor with speed 1 + Q_V2 |omega| R0 / V0 within [0.8, 1.5] at the top speed;
* loaded radius within the tyre: 0.5 R0 < Rl <= R_omega and deflection >= 0 at every load > 0; Fz(rho)
  increasing (the vertical stiffness positive) at every pressure;
* effective rolling radius within [0.7 R0, 1.05 R_omega];
* pure-slip signs (ISO-W): Fx > 0 for kappa >= 0.05 and < 0 for kappa <= -0.05, Fy < 0 for alpha >= 3 deg and
  > 0 for alpha <= -3 deg (camber 0), at every load and pressure and at the slip limits of the domain;
* no invented asymmetry: at camber 0, |Fx(+kappa)| / |Fx(-kappa)| and |Fy(+alpha)| / |Fy(-alpha)| within
  [1/1.5, 1.5] at kappa = 0.05, 0.1 and alpha = 3, 6 deg (where the domain holds both signs);
* friction plausible: |Fx|, |Fy| <= 4 Fz + 0.1 FNOMIN; moments: |Mz| <= 0.5 Fz R0 + 0.02 FNOMIN R0,
  |Mx| <= Fz R0, |My| <= 0.1 Fz R0 + 0.01 FNOMIN R0.
"""
from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from ..backend import NUMPY
from ..formula import vertical
from ..inputs import load_factor_edges, pressure_factor_edges
from ..params import PHYSICAL_PRESSURE_SPAN

__all__ = ["verify_tir", "verification", "Verification", "Problem", "Domain", "physical_domain", "data_domain",
           "check_speeds", "MARGINS", "STANDARD_PROGRAMME"]

_ASYMMETRY = 1.5
#: How far beyond the data's range the checked domain reaches: loads x (1 -/+ 0.1), pressures +-0.05 NOMPRES,
#: slip angle +-1 deg, slip ratio +-0.02, camber +-0.5 deg, speeds up to 1.25 x the top speed.
MARGINS = dict(load=0.1, pressure=0.05, alpha=math.radians(1.0), kappa=0.02, camber=math.radians(0.5), speed=1.25)
#: The stand-in for the data when none are given (fractions of FNOMIN and NOMPRES).
STANDARD_PROGRAMME = dict(loads=(0.25, 1.5), pressures=(0.8, 1.2))


class Problem(str):
    """A verification problem: the sentence, with ``kind`` naming the check (e.g. ``"fy_sign"``)."""

    kind: str

    def __new__(cls, kind: str, text: str):
        obj = super().__new__(cls, text)
        obj.kind = kind
        return obj


@dataclass(frozen=True)
class Domain:
    """Ranges (lo, hi) of load [N], pressure [Pa], slip ratio, slip angle [rad], camber [rad], and the top speed
    [m/s] over which the model is checked."""

    loads: tuple
    pressures: tuple
    kappa: tuple
    alpha: tuple
    gamma: tuple
    top_speed: float

    def describe(self) -> str:
        return (f"Fz {self.loads[0]:.0f}..{self.loads[1]:.0f} N, p {self.pressures[0] / 1e3:.0f}.."
                f"{self.pressures[1] / 1e3:.0f} kPa, kappa {self.kappa[0]:.3g}..{self.kappa[1]:.3g}, alpha "
                f"{math.degrees(self.alpha[0]):.3g}..{math.degrees(self.alpha[1]):.3g} deg, camber "
                f"{math.degrees(self.gamma[0]):.3g}..{math.degrees(self.gamma[1]):.3g} deg, speed up to "
                f"{self.top_speed:.3g} m/s")


@dataclass
class Verification:
    """``problems``: reasons to reject (in the checked domain, not shared by the baseline); ``warnings``: problems
    beyond the data (in the physical domain) or shared by the baseline; the two domains."""

    problems: list
    warnings: list
    domain: Domain
    physical: Domain


def _intersect(a, b):
    """(lo, hi) of a within b; a point at b's nearest bound when they do not overlap."""
    lo, hi = max(a[0], b[0]), min(a[1], b[1])
    if lo > hi:
        x = float(np.clip(0.5 * (a[0] + a[1]), b[0], b[1]))
        return x, x
    return lo, hi


def _declared(lo, hi, fallback):
    return (lo, hi) if hi > lo else fallback


def _data_top_speed(data_ranges) -> float:
    if data_ranges is None:
        return 0.0
    if hasattr(data_ranges, "array"):  # TyreData
        return float(np.nanmax(np.abs(data_ranges.array("VX"))))
    vx = data_ranges.get("VX", 0.0)
    return float(np.max(np.abs(vx))) if np.size(vx) else 0.0


def check_speeds(prm, data_ranges=None) -> np.ndarray:
    """The speeds [m/s] of the physical domain: 1 m/s up to max(1.25 x the data's top speed, 2 LONGVL)."""
    top = _data_top_speed(data_ranges)
    return np.linspace(1.0, max(MARGINS["speed"] * top, 2.0 * prm.LONGVL), 9)


def physical_domain(prm, data=None) -> Domain:
    """The physical domain of a pneumatic tyre within the file's declared ranges (see the module text)."""
    fz0, p0 = prm.FNOMIN, prm.NOMPRES
    fz_lo = max(prm.FZMIN, 0.05 * fz0)
    loads = (fz_lo, min(prm.FZMAX, 2.5 * fz0) if prm.FZMAX > fz_lo else 2.5 * fz0)
    pressures = ((1.0 - PHYSICAL_PRESSURE_SPAN) * p0, (1.0 + PHYSICAL_PRESSURE_SPAN) * p0)
    if prm.PRESMAX > prm.PRESMIN > 0:
        pressures = _intersect(pressures, (prm.PRESMIN, prm.PRESMAX))
    return Domain(loads, pressures, _declared(prm.KPUMIN, prm.KPUMAX, (-0.1, 0.1)),
                  _declared(prm.ALPMIN, prm.ALPMAX, (-0.2, 0.2)), _declared(prm.CAMMIN, prm.CAMMAX, (0.0, 0.0)),
                  float(check_speeds(prm, data)[-1]))


def data_domain(prm, data=None) -> Domain:
    """The data's range (``data``: :class:`mftyre.data.TyreData`; None: :data:`STANDARD_PROGRAMME`) widened by
    :data:`MARGINS`, within the physical domain."""
    phys = physical_domain(prm, data)
    m = MARGINS
    if not hasattr(data, "array") or len(data) == 0:
        loads = tuple(f * prm.FNOMIN for f in STANDARD_PROGRAMME["loads"])
        pressures = tuple(f * prm.NOMPRES for f in STANDARD_PROGRAMME["pressures"])
        return Domain(_intersect(loads, phys.loads), _intersect(pressures, phys.pressures), phys.kappa, phys.alpha,
                      phys.gamma, phys.top_speed)

    def span(name):
        x = data.array(name)
        x = x[np.isfinite(x)]
        return (float(np.min(x)), float(np.max(x))) if x.size else (0.0, 0.0)

    loads, pressures = span("FZ"), span("P")
    kappa, alpha, gamma = span("SL"), span("SA"), span("IA")
    kappa = (kappa[0] - m["kappa"], kappa[1] + m["kappa"])
    alpha = (alpha[0] - m["alpha"], alpha[1] + m["alpha"])
    gamma = (gamma[0] - m["camber"], gamma[1] + m["camber"])
    top = m["speed"] * _data_top_speed(data)
    loads = ((1 - m["load"]) * loads[0], (1 + m["load"]) * loads[1])
    pressures = (pressures[0] - m["pressure"] * prm.NOMPRES, pressures[1] + m["pressure"] * prm.NOMPRES)
    return Domain(_intersect(loads, phys.loads), _intersect(pressures, phys.pressures),
                  _intersect(kappa, phys.kappa), _intersect(alpha, phys.alpha), _intersect(gamma, phys.gamma),
                  min(max(top, 1.0), phys.top_speed))


def _within(values, lo_hi):
    values = np.asarray(values, float)
    return np.unique(values[(values >= lo_hi[0] - 1e-12) & (values <= lo_hi[1] + 1e-12)])


def _worst_asymmetry(up, down):
    """(ratio, i): |up| / |down| of a force under opposite pure slips (last axis), and the index of its worst point
    when some ratio lies outside 1/_ASYMMETRY.._ASYMMETRY (else None)."""
    ratio = np.abs(up) / np.maximum(np.abs(down), 1e-9)
    if np.any((ratio > _ASYMMETRY) | (ratio < 1 / _ASYMMETRY)):
        return ratio, np.unravel_index(np.argmax(np.abs(np.log(ratio))), ratio.shape)
    return ratio, None


def problems_in(model, dom: Domain) -> list:
    """The :class:`Problem` list of ``model`` (an :class:`mftyre.MFModel`) over the domain ``dom``."""
    prm = model.params
    problems = []
    r0, fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    loads = np.linspace(dom.loads[0], dom.loads[1], 6)
    pressures = np.unique([dom.pressures[0], float(np.clip(prm.NOMPRES, *dom.pressures)), dom.pressures[1]])
    speeds = np.linspace(1.0, max(dom.top_speed, 1.0), 9)
    kappas = np.unique(np.concatenate([np.linspace(*dom.kappa, 9), _within([-0.1, -0.05, 0.0, 0.05, 0.1],
                                                                           dom.kappa)]))
    alphas = np.unique(np.concatenate([np.linspace(*dom.alpha, 9), _within(np.radians([-6, -3, 0, 3, 6]),
                                                                           dom.alpha)]))
    gammas = np.unique([dom.gamma[0], float(np.clip(0.0, *dom.gamma)), dom.gamma[1]])

    def run(fz, kappa, alpha, gamma, vx, p, what):
        try:
            out = model.evaluate(fz, kappa, alpha, gamma, 0.0, vx, p)
        except (ArithmeticError, ValueError, FloatingPointError) as exc:
            problems.append(Problem("fails", f"{what}: the model fails ({type(exc).__name__}: {exc})"))
            return None
        bad = [k for k in ("fx", "fy", "mx", "my", "mz", "rl", "re", "omega") if not np.all(np.isfinite(out[k]))]
        if bad:
            problems.append(Problem("non_finite", f"{what}: non-finite {', '.join(bad)}"))
            return None
        return out

    # combined slip, camber, pressure and load over the domain at the reference speed
    F, K, A, G, P = np.meshgrid(loads, kappas, alphas, gammas, pressures, indexing="ij")
    out = run(F, K, A, G, prm.LONGVL, P, "slip/camber/load/pressure range")
    if out is not None:
        mu_lim = 4.0 * F + 0.1 * fz0
        for name, lim in (("fx", mu_lim), ("fy", mu_lim)):
            worst = np.max(np.abs(out[name]) - lim)
            if worst > 0:
                i = np.unravel_index(np.argmax(np.abs(out[name]) - lim), F.shape)
                problems.append(Problem(f"{name}_friction",
                                        f"|{name.upper()}| = {abs(out[name][i]):.0f} N exceeds 4 Fz at Fz {F[i]:.0f} N, "
                                        f"kappa {K[i]:.3g}, alpha {math.degrees(A[i]):.3g} deg, p {P[i]:.0f} Pa"))
        for name, lim in (("mz", 0.5 * F * r0 + 0.02 * fz0 * r0), ("mx", F * r0 + 0.02 * fz0 * r0),
                          ("my", 0.1 * F * r0 + 0.01 * fz0 * r0)):
            excess = np.abs(out[name]) - lim
            if np.max(excess) > 0:
                i = np.unravel_index(np.argmax(excess), F.shape)
                problems.append(Problem(f"{name}_size",
                                        f"|{name.upper()}| = {abs(out[name][i]):.4g} N m implausibly large at Fz "
                                        f"{F[i]:.0f} N, kappa {K[i]:.3g}, alpha {math.degrees(A[i]):.3g} deg, camber "
                                        f"{math.degrees(G[i]):.3g} deg"))
    # pure-slip signs (slips of one sign beyond a small threshold) and symmetry (both signs) at camber 0
    _pure_slip(run, problems, prm, loads, pressures, "fx", dom.kappa, [0.05, 0.1], 0.05, "kappa", 1.0,
               "shifts PHX*/PVX*")
    _pure_slip(run, problems, prm, loads, pressures, "fy", dom.alpha, np.radians([3.0, 6.0]), math.radians(3.0),
               "alpha", math.degrees(1.0), "shifts PHY*/PVY*")
    # the properties that must keep their sign over the domain: the pressure and load factors (closed forms) and the
    # aligning moment at small slip angles (Mz with the sign of alpha in ISO-W: a positive trail)
    for edge, side, names, what in pressure_factor_edges(prm):
        if dom.pressures[0] <= edge <= dom.pressures[1]:
            problems.append(Problem("pressure_sign", f"{names} makes the {what} change sign at p = {edge:.6g} Pa "
                                                     f"({edge / 1e5:.3g} bar), inside the pressures "
                                                     f"{dom.pressures[0] / 1e5:.3g}..{dom.pressures[1] / 1e5:.3g} bar: "
                                                     "expected the same sign over the whole range"))
    for lo_p in sorted(set(pressures)):
        for edge, names, what in load_factor_edges(prm, float(vertical.pressure_increment(prm, lo_p))):
            if dom.loads[0] <= edge <= dom.loads[1]:
                problems.append(Problem("load_sign", f"{names} make the {what} change sign at Fz = {edge:.6g} N, "
                                                     f"inside the loads {dom.loads[0]:.0f}..{dom.loads[1]:.0f} N"))
                break
    a1, a2 = max(dom.alpha[0], -math.radians(0.5)), min(dom.alpha[1], math.radians(0.5))
    if a2 - a1 > math.radians(0.1):  # the slope of Mz at zero slip (positive trail: Mz rises with alpha in ISO-W)
        Fm, Pm, Am = np.meshgrid(loads, pressures, [a1, a2], indexing="ij")
        out = run(Fm, 0.0, Am, 0.0, prm.LONGVL, Pm, "aligning moment at small slip angles")
        if out is not None:
            slope = (out.mz[..., 1] - out.mz[..., 0]) / (a2 - a1)
            if np.any(slope <= 0):
                i = np.unravel_index(np.argmin(slope), slope.shape)
                problems.append(Problem("mz_sign", f"the Mz slope at zero slip angle is {slope[i] * math.pi / 180:.3g} "
                                                   f"N m/deg at Fz {Fm[i][0]:.0f} N, p {Pm[i][0]:.0f} Pa: the "
                                                   "pneumatic trail is negative (expected Mz rising with alpha, ISO-W; "
                                                   "QDZ1/QDZ2, PPZ1, QBZ*)"))
    # speed: free rolling up to the top speed
    Fs, Ps, Vs = np.meshgrid(loads, pressures, speeds, indexing="ij")
    out = run(Fs, 0.0, 0.0, 0.0, Vs, Ps, f"free rolling up to {speeds[-1]:.0f} m/s")
    if out is not None:
        r_omega = vertical.free_radius(prm, out.omega, NUMPY)
        growth = r_omega / (r0 * prm.Q_RE0) - 1.0
        if np.max(growth) > 0.05 or np.min(growth) < -0.01:
            problems.append(Problem("radius_growth",
                                    f"free radius grows by {100 * np.max(growth):.3g} % (min {100 * np.min(growth):.3g}"
                                    f" %) up to {speeds[-1]:.0f} m/s: expected a few percent at most (Q_V1 = "
                                    f"{prm.Q_V1:.4g})"))
        speed_factor = 1.0 + prm.Q_V2 * r0 / prm.LONGVL * np.abs(out.omega)
        if np.max(speed_factor) > 1.5 or np.min(speed_factor) < 0.8:
            problems.append(Problem("speed_stiffness",
                                    f"vertical stiffness factor with speed 1 + Q_V2 |omega| R0/V0 reaches "
                                    f"{np.max(speed_factor):.3g} (min {np.min(speed_factor):.3g}) up to "
                                    f"{speeds[-1]:.0f} m/s: expected 0.8..1.5 (Q_V2 = {prm.Q_V2:.4g})"))
        rl, re = out.rl, out.re
        if np.any(rl <= 0.5 * r0) or np.any(rl > r_omega * (1 + 1e-9)):
            problems.append(Problem("loaded_radius",
                                    f"loaded radius {np.min(rl):.4g}..{np.max(rl):.4g} m outside the tyre (0.5 R0 = "
                                    f"{0.5 * r0:.4g} m .. R_omega up to {np.max(r_omega):.4g} m)"))
        if np.any(out.rho < 0):
            problems.append(Problem("deflection", f"negative deflection {np.min(out.rho):.3g} m at positive load"))
        if np.any(re < 0.7 * r0) or np.any(re > 1.05 * r_omega):
            problems.append(Problem("rolling_radius",
                                    f"effective rolling radius {np.min(re):.4g}..{np.max(re):.4g} m outside 0.7 R0 .. "
                                    f"1.05 R_omega (BREFF, DREFF, FREFF)"))
    # vertical stiffness: Fz increases with deflection at every pressure
    for p in pressures:
        dpi = vertical.pressure_increment(prm, p)
        cz = vertical.vertical_stiffness(prm, dpi)
        if not cz > 0 or prm.Q_FZ2 < 0:
            problems.append(Problem("vertical_stiffness",
                                    f"vertical stiffness not positive at p = {p:.0f} Pa (VERTICAL_STIFFNESS "
                                    f"{prm.VERTICAL_STIFFNESS:.4g}, PFZ1 {prm.PFZ1:.4g}, Q_FZ2 {prm.Q_FZ2:.4g})"))
    return problems


def _pure_slip(run, problems, prm, loads, pressures, force, slip_range, levels, threshold, slip, to_unit, shifts):
    """Sign (where the domain holds slips beyond ``threshold``) and asymmetry (at ``levels`` present with both
    signs) of ``force`` under pure slip ``slip`` (kappa or alpha) at camber 0."""
    lo, hi = slip_range
    slips = np.unique(np.concatenate([_within(levels, (threshold, hi)), [hi] if hi >= threshold else [],
                                      -_within(levels, (threshold, -lo)), [lo] if lo <= -threshold else []]))
    if slips.size == 0:
        return
    Fq, Pq, Sq = np.meshgrid(loads, pressures, slips, indexing="ij")
    kw = dict(kappa=Sq, alpha=0.0) if slip == "kappa" else dict(kappa=0.0, alpha=Sq)
    out = run(Fq, kw["kappa"], kw["alpha"], 0.0, prm.LONGVL, Pq, f"pure {slip}")
    if out is None:
        return
    f = out[force]
    name = force.capitalize()
    expected = 1.0 if force == "fx" else -1.0   # ISO-W: Fx > 0 for kappa > 0, Fy < 0 for alpha > 0
    wrong = np.sign(Sq) * expected * f <= 0
    if np.any(wrong):
        i = np.unravel_index(np.argmax(wrong), wrong.shape)
        unit = "" if slip == "kappa" else " deg"
        problems.append(Problem(f"{force}_sign",
                                f"{name} has the wrong sign under pure {'longitudinal slip' if slip == 'kappa' else 'slip angle'}"
                                f" ({name} {f[i]:.0f} N at {slip} {Sq[i] * to_unit:.3g}{unit}, Fz {Fq[i]:.0f} N, p "
                                f"{Pq[i]:.0f} Pa): expected {name} {'>' if expected * Sq[i] > 0 else '<'} 0 (ISO-W)"))
    both = [s for s in levels if np.any(np.isclose(slips, s)) and np.any(np.isclose(slips, -s))]
    if not both:
        return
    up = np.stack([f[..., np.argmin(np.abs(slips - s))] for s in both], axis=-1)
    down = np.stack([f[..., np.argmin(np.abs(slips + s))] for s in both], axis=-1)
    ratio, i = _worst_asymmetry(up, down)
    if i is not None:
        s = both[i[-1]]
        problems.append(Problem(f"{force}_asymmetry",
                                f"{name} asymmetry at camber 0: {name} = {down[i]:.0f} / {up[i]:.0f} N at {slip} = -/+"
                                f"{s * to_unit:.3g}{'' if slip == 'kappa' else ' deg'}, Fz {loads[i[0]]:.0f} N (ratio "
                                f"{ratio[i]:.2f}, expected within 1/{_ASYMMETRY}..{_ASYMMETRY}; {shifts})"))


#: The kinds of problem of baselines (the given file of a search, checked against every candidate of it): the
#: parameters (immutable) by identity, the side and the domain -> (parameters, kinds); the last few, shared by
#: threads.
_BASELINE_KINDS: dict = {}
_BASELINE_LOCK = threading.Lock()


def _baseline_kinds(baseline, dom: Domain) -> frozenset:
    """The kinds of :func:`problems_in` of ``baseline`` (model or parameters) over ``dom``, computed once."""
    from ..model import MFModel

    base = baseline if isinstance(baseline, MFModel) else MFModel(baseline)
    prm = base.params
    key = (id(prm), base.side, dom)
    with _BASELINE_LOCK:
        found = _BASELINE_KINDS.get(key)
    if found is not None and found[0] is prm:
        return found[1]
    kinds = frozenset(q.kind for q in problems_in(base, dom))
    with _BASELINE_LOCK:
        while len(_BASELINE_KINDS) >= 8:
            del _BASELINE_KINDS[next(iter(_BASELINE_KINDS))]
        _BASELINE_KINDS[key] = (prm, kinds)
    return kinds


def verification(model, data=None, baseline=None, *, beyond_the_data: bool = True) -> Verification:
    """Problems and warnings of ``model`` (an :class:`mftyre.MFModel` or parameters) over the checked and the
    physical domain, relative to ``baseline`` (model or parameters; None: no baseline). ``data``: the measured
    data (:class:`mftyre.data.TyreData`), or a dict with ``"VX"`` (speeds or the top speed, m/s), or None (a
    standard programme stands in for the data). ``beyond_the_data=False``: no check of the physical domain beyond
    the data's (no warnings of it). See the module text."""
    from ..model import MFModel

    model = model if isinstance(model, MFModel) else MFModel(model)
    prm = model.params
    dom, phys = data_domain(prm, data), physical_domain(prm, data)
    if not hasattr(data, "array") and data is not None:   # a dict of speeds only: the standard programme's domain
        dom = Domain(dom.loads, dom.pressures, dom.kappa, dom.alpha, dom.gamma, phys.top_speed)
    inside = problems_in(model, dom)
    beyond = problems_in(model, phys) if beyond_the_data and phys != dom else []
    shared = set() if baseline is None else _baseline_kinds(baseline, dom)
    problems = [q for q in inside if q.kind not in shared]
    kinds = {q.kind for q in inside}
    warnings = [Problem(q.kind, f"the given file has it too, in the data's domain ({dom.describe()}): {q}")
                for q in inside if q.kind in shared]
    warnings += [Problem(q.kind, f"beyond the data's domain ({dom.describe()}), within {phys.describe()}: {q}")
                 for q in beyond if q.kind not in kinds]
    return Verification(problems, warnings, dom, phys)


def verify_tir(model, data_ranges=None, baseline=None) -> list:
    """Problems of ``model`` (an :class:`mftyre.MFModel`, or parameters) in the domain that matters (the data's
    range with a margin within the physical domain) that ``baseline`` does not have; [] when none
    (:func:`verification`'s ``problems``)."""
    return verification(model, data_ranges, baseline, beyond_the_data=False).problems
