"""Checks of the model inputs shared by every evaluator (NumPy :meth:`mftyre.MFModel.evaluate`, the compiled C of
:mod:`mftyre.compiled` and the tables of ``mftyre eval``), so that all reject, saturate and warn alike:

* every input must be finite (NaN and +-inf raise :class:`ModelInputError` naming the input);
* the inflation pressure must be positive;
* with ``limits=True`` the equations saturate fz, kappa, alpha, gamma and p to the ranges of the .tir file
  (:data:`RANGE_PARAMETERS`): values outside them are evaluated at the bound, and one
  :class:`InputClippedWarning` per call names each such input, its range (parameter names and values) and how
  many points lay outside it. ``limits=False`` evaluates the values as given.

Fz has an upper bound only. Above FZMAX (the split of the reference evaluator MFeval) the fitted force and moment
equations (Fx, Fy, Mz, Mx) and the relaxation outputs use the load saturated at FZMAX, while the vertical relations
(Re and the spin, the loaded radius, deflection and vertical stiffness, the contact patch) and the rolling
resistance My use the load as given. FZMIN is not a bound of the input: loads in
(0, FZMIN) are evaluated as given, except that the aligning-torque coefficients and the MF 6.1 deflection use
max(Fz, FZMIN) and Mx, My scale down below FZMIN (the TNO practice the reference evaluator encodes), so they give
no warning; Fz <= 0 is no contact, not a range violation either. The compiled C counts one interval per input,
the same as :func:`saturate` here.

Beyond what a tyre can be the model refuses (:class:`ModelInputError` naming the input, its value and the limit;
:func:`check_limits`, the policy of docs/model-input-policy.md), in every entry:

* with limits, loads above :data:`LOAD_MARGIN` FZMAX (the split above is the reference evaluator's answer up to
  there, with the warning);
* wheel-centre speeds at which the rolling-resistance terms of My, QSY3 |vx|/LONGVL + QSY4 (vx/LONGVL)^4, reach
  :data:`ROLLING_RESISTANCE_LIMIT` (My = Fz0 R0: a moment no contact force makes);
* rim speeds |omega R0| (|(1 + kappa) vx| where omega is estimated) at which the free radius grows by more than
  :data:`FREE_RADIUS_GROWTH_LIMIT` of UNLOADED_RADIUS (Q_V1 (omega R0/LONGVL)^2, paper (1)).

:func:`check_tyre_outputs` backs them up on the outputs of :meth:`mftyre.MFModel.evaluate` (a negative deflection
or a radius <= 0 under load). The reference evaluator's own answers stay available in :func:`mftyre.compat.mfeval`,
which warns where they are outside these limits.
"""
from __future__ import annotations

import math
import threading
import warnings

import numpy as np

from .errors import InputClippedWarning, LoadFactorWarning, ModelInputError, PressureFactorWarning, spelled
from .formula.vertical import pressure_increment

__all__ = ["LOAD_MARGIN", "ROLLING_RESISTANCE_LIMIT", "FREE_RADIUS_GROWTH_LIMIT", "hard_limits", "check_limits",
           "limit_problems", "point_limit_checks", "check_speed_limits", "beyond_limits", "check_tyre_outputs", "RANGE_PARAMETERS", "input_ranges", "saturate", "check_finite", "check_pressure", "warn_outside",
           "check_finite_outputs", "saturate_inputs", "warn_data_outside", "PRESSURE_FACTORS", "pressure_factor_edges",
           "PressureFactorCheck", "load_factor_edges", "load_factor_problems", "LoadFactorCheck"]

#: input -> (.tir parameter of the lower bound or None, of the upper bound, unit): the ranges ``limits=True``
#: saturates the inputs to (see the module docstring for Fz and FZMIN).
RANGE_PARAMETERS = {
    "fz": (None, "FZMAX", "N"),
    "kappa": ("KPUMIN", "KPUMAX", "-"),
    "alpha": ("ALPMIN", "ALPMAX", "rad"),
    "gamma": ("CAMMIN", "CAMMAX", "rad"),
    "p": ("PRESMIN", "PRESMAX", "Pa"),
}
_MIRRORED = ("alpha", "gamma")  # ranges of the measured side, negated for a tyre mounted on the other side


