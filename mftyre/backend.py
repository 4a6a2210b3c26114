"""The few operations whose NumPy and CasADi spellings differ.

The Magic Formula equations in :mod:`mftyre.formula` are written once against a backend object ``be`` and
never call ``numpy`` or ``casadi`` directly. Two backends exist:

* :data:`NUMPY` evaluates on (broadcast) float64 arrays;
* :data:`CASADI` builds ``casadi.SX`` (or ``MX``) expressions with the same operations.

Both offer the elementary functions, comparisons folded into :meth:`where`, the MATLAB-style ``sign`` (with
sign(0) = 0) and the "non-zero" sign used by the Magic Formula's singularity guards (sign(0) = +1), and two
iteration primitives: :meth:`fixed_point` and :meth:`solve_newton` (safeguarded Newton in a bracket). NumPy
iterates until every element has converged (with an iteration cap); CasADi unrolls a fixed, documented number
of iterations so the resulting expression graph is static and differentiable.
"""
from __future__ import annotations

import numpy as np

from .errors import ModelInputError

__all__ = ["ExactCoefficient", "NumpyBackend", "CasadiBackend", "NUMPY", "NUMPY_FOLDING", "CASADI", "casadi_backend",
           "SMOOTH_WIDTHS", "LIMITS_SLACK"]

#: The quantities whose kinks ``smooth`` rounds, each with its own width (in its unit), and the widths
#: ``smooth=True`` uses: a width is small against the scale that matters for its quantity, yet the kink it
#: rounds is visible to a solver at the quantity's own scale (a single 1e-6 for all left the kink at Fz = 0
#: a step of the slope within a micronewton).
SMOOTH_WIDTHS = {
    "force": 1.0,   # N: the contact kink at Fz = 0, FZMIN in the aligning torque
    "speed": 0.01,  # m/s: |Vx|, sign(Vx), the low-speed switch at VXLOW
    "angle": 1e-4,  # rad: |gamma|, sign(alpha_r), sign(alpha_t)
    "slip": 1e-4,   # -: sign(kappa) in E_x
    "other": 1e-6,  # every other kink (dimensionless factors such as E <= 1, turn slip)
}

_ULP4 = 4.0 * np.finfo(float).eps  # the root searches' relative floor: 4 units in the last place


def _whole(chosen, cond, other) -> bool:
    """Whether ``np.where(cond, ...)`` choosing ``chosen`` everywhere would give ``chosen``'s values unchanged: an
    array condition, ``chosen`` a float64 array of its shape, the other side a number or of the same shape."""
    return (type(cond) is np.ndarray and type(chosen) is np.ndarray and chosen.dtype == np.float64
            and chosen.shape == cond.shape and getattr(other, "shape", ()) in ((), chosen.shape))


#: CasADi's saturation at the .tir ranges keeps the full slope this share of max(1, |bound|) beyond a bound (100
#: times IPOPT's bound relaxation, 1e-8) before it returns to the bound: see CasadiBackend.saturate.
LIMITS_SLACK = 1e-6

class ExactCoefficient(float):
    """A .tir coefficient that is exactly 0 or 1 (a scaling factor lambda = 1, an unused term's coefficient 0), for
    :meth:`NumpyBackend.known_coefficients`: arithmetic with it skips the array operation it would be an identity
    in (x + 0, x - 0, x * 1, x / 1 give x; 0 * x and 0 / x give 0, 0 - x gives -x), so that the equations keep
    their published form while a file's absent terms cost nothing. Arithmetic between numbers stays exact and
    keeps the result an ExactCoefficient where it is 0 or 1 (1 + 0 * x is 1); every other operation is the plain
    float one. A folded 0 * x is 0 also where x is not finite (the term is absent from the equation)."""

    __slots__ = ()

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        if method == "__call__" and not kwargs and len(inputs) == 2:
            folded = _fold(ufunc, *inputs)
            if folded is not None:
                return folded
        plain = [float(v) if type(v) is ExactCoefficient else v for v in inputs]
        return _exact(getattr(ufunc, method)(*plain, **kwargs))

    def __add__(self, other):
        return _binary(np.add, self, other)

    def __radd__(self, other):
        return _binary(np.add, other, self)

    def __sub__(self, other):
        return _binary(np.subtract, self, other)

    def __rsub__(self, other):
        return _binary(np.subtract, other, self)

    def __mul__(self, other):
        return _binary(np.multiply, self, other)

    def __rmul__(self, other):
        return _binary(np.multiply, other, self)

    def __truediv__(self, other):
        return _binary(np.divide, self, other)

    def __rtruediv__(self, other):
        return _binary(np.divide, other, self)

    def __pow__(self, other):
        return _exact(float(self) ** other)

    def __neg__(self):
        return _exact(-float(self))


