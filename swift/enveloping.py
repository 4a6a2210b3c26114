"""Tandem-cam enveloping: the effective road a tyre feels on short obstacles, and the quasi-static tyre on it.

Concept (Schmeitz 2004; Pacejka 2012 sec. 10.1.3; Schmeitz et al. 2005 sec. 3.1): two rigid elliptical cams in
tandem, at distance l_s, move vertically over the real profile; the midpoint and the inclination of the line
through their lowest points give the effective road height w and forward slope beta_y. Equations (symbols of
``../shared/reference/swift/NOTES.md`` sec. 3):

* cam contour (super-ellipse), lowest point at height h, for |xi| <= a_e:
      z_cam(xi) = h + z_c(xi),   z_c(xi) = b_e - b_e (1 - |xi/a_e|^c_e)^(1/c_e)
  with a_e = ELLIPS_LENGTH R0, b_e = ELLIPS_HEIGHT R0, c_e = ELLIPS_ORDER                       [chosen: sizes
  scaled by the unloaded radius, so the defaults 1/1/1.8 give a cam the size of the free tyre; App. 3 calls
  them p_ae, p_be, c_e]
* cam height: the lowest position that does not penetrate the road                               [chosen]
      h(x) = max_{|xi| <= a_e} [w_r(x + xi) - z_c(xi)]
  (over a step of height H < b_e it rises over the basic-function length
   l_b = a_e (1 - (1 - H/b_e)^c_e)^(1/c_e))
* tandem (two-point follower over the cams), l_s = ELLIPS_SHIFT 2a                             [published, Zegelaar
  eq. 4.15; a = current half contact length from Q_RA1/Q_RA2 (paper (9)) at the current load and pressure]
      h_f = h(x + l_s/2),  h_r = h(x - l_s/2),  w = (h_f + h_r)/2,  beta_y = atan((h_f - h_r)/l_s)
* beta_y > 0: road rising ahead [chosen sign]; effective curvature = d beta_y / dx, central difference over
  ``CURVATURE_STEP`` [chosen; the MF-Swift definition is open]
* pressure enters only through l_s: a(Fz, p) with Fz = Fz(rho, p) (Schmeitz et al. 2005 sec. 3.2: "no additional
  enveloping model parameters are required"; the cam sizes do not depend on load or pressure)
* two-track / 3D roads: ELLIPS_NWIDTH parallel tandems spread uniformly over the contact width 2b [chosen; the
  lateral placement is open]; w and beta_y = means over the tracks, road camber (banking)
  beta_x = atan(least-squares slope of w_j over y_j)
* no cam rotation with the local grade [chosen]: on a constant grade s, beta_y = atan(s) exactly and w carries
  the offset max_xi(s xi - z_c(xi)) (0.06 mm at 5 %).
* ENV_C1/ENV_C2 (attenuation, formula unpublished) are not modelled: a non-zero value gives a warning.
* ELLIPS_NLENGTH ("number of ellipsoids at sides of contact patch", TNO comment) is not used: its role in MF-Swift
  is unpublished (NOTES sec. 3.3, 9.1; Adams' "nlength" for oblique cleats suggests a count of cams or sample
  positions along the tandem). Here each cam's height is the exact maximum over the profile (breakpoints plus a
  0.5 mm grid), so no count of cams along the length enters; a value set in the file gives a warning.

Numerics: the max over xi runs over a uniform grid (``dx``, default 0.5 mm) restricted to |xi| <= l_b(H_road),
with H_road the height range of the profile (outside, z_c > H_road, so no such xi can win: the restriction is
exact), plus every road breakpoint inside the window evaluated exactly, so flat parts and cleat edges carry no
sampling error. Where the whole window lies on a level part of the road (``Road.level_spans``) the max is that
level (z_c >= 0, z_c(0) = 0) and the search is skipped: the same numbers, without the search on the floor between
obstacles.

Quasi-static tyre (:func:`quasi_static`): the MF vertical spring Fz(rho, p) normal to the effective plane,
rho = R_Omega - d with d the normal distance from the wheel centre to the plane; the tandem is centred under the
wheel centre, the cams moving only vertically (Schmeitz et al. 2005 sec. 3.1, as in :mod:`swift.ring`); free
rolling (in-plane force F'_x = 0), so the wheel-centre forces are Fx = -F'_z sin(beta_y), Fz = F'_z cos(beta_y)
(NOTES sec. 3.5). ``QuasiStatic.road`` holds the effective road at the wheel positions. Load and tandem base are
solved to convergence (bracketed, continued along x, see :func:`quasi_static`), with a residual check.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from mftyre.backend import NUMPY
from mftyre.errors import ModelInputError
from mftyre.formula import vertical

from .road import MAX_DISTANCE, Road, check_road

__all__ = ["Cams", "cam_height", "CamTable", "tandem_base", "EffectiveRoad", "effective_road",
           "effective_road_3d", "QuasiStatic", "quasi_static", "CURVATURE_STEP"]

#: Step [m] of the central difference that gives the effective curvature d beta_y / dx.
CURVATURE_STEP = 2e-3
_CHUNK = 4096
#: Clearance [m] between a cam's window and the edge of a level span for the search to be skipped there (rounding
#: of x + xi is below 1e-9 m for |x| <= MAX_DISTANCE).
_LEVEL_MARGIN = 1e-6

#: Largest cam half length / height [m] and ELLIPS_SHIFT: a hundred metres is no tyre's (real: ~0.3 m, shift ~0.8).
_CAM_LIMIT = 100.0


def _warn_unmodelled(prm) -> None:
    """Warn about the [CONTACT_PATCH] parameters of ``prm`` that the enveloping model does not use."""
    for name in ("ENV_C1", "ENV_C2"):
        if name in prm and prm[name] != 0:
            warnings.warn(f"{name} = {prm[name]} is not modelled (its formula is unpublished); treated as 0",
                          stacklevel=3)
    if "ELLIPS_NLENGTH" not in prm.missing:
        line = prm.lines.get("ELLIPS_NLENGTH")
        where = f"{prm.source or 'parameters'}{f', line {line}' if line else ''}"
        warnings.warn(f"ELLIPS_NLENGTH = {prm.ELLIPS_NLENGTH} ({where}) is not used: its role in MF-Swift is "
                      f"unpublished; each cam's height is the exact maximum over the road profile instead",
                      stacklevel=3)


@dataclass(frozen=True)
class Cams:
    """Cam shape: semi-axes ``ae`` (horizontal), ``be`` (vertical) [m], exponent ``ce``; tandem base factor
    ``shift`` (l_s = shift 2a); ``max_step`` (ELLIPS_MAX_STEP, warn above); ``n_width`` tracks for 3D roads."""

    ae: float
    be: float
    ce: float
    shift: float
    max_step: float = np.inf
    n_width: int = 10

    @classmethod
    def from_params(cls, prm, warn: bool = True) -> "Cams":
        """Cams of a parameter set ([CONTACT_PATCH]: ELLIPS_LENGTH/HEIGHT scaled by UNLOADED_RADIUS); ``warn``:
        warn about the parameters that are not modelled (callers that build the cams twice for one model pass
        False once, so each model warns once)."""
        R0 = prm.UNLOADED_RADIUS
        if warn:
            _warn_unmodelled(prm)
        return cls(ae=prm.ELLIPS_LENGTH * R0, be=prm.ELLIPS_HEIGHT * R0, ce=prm.ELLIPS_ORDER,
                   shift=prm.ELLIPS_SHIFT, max_step=prm.ELLIPS_MAX_STEP, n_width=int(prm.ELLIPS_NWIDTH))

    def __post_init__(self):
        if not (self.ae >= 0 and self.be > 0 and self.ce > 0 and self.shift >= 0):
            raise ModelInputError(f"cam sizes must be ae >= 0, be > 0, ce > 0, shift >= 0; got {self}")
        if not (self.ae <= _CAM_LIMIT and self.be <= _CAM_LIMIT and self.shift <= _CAM_LIMIT
                and math.isfinite(self.ce)):  # 1e308: the road tables around the cams overflow
            raise ModelInputError(f"cam sizes (ELLIPS_LENGTH, ELLIPS_HEIGHT times UNLOADED_RADIUS; ELLIPS_SHIFT) must "
                                  f"be at most {_CAM_LIMIT:g} and ELLIPS_ORDER finite; got {self}")

    def contour(self, xi):
        """z_c(xi) >= 0: height of the cam contour above its lowest point (inf beyond |xi| > ae)."""
        xi = np.abs(np.asarray(xi, dtype=float))
        if self.ae == 0:
            return np.where(xi == 0, 0.0, np.inf)
        t = np.clip(xi / self.ae, 0.0, 1.0) ** self.ce
        return np.where(xi <= self.ae, self.be - self.be * (1.0 - t) ** (1.0 / self.ce), np.inf)

    def basic_length(self, height):
        """l_b: horizontal length over which the cam climbs a step of ``height`` (ae for height >= be)."""
        q = np.clip(np.abs(np.asarray(height, dtype=float)) / self.be, 0.0, 1.0)
        return self.ae * (1.0 - (1.0 - q) ** self.ce) ** (1.0 / self.ce)


def cam_height(road: Road, x, cams: Cams, *, y=0.0, dx: float = 5e-4):
    """h(x): height of the lowest point of a cam centred at ``x`` resting on ``road`` (module notes)."""
    x = np.asarray(x, dtype=float)
    shape = x.shape
    xf = x.ravel()
    lo, hi = road.height_range()
    if hi - lo > cams.max_step:
        warnings.warn(f"road height range {1e3 * (hi - lo):.1f} mm exceeds ELLIPS_MAX_STEP "
                      f"{1e3 * cams.max_step:.1f} mm: outside the range the cams were fitted for", stacklevel=2)
    window = float(cams.basic_length(hi - lo)) if hi - lo < cams.be else cams.ae
    k = int(np.ceil(window / dx))
    xi = np.clip(np.arange(-k, k + 1) * dx, -window, window) if k > 0 else np.zeros(1)
    zc = cams.contour(xi)
    bp = np.asarray(sorted(road.breakpoints), dtype=float)
    out = np.empty(xf.size)
    level = _level_windows(road, xf, window)
    out[level] = road.height(xf[level], y)  # z_c >= 0 with z_c(0) = 0: the max is the level height itself
    searched = np.flatnonzero(~level)
    for start in range(0, searched.size, _CHUNK):
        xc = xf[searched[start:start + _CHUNK]]
        h = np.max(road.height(xc[:, None] + xi[None, :], y) - zc[None, :], axis=1)
        if bp.size and window > 0:  # breakpoints inside the window, exactly
            i0 = np.searchsorted(bp, xc - window, side="left")
            i1 = np.searchsorted(bp, xc + window, side="right")
            m = int(np.max(i1 - i0)) if xc.size else 0
            if m > 0:
                idx = i0[:, None] + np.arange(m)[None, :]
                valid = idx < i1[:, None]
                xb = bp[np.minimum(idx, bp.size - 1)]
                cand = road.height(xb, y) - cams.contour(xb - xc[:, None])
                h = np.maximum(h, np.max(np.where(valid, cand, -np.inf), axis=1))
        out[searched[start:start + _CHUNK]] = h
    return out.reshape(shape)


def _level_windows(road: Road, x, window):
    """True where the whole window [x - window, x + window] lies inside one of the road's level spans, with
    ``_LEVEL_MARGIN`` to spare (so that rounding in x + xi cannot reach the span's edge)."""
    spans = np.asarray(road.level_spans(), dtype=float).reshape(-1, 2)
    if not spans.size:
        return np.zeros(x.shape, dtype=bool)
    j = np.maximum(np.searchsorted(spans[:, 0], x - window, side="right") - 1, 0)
    return (x - window > spans[j, 0] + _LEVEL_MARGIN) & (x + window < spans[j, 1] - _LEVEL_MARGIN)


@dataclass(frozen=True)
class CamTable:
    """Cam heights h on the uniform grid ``x0 + i dx`` (load independent: computed once per road and cam shape),
    linearly interpolated; the road input of the rigid-ring simulation (:mod:`swift.simulate`).

    For roads that vary across y (``Road.varies_with_y``) the table holds the multi-track cams: ``h`` is the mean
    cam height of ``n_width`` tracks spread over y in [-half_width, half_width] and ``camber`` the least-squares
    slope of the track heights over y, so that the tandem's mean height, slope and road camber
    beta_x = atan((camber_f + camber_r)/2) (:func:`effective_road_3d`, with the slope of the mean heights) come from
    two interpolations; 2D roads have ``camber`` = 0."""

    x0: float
    dx: float
    h: np.ndarray
    camber: np.ndarray | None = None

    @classmethod
    def build(cls, road: Road, cams: Cams, x_start: float, x_end: float, dx: float = 1e-3, y: float = 0.0,
              half_width: float | None = None):
        """Table from ``x_start`` to ``x_end``; ``half_width`` [m] (3D roads: the tracks' half spread, normally the
        contact half width b at the nominal load) is required when ``road.varies_with_y``."""
        if not x_end > x_start:
            raise ModelInputError(f"x_end ({x_end}) must exceed x_start ({x_start})")
        if not (abs(x_start) <= MAX_DISTANCE and abs(x_end) <= MAX_DISTANCE):
            raise ModelInputError(f"the table's range {x_start!r}..{x_end!r} m: expected positions within "
                                  f"+-{MAX_DISTANCE:g} m")
        check_road(road)
        n = int(np.ceil((x_end - x_start) / dx)) + 1
        grid = x_start + dx * np.arange(n)
        if not road.varies_with_y:
            return cls(float(x_start), float(dx), cam_height(road, grid, cams, y=y, dx=min(dx, 5e-4)), np.zeros(n))
        if half_width is None or not half_width > 0 or cams.n_width < 2:
            raise ModelInputError("a road that varies across y needs half_width > 0 and ELLIPS_NWIDTH >= 2 tracks")
        ys = y + np.linspace(-half_width, half_width, cams.n_width)
        h = np.array([cam_height(road, grid, cams, y=yj, dx=min(dx, 5e-4)) for yj in ys])
        yc = ys - ys.mean()
        return cls(float(x_start), float(dx), h.mean(axis=0), np.tensordot(yc, h, axes=1) / np.sum(yc**2))

    @property
    def x(self):
        return self.x0 + self.dx * np.arange(self.h.size)

    def __call__(self, x):
        return np.interp(x, self.x, self.h)


def tandem_base(prm, fz, dpi, be=NUMPY):
    """l_s = ELLIPS_SHIFT * 2a(Fz, p): distance between the cams (Zegelaar eq. 4.15; a from paper (9))."""
    a, _ = vertical.contact_patch(prm, fz, dpi, be)
    return prm.ELLIPS_SHIFT * 2.0 * a


@dataclass
class EffectiveRoad:
    """Effective road inputs along x: height ``w`` [m], forward slope ``beta`` [rad] (> 0 rising ahead),
    ``curvature`` [1/m]; ``h_front``/``h_rear`` cam heights; ``beta_x`` road camber [rad] (3D only, else 0)."""

    x: np.ndarray
    w: np.ndarray
    beta: np.ndarray
    curvature: np.ndarray
    h_front: np.ndarray
    h_rear: np.ndarray
    beta_x: np.ndarray | float = 0.0


def _tandem(heights, x, ls):
    hf, hr = heights(x + ls / 2), heights(x - ls / 2)
    safe = np.where(ls > 0, ls, 1.0)
    return hf, hr, np.where(ls > 0, np.arctan((hf - hr) / safe), 0.0)


def effective_road(road: Road, x, ls, cams: Cams, *, y=0.0, dx: float = 5e-4) -> EffectiveRoad:
    """Effective height, slope and curvature at wheel positions ``x`` for tandem base(s) ``ls`` [m]."""
    x, ls = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(ls, dtype=float))

    def heights(xq):
        return cam_height(road, xq, cams, y=y, dx=dx)

    hf, hr, beta = _tandem(heights, x, ls)
    d = CURVATURE_STEP
    curvature = (_tandem(heights, x + d, ls)[2] - _tandem(heights, x - d, ls)[2]) / (2 * d)
    return EffectiveRoad(x, (hf + hr) / 2, beta, curvature, hf, hr)