#: With limits, loads up to LOAD_MARGIN FZMAX are evaluated with the split above FZMAX and warned; above: refused.
LOAD_MARGIN = 1.5
#: The rolling-resistance coefficient |My| / (Fz0 R0) of the speed terms at which a speed is refused (published
#: tyres: about 0.01 at LONGVL; 1 puts the vertical force a radius away from the wheel centre, outside any patch).
ROLLING_RESISTANCE_LIMIT = 1.0
#: The growth of the free radius with the rim speed, as a share of UNLOADED_RADIUS, at which a speed is refused
#: (the value checks of mftyre.params ask for less than this at 3 LONGVL; published tyres: ~1.5 % at 300 km/h).
FREE_RADIUS_GROWTH_LIMIT = 0.1


def hard_limits(params) -> dict:
    """{quantity: (limit, description)} of :func:`check_limits` for ``params``: 'fz' [N] (with limits), 'vx' the
    wheel-centre speed [m/s], 'rim' the rim speed |omega R0| [m/s] (inf where the file's terms never reach the
    limit)."""
    v0 = float(params.LONGVL)
    qsy3, qsy4 = abs(float(params.QSY3)), abs(float(params.QSY4))
    if qsy3 or qsy4:  # smallest x >= 0 with qsy3 x + qsy4 x^4 = limit (monotone: the real positive root)
        roots = np.roots([qsy4, 0.0, 0.0, qsy3, -ROLLING_RESISTANCE_LIMIT]) if qsy4 else \
            np.array([ROLLING_RESISTANCE_LIMIT / qsy3])
        x = float(min(r.real for r in np.atleast_1d(roots) if abs(r.imag) <= 1e-9 * abs(r) and r.real > 0))
        vx = (x * v0, f"{x * v0:.6g} m/s, where the rolling-resistance terms QSY3 |vx|/LONGVL + QSY4 (vx/LONGVL)^4 "
                      f"(QSY3 = {params.QSY3:g}, QSY4 = {params.QSY4:g}, LONGVL = {v0:g} m/s) reach "
                      f"{ROLLING_RESISTANCE_LIMIT:g}: My = Fz0 R0, a moment no contact force makes")
    else:
        vx = (np.inf, "none (QSY3 = QSY4 = 0)")
    q_v1 = abs(float(params.Q_V1))
    if q_v1:
        v = v0 * float(np.sqrt(FREE_RADIUS_GROWTH_LIMIT / q_v1))
        rim = (v, f"{v:.6g} m/s, where the free radius R0 (Q_RE0 + Q_V1 (omega R0/LONGVL)^2) changes by "
                  f"{100 * FREE_RADIUS_GROWTH_LIMIT:g} % of UNLOADED_RADIUS (Q_V1 = {params.Q_V1:g})")
    else:
        rim = (np.inf, "none (Q_V1 = 0)")
    fzmax = float(params.FZMAX)
    return {"fz": (LOAD_MARGIN * fzmax, f"{LOAD_MARGIN:g} FZMAX = {LOAD_MARGIN * fzmax:.6g} N (FZMAX = {fzmax:g} N; "
                                        "up to there the forces and moments are those at FZMAX, the radii, patch and "
                                        "My those at the load)"),
            "vx": vx, "rim": rim}


def _limit_masks(params, arrays: dict, limits, omega_given, lim) -> list:
    """[(input, values, beyond mask, limit, what, rim speeds or None)] of :func:`hard_limits`, broadcast."""
    masks = []
    if limits and "fz" in arrays:
        fz = np.asarray(arrays["fz"])
        masks.append(("fz", fz, fz > lim["fz"][0], lim["fz"], "fz", None))
    if "vx" not in arrays:
        return masks
    vx = np.asarray(arrays["vx"])
    masks.append(("vx", vx, np.abs(vx) > lim["vx"][0], lim["vx"], "|vx|", None))
    if np.isfinite(lim["rim"][0]):  # rim speed: omega R0 where omega is given, else (1 + kappa) vx (2.5)
        kappa, omega = np.asarray(arrays.get("kappa", 0.0)), np.asarray(arrays.get("omega", 0.0))
        given = np.asarray(omega_given, dtype=bool)
        with np.errstate(all="ignore"):
            rim = np.where(given, np.abs(omega) * float(params.UNLOADED_RADIUS), np.abs((1.0 + kappa) * vx))
        shape = np.broadcast_shapes(rim.shape, vx.shape)
        bad = np.broadcast_to(rim > lim["rim"][0], shape)
        if bad.any():  # named by the input that makes the rim speed at the first such point
            i = np.unravel_index(np.argmax(bad), shape) if shape else ()
            name = ("omega" if np.broadcast_to(given, shape)[i]
                    else "kappa" if abs(float(np.broadcast_to(kappa, shape)[i])) > 1.0 else "vx")
            values = np.broadcast_to({"omega": omega, "vx": vx, "kappa": kappa}[name], shape)
            masks.append((name, values, bad, lim["rim"], "|omega R0|" if name == "omega" else "|(1 + kappa) vx|",
                          np.broadcast_to(rim, shape)))
    return masks