_ZERO, _ONE = ExactCoefficient(0.0), ExactCoefficient(1.0)


def _exact(value):
    """``value`` as an ExactCoefficient where it is a number equal to 0 or 1, else unchanged."""
    if type(value) in (float, np.float64, ExactCoefficient):
        if value == 0.0:
            return _ZERO
        if value == 1.0:
            return _ONE
    return value


_FLOAT_OPERATORS = {np.add: float.__add__, np.subtract: float.__sub__, np.multiply: float.__mul__,
                    np.divide: float.__truediv__}


def _binary(ufunc, a, b):
    """``ufunc(a, b)`` where a or b is an ExactCoefficient: folded with an array, exact between numbers."""
    if type(a) is np.ndarray or type(b) is np.ndarray:
        folded = _fold(ufunc, a, b)
        return folded if folded is not None else ufunc(float(a) if type(a) is ExactCoefficient else a,
                                                        float(b) if type(b) is ExactCoefficient else b)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return _exact(_FLOAT_OPERATORS[ufunc](float(a), float(b)))
    return NotImplemented


def _fold(ufunc, a, b):
    """The result of ``ufunc(a, b)`` without computing it where one of them is an ExactCoefficient in which it is an
    identity (or zero), else None (NumPy: compute)."""
    if ufunc is np.multiply:
        for x, y in ((a, b), (b, a)):
            if type(x) is ExactCoefficient:
                return y if x == 1.0 else _ZERO
    elif ufunc is np.add:
        if type(a) is ExactCoefficient and a == 0.0:
            return b
        if type(b) is ExactCoefficient and b == 0.0:
            return a
    elif ufunc is np.subtract:
        if type(b) is ExactCoefficient and b == 0.0:
            return a
        if type(a) is ExactCoefficient and a == 0.0:
            return -b
    elif ufunc is np.divide:
        if type(b) is ExactCoefficient and b == 1.0:
            return a
        if type(a) is ExactCoefficient and a == 0.0:
            return _ZERO
    return None


