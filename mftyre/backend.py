"""The few operations whose NumPy and CasADi spellings differ.

The Magic Formula equations in :mod:`mftyre.formula` are written once against a backend object ``be`` and
never call ``numpy`` or ``casadi`` directly. Two backends exist:

* :data:`NUMPY` evaluates on (broadcast) float64 arrays;
* :data:`CASADI` builds ``casadi.SX`` (or ``MX``) expressions with the same operations.

Both offer the elementary functions, comparisons folded into :meth:`where`, the MATLAB-style ``sign`` (with
sign(0) = 0) and the "non-zero" sign used by the Magic Formula's singularity guards (sign(0) = +1), and two
iteration primitives: :meth:`fixed_point` and :meth:`solve_bracketed`, with :meth:`bracket` (widening or
grid scan) that feeds the latter. NumPy iterates until every element has
converged (with an iteration cap); CasADi unrolls a fixed, documented number of iterations so the resulting
expression graph is static and differentiable.
"""
from __future__ import annotations

import numpy as np

from .errors import ModelInputError

__all__ = ["NumpyBackend", "CasadiBackend", "NUMPY", "CASADI", "casadi_backend"]

_ULP4 = 4.0 * np.finfo(float).eps  # the root searches' relative floor: 4 units in the last place


def _whole(chosen, cond, other) -> bool:
    """Whether ``np.where(cond, ...)`` choosing ``chosen`` everywhere would give ``chosen``'s values unchanged: an
    array condition, ``chosen`` a float64 array of its shape, the other side a number or of the same shape."""
    return (type(cond) is np.ndarray and type(chosen) is np.ndarray and chosen.dtype == np.float64
            and chosen.shape == cond.shape and getattr(other, "shape", ()) in ((), chosen.shape))