def beyond_limits(params, arrays: dict, limits, omega_given=False, lim=None) -> np.ndarray:
    """Boolean array: the points :func:`check_limits` refuses (``arrays`` as for :func:`limit_problems`)."""
    lim = hard_limits(params) if lim is None else lim
    masks = [bad for _, _, bad, _, _, _ in _limit_masks(params, arrays, limits, omega_given, lim)]
    shape = np.broadcast_shapes(*(np.shape(v) for v in arrays.values()))
    return np.logical_or.reduce([np.broadcast_to(m, shape) for m in masks] + [np.zeros(shape, dtype=bool)])


def limit_problems(params, arrays: dict, limits, omega_given=False, lim=None) -> list[tuple[str, str]]:
    """[(input, message)] for the inputs beyond :func:`hard_limits` (``arrays``: float arrays of the inputs,
    fz kappa vx and omega where present; ``omega_given``: bool or boolean array, where omega is an input; ``lim``:
    the :func:`hard_limits` of ``params`` if known)."""
    source = getattr(params, "source", None) or "the parameter set"
    lim = hard_limits(params) if lim is None else lim
    found = []
    for name, values, bad, limit, what, rim in _limit_masks(params, arrays, limits, omega_given, lim):
        if bad.any():
            i = np.unravel_index(np.argmax(bad), bad.shape) if bad.ndim else ()
            value = float(np.broadcast_to(values, bad.shape)[i])
            shown = "" if rim is None else f" (rim speed {float(rim[i]):.6g} m/s)"
            where = ", ".join(str(int(j)) for j in i)
            count = f" at {int(bad.sum())} of {bad.size} points, first at point {where}," if bad.size > 1 else ""
            found.append((name, _limit_message(source, name, f"{value:.6g}{shown}{count}", what, limit[1])))
    return found


def _limit_message(source, name, value, what, limit) -> str:
    """The refusal of :func:`limit_problems` (``value``: the value as written, with the rim speed and count)."""
    return f"input {name} = {value} is beyond the limit of {source}: {what} <= {limit}"


def point_limit_checks(params, omega_given: bool, rim: bool = True) -> list[tuple[str, float, float, str]]:
    """The speed limits of :func:`check_limits` at one point with the inputs vx and omega (no kappa: free rolling
    where the spin is not given), for code that cannot call Python (the native FMUs' C): [(input, scale, limit,
    message)], refused where scale |input| > limit, with the message printf-style of two doubles, the input's value
    and scale |input| (C's ``%.6g`` is Python's ``.6g``): the text :func:`check_limits` raises, in its order.
    ``rim=False``: the wheel-centre speed only (where the spin follows from an input slip, which this form has not)."""
    source = str(getattr(params, "source", None) or "the parameter set").replace("%", "%%")
    lim = hard_limits(params)
    checks = [("vx", 1.0, lim["vx"], "|vx|", "")]
    shown = " (rim speed %.6g m/s)"
    if rim:
        checks.append(("omega", float(params.UNLOADED_RADIUS), lim["rim"], "|omega R0|", shown) if omega_given else
                      ("vx", 1.0, lim["rim"], "|(1 + kappa) vx|", shown))
    return [(name, scale, float(limit[0]),
             _limit_message(source, name, "%.6g" + shown, what, limit[1].replace("%", "%%")))
            for name, scale, limit, what, shown in checks if np.isfinite(limit[0])]