class NumpyBackend:
    """Element-wise operations on NumPy float64 arrays. ``fold``: :meth:`exact` gives numbers whose identity
    operations on arrays are skipped (see :class:`ExactCoefficient`; worth its Python dispatch on large arrays)."""

    name = "numpy"

    def __init__(self, fold: bool = False):
        self.fold = fold
    pi = np.pi
    sin = staticmethod(np.sin)
    cos = staticmethod(np.cos)
    tan = staticmethod(np.tan)
    atan = staticmethod(np.arctan)
    tanh = staticmethod(np.tanh)
    acos = staticmethod(np.arccos)
    acosh = staticmethod(np.arccosh)
    cosh = staticmethod(np.cosh)
    sqrt = staticmethod(np.sqrt)
    exp = staticmethod(np.exp)
    log10 = staticmethod(np.log10)
    abs = staticmethod(np.abs)
    sign = staticmethod(np.sign)
    fmin = staticmethod(np.minimum)
    fmax = staticmethod(np.maximum)
    logical_and = staticmethod(np.logical_and)
    logical_or = staticmethod(np.logical_or)

    def of(self, quantity: str):
        """The operations for kinks in ``quantity`` (see :data:`SMOOTH_WIDTHS`): the same exact ones here."""
        return self

    def exact(self, value: float):
        """``value`` as a number the arithmetic may fold (with ``fold``: an :class:`ExactCoefficient` where it is 0
        or 1)."""
        return _exact(float(value)) if self.fold else float(value)

    @staticmethod
    def known_coefficients(values: dict) -> dict:
        """``values`` with every float equal to 0 or 1 as an :class:`ExactCoefficient` (for array evaluations: a
        file's unit scaling factors and zero coefficients then cost no array operation)."""
        return {k: _exact(v) if type(v) is float else v for k, v in values.items()}

    #: sqrt of a quantity >= 0 (CasADi: with the derivative 0 where it is 0)
    sqrt0 = staticmethod(np.sqrt)

    @staticmethod
    def cos_atan(x):
        """cos(atan(x)) = 1 / sqrt(1 + x^2), without the two transcendental functions."""
        if type(x) is np.ndarray and x.dtype == np.float64:  # in place: one temporary instead of four
            value = x * x
            value += 1.0
            np.sqrt(value, out=value)
            return np.divide(1.0, value, out=value)
        return 1.0 / np.sqrt(1.0 + x * x)

    @staticmethod
    def any(cond) -> bool:
        """Whether any element meets ``cond``: equations skip a case no element is in (CasADi: always True)."""
        if type(cond) is np.ndarray:
            return np.count_nonzero(cond) > 0
        return bool(cond) if type(cond) is np.bool_ else bool(np.any(cond))

    @staticmethod
    def where(cond, a, b):
        """``a`` where ``cond``, else ``b``; may return ``a`` or ``b`` itself (not a copy): write into the result
        only after copying it."""
        if type(cond) is np.bool_:  # one point (scalars): a Python choice, np.where costs microseconds
            return a if cond else b
        # the same side for every element (most guards hold nowhere or everywhere): that side as it is, without
        # the selection pass (which costs as much as several arithmetic operations)
        if type(cond) is np.ndarray:
            chosen = np.count_nonzero(cond)  # (faster than any() and all())
            if chosen == 0 and _whole(b, cond, a):
                return b
            if chosen == cond.size and _whole(a, cond, b):
                return a
        return np.where(cond, a, b)

    @staticmethod
    def sign_nz(x):
        """sign(x) with sign(0) = +1: the guard used in the Magic Formula's epsilon terms (a plain number where
        every element has the same sign)."""
        if type(x) is np.float64:
            return -1.0 if x < 0 else 1.0
        negative = x < 0
        count = np.count_nonzero(negative)
        if count == 0:
            return 1.0
        if count == negative.size:
            return -1.0
        return np.where(negative, -1.0, 1.0)

    @staticmethod
    def clip(x, lo, hi):
        if type(x) is np.ndarray:
            return np.clip(x, lo, hi)  # min(max(x, lo), hi) in one pass
        return np.minimum(np.maximum(x, lo), hi)  # (np.clip costs more on numbers)

    @staticmethod
    def saturate(x, lo, hi):
        """x held in [lo, hi] (``lo`` None: below ``hi``), the .tir range limits (see CasADi's for the slope)."""
        if lo is None:
            return np.minimum(x, hi)
        return NumpyBackend.clip(x, lo, hi)

    @staticmethod
    def broadcast(*values):
        """The values as float arrays of one common shape, at least 1-D (writable copies); scalars alone stay
        scalars (one point: scalar arithmetic, several times faster than arrays of one element)."""
        if all(np.ndim(v) == 0 for v in values):
            return [np.float64(v) for v in values]
        return [np.atleast_1d(np.array(v, dtype=float)) for v in np.broadcast_arrays(*values)]

    @staticmethod
    def fixed_point(step, x0, tol, max_iter=100, unrolled=None):
        """Iterate ``x = step(x)`` until every element changes by at most ``tol``.

        Returns ``(x, aux)`` where ``step`` returns ``(x_new, aux)``. Raises if not converged in
        ``max_iter`` iterations (never returns an unconverged value silently): ModelInputError.
        """
        x = x0
        for _ in range(max_iter):
            x_new, aux = step(x)
            close = np.abs(x_new - x) <= tol
            done = close.all() or bool(np.all(close | ~np.isfinite(x_new)))
            x = x_new
            if done:
                return x, aux
        raise ModelInputError(f"fixed-point iteration did not converge in {max_iter} iterations: inputs far outside "
                              "the range the model was fitted for?")

    @staticmethod
    def solve_newton(fun, x, f, df, lo, hi, xtol, ftol=0.0, max_iter=100, unrolled=None, kink=None):
        """Root of ``fun`` in [lo, hi], element-wise, where fun(lo) > 0 >= fun(hi) (a function falling through its
        root; lo < hi), from ``x`` with ``f = fun(x)`` and slope ``df``. ``fun(x, idx) -> (value, slope)``
        evaluates the elements ``idx`` (a tuple of index arrays, None while every element is still iterating).
        ``kink``: a point (a number) where the slope jumps; a Newton step across it stops there (the slope of the
        side it starts from says nothing of the other), and is not taken as converged.

        Safeguarded Newton: a Newton step that would leave the bracket (or a slope that is not negative) is replaced
        by bisection of the bracket narrowed by the evaluated points (narrowed on the steps where some element
        bisects: a Newton step inside the bracket stays inside the narrowed one too). An element has converged when
        |f| <= ``ftol`` (a scalar or one value per element), when its Newton step is at most ``xtol`` (plus 4 ulp of
        x) or the bracket is that narrow, or when the error left after its Newton step s1, |f''/(2 f')| s1^2 with
        f'' from the change of the slope over the Newton step s0 before, is estimated at a quarter of that at most;
        the result is the last point moved by its Newton step where that stays in the bracket. All elements iterate
        until at most a quarter of them are left, then only those (a gather costs more than a few needless
        evaluations; the results of the converged ones are kept). An element given ``f = 0`` returns ``x``.
        Scalars (one point) stay scalars. Raises ModelInputError if not converged in ``max_iter`` steps.
        """
        where = NumpyBackend.where  # one point (scalars): Python choices, no arrays
        scalar = all(np.ndim(v) == 0 for v in (x, f, df, lo, hi, ftol))
        if not scalar:
            x, f, df, lo, hi = np.broadcast_arrays(x, f, df, lo, hi)
            ftol = np.broadcast_to(ftol, x.shape)
            result = np.empty(x.shape)
        # the elements iterating (None: all), the sizes of their last Newton steps (0: bisection) and the slopes before
        # them, those of them already converged (None: none; they iterate on with the others, their results kept)
        idx, previous, df_previous, converged = None, None, None, None
        for _ in range(max_iter):
            descending = df < 0
            step = f / where(descending, df, -1.0)
            newton = x - step
            crossed = np.False_
            if kink is not None:
                crossed = (x - kink) * (newton - kink) < 0
                newton = where(crossed, kink, newton)
                step = x - newton
            ok = descending & (newton >= lo) & (newton <= hi)  # the same in the bracket narrowed by x
            all_newton = ok if scalar else ok.all()
            if not all_newton:  # x narrows the bracket (only needed for bisection: a mixed where is dear)
                falling = f > 0
                lo, hi = where(falling, x, lo), where(falling, hi, x)
            size = np.abs(step)
            tol = xtol + _ULP4 * np.abs(x)
            done = (np.abs(f) <= ftol) | (hi - lo <= tol) | (ok & ~crossed & (size <= tol))
            if previous is not None:  # the error left after this step: (f''/2f') s1^2, f'' from the slopes' change
                left_after = 2.0 * np.abs(df - df_previous) * size * size  # times 1 / (|df| previous): 4x the error
                done |= ok & ~crossed & (previous > 0) & (left_after <= np.abs(df) * previous * tol)
            moved = where(ok, newton, x)
            if scalar:
                if done:
                    return moved
            elif converged is not None:
                if idx is None:
                    np.copyto(result, moved, where=~converged)
                else:
                    result[idx] = np.where(converged, result[idx], moved)
                done |= converged
            elif idx is None:
                result[...] = moved
            else:
                result[idx] = moved
            left = None if scalar else done.size - np.count_nonzero(done)
            if left == 0:
                return result
            new = newton if all_newton else where(ok, newton, 0.5 * (lo + hi))
            previous = size if all_newton else where(ok, size, 0.0)
            df_previous = df
            if left is not None and 4 * left <= done.size:  # iterate on the few left only
                keep = np.nonzero(~done)
                idx = keep if idx is None else tuple(i[keep] for i in idx)
                new, lo, hi, previous, df_previous, ftol = (v[keep] for v in (new, lo, hi, previous, df, ftol))
                converged = None
            elif left is not None and left < done.size:
                converged = done
            x = new
            f, df = fun(x, idx)
        raise ModelInputError(f"Newton root search did not converge in {max_iter} iterations: inputs far outside the "
                              "range the model was fitted for?")


