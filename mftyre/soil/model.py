"""SoftSoilTyre: a .tir tyre on a soil, evaluated with the equations of :mod:`mftyre.soil.equations`.

    >>> from mftyre.soil import SoftSoilTyre
    >>> tyre = SoftSoilTyre("tir_files/agri_460_85R34_mf61.tir", "sandy_loam")
    >>> out = tyre.evaluate(fz=25e3, slip=np.linspace(0, 0.5, 26), p=1.2e5)
    >>> out.drawbar_pull, out.sinkage, out.to_frame()

Slip i = 1 - V / (omega Re), Re the hard-ground effective rolling radius (= kappa / (1 + kappa) of the Magic
Formula); see :class:`mftyre.soil.Ground` for the switch between hard ground, soft soil and a blend.
"""
from __future__ import annotations

import math

import numpy as np

from ..backend import NUMPY
from ..errors import ModelInputError
from ..formula import vertical
from ..model import MFModel, load_tir
from .equations import OUTPUTS, SoilEffects, soft_soil
from .soils import Soil, soil as named_soil

__all__ = ["SoftSoilTyre", "SoilOutputs", "SinkageError"]

_INPUTS = ("fz", "slip", "alpha", "p", "vx")
_CHUNK = 16384


class SinkageError(ModelInputError):
    """The tyre would sink so deep that the soil reaches the axle: outside the model (and the vehicle is stuck)."""


class SoilOutputs:
    """Every output of one soft-soil evaluation as named NumPy arrays (see :data:`OUTPUTS`)."""

    __slots__ = tuple(OUTPUTS)

    def __init__(self, **values):
        for name in OUTPUTS:
            setattr(self, name, values[name])

    def __getitem__(self, name):
        if name not in OUTPUTS:
            raise KeyError(f"no output {name!r}; outputs are {', '.join(OUTPUTS)}")
        return getattr(self, name)

    def keys(self):
        return tuple(OUTPUTS)

    def to_frame(self):
        """A pandas DataFrame, one row per operating point, one column per output (SI)."""
        import pandas as pd

        shape = np.shape(self.sinkage)
        return pd.DataFrame({k: np.ravel(np.broadcast_to(getattr(self, k), shape)) for k in OUTPUTS})

    def __repr__(self):
        return f"SoilOutputs(shape={np.shape(self.sinkage)})"