def check_limits(params, arrays: dict, limits, omega_given=False, lim=None) -> None:
    """Raise :class:`ModelInputError` for the first of :func:`limit_problems` (the refusals of the policy in the
    module docstring)."""
    lim = hard_limits(params) if lim is None else lim

    def peak(name):  # the largest |value| of an input (0 if absent); a 0-d array as a float (faster)
        v = arrays.get(name, 0.0)
        return abs(float(v)) if np.ndim(v) == 0 else float(np.max(np.abs(v)))

    speed = peak("vx")
    rim = max(speed * (1.0 + peak("kappa")), peak("omega") * float(params.UNLOADED_RADIUS))
    if (not limits or peak("fz") <= lim["fz"][0]) and speed <= lim["vx"][0] and rim <= lim["rim"][0]:
        return  # (every point inside: a few reductions)
    problems = limit_problems(params, arrays, limits, omega_given, lim)
    if problems:
        raise ModelInputError(problems[0][1])


def check_speed_limits(params, vx, omega=None, omega_given: bool = True, lim=None) -> None:
    """:func:`check_limits` at one point of the wheel's speeds (the starts and steps of the SWIFT tyre and the wheels,
    whose C twin is :func:`point_limit_checks`): ``vx`` and, where given, the spin ``omega`` (``omega_given``: the rim
    spins at it; else the spin is free rolling's)."""
    arrays = {"vx": np.asarray(float(vx))} | ({} if omega is None else {"omega": np.asarray(float(omega))})
    check_limits(params, arrays, False, omega_given=omega_given, lim=lim)


def check_tyre_outputs(out: dict, arrays: dict, params=None, lim=None) -> None:
    """Outputs no tyre has, under load (fz > 0): a negative deflection rho, an effective rolling radius or loaded
    radius <= 0, and (with ``params``) a spin whose rim speed |omega R0| is beyond :func:`hard_limits` (an estimated
    spin runs away where Re shrinks towards 0): ModelInputError naming the output and the inputs of the first such
    point (the backstop of :func:`check_limits`)."""
    loaded = np.asarray(out["fz"]) > 0
    tests = [("rho", lambda v: v < 0, "negative deflection", "m"),
             ("re", lambda v: ~(v > 0), "effective rolling radius <= 0", "m"),
             ("rl", lambda v: ~(v > 0), "loaded radius <= 0", "m")]
    if params is not None:
        rim = (hard_limits(params) if lim is None else lim)["rim"]
        r0 = float(params.UNLOADED_RADIUS)
        tests.append(("omega", lambda v: np.abs(v) * r0 > rim[0], f"spin beyond the limit |omega R0| <= {rim[1]}",
                      "rad/s"))
    for name, bad, what, unit in tests:
        if name in out:
            wrong = loaded & bad(np.asarray(out[name]))
            if wrong.any():
                i = np.unravel_index(np.argmax(wrong), wrong.shape) if wrong.ndim else ()
                at = ", ".join(f"{k} = {float(np.broadcast_to(v, wrong.shape)[i]):.6g}" for k, v in arrays.items())
                raise ModelInputError(f"the equations give a {what} ({name} = {float(np.asarray(out[name])[i]):.6g} "
                                      f"{unit}) under load at {int(wrong.sum())} point(s), first at {at}: no tyre has "
                                      "it there (check the load and the vertical parameters)")


def input_ranges(params, mirrored: bool = False) -> dict:
    """{input: (lower, upper, description)} in the axes of the caller (a mirrored tyre sees -ALPMAX..-ALPMIN);
    the description names the parameters, their values and the unit, e.g. 'PRESMIN..PRESMAX = [186000, 255000]
    Pa'."""
    ranges = {}
    for name, (lo_name, hi_name, unit) in RANGE_PARAMETERS.items():
        lo = -np.inf if lo_name is None else float(params[lo_name])
        hi = float(params[hi_name])
        if mirrored and name in _MIRRORED:
            lo, hi = -hi, -lo
        bounds = f"{lo_name}..{hi_name}" if lo_name else hi_name
        ranges[name] = (lo, hi, f"{bounds} = [{lo:.6g}, {hi:.6g}] {unit}")
    return ranges