class CasadiBackend:
    """The same operations on CasADi SX/MX expressions (fixed iteration counts for loops).

    ``smooth`` replaces the kinks of the equations by smooth functions, for gradient-based optimisation
    only (the exact model is the default). Each kink is rounded over a width ``eps`` in the unit of its
    quantity (:data:`SMOOTH_WIDTHS`: force, speed, angle, slip, other): ``smooth=True`` takes those widths, a
    mapping overrides some of them (``{"force": 10.0}``), a number uses one width for every kink:

    ========  =====================================  ==================================
    exact      smooth                                 largest difference
    ========  =====================================  ==================================
    |x|        sqrt(x^2 + eps^2)                      eps (at x = 0)
    sign(x)    x / sqrt(x^2 + eps^2)                  1 at x = 0, < 0.5 (eps/x)^2 for |x| >> eps
    sign_nz    (x+eps) / sqrt((x+eps)^2 + eps^2)      0.29 at x = 0, < (eps/x)^2 for |x| >> eps
    min(a,b)   (a + b - sqrt((a - b)^2 + eps^2)) / 2  eps / 2 (at a = b)
    max(a,b)   (a + b + sqrt((a - b)^2 + eps^2)) / 2  eps / 2 (at a = b)
    ========  =====================================  ==================================

    The low-speed switch at VXLOW (kappa and alpha scaled by min(|Vx|, VXLOW)/VXLOW) is rounded with the speed
    width. Other case distinctions (rolling backwards, outside the .tir ranges: see ``limits="smooth"``) stay
    exact. The iterations (spin, MF 6.2 loaded radius) always use the exact operations.
    """

    name = "casadi"
    pi = np.pi
    def __init__(self, smooth: float | bool | dict | None = None, early_stop: bool = False):
        import casadi as ca

        self.ca = ca
        self.early_stop = early_stop  # the unrolled root searches stay put once converged (see solve_newton)
        self.widths = _smooth_widths(smooth)
        smooth = None if self.widths is None else self.widths["other"]
        self._quantities = {}
        self.smooth = smooth
        self.sin, self.cos, self.tan = ca.sin, ca.cos, ca.tan
        self.atan, self.acos, self.tanh = ca.atan, ca.acos, ca.tanh
        self.acosh, self.cosh = ca.acosh, ca.cosh
        self.sqrt, self.exp = ca.sqrt, ca.exp
        self.logical_and, self.logical_or = ca.logic_and, ca.logic_or
        if smooth is None:
            self.abs, self.sign = ca.fabs, ca.sign
            self.fmin, self.fmax = ca.fmin, ca.fmax
        else:
            e2 = float(smooth) ** 2
            self.abs = lambda x: ca.sqrt(x * x + e2)
            self.sign = lambda x: x / ca.sqrt(x * x + e2)
            self.fmin = lambda a, b: 0.5 * (a + b - ca.sqrt((a - b) ** 2 + e2))
            self.fmax = lambda a, b: 0.5 * (a + b + ca.sqrt((a - b) ** 2 + e2))

    def log10(self, x):
        return self.ca.log(x) / np.log(10.0)

    def of(self, quantity: str):
        """The operations for kinks in ``quantity`` (a key of :data:`SMOOTH_WIDTHS`), rounded over its width."""
        if self.widths is None:
            return self
        if quantity not in self._quantities:
            width = self.widths[quantity]
            self._quantities[quantity] = self if width == self.smooth else CasadiBackend(width)
        return self._quantities[quantity]

    @staticmethod
    def exact(value: float) -> float:
        """``value`` (CasADi folds 0 and 1 itself)."""
        return float(value)

    def cos_atan(self, x):
        """cos(atan(x)) = 1 / sqrt(1 + x^2)."""
        return 1.0 / self.ca.sqrt(1.0 + x * x)

    def sqrt0(self, square):
        """sqrt of a quantity >= 0 (a speed sqrt(Vx^2 + Vsy^2), a load ratio Fz/Fz0) with the derivative 0 where it
        is 0: there sqrt's infinite slope times the quantity's zero slope would make NaN of every derivative
        through it (the derivative of Fz sqrt(Fz/Fz0) at Fz = 0 is 0 indeed)."""
        ca = self.ca
        positive = square > 0
        return ca.if_else(positive, ca.sqrt(ca.if_else(positive, square, 1.0)), 0.0)

    @staticmethod
    def any(cond) -> bool:
        """True: a symbolic graph keeps every case."""
        return True

    def where(self, cond, a, b):
        return self.ca.if_else(cond, a, b)

    def sign_nz(self, x):
        """sign(x) with sign(0) = +1; smooth: (x + eps)/sqrt((x + eps)^2 + eps^2), 0.71 at x = 0, so that a guarded
        denominator x + 1e-6 sign_nz(x) stays positive where x and its numerator vanish together (zero load)."""
        if self.smooth is None:
            return self.ca.if_else(x < 0, -1.0, 1.0)
        shifted = x + self.smooth
        return shifted / self.ca.sqrt(shifted * shifted + self.smooth**2)

    def clip(self, x, lo, hi):
        return self.fmin(self.fmax(x, lo), hi)

    def saturate(self, x, lo, hi):
        """x held in [lo, hi] (``lo`` None: below ``hi``), exact also with ``smooth`` except in a band just beyond
        each bound b: up to d = LIMITS_SLACK max(1, |b|) beyond it the input keeps its full slope (the identity), over
        the next d it returns to the bound (slope -1), and further out it is held there (slope 0), as NumPy's clip.
        An interior-point solver relaxes a bound by 1e-8 max(1, |b|) (IPOPT's bound_relax_factor) and ends a hair
        outside an active one: there it sees the true slope, so the bound's multiplier is the true sensitivity (with
        a plain clip it is 0). The outputs differ from NumPy's only inside the band, by at most the slope times d."""
        ca = self.ca

        def beyond(over, bound):  # the input used at ``over`` > 0 beyond ``bound``, moving away from it
            d = LIMITS_SLACK * ca.fmax(1.0, ca.fabs(bound))
            return ca.fmax(0.0, d - ca.fabs(over - d))

        held = ca.if_else(x > hi, hi + beyond(x - hi, hi), x)
        return held if lo is None else ca.if_else(x < lo, lo - beyond(lo - x, lo), held)

    @staticmethod
    def broadcast(*values):
        """Symbols broadcast themselves: unchanged."""
        return list(values)

    def fixed_point(self, step, x0, tol, max_iter=100, unrolled=8):
        """``unrolled`` iterations of ``x = step(x)`` (the contraction rate must make that enough)."""
        x, aux = x0, None
        for _ in range(unrolled):
            x, aux = step(x)
        return x, aux

    def solve_newton(self, fun, x, f, df, lo, hi, xtol, ftol=0.0, max_iter=100, unrolled=12, kink=None):
        """``unrolled`` steps of :meth:`NumpyBackend.solve_newton`, then the final Newton step (never stopped at
        the ``kink``), whose derivatives are those of the implicit function. Without ``early_stop`` no stopping
        test (at the root a Newton step stays put); with it, the stopping tests of the NumPy solver, and once they
        hold the point stays put: the steps after it are ``if_else(done, x, step)``, whose ``step`` the compiled
        one-point C skips (:mod:`mftyre.compiled`)."""
        ca = self.ca

        def step(x, f, df, lo, hi, kink=None):
            falling = f > 0
            lo, hi = ca.if_else(falling, x, lo), ca.if_else(falling, hi, x)
            newton = x - f / ca.if_else(df < 0, df, -1.0)
            if kink is not None:
                newton = ca.if_else((x - kink) * (newton - kink) < 0, kink, newton)
            ok = ca.logic_and(df < 0, ca.logic_and(newton >= lo, newton <= hi))
            return newton, ok, lo, hi

        done = previous = df_previous = None  # (early_stop) converged; the last Newton step's size, the slope
        # before it
        for _ in range(unrolled):
            newton, ok, lo_next, hi_next = step(x, f, df, lo, hi, kink)
            x_next = ca.if_else(ok, newton, 0.5 * (lo_next + hi_next))
            if not self.early_stop:
                x, lo, hi = x_next, lo_next, hi_next
                f, df = fun(x, None)
                continue
            newton_only = ok if kink is None else ca.logic_and(ok, (x - kink) * (newton - kink) >= 0)  # not cut
            size, tol = ca.fabs(x - newton), xtol + _ULP4 * ca.fabs(x)
            converged = ca.logic_or(ca.logic_or(ca.fabs(f) <= ftol, hi_next - lo_next <= tol),
                                    ca.logic_and(newton_only, size <= tol))
            if previous is not None:  # the error left after this step (see NumpyBackend.solve_newton)
                left_after = 2.0 * ca.fabs(df - df_previous) * size * size
                converged = ca.logic_or(converged, ca.logic_and(ca.logic_and(newton_only, previous > 0),
                                                                left_after <= ca.fabs(df) * previous * tol))
            done = converged if done is None else ca.logic_or(done, converged)  # and stays so
            f_next, df_next = fun(x_next, None)
            previous, df_previous, lo, hi = ca.if_else(ok, size, 0.0), df, lo_next, hi_next  # (idle once done)
            x, f, df = ca.if_else(done, x, x_next), ca.if_else(done, f, f_next), ca.if_else(done, df, df_next)
        newton, ok, _, _ = step(x, f, df, lo, hi)
        return ca.if_else(ok, newton, x)