class SoftSoilTyre:
    """A tyre (a :class:`~mftyre.model.MFModel` or a .tir path) on a soil (a :class:`Soil` or a built-in name).

    Optional effects (see :mod:`mftyre.soil.equations`), absent at their defaults: ``slip_sinkage`` s_j >= 0
    (Lyasko's slip-sinkage factor [(1 + i)/(1 - 0.5 i)]^s_j, 1 = Lyasko), ``bulldozing_depth`` z_bd >= 0 [m]
    (Bekker's bulldozing resistance on the rut depth beyond z_bd; needs the soil's unit weight gamma) and ``rut``
    z_1 >= 0 [m] with ``unloading`` = (k_0 [N/m^3], A_u [N/m^4]): the tyre runs in a rut of depth z_1 left by the
    tyre ahead (multi-pass, Wong's repetitive loading; :meth:`following` builds it from the front tyre's outputs).
    """

    def __init__(self, tyre, soil, *, slip_sinkage=0.0, bulldozing_depth=math.inf, rut=0.0, unloading=None):
        self.tyre = tyre if isinstance(tyre, MFModel) else load_tir(tyre)
        self.soil = soil if isinstance(soil, Soil) else named_soil(soil)
        for name, value in (("slip_sinkage", slip_sinkage), ("bulldozing_depth", bulldozing_depth), ("rut", rut)):
            if not (isinstance(value, (int, float)) and value >= 0):
                raise ModelInputError(f"{name} must be a number >= 0, got {value!r}")
        for name, value in (("slip_sinkage", slip_sinkage), ("rut", rut)):
            if not math.isfinite(value):
                raise ModelInputError(f"{name} must be finite, got {value!r}")
        if math.isfinite(bulldozing_depth) and math.isnan(self.soil.gamma):
            raise ModelInputError(f"bulldozing_depth = {bulldozing_depth!r} m needs the unit weight gamma of soil "
                                  f"{self.soil.name!r} (column gamma of the soil file, kN/m^3); it is unknown")
        if unloading is not None and not (
                len(unloading) == 2 and all(isinstance(v, (int, float)) and math.isfinite(v) and v >= 0
                                            for v in unloading) and unloading[0] + unloading[1] > 0):
            raise ModelInputError(f"unloading must be (k_0 [N/m^3], A_u [N/m^4]), finite numbers >= 0, not both 0; "
                                  f"got {unloading!r}")
        if rut > 0:
            if unloading is None:
                raise ModelInputError(f"rut = {rut!r} m needs unloading=(k_0 [N/m^3], A_u [N/m^4]), the constants of "
                                      f"Wong's unloading slope k_u = k_0 + A_u z_1 for soil {self.soil.name!r}")
            if slip_sinkage:
                raise ModelInputError("slip_sinkage and rut cannot be combined (the slip-sinkage factor is defined "
                                      "for virgin soil)")
        self.effects = SoilEffects(float(slip_sinkage), float(bulldozing_depth), float(rut),
                                   tuple(float(v) for v in (unloading or (0.0, 0.0))))

    def following(self, front) -> "SoftSoilTyre":
        """This tyre running in the rut of ``front`` (a front tyre's :class:`SoilOutputs` at one operating point):
        multi-pass with Wong's repetitive loading, this tyre's ``unloading`` constants."""
        depth = np.ravel(front.sinkage)
        if depth.size != 1:
            raise ModelInputError(f"following: expected the front tyre's outputs at one point, got {depth.size}")
        if self.effects.unloading == (0.0, 0.0):
            raise ModelInputError("following() needs unloading=(k_0, A_u) given to this SoftSoilTyre")
        return SoftSoilTyre(self.tyre, self.soil, bulldozing_depth=self.effects.bulldozing_depth,
                            rut=float(depth[0]), unloading=self.effects.unloading)

    @property
    def params(self):
        return self.tyre.params

    def evaluate(self, fz, slip, alpha=0.0, p=None, vx=None) -> SoilOutputs:
        """All outputs at the operating points; inputs broadcast like NumPy.

        fz [N] > 0, slip i [-] < 1 (1 - V/(omega Re)), alpha [rad], p [Pa] > 0 (default INFLPRES), vx [m/s]
        (default LONGVL). Raises :class:`ModelInputError` on invalid inputs and :class:`SinkageError` where the
        soil would reach the axle.
        """
        prm = self.params
        values = dict(fz=fz, slip=slip, alpha=alpha, p=prm.INFLPRES if p is None else p,
                      vx=prm.LONGVL if vx is None else vx)
        arrays = {}
        for name, value in values.items():
            try:
                arrays[name] = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise ModelInputError(f"{name} must be numeric, got {value!r}") from None
        try:
            arrays = dict(zip(arrays, np.broadcast_arrays(*arrays.values())))
        except ValueError:
            shapes = ", ".join(f"{k}{np.shape(v)}" for k, v in arrays.items())
            raise ModelInputError(f"inputs do not broadcast to one shape: {shapes}") from None
        check_soil_inputs(arrays)
        shape = arrays["fz"].shape
        flat = {k: np.ravel(v) for k, v in arrays.items()}
        size = flat["fz"].size
        out = {k: np.empty(size) for k in OUTPUTS}
        for start in range(0, size, _CHUNK):  # chunks keep the temporaries in the CPU cache
            part = slice(start, min(start + _CHUNK, size))
            with np.errstate(all="ignore"):
                values = soft_soil(prm, self.soil, *(flat[k][part] for k in _INPUTS), NUMPY, self.effects)
            for k, v in values.items():
                out[k][part] = v
        self._check_sinkage(out, flat)
        return SoilOutputs(**{k: v.reshape(shape) for k, v in out.items()})

    def towed(self, fz, alpha=0.0, p=None, vx=None, *, tol=1e-9) -> SoilOutputs:
        """All outputs of the towed wheel (zero driving torque) at the operating points; its slip is ``.slip``.

        The torque T(i) rises with the slip i; the zero is bracketed by i = -1 (the wheel turns at half the
        free-rolling speed: every tread skids, T < 0) and i = 0.5 (T > 0), and found by the Illinois variant of
        regula falsi, vectorised, to |T| <= tol x Fz x r (or a bracket narrower than 1e-15). Raises
        :class:`ModelInputError` where the bracket does not hold.
        """
        prm = self.params
        values = dict(fz=fz, alpha=alpha, p=prm.INFLPRES if p is None else p, vx=prm.LONGVL if vx is None else vx)
        try:
            args = dict(zip(values, np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in values.values()))))
        except (TypeError, ValueError):
            raise ModelInputError(f"towed: inputs must be numeric and broadcast to one shape, got {values!r}") from None
        if not np.all(args["vx"] > 0):
            raise ModelInputError("towed: vx must be > 0 (the slip of a wheel standing still is undefined)")
        r = float(vertical.free_radius(prm, 0.0, NUMPY))
        shape = np.shape(args["fz"])
        lo, hi = np.full(shape, -1.0), np.full(shape, 0.5)
        t_lo, t_hi = self.evaluate(slip=lo, **args).torque, self.evaluate(slip=hi, **args).torque
        if not np.all(t_lo < 0):
            i = int(np.argmax(~(t_lo < 0)))
            sunk = float(np.ravel(self.evaluate(slip=lo, **args).sinkage)[i])
            raise ModelInputError(f"towed: at fz = {np.ravel(args['fz'])[i]:g} N, p = {np.ravel(args['p'])[i]:g} Pa "
                                  f"the wheel needs a driving torque even turning at half its free-rolling speed "
                                  f"(slip -1; sinkage {sunk:.3g} m, free radius {r:.3g} m): sunk this deep, a towed "
                                  f"wheel would all but stop turning, outside the model; expected a smaller load, a "
                                  f"lower pressure or a firmer soil")
        if not np.all(t_hi > 0):
            i = int(np.argmax(~(t_hi > 0)))
            raise ModelInputError(f"towed: at fz = {np.ravel(args['fz'])[i]:g} N, p = {np.ravel(args['p'])[i]:g} Pa "
                                  f"the driving torque is not positive even at slip 0.5 (the soil cannot turn the "
                                  f"wheel)")
        scale = tol * args["fz"] * r
        slip, torque = hi.copy(), t_hi.copy()
        side = np.zeros(shape)                                  # Illinois: +1 the low end moved last, -1 the high
        for _ in range(200):
            active = (np.abs(torque) > scale) & (hi - lo > 1e-15)
            if not np.any(active):
                break
            with np.errstate(all="ignore"):
                guess = np.where(t_hi != t_lo, hi - t_hi * (hi - lo) / (t_hi - t_lo), 0.5 * (lo + hi))
            guess = np.where(active & (guess > lo) & (guess < hi), guess, np.where(active, 0.5 * (lo + hi), slip))
            t_guess = self.evaluate(slip=guess, **args).torque
            below, above = active & (t_guess < 0), active & (t_guess >= 0)
            t_hi = np.where(above, t_guess, np.where(below & (side > 0), 0.5 * t_hi, t_hi))
            t_lo = np.where(below, t_guess, np.where(above & (side < 0), 0.5 * t_lo, t_lo))
            lo, hi = np.where(below, guess, lo), np.where(above, guess, hi)
            side = np.where(below, 1.0, np.where(above, -1.0, side))
            slip, torque = np.where(active, guess, slip), np.where(active, t_guess, torque)
        return self.evaluate(slip=slip, **args)

    def casadi_function(self, inputs=("fz", "slip", "alpha", "p"), outputs=tuple(OUTPUTS), *, fixed=None,
                        name="soft_soil"):
        """A ``casadi.Function`` of the same equations (SX). ``inputs``: any of fz slip alpha p vx, symbolic
        in the order given; the others take ``fixed`` values or their defaults (alpha 0, p INFLPRES, vx LONGVL;
        fz and slip must be given). The vertical balance is a fixed number of Newton steps (see
        :func:`mftyre.soil.equations.flat_load`). No sinkage check is made:
        evaluate with :meth:`evaluate` to be told when the soil reaches the axle."""
        import casadi as ca
        from ..backend import casadi_backend

        unknown = [k for k in (*inputs, *(fixed or {})) if k not in _INPUTS]
        if unknown:
            raise ModelInputError(f"unknown input(s) {unknown}; inputs are {', '.join(_INPUTS)}")
        bad = [k for k in outputs if k not in OUTPUTS]
        if bad:
            raise ModelInputError(f"unknown output(s) {bad}; outputs are {', '.join(OUTPUTS)}")
        prm = self.params
        values = dict(alpha=0.0, p=prm.INFLPRES, vx=prm.LONGVL)
        values.update(fixed or {})
        symbols = {k: ca.SX.sym(k) for k in inputs}
        values.update(symbols)
        missing = [k for k in ("fz", "slip") if k not in values]
        if missing:
            raise ModelInputError(f"input(s) {missing} must be symbolic or given in `fixed`")
        # the constant inputs become SX too, so every output is an expression
        args = [ca.SX(values[k]) if not isinstance(values[k], ca.SX) else values[k] for k in _INPUTS]
        out = soft_soil(prm, self.soil, *args, casadi_backend(), self.effects)
        names = [f"{k}_out" if k in inputs else k for k in outputs]
        return ca.Function(name, [symbols[k] for k in inputs], [ca.SX(out[k]) for k in outputs], list(inputs), names)

    def _check_sinkage(self, out, flat):
        r = self.params.UNLOADED_RADIUS * self.params.Q_RE0
        axle_height = np.sqrt(np.maximum(r * r - (0.5 * out["flat_length"]) ** 2, 0.0))
        too_deep = ~(out["sinkage"] < axle_height)
        if np.any(too_deep):
            i = int(np.argmax(too_deep))
            raise SinkageError(
                f"soil {self.soil.name!r}: at fz = {flat['fz'][i]:g} N, p = {flat['p'][i]:g} Pa the sinkage "
                f"{out['sinkage'][i]:.3g} m reaches the axle (height {axle_height[i]:.3g} m above the rut bottom) at "
                f"{int(too_deep.sum())} point(s), first at index {i}: the wheel is buried; expected a smaller load, "
                f"a lower pressure or a firmer soil")

    def __repr__(self):
        return f"SoftSoilTyre({self.tyre!r}, soil={self.soil.name!r})"


def check_soil_inputs(arrays):
    """Typed errors for inputs outside the model's domain."""
    rules = (("fz", lambda v: v > 0, "positive (in N)"), ("slip", lambda v: v < 1, "below 1 (i = 1 - V/(omega Re))"),
             ("alpha", lambda v: np.abs(v) < np.pi / 2, "within (-90, 90) deg (in rad)"),
             ("p", lambda v: v > 0, "positive (in Pa)"), ("vx", lambda v: v >= 0, ">= 0 (in m/s)"))
    for name, ok, expected in rules:
        value = np.asarray(arrays[name])
        good = ok(value) & np.isfinite(value)
        if not np.all(good):
            bad = np.ravel(value)[np.argmin(np.ravel(good))] if value.ndim else value
            raise ModelInputError(f"{name} must be finite and {expected}; got {float(bad)!r}")