#: The pressure factors of the equations, 1 + sign (c1 dpi + c2 dpi^2) with c1, c2 the named parameters (None: no
#: quadratic term), and what each scales. Fitted over the measured pressures, a factor can reach zero inside the
#: file's PRESMIN..PRESMAX (TNO_car205_60R15.tir: PPY1 = -0.6249 at 5.72 bar, PRESMAX 10 bar): beyond it the
#: property has the wrong sign (a cornering stiffness pushing the wrong way), which :class:`PressureFactorCheck`
#: warns about.
PRESSURE_FACTORS = (
    ("PPX1", "PPX2", 1, "longitudinal slip stiffness K_xk (4.E15)"),
    ("PPX3", "PPX4", 1, "longitudinal friction mu_x (4.E13)"),
    ("PPY1", None, 1, "cornering stiffness K_ya (4.E25)"),
    ("PPY2", None, 1, "load at the peak of the cornering stiffness (4.E25)"),
    ("PPY3", "PPY4", 1, "lateral friction mu_y (4.E23)"),
    ("PPY5", None, 1, "camber stiffness K_yg0 (4.E30)"),
    ("PPZ1", None, -1, "pneumatic trail D_t (paper A60)"),
    ("PFZ1", None, 1, "vertical stiffness C_z (paper (5))"),
    ("PCFX3", None, 1, "longitudinal carcass stiffness C_x (paper (17))"),
    ("PCFY3", None, 1, "lateral carcass stiffness C_y (paper (18))"),
)


def _real_roots(c2: float, c1: float) -> np.ndarray:
    """The real roots of c2 x^2 + c1 x + 1 = 0, sorted (none when c1 = c2 = 0), in the closed forms that keep their
    digits: q = -(c1 + sign(c1) sqrt(c1^2 - 4 c2)) / 2, x = q / c2 and 1 / q (no cancellation)."""
    if c2 == 0.0:
        return np.array([-1.0 / c1]) if c1 else np.array([])
    disc = c1 * c1 - 4.0 * c2
    if disc < 0.0:
        return np.array([])
    q = -0.5 * (c1 + math.copysign(math.sqrt(disc), c1))
    return np.sort(np.array([1.0 / q, q / c2])) if q else np.array([])


def pressure_factor_edges(params) -> list[tuple[float, int, str, str]]:
    """[(p_edge [Pa], side, parameters, what)]: the pressures nearest NOMPRES, above (side +1) or below (side -1),
    at which a factor of :data:`PRESSURE_FACTORS` reaches zero (at NOMPRES every factor is 1); beyond p_edge on
    that side the factor is <= 0. Only positive pressures; ``parameters`` as written, e.g. 'PPY1 = -0.6249'."""
    edges = []
    for c1_name, c2_name, sign, what in PRESSURE_FACTORS:
        c1 = sign * float(params[c1_name]) if c1_name in params else 0.0
        c2 = sign * float(params[c2_name]) if c2_name is not None and c2_name in params else 0.0
        real = _real_roots(c2, c1)  # c2 dpi^2 + c1 dpi + 1 = 0
        names = f"{c1_name} = {params[c1_name]:g}" + (f", {c2_name} = {params[c2_name]:g}" if c2 else "")
        for side, candidates in ((1, real[real > 0]), (-1, real[(real < 0) & (real > -1)][::-1])):
            if candidates.size:
                edges.append((float(params.NOMPRES * (1.0 + candidates[0])), side, names, what))
    return edges