NUMPY = NumpyBackend()
#: NumPy with folding, for large arrays with parameters from :meth:`NumpyBackend.known_coefficients`
NUMPY_FOLDING = NumpyBackend(fold=True)
_CASADI = None


def __getattr__(name):  # lazy CASADI so that importing mftyre does not import casadi
    global _CASADI
    if name == "CASADI":
        if _CASADI is None:
            _CASADI = CasadiBackend()
        return _CASADI
    raise AttributeError(name)


def _smooth_widths(smooth) -> dict | None:
    """The width of every quantity for ``smooth`` (None, True, a positive number or a partial mapping)."""
    if smooth is None or smooth is False:
        return None
    if smooth is True:
        return dict(SMOOTH_WIDTHS)
    if isinstance(smooth, dict):
        unknown = sorted(set(smooth) - set(SMOOTH_WIDTHS))
        if unknown:
            raise ValueError(f"smooth: unknown quantities {unknown}; they are {', '.join(SMOOTH_WIDTHS)}")
        widths = {**SMOOTH_WIDTHS, **smooth}
    else:
        widths = dict.fromkeys(SMOOTH_WIDTHS, smooth)
    for quantity, width in widths.items():
        if isinstance(width, bool) or not isinstance(width, (int, float)) or not width > 0:
            raise ValueError(f"smooth must be True, a positive number or a mapping of quantities to positive "
                             f"widths; got {width!r} for {quantity!r}")
    return {k: float(v) for k, v in widths.items()}


def casadi_backend(smooth: float | bool | dict | None = None, early_stop: bool = False) -> CasadiBackend:
    """The exact CasADi backend, or a smoothed one, or one whose root searches stop early (see
    :class:`CasadiBackend`, :meth:`CasadiBackend.solve_newton`)."""
    if early_stop or not (smooth is None or smooth is False):
        return CasadiBackend(smooth, early_stop)
    return __getattr__("CASADI")