class NumpyBackend:
    """Element-wise operations on NumPy float64 arrays."""

    name = "numpy"
    pi = np.pi
    sin = staticmethod(np.sin)
    cos = staticmethod(np.cos)
    tan = staticmethod(np.tan)
    atan = staticmethod(np.arctan)
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

    @staticmethod
    def cos_atan(x):
        """cos(atan(x)) = 1 / sqrt(1 + x^2), without the two transcendental functions."""
        return 1.0 / np.sqrt(1.0 + x * x)

    @staticmethod
    def any(cond) -> bool:
        """Whether any element meets ``cond``: equations skip a case no element is in (CasADi: always True)."""
        if type(cond) is np.ndarray:
            return np.count_nonzero(cond) > 0
        return bool(np.any(cond))

    @staticmethod
    def where(cond, a, b):
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
    def broadcast(*values):
        """The values as float arrays of one common shape, at least 1-D (writable copies)."""
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
    def bracket(fun, contact, a, b, fa, fb, widen, x0, f0, scale, offsets, max_iter=100):
        """Brackets for :meth:`solve_bracketed`, two ways. Where ``contact``: ``widen(a, b, fb, idx) -> b'`` moves
        ``b`` (only while fa and fb have the same non-zero sign, at most ``max_iter`` times) until [a, b] holds a
        sign change. Elsewhere, where ``f0 = fun(x0) > 0``: a scan of ``x0 + offsets[k] scale`` (increasing offsets)
        for the first point where ``fun`` is <= 0. ``fun(x, idx)`` evaluates the elements ``idx`` (a tuple of index
        arrays, or None for all).

        Returns ``(found, a, b, fa, fb)``: found is ``contact`` or a scan that changed sign, whose [a, b] is the first
        grid interval with f(a) > 0 >= f(b); elsewhere a = b = x0 and fa = fb = 0.
        """
        x0, f0, scale, a, b, fa, fb = (np.atleast_1d(np.array(v, dtype=float))
                                       for v in np.broadcast_arrays(x0, f0, scale, a, b, fa, fb))
        contact = np.broadcast_to(contact, x0.shape)
        for _ in range(max_iter):  # widening, in contact
            idx = np.nonzero(contact & (fa * fb > 0))
            if idx[0].size == 0:
                break
            b[idx] = widen(a[idx], b[idx], fb[idx], idx)
            fb[idx] = fun(b[idx], idx)
        lifted = ~contact
        a[lifted], b[lifted], fa[lifted], fb[lifted] = x0[lifted], x0[lifted], 0.0, 0.0
        found = contact.copy()
        idx = np.nonzero(lifted & (f0 > 0))  # the scan
        x_prev, f_prev = x0[idx], f0[idx]
        for offset in offsets:
            if idx[0].size == 0:
                break
            x = x0[idx] + offset * scale[idx]
            f = fun(x, idx)
            hit = f <= 0
            hit_idx = tuple(i[hit] for i in idx)
            a[hit_idx], b[hit_idx], fa[hit_idx], fb[hit_idx] = x_prev[hit], x[hit], f_prev[hit], f[hit]
            found[hit_idx] = True
            idx = tuple(i[~hit] for i in idx)
            x_prev, f_prev = x[~hit], f[~hit]
        return found, a, b, fa, fb

    @staticmethod
    def solve_bracketed(fun, a, b, fa, fb, xtol, max_iter=100, unrolled=None, ftol=0.0):
        """Root of ``fun`` between ``a`` and ``b`` (``fa``, ``fb`` of opposite sign or zero), element-wise.

        Dekker's method: secant steps from the best point ``b``, bisection whenever the secant leaves
        the half of the bracket next to ``b``, steps of at least xtol/2; the bracket [a, b] always holds a
        sign change. ``fun(x, idx)``
        evaluates the elements ``idx`` (a tuple of index arrays) at ``x``. Iterates until |b - a| <= xtol (plus
        4 ulp of b, for roots far from zero)
        or |f(b)| <= ``ftol`` (a scalar or one value per element) for every element. ``idx`` is None while every
        element is still iterating (no gathering). Elements without a sign change return the end with the smaller
        |f| (see :meth:`bracket`).
        """
        shape = np.shape(a)
        a, b = np.atleast_1d(np.array(a, dtype=float)), np.atleast_1d(np.array(b, dtype=float))
        fa, fb = np.atleast_1d(np.array(fa, dtype=float)), np.atleast_1d(np.array(fb, dtype=float))
        swap = np.abs(fa) < np.abs(fb)
        a, b, fa, fb = np.where(swap, b, a), np.where(swap, a, b), np.where(swap, fb, fa), np.where(swap, fa, fb)
        c, fc = a.copy(), fa.copy()
        ftol = np.broadcast_to(ftol, a.shape)
        active = (fa * fb < 0) & (np.abs(b - a) > xtol + _ULP4 * np.abs(b)) & (np.abs(fb) > ftol)
        for _ in range(max_iter):
            if not active.any():
                break
            idx = None if active.all() else np.nonzero(active)
            if idx is None:
                ai, bi, ci, fai, fbi, fci, ftoli = a, b, c, fa, fb, fc, ftol
            else:
                ai, bi, ci, fai, fbi, fci, ftoli = a[idx], b[idx], c[idx], fa[idx], fb[idx], fc[idx], ftol[idx]
            mid = 0.5 * (ai + bi)
            secant = bi - fbi * (bi - ci) / (fbi - fci)
            inside = (fbi != fci) & ((secant - bi) * (secant - mid) <= 0)
            new = np.where(inside, secant, mid)
            # a step shorter than xtol/2 is lengthened to xtol/2 towards a: once b is that close to the
            # root the next point lands beyond it and the bracket collapses (as in Brent's method)
            tol = xtol + _ULP4 * np.abs(bi)
            new = np.where(np.abs(new - bi) < 0.5 * tol, bi + 0.5 * tol * np.sign(ai - bi), new)
            fnew = fun(new, idx)
            keep_a = fnew * fai < 0
            ai, fai = np.where(keep_a, ai, bi), np.where(keep_a, fai, fbi)
            ci, fci = bi, fbi
            bi, fbi = new, fnew
            swap = np.abs(fai) < np.abs(fbi)
            ai, bi = np.where(swap, bi, ai), np.where(swap, ai, bi)
            fai, fbi = np.where(swap, fbi, fai), np.where(swap, fai, fbi)
            still = (np.abs(fbi) > ftoli) & (np.abs(bi - ai) > xtol + _ULP4 * np.abs(bi))
            if idx is None:
                a, b, c, fa, fb, fc, active = ai, bi, ci, fai, fbi, fci, still
            else:
                a[idx], b[idx], c[idx], fa[idx], fb[idx], fc[idx] = ai, bi, ci, fai, fbi, fci
                active[idx] = still
        else:
            if active.any():
                raise ModelInputError(f"bracketed root search did not converge in {max_iter} iterations: inputs far "
                                      "outside the range the model was fitted for?")
        return np.where(np.abs(fb) <= np.abs(fa), b, a).reshape(shape)