def load_factor_edges(params, dpi: float = 0.0) -> list[tuple[float, str, str]]:
    """[(Fz_edge [N], parameters, what)]: the positive loads at which a slip stiffness's load factor reaches zero at
    zero camber and dpi = (p - NOMPRES)/NOMPRES ``dpi``; on the far side of Fz_edge from FNOMIN the stiffness has
    the opposite sign to the one at FNOMIN (the steady-state tyre pushes along the slip). Closed forms, Fz0' =
    FNOMIN LFZO:
        K_xk = Fz (PKX1 + PKX2 dfz) exp(PKX3 dfz) ...  (4.E15): zero at dfz = -PKX1/PKX2
        K_ya = PKY1 Fz0' ... sin(PKY4 atan(Fz / (PKY2 (1 + PPY2 dpi) Fz0')))  (4.E25): zero at PKY4 atan(.) = pi,
               i.e. Fz = PKY2 (1 + PPY2 dpi) Fz0' tan(pi/PKY4), only where PKY4 > 2
    (FSAE_Defaults.tir of MFeval: PKX1 = 50, PKX2 = -80, K_xk < 0 above 1625 N, FZMAX 2000 N)."""
    fz0 = float(params.FNOMIN) * float(params.LFZO)
    edges = []
    if not fz0 > 0.0:  # no nominal load (a file the value checks refuse): no load scale to place an edge on
        return edges
    pkx1, pkx2 = float(params.PKX1), float(params.PKX2)
    if pkx2 != 0.0 and fz0 * (1.0 - pkx1 / pkx2) > 0.0:
        edges.append((fz0 * (1.0 - pkx1 / pkx2), f"PKX1 = {pkx1:g}, PKX2 = {pkx2:g}",
                      "longitudinal slip stiffness K_xk = Fz (PKX1 + PKX2 dfz) exp(PKX3 dfz) (4.E15)"))
    pky2 = float(params.PKY2) * (1.0 + float(params.PPY2) * dpi)
    pky4 = float(params.PKY4)
    if pky4 > 2.0 and pky2 > 0.0:
        edges.append((pky2 * fz0 * float(np.tan(np.pi / pky4)), f"PKY2 = {params.PKY2:g}, PKY4 = {pky4:g}"
                      + (f", PPY2 = {params.PPY2:g}" if dpi and params.PPY2 else ""),
                      "cornering stiffness K_ya = PKY1 Fz0' sin(PKY4 atan(Fz / (PKY2 Fz0'))) (4.E25)"))
    return edges


def load_factor_problems(params) -> list[tuple[str, str]]:
    """[(first parameter, message)]: the :func:`load_factor_edges` inside the file's load range (0, FZMAX] at any
    pressure of PRESMIN..PRESMAX (the edges are linear in the pressure factor: its ends suffice), each message naming
    the parameters, the property, the load and what is expected (the property keeps its sign up to FZMAX)."""
    fz0, fzmax = float(params.FNOMIN) * float(params.LFZO), float(params.FZMAX)
    found: dict = {}
    for p in (params.PRESMIN, params.PRESMAX):
        dpi = _pressure_increment(params, p)
        for edge, names, what in load_factor_edges(params, dpi):
            if edge <= fzmax and (what not in found or edge < found[what][0]):
                found[what] = (edge, names, p)
    return [(names.split(" ")[0],
             f"{names} make the {what} change sign at Fz = {edge:.6g} N ({edge / fz0:.3g} FNOMIN"
             f"{f', p = {p:g} Pa' if 'PPY2' in names else ''}), "
             f"inside the load range up to FZMAX = {fzmax:g} N: {'above' if edge > fz0 else 'below'} it the tyre "
             f"pushes along the slip (a slip stiffness is expected to keep its sign from 0 to FZMAX); a dynamic "
             f"tyre rolling freely there (the SWIFT ring) is unstable")
            for what, (edge, names, p) in found.items()]


def _pressure_increment(params, p) -> float:
    """dpi of :func:`mftyre.formula.vertical.pressure_increment` at ``p``; 0 where NOMPRES is not positive (a file
    the value checks refuse, still read by ``mftyre check``)."""
    return float(pressure_increment(params, float(p))) if params.NOMPRES > 0 else 0.0


class _WarnOnce:
    """The state of a check that warns once per key, from any thread: the source named in the message."""

    def __init__(self, params):
        self._source = getattr(params, "source", None) or "the parameter set"
        self._warned: set = set()
        self._lock = threading.Lock()

    def _first(self, key) -> bool:
        """True the first time ``key`` is seen (then the caller warns)."""
        with self._lock:
            if key in self._warned:
                return False
            self._warned.add(key)
            return True