def effective_road_3d(road: Road, x, ls, half_width, cams: Cams, *, dx: float = 5e-4) -> EffectiveRoad:
    """Multi-track tandems (``cams.n_width`` tracks over y in [-half_width, half_width]): mean w, beta_y and
    curvature over the tracks, and road camber beta_x from the least-squares slope of w_j over y_j."""
    if cams.n_width < 2:
        raise ModelInputError("road camber needs at least 2 tracks (ELLIPS_NWIDTH >= 2)")
    ys = np.linspace(-half_width, half_width, cams.n_width)
    tracks = [effective_road(road, x, ls, cams, y=yj, dx=dx) for yj in ys]
    w = np.array([t.w for t in tracks])
    yc = ys - ys.mean()
    slope = np.tensordot(yc, w - w.mean(axis=0), axes=1) / np.sum(yc**2)
    mean = lambda name: np.mean([getattr(t, name) for t in tracks], axis=0)  # noqa: E731
    return EffectiveRoad(tracks[0].x, w.mean(axis=0), mean("beta"), mean("curvature"), mean("h_front"),
                         mean("h_rear"), np.arctan(slope))


@dataclass
class QuasiStatic:
    """Quasi-static rolling over a profile: wheel-centre forces ``fx``, ``fz`` [N] (ISO-W: fz > 0 up on the
    wheel), normal force ``fz_normal`` [N], axle height change ``dz`` [m] (0 at fixed axle height), deflection
    ``rho`` [m], tandem base ``ls`` [m] and the effective road ``road``."""

    x: np.ndarray
    fx: np.ndarray
    fz: np.ndarray
    fz_normal: np.ndarray
    dz: np.ndarray
    rho: np.ndarray
    ls: np.ndarray
    road: EffectiveRoad