class CasadiBackend:
    """The same operations on CasADi SX/MX expressions (fixed iteration counts for loops).

    ``smooth=eps`` replaces the kinks of the equations by smooth functions, for gradient-based optimisation
    only (the exact model is the default):

    ========  =====================================  ==================================
    exact      smooth                                 largest difference
    ========  =====================================  ==================================
    |x|        sqrt(x^2 + eps^2)                      eps (at x = 0)
    sign(x)    x / sqrt(x^2 + eps^2)                  1 at x = 0, < 0.5 (eps/x)^2 for |x| >> eps
    sign_nz    (x+eps) / sqrt((x+eps)^2 + eps^2)      0.29 at x = 0, < (eps/x)^2 for |x| >> eps
    min(a,b)   (a + b - sqrt((a - b)^2 + eps^2)) / 2  eps / 2 (at a = b)
    max(a,b)   (a + b + sqrt((a - b)^2 + eps^2)) / 2  eps / 2 (at a = b)
    ========  =====================================  ==================================

    ``eps`` is in the units of the argument (forces, angles, slips alike), so choose it small against the
    smallest scale that matters (1e-6 is a good start). Case distinctions on conditions (below VXLOW, rolling
    backwards, outside the .tir ranges) stay exact: keep an optimisation inside one case. The iterations
    (spin, MF 6.2 loaded radius) always use the exact operations.
    """

    name = "casadi"
    pi = np.pi
    def __init__(self, smooth: float | None = None):
        import casadi as ca

        self.ca = ca
        self.smooth = smooth
        self.sin, self.cos, self.tan = ca.sin, ca.cos, ca.tan
        self.atan, self.acos = ca.atan, ca.acos
        self.acosh, self.cosh = ca.acosh, ca.cosh
        self.sqrt, self.exp = ca.sqrt, ca.exp
        self.logical_and, self.logical_or = ca.logic_and, ca.logic_or
        if smooth is None:
            self.abs, self.sign = ca.fabs, ca.sign
            self.fmin, self.fmax = ca.fmin, ca.fmax
        else:
            if not smooth > 0:
                raise ValueError(f"smooth must be a positive number, got {smooth!r}")
            e2 = float(smooth) ** 2
            self.abs = lambda x: ca.sqrt(x * x + e2)
            self.sign = lambda x: x / ca.sqrt(x * x + e2)
            self.fmin = lambda a, b: 0.5 * (a + b - ca.sqrt((a - b) ** 2 + e2))
            self.fmax = lambda a, b: 0.5 * (a + b + ca.sqrt((a - b) ** 2 + e2))

    def log10(self, x):
        return self.ca.log(x) / np.log(10.0)

    def cos_atan(self, x):
        """cos(atan(x)) = 1 / sqrt(1 + x^2)."""
        return 1.0 / self.ca.sqrt(1.0 + x * x)

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

    def bracket(self, fun, contact, a, b, fa, fb, widen, x0, f0, scale, offsets, max_iter=100):
        """:meth:`NumpyBackend.bracket` in one set of unrolled evaluations, one per offset: each element needs
        either the widening or the scan, so each evaluation serves the one it needs (len(offsets) widening steps)."""
        ca = self.ca
        found = contact
        lo = hi = x0
        f_lo = f_hi = 0 * f0
        x_prev, f_prev = x0, f0
        searching = ca.logic_and(ca.logic_not(contact), f0 > 0)
        for offset in offsets:
            widening = ca.logic_and(contact, fa * fb > 0)
            x = ca.if_else(contact, widen(a, b, fb, None), x0 + offset * scale)
            f = fun(x, None)
            b, fb = ca.if_else(widening, x, b), ca.if_else(widening, f, fb)
            hit = ca.logic_and(ca.logic_and(searching, ca.logic_not(found)), f <= 0)
            lo, hi = ca.if_else(hit, x_prev, lo), ca.if_else(hit, x, hi)
            f_lo, f_hi = ca.if_else(hit, f_prev, f_lo), ca.if_else(hit, f, f_hi)
            found = ca.logic_or(found, hit)
            x_prev, f_prev = x, f
        return (found, ca.if_else(contact, a, lo), ca.if_else(contact, b, hi), ca.if_else(contact, fa, f_lo),
                ca.if_else(contact, fb, f_hi))

    def solve_bracketed(self, fun, a, b, fa, fb, xtol, max_iter=100, unrolled=40, ftol=0.0):
        """``unrolled`` steps of Dekker's method (see :meth:`NumpyBackend.solve_bracketed`; ``ftol`` is not
        needed: the final Newton step polishes)."""
        ca = self.ca

        def ordered(a, b, fa, fb):
            swap = ca.fabs(fa) < ca.fabs(fb)
            return (ca.if_else(swap, b, a), ca.if_else(swap, a, b), ca.if_else(swap, fb, fa),
                    ca.if_else(swap, fa, fb))

        a, b, fa, fb = ordered(a, b, fa, fb)
        # without a sign change the end with the smaller |f| (as NumPy); with one, the steps need no freezing once
        # converged: a step of xtol/2 beyond a leaves a bracket of at most xtol round the root
        start, bracketed = b, fa * fb < 0
        c, fc = a, fa
        for _ in range(unrolled):
            tol = xtol + _ULP4 * ca.fabs(b)
            mid = 0.5 * (a + b)
            secant = b - fb * (b - c) / (fb - fc)
            inside = ca.logic_and(fb != fc, (secant - b) * (secant - mid) <= 0)
            new = ca.if_else(inside, secant, mid)
            new = ca.if_else(ca.fabs(new - b) < 0.5 * tol, b + 0.5 * tol * ca.sign(a - b), new)
            fnew = fun(new, None)
            keep_a = fnew * fa < 0
            c, fc = b, fb
            a, b, fa, fb = ordered(ca.if_else(keep_a, a, b), new, ca.if_else(keep_a, fa, fb), fnew)
        best = ca.if_else(bracketed, ca.if_else(ca.fabs(fb) <= ca.fabs(fa), b, a), start)
        # one Newton step at the converged point: same value, and derivatives that are exactly those of
        # the implicit function (the unrolled bracketing steps alone would differentiate the iteration)
        x = ca.SX.sym("x") if isinstance(best, ca.SX) else ca.MX.sym("x")
        fx = fun(x, None)
        slope = ca.substitute(ca.jacobian(fx, x), x, best)
        f_best = ca.substitute(fx, x, best)
        return best - ca.if_else(slope != 0, f_best / slope, 0.0)


NUMPY = NumpyBackend()
_CASADI = None


def __getattr__(name):  # lazy CASADI so that importing mftyre does not import casadi
    global _CASADI
    if name == "CASADI":
        if _CASADI is None:
            _CASADI = CasadiBackend()
        return _CASADI
    raise AttributeError(name)


def casadi_backend(smooth: float | None = None) -> CasadiBackend:
    """The exact CasADi backend, or a smoothed one (see :class:`CasadiBackend`)."""
    return __getattr__("CASADI") if smooth is None else CasadiBackend(smooth)