class PressureFactorCheck(_WarnOnce):
    """Warns (:class:`PressureFactorWarning`, once per factor) where a model is used at a pressure beyond one of
    :func:`pressure_factor_edges`, naming the file, the parameters and the pressure; the file is not rejected (its
    fit may only cover the measured pressures). Thread-safe; the common case (every pressure inside) costs two
    comparisons."""

    def __init__(self, params):
        super().__init__(params)
        self._edges = pressure_factor_edges(params)
        self.low = max([p for p, side, _, _ in self._edges if side < 0], default=-np.inf)
        self.high = min([p for p, side, _, _ in self._edges if side > 0], default=np.inf)

    def __call__(self, p_min: float, p_max: float, stacklevel: int = 3) -> None:
        """Warn for the factors that are <= 0 somewhere in the pressures used, ``p_min``..``p_max`` [Pa]."""
        if self.low < p_min and p_max < self.high:
            return
        for edge, side, names, what in self._edges:
            crossed = p_max >= edge if side > 0 else p_min <= edge
            if not crossed or not self._first(names):
                continue
            used = p_max if side > 0 else p_min
            warnings.warn(f"{self._source}: {names} makes the {what} factor change sign at p = {edge:.6g} Pa "
                          f"({edge / 1e5:.3g} bar); the model is used at p = {used:.6g} Pa, "
                          f"{'above' if side > 0 else 'below'} it, where that property has the wrong sign (the "
                          f"file's PRESMIN..PRESMAX does not exclude it)", PressureFactorWarning,
                          stacklevel=stacklevel)


class LoadFactorCheck(_WarnOnce):
    """Warns (:class:`LoadFactorWarning`, once per factor) where a model is used at loads beyond one of
    :func:`load_factor_edges` at the pressures used (a slip stiffness with the opposite sign to the one at FNOMIN),
    naming the file, the parameters, the edge and the load; the file is not rejected (its fit may only cover the
    measured loads). Thread-safe. The common case costs two comparisons: every load inside the band between the
    edges below and above FNOMIN LFZO, which holds at every pressure where no edge depends on the pressure (K_xk's);
    where one does (K_ya's with PPY2, MFeval's 6.1/6.2 files), the band holds over the file's PRESMIN..PRESMAX and
    NOMPRES, and two more comparisons check that the pressures lie there. Loads <= 0 carry no force and cross no
    edge."""

    def __init__(self, params):
        super().__init__(params)
        self._params = params
        self._fz0 = float(params.FNOMIN) * float(params.LFZO)
        self._fixed = load_factor_edges(params, 0.0) == load_factor_edges(params, 1.0)  # no edge moves with p
        pressures = [float(params[n]) for n in ("PRESMIN", "PRESMAX", "NOMPRES")]
        self.p_low, self.p_high = (-np.inf, np.inf) if self._fixed else (min(pressures), max(pressures))
        dpis = (0.0,) if self._fixed else tuple(_pressure_increment(params, p) for p in (self.p_low, self.p_high))
        edges = [edge for dpi in dpis for edge, _, _ in load_factor_edges(params, dpi)]
        self.low = max([e for e in edges if e <= self._fz0], default=0.0)
        self.high = min([e for e in edges if e >= self._fz0], default=np.inf)

    def __call__(self, fz_min: float, fz_max: float, p_min: float, p_max: float, stacklevel: int = 3) -> None:
        """Warn for the slip stiffnesses whose sign is the opposite of FNOMIN's somewhere in the loads used,
        ``fz_min``..``fz_max`` [N], at the pressures used, ``p_min``..``p_max`` [Pa]."""
        if self.low < fz_min and fz_max < self.high and (self._fixed or self.p_low <= p_min and p_max <= self.p_high):
            return
        for p in (p_min, p_max):  # the edges are monotonic in the pressure: its ends bound them
            for edge, names, what in load_factor_edges(self._params, _pressure_increment(self._params, p)):
                above = edge > self._fz0
                crossed = fz_max >= edge if above else 0.0 < fz_min <= edge
                if not crossed or not self._first(what):
                    continue
                used = fz_max if above else fz_min
                warnings.warn(f"{self._source}: {names} make the {what} change sign at Fz = {edge:.6g} N"
                              f"{f' (p = {p:g} Pa)' if 'PPY2' in names else ''}; the model is used at Fz = "
                              f"{used:.6g} N, {'above' if above else 'below'} it, where the tyre pushes along the "
                              f"slip (the slip stiffness has the opposite sign to the one at FNOMIN; the file's FZMAX "
                              f"does not exclude it)", LoadFactorWarning, stacklevel=stacklevel)


def saturate(values, bounds) -> tuple[np.ndarray, int]:
    """(values used by ``limits=True``, number of values outside) for ``bounds`` = (lower, upper, ...) of
    :func:`input_ranges`."""
    lo, hi = bounds[0], bounds[1]
    values = np.asarray(values, dtype=float)
    outside = int(np.count_nonzero((values < lo) | (values > hi)))
    return (np.clip(values, lo, hi) if outside else values), outside