def _bisect(fun, lo, hi, steps):
    """Bisection of the increasing-or-decreasing sign of ``fun`` between the arrays ``lo`` and ``hi`` (fun(lo) and
    fun(hi) of opposite signs, or either zero), ``steps`` halvings; returns the midpoints."""
    f_lo = fun(lo)
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        f_mid = fun(mid)
        left = np.sign(f_mid) == np.sign(f_lo)
        lo, f_lo = np.where(left, mid, lo), np.where(left, f_mid, f_lo)
        hi = np.where(left, hi, mid)
    return 0.5 * (lo + hi)


def quasi_static(model, road: Road, x, fz0: float, *, p: float | None = None, mode: str = "fixed_axle",
                 dx: float = 5e-4, iterations: int = 40, table_step: float = 1e-4, tol: float = 1e-5) \
        -> QuasiStatic:
    """The tyre rolling slowly over ``road`` at wheel positions ``x`` (visited in the given order).

    ``mode="fixed_axle"``: axle height fixed where the flat road at the height of ``x[0]`` carries ``fz0``;
    ``mode="constant_load"``: the vertical wheel-centre force stays ``fz0`` and the axle follows.

    The tandem is centred under the wheel centre (the cams move only vertically, module notes); the contact load
    F'_z and the tandem base l_s = ELLIPS_SHIFT 2a(F'_z) depend on each other. Solved as a bracketed problem in
    F'_z: the load residual F'(F) - F changes sign between F = 0 and the load at the deepest possible deflection,
    so a root always exists; every sign change on a grid of loads is refined by bisection (``iterations``
    halvings) and, at each x, the root nearest the previous point's load is taken (continuation along x, as a tyre
    creeping forward follows its branch; with the cams under the centre there is one root on the obstacles tried).
    Cam heights from a table at ``table_step`` (cam heights exact at ``dx`` resolution, linear between); raises
    :class:`ModelInputError` if the load residual exceeds ``tol`` relative to ``fz0``.
    """
    if mode not in ("fixed_axle", "constant_load"):
        raise ModelInputError(f"mode must be 'fixed_axle' or 'constant_load', got {mode!r}")
    if not iterations >= 30:
        raise ModelInputError(f"iterations (bisection halvings) must be >= 30 for a converged solution, got "
                              f"{iterations}")
    prm = model.params
    p = prm.INFLPRES if p is None else float(p)
    dpi = vertical.pressure_increment(prm, p)
    cams = Cams.from_params(prm)
    x = np.asarray(x, dtype=float)
    shape, xs = x.shape, x.ravel()
    rl0, _ = model.loaded_radius(fz0, p=p)
    r_omega = float(vertical.free_radius(prm, 0.0, NUMPY))
    z_axle = float(road.height(xs[0])) + float(rl0)
    hi_road = road.height_range()[1]
    if mode == "fixed_axle":  # the deepest deflection: the plane cannot rise above the highest road point
        f_max = float(model.vertical_force(min(z_axle - hi_road, r_omega), p=p))
    else:
        f_max = float(fz0) / np.cos(np.radians(80.0))
    reach = float(tandem_base(prm, f_max, dpi)) / 2
    x0 = xs.min() - reach - 2 * table_step
    samples = x0 + table_step * np.arange(int(np.ceil((xs.max() - xs.min() + 2 * reach) / table_step)) + 5)
    table = CamTable(float(x0), float(table_step), cam_height(road, samples, cams, dx=min(dx, 5e-4)))

    def load(xw, f):  # (load of the plane of the tandem at the base l_s(f) under xw, distance d, w, beta)
        ls = tandem_base(prm, f, dpi)
        hf, hr = table(xw + ls / 2), table(xw - ls / 2)
        w, beta = (hf + hr) / 2, np.arctan((hf - hr) / np.maximum(ls, 1e-9))
        cosb = np.cos(beta)
        if mode == "fixed_axle":  # normal distance of the axle from the plane through (xw, w)
            d = np.minimum((z_axle - w) * cosb, r_omega)
            return np.maximum(model.vertical_force(d, p=p), 0.0), d, w, beta
        return fz0 / cosb, model.loaded_radius(f, p=p)[0], w, beta

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the vertical relation's range warnings on the trial loads
        grid = np.linspace(0.0, f_max, 161)
        r = load(xs[:, None] + 0 * grid, grid[None, :] + 0 * xs[:, None])[0] - grid
        change = np.sign(r[:, :-1]) != np.sign(r[:, 1:])
        change[:, -1] |= r[:, -1] == 0.0
        roots = np.full((xs.size, 4), np.nan)
        for k in range(roots.shape[1]):  # up to four roots per position, in order of load
            first = np.argmax(change, axis=1)
            has = change[np.arange(xs.size), first]
            if not has.any():
                break
            f_root = _bisect(lambda f: load(xs, f)[0] - f, grid[first], grid[first + 1], iterations)
            roots[has, k] = f_root[has]
            change[np.arange(xs.size), first] = False
        f = np.empty(xs.size)
        for i in range(xs.size):  # continuation: the root nearest the previous load
            f[i] = roots[i, np.nanargmin(np.abs(roots[i] - (f[i - 1] if i else fz0)))]
        ls = tandem_base(prm, f, dpi)
        fzn, d, w, beta = load(xs, f)
    bad = np.abs(fzn - f) / max(fz0, 1.0)
    if np.any(bad > tol):
        i = int(np.argmax(bad))
        raise ModelInputError(f"quasi-static contact solution did not converge at x = {xs[i]:.4f} m: load residual "
                              f"{fzn[i] - f[i]:.3g} N")
    eff = effective_road(road, xs, ls, cams, dx=dx)
    cosb = np.cos(beta)
    dz = np.zeros_like(xs) if mode == "fixed_axle" else w + d / cosb - z_axle
    rs = lambda a: np.reshape(a, shape)  # noqa: E731
    return QuasiStatic(x, rs(-f * np.sin(beta)), rs(f * cosb), rs(f), rs(dz), rs(r_omega - d), rs(ls), eff)