def check_finite(name: str, values) -> None:
    """Raise :class:`ModelInputError` if ``values`` holds NaN or +-inf or a number beyond binary64 (an int such as
    10**400), naming the input and the first places."""
    try:
        values = np.asarray(values, dtype=float) if np.asarray(values).dtype.kind in "Oiu" else np.asarray(values)
    except OverflowError:
        raise ModelInputError(f"input {name!r} must be finite; got a number beyond the largest float (~1.8e308)") \
            from None
    except (TypeError, ValueError):
        values = np.asarray(values)
    bad = ~np.isfinite(values)
    if bad.any():
        where = np.argwhere(bad)[:5].tolist() if values.ndim else "scalar"
        raise ModelInputError(f"input {name!r} must be finite; got {values[bad][:3].tolist()} at {where}")


def check_pressure(p, name: str = "p") -> None:
    """Raise :class:`ModelInputError` unless every inflation pressure is positive (in Pa)."""
    p = np.asarray(p)
    if np.any(~(p > 0)):
        raise ModelInputError(f"inflation pressure {name!r} must be positive (in Pa); got minimum {float(np.min(p))!r}")


def warn_outside(counts: dict, total: int, ranges: dict, stacklevel: int = 3) -> None:
    """One :class:`InputClippedWarning` naming every input with points outside its range (none if no such)."""
    parts = [f"{name} outside {ranges[name][2]} at {n} of {total} point(s)" for name, n in counts.items() if n]
    if parts:
        given = spelled("limits=False", "mftyre eval --no-limits")
        warnings.warn(f"inputs outside the .tir ranges, saturated to them ({given} evaluates them as given): "
                      + "; ".join(parts), InputClippedWarning, stacklevel=stacklevel)


def check_finite_outputs(out: dict, arrays: dict) -> None:
    """Finite inputs must give finite outputs (``out``: name -> array, ``arrays``: input name -> array of the same
    shape; the check of :meth:`mftyre.MFModel.evaluate` and of the compiled model alike): where the .tir parameters admit no finite solution (e.g. Q_V1, Q_V2
    that make the free radius vanish at the speed asked for), raise ModelInputError naming the outputs and the
    first such point instead of returning NaN."""
    bad = [k for k, v in out.items() if not np.isfinite(v).all()]
    if not bad:
        return
    mask = np.zeros(np.shape(out[bad[0]]), dtype=bool)
    for k in bad:
        mask |= ~np.isfinite(out[k])
    i = np.unravel_index(np.argmax(mask), mask.shape) if mask.ndim else ()
    index = "" if not i else f" {int(i[0])}" if len(i) == 1 else f" {tuple(int(j) for j in i)}"
    at = ", ".join(f"{k}={np.broadcast_to(v, mask.shape)[i]:.6g}" for k, v in arrays.items())
    raise ModelInputError(f"the equations give non-finite {', '.join(bad)} at {int(mask.sum())} of {mask.size} "
                          f"point(s), first at point{index}: {at}: the .tir parameters have no finite solution there "
                          "(check the speed terms Q_V1, Q_V2 and the vertical parameters)")


def saturate_inputs(model, inputs: dict) -> dict:
    """``inputs`` (keyword arguments of :meth:`mftyre.MFModel.evaluate`) saturated to ``model``'s ranges, as
    ``limits=True`` would saturate them, so that a workflow evaluating the same measured rows many times (fitting,
    the gap finder) warns once (:func:`warn_data_outside`) rather than at every evaluation."""
    return {k: (model.used_input(k, v) if k in RANGE_PARAMETERS else v) for k, v in inputs.items()}


def warn_data_outside(model, inputs: dict, what: str) -> None:
    """One :class:`InputClippedWarning` when measured ``inputs`` lie outside ``model``'s ranges (``what``: the
    data, named in the message)."""
    ranges = input_ranges(model.params, model.mirrored)
    counts = {name: saturate(inputs[name], ranges[name])[1] for name in ranges if name in inputs}
    parts = [f"{name} outside {ranges[name][2]} at {n} of {np.size(inputs['fz'])} row(s)"
             for name, n in counts.items() if n]
    if parts:
        warnings.warn(f"{what}: inputs outside the .tir ranges; the model saturates them there: " + "; ".join(parts),
                      InputClippedWarning, stacklevel=3)
