"""The fitting stages: which data, which measured channel, which parameters, in the order test engineers
use (pure Fx, pure Fy, Mz, combined Fx and Fy, combined Mz, Mx, My, vertical, effective rolling radius).

Every parameter named here is a schema parameter (:data:`mftyre.params.PARAMETERS`) whose schema ``stage`` is
this stage (checked when the module loads). A parameter group is fitted only when the stage's
data can determine it (``needs``):

* ``loads``: two or more load levels (load-variation terms, dfz); ``loads3``: three or more (dfz^2,
  exponents, curvature of the load dependency);
* ``camber``: an inclination other than zero; ``camber2``: two or more distinct non-zero |inclinations| (the
  second-order camber terms in gamma|gamma| or gamma^2 whose first-order partner of the same parity, gamma or
  |gamma|, would be indistinguishable from them with one |gamma| level); ``pressure``: two or more pressures and
  ``fit_pressure``
  (the dpi terms); ``pressure3``: three or more pressures (dpi^2 terms);
* ``speeds`` / ``speeds3``: two / three speed levels; ``fx`` / ``fy``: a non-zero longitudinal / lateral force;
* ``kappa_sides`` / ``alpha_sides``: slip ratio (beyond +-0.01) / slip angle (beyond +-1 deg) of both signs: the
  shifts and the asymmetric curvature terms (PHX*, PVX*, PEX4; PHY*, PVY*, PEY3; QHZ*, QEZ4) act across zero
  slip, so data of one sign (a drive/brake run at alpha 0, -3, -6 deg) cannot tell them from the curve's
  shape; held at their start (neutral) values they add no asymmetry where there are no data.

Each stage is fitted in passes, as on the test bench: the base parameters on the data at zero camber and
nominal pressure, then the pressure terms added with all pressures, then the camber terms with all data.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..backend import NUMPY
from ..data import TyreData, levels
from ..formula import aligning, lateral, longitudinal, vertical
from ..params import PARAMETERS
from ..programme import cluster_levels

__all__ = ["Stage", "STAGES", "STAGE_NAMES", "conditions", "stage_parameters", "shape_violations", "data_corners",
           "supported_parameters"]

_KAPPA_TOL = 0.005
_ALPHA_TOL = math.radians(0.25)
_CAMBER_TOL = math.radians(0.25)


@dataclass(frozen=True)
class Stage:
    name: str
    title: str
    channel: str            # measured channel
    output: str             # model output compared with it ("fz_from_rl": the vertical-force relation)
    rows: str               # "pure_lateral", "pure_longitudinal", "combined", "free_rolling", "all_rl", ...
    groups: tuple           # ((needs tuple, parameter names tuple), ...)


def _g(needs, names):
    return (tuple(needs.split()) if needs else (), tuple(names.split()))


STAGES: dict[str, Stage] = {s.name: s for s in (
    Stage("pure_fx", "Pure longitudinal force Fx0 (4.E9-4.E18)", "FX", "fx", "pure_longitudinal", (
        _g("", "PCX1 PDX1 PEX1 PKX1"), _g("kappa_sides", "PEX4 PHX1 PVX1"),
        _g("loads", "PDX2 PEX2 PKX2"), _g("loads kappa_sides", "PHX2 PVX2"), _g("loads3", "PEX3 PKX3"),
        _g("camber", "PDX3"), _g("pressure", "PPX1 PPX3"), _g("pressure3", "PPX2 PPX4"))),
    Stage("pure_fy", "Pure lateral force Fy0 (4.E19-4.E30)", "FY", "fy", "pure_lateral", (
        _g("", "PCY1 PDY1 PEY1 PKY1"), _g("alpha_sides", "PEY3 PHY1 PVY1"),
        _g("loads", "PDY2 PEY2 PKY2"), _g("loads alpha_sides", "PHY2 PVY2"), _g("loads3", "PKY4"),
        _g("camber", "PDY3 PEY4 PEY5 PKY3 PKY6 PVY3"), _g("camber2", "PKY5"), _g("camber loads", "PKY7 PVY4"),
        _g("pressure", "PPY1 PPY3"), _g("pressure loads", "PPY2"), _g("pressure3", "PPY4"),
        _g("pressure camber", "PPY5"))),
    Stage("mz", "Pure aligning moment Mz0 (4.E31-4.E49)", "MZ", "mz", "pure_lateral", (
        _g("", "QBZ1 QCZ1 QDZ1 QEZ1 QDZ6 QBZ9"), _g("alpha_sides", "QEZ4 QHZ1"),
        _g("loads", "QBZ2 QDZ2 QEZ2 QDZ7"), _g("loads alpha_sides", "QHZ2"), _g("loads3", "QBZ3 QEZ3"),
        _g("camber", "QBZ4 QBZ5 QDZ3 QDZ4 QEZ5 QHZ3 QDZ8"), _g("camber2", "QDZ10"),
        _g("camber loads", "QHZ4 QDZ9"), _g("camber2 loads", "QDZ11"),
        _g("pressure", "PPZ1"), _g("pressure camber", "PPZ2"))),
    Stage("combined_fx", "Combined-slip Fx (4.E50-4.E57)", "FX", "fx", "combined", (
        _g("", "RBX1 RBX2 RCX1 REX1 RHX1"), _g("loads", "REX2"), _g("camber", "RBX3"))),
    Stage("combined_fy", "Combined-slip Fy (4.E58-4.E67)", "FY", "fy", "with_kappa", (
        _g("", "RBY1 RBY2 RBY3 RCY1 REY1 RHY1 RVY1 RVY4 RVY5 RVY6"), _g("loads", "REY2 RHY2 RVY2"),
        _g("camber", "RBY4 RVY3"))),
    Stage("mz_combined", "Combined-slip Mz: moment arm of Fx (paper A56)", "MZ", "mz", "slip", (
        _g("", "SSZ1 SSZ2"), _g("camber", "SSZ3"), _g("camber loads", "SSZ4"))),
    Stage("mx", "Overturning moment Mx (4.E69, MF-Tyre 6.1 form)", "MX", "mx", "slip", (
        _g("fy", "QSX1 QSX3"), _g("camber", "QSX2"), _g("camber loads", "QSX10 QSX11"),
        _g("pressure camber", "PPMX1"))),
    Stage("my", "Rolling-resistance moment My (paper A48)", "MY", "my", "free_rolling", (
        _g("", "QSY1"), _g("speeds", "QSY3"), _g("speeds3", "QSY4"), _g("loads", "QSY7"), _g("camber", "QSY5"),
        _g("camber loads", "QSY6"), _g("pressure", "QSY8"))),
    Stage("vertical", "Vertical load vs deflection and loaded radius (A3.3, paper (3)-(5)); RL, or RHO without RL",
          "FZ", "fz_from_rl",
          "all_rl", (
              _g("", "VERTICAL_STIFFNESS Q_FZ2 Q_RE0"), _g("pressure", "PFZ1"), _g("speeds", "Q_V1 Q_V2"),
              _g("fx", "Q_FCX"), _g("fy", "Q_FCY"))),
    Stage("rolling_radius", "Effective rolling radius Re (paper (7))", "RE", "re", "free_rolling_re", (
        _g("loads", "BREFF DREFF FREFF"),)),
)}
STAGE_NAMES: tuple[str, ...] = tuple(STAGES)
_MISPLACED = [f"{n} (in stage {s.name})" for s in STAGES.values() for _, names in s.groups for n in names
              if n not in PARAMETERS or PARAMETERS[n].stage != s.name]
if _MISPLACED:  # pragma: no cover - guards the table: the schema's stage (mftyre.params.STAGE_MEMBERS) must agree
    raise RuntimeError(f"stage parameters not of that stage in the schema: {_MISPLACED}")


def combined_fy(results) -> bool:
    """Whether the combined-slip Fy stage is among the fitted stage ``results`` (so Mx may use combined slip)."""
    return "combined_fy" in results and bool(results["combined_fy"].fitted)


def stage_rows(stage: Stage, data: TyreData, combined_fy: bool = True) -> np.ndarray:
    """Boolean mask of the rows a stage fits (by the slip values; the measured channel must be finite).
    ``combined_fy=False`` (the combined-slip Fy not fitted): Mx, which follows the model's Fy, only where that Fy
    is the pure-slip one (no slip ratio); on combined-slip rows the Mx stage would make up for an Fy it does not
    describe (on a pooled drive/brake run: Fy 39-48 N RMS off, Mx 2x the repeatability floor)."""
    sl, sa = np.abs(data.array("SL")), np.abs(data.array("SA"))
    pure_kappa, pure_alpha = sl <= _KAPPA_TOL, sa <= _ALPHA_TOL
    kind = stage.rows
    if kind == "pure_lateral":
        mask = pure_kappa & ~pure_alpha
    elif kind == "pure_longitudinal":
        mask = pure_alpha & ~pure_kappa
    elif kind == "combined":
        mask = ~pure_alpha & ~pure_kappa
    elif kind == "with_kappa":  # kappa-induced Fy (SVyk) is largest at alpha = 0: pure-kappa rows too
        mask = ~pure_kappa
    elif kind == "slip":
        mask = ~(pure_alpha & pure_kappa)
        if stage.name == "mx" and not combined_fy:
            mask &= pure_kappa
    elif kind in ("free_rolling", "free_rolling_re"):
        mask = pure_alpha & pure_kappa
    elif kind == "all_rl":  # the loaded radius, or else the deflection, measured
        ch = "RL" if data.has("RL") else "RHO"
        if not data.has(ch):
            return np.zeros(len(data), bool)
        mask = np.isfinite(data.array(ch))
    else:  # pragma: no cover - guards the table
        raise ValueError(kind)
    if stage.channel not in data:
        return np.zeros(len(data), bool)
    return mask & np.isfinite(data.array(stage.channel))


def level_labels(data: TyreData, channel: str) -> np.ndarray:
    """Level index per row of a condition channel: the recognised programme's (column ``<channel>_LEVEL``, see
    :func:`mftyre.programme.recognise`) when present, else :func:`mftyre.programme.cluster_levels` of the
    values; -1 off-level."""
    col = f"{channel}_LEVEL"
    if col in data:
        return np.round(data.frame[col].to_numpy(float)).astype(int)
    return cluster_levels(data.array(channel))[0]


def _count(data: TyreData, channel: str, width: float) -> int:
    """Number of distinct values of a condition channel: its levels plus, when at least 10 values (and 1 %) are
    on no level (the channel is swept somewhere, or held at settings too brief to count as levels), the
    occupied bins of ``width`` among those."""
    labels = level_labels(data, channel)
    off = labels < 0
    n = len(np.unique(labels[~off]))
    if off.sum() >= max(10, 0.01 * labels.size):
        n += len(np.unique(np.round(data.array(channel)[off] / width)))
    return n


def _count_levels(x: np.ndarray, width: float) -> int:
    """Number of distinct values of a condition channel: its levels (:func:`mftyre.programme.cluster_levels`),
    levels less than ``width`` apart counted as one (a speed held at 16.7 +- 0.02 m/s and recorded to 0.01 m/s
    holds each recorded value many times over, which the clustering reads as a dozen exact settings: one speed),
    plus, when at least 10 values (and 1 %) are on no
    level (the channel is swept somewhere, or held at settings too brief to count as levels), the occupied bins
    of ``width`` among those."""
    labels, centres = cluster_levels(x)
    distinct = 1 + int(np.count_nonzero(np.diff(np.sort(centres)) >= width)) if centres.size else 0
    off = labels < 0
    if off.sum() >= max(10, 0.01 * x.size):
        return distinct + len(np.unique(np.round(x[off] / width)))
    return distinct


def conditions(data: TyreData) -> dict:
    """Number of load, pressure and speed levels, camber present, Fx/Fy present, of a data subset. Levels are
    clusters separated by empty room (:func:`mftyre.programme.cluster_levels`), not by a fraction of the
    largest value; a swept speed counts its 1 m/s bins."""
    if len(data) == 0:
        return dict(loads=0, pressures=0, speeds=0, camber=False, camber_levels=0, fx=False, fy=False,
                    kappa_sides=False, alpha_sides=False)
    fz = data.array("FZ")
    sl, sa = data.array("SL"), data.array("SA")
    return dict(
        loads=_count(data, "FZ", 0.05 * float(np.median(np.abs(fz))) + 1e-9),
        pressures=_count(data, "P", 0.02 * float(np.median(data.array("P")))),
        speeds=_count_levels(data.array("VX"), 1.0),
        camber=bool(np.any(np.abs(data.array("IA")) > _CAMBER_TOL)),
        camber_levels=_nonzero_camber_levels(data.array("IA")),
        fx=bool(data.has("FX") and np.nanmax(np.abs(data.array("FX"))) > 0.05 * float(np.max(fz))),
        fy=bool(data.has("FY") and np.nanmax(np.abs(data.array("FY"))) > 0.05 * float(np.max(fz))),
        kappa_sides=bool(np.any(sl >= _SIDE_KAPPA) and np.any(sl <= -_SIDE_KAPPA)),
        alpha_sides=bool(np.any(sa >= _SIDE_ALPHA) and np.any(sa <= -_SIDE_ALPHA)),
    )


#: the slip beyond which data count as measured on that side of zero (conditions' kappa_sides, alpha_sides)
_SIDE_KAPPA, _SIDE_ALPHA = 0.01, math.radians(1.0)


# the channel each stage's characteristic runs along, and the bin width that makes two values distinct
_ALONG = {"pure_fx": ("SL", 0.005), "combined_fx": ("SL", 0.005), "combined_fy": ("SL", 0.005),
          "mz_combined": ("SL", 0.005), "pure_fy": ("SA", math.radians(0.5)), "mz": ("SA", math.radians(0.5)),
          "mx": ("SA", math.radians(0.5)), "my": ("VX", 1.0), "rolling_radius": ("VX", 1.0), "vertical": ("FZ", 1.0)}
#: the leading letters (after P or Q) of the terms a characteristic measured at fewer than 5 distinct slip values
#: can determine: slope and shifts (pure Fx, Fy; PPX1/2, PPY1/2 scale the slope), trail and residual torque (Mz)
_SLOPE_TERMS = {"pure_fx": ("PK", "PH", "PV", "PPX1", "PPX2"), "pure_fy": ("PK", "PH", "PV", "PPY1", "PPY2"),
                "mz": ("QD", "QH", "PPZ")}


def supported_parameters(stage: Stage, groups: dict, data: TyreData):
    """(groups, {dropped: reason}): never more parameters than the distinct conditions support.

    A distinct condition is a cell (load level, pressure level, camber level, bin of the channel the
    characteristic runs along: slip 0.005, slip angle 0.5 deg, speed 1 m/s, load 1 N); at most one
    parameter per two cells is freed, the last groups of the stage's list (the highest-order terms) dropped
    first. A pure-slip characteristic measured at fewer than 5 distinct slip values per condition determines
    only its slope and shifts (and Mz its trail): the shape and peak terms are dropped."""
    names = [n for kind in ("base", "pressure", "camber") for n in groups[kind]]
    if not names or len(data) == 0:
        return groups, {}
    along, width = _ALONG[stage.name]
    x = data.array(along) if along in data else np.zeros(len(data))
    keys = [level_labels(data, ch) for ch in ("FZ", "P", "IA")]
    cond = np.stack(keys, axis=1)
    cells = np.column_stack([cond, np.round(np.nan_to_num(x) / width).astype(np.int64)])
    support = len(np.unique(cells, axis=0))
    per_condition = [len(np.unique(cells[np.all(cond == c, axis=1), 3])) for c in np.unique(cond, axis=0)]
    n_along = int(np.median(per_condition))
    dropped = {}
    if stage.name in _SLOPE_TERMS and n_along < 5:
        keep = _SLOPE_TERMS[stage.name]
        for n in names:
            if not n.startswith(keep):
                dropped[n] = (f"only {n_along} distinct {'slip' if along == 'SL' else 'slip-angle'} value(s) per "
                              "condition: the shape and peak are not measured")
    order = [n for _, group in stage.groups for n in group if n in names and n not in dropped]
    cap = max(support // 2, 1)
    for n in reversed(order[cap:]):
        dropped[n] = f"{support} distinct conditions support at most {cap} parameters"
    out = {kind: [n for n in groups[kind] if n not in dropped] for kind in groups}
    return out, dropped


def _nonzero_camber_levels(gamma) -> int:
    magnitude = np.abs(np.asarray(gamma, dtype=float))
    magnitude = magnitude[magnitude > _CAMBER_TOL]
    return len(levels(magnitude, _CAMBER_TOL)[1]) if magnitude.size else 0


def need_met(need: str, cond: dict, fit_pressure: bool) -> bool:
    return {
        "loads": cond["loads"] >= 2, "loads3": cond["loads"] >= 3, "camber": cond["camber"],
        "camber2": cond["camber_levels"] >= 2,
        "pressure": fit_pressure and cond["pressures"] >= 2, "pressure3": fit_pressure and cond["pressures"] >= 3,
        "speeds": cond["speeds"] >= 2, "speeds3": cond["speeds"] >= 3, "fx": cond["fx"], "fy": cond["fy"],
        "kappa_sides": cond["kappa_sides"], "alpha_sides": cond["alpha_sides"],
    }[need]


SKIP_REASONS = {"loads": "one load level only", "loads3": "fewer than three load levels", "camber": "no camber in the data",
            "camber2": "fewer than two non-zero camber magnitudes (collinear with the first-order camber term)",
            "pressure": "one pressure only (or fit_pressure=False)", "pressure3": "fewer than three pressures "
            "(or fit_pressure=False)", "speeds": "one speed only", "speeds3": "fewer than three speeds",
            "fx": "no longitudinal force in the data", "fy": "no lateral force in the data",
            "kappa_sides": "longitudinal slip of one sign only: the Fx shifts and driving/braking asymmetry act "
                           "across kappa = 0",
            "alpha_sides": "slip angle of one sign only: the shifts and asymmetry of Fy and Mz act across "
                           "alpha = 0"}


def stage_parameters(stage: Stage, cond: dict, fit_pressure: bool):
    """(fitted parameter names grouped by pass kind, {skipped name: reason}).

    Pass kinds: "base" (no camber or pressure term), "pressure" (needs pressure, no camber), "camber" (the rest).
    """
    passes = {"base": [], "pressure": [], "camber": []}
    skipped = {}
    for needs, names in stage.groups:
        unmet = [n for n in needs if not need_met(n, cond, fit_pressure)]
        if unmet:
            skipped.update({n: SKIP_REASONS[unmet[0]] for n in names})
            continue
        kind = "camber" if any(n.startswith("camber") for n in needs) else ("pressure" if any(n.startswith("pressure") for n in needs)
                                                    else "base")
        passes[kind].extend(names)
    return passes, skipped


# ------------------------------------------------------------------------------------- shape checks
def data_corners(data: TyreData, prm) -> dict:
    """The corners of the data's range where :func:`shape_violations` checks: (dfz, dpi, gamma) arrays over the
    lowest and highest load and pressure and the lowest, zero and highest inclination."""
    fz, p, g = data.array("FZ"), data.array("P"), data.array("IA")
    fz0 = prm.FNOMIN * prm.LFZO
    grid = np.array(np.meshgrid([fz.min(), fz.max()], [p.min(), p.max()], [g.min(), 0.0, g.max()])).reshape(3, -1)
    return dict(dfz=(grid[0] - fz0) / fz0, dpi=vertical.pressure_increment(prm, grid[1]), gamma=grid[2])


def shape_violations(stage_name: str, prm, corners: dict) -> np.ndarray:
    """Amounts by which the Magic Formula shape conditions C > 0, D > 0, E <= 1 (and positive slip
    stiffness, trail and weighting slopes) are violated at the corners of the data range (``corners``:
    arrays dfz, dpi, gamma); all zeros when they hold. The factors are the formula's coefficient functions
    (4.E13-4.E15, 4.E23-4.E25, paper A58, A60, 4.E44, 4.E54-4.E56, 4.E62-4.E64) without the scale factors, at
    gamma* = gamma."""
    dfz, dpi, g = corners["dfz"], corners["dpi"], corners["gamma"]
    g2, dfz2, dpi2 = g**2, dfz**2, dpi**2
    checks = []
    if stage_name == "pure_fx":
        mux = longitudinal.friction_x(prm, dfz, dpi, dpi2, g2)
        kxk = longitudinal.slip_stiffness_x(prm, 1.0, dfz, dpi, dpi2, NUMPY)
        # Ex at both signs of kappa_x, the larger (1 + |PEX4|) first
        ex = [longitudinal.curvature_x(prm, dfz, dfz2, sign) for sign in (-np.sign(prm.PEX4), np.sign(prm.PEX4))]
        checks += [prm.PCX1, mux, kxk, 1 - ex[0], 1 - ex[1]]
    elif stage_name == "pure_fy":
        muy = lateral.friction_y(prm, dfz, dpi, dpi2, g2)
        for sign in (-1.0, 1.0):
            checks.append(1 - lateral.curvature_y(prm, dfz, g, g2, sign))
        checks += [prm.PCY1, muy, lateral.cornering_peak_load(prm, g2, dpi),
                   lateral.cornering_pressure_factor(prm, dpi)]
    elif stage_name == "mz":
        dt = aligning.peak_trail(prm, dfz, dpi, g, g2)
        bt = aligning.trail_slope(prm, dfz, dfz2, g, np.abs(g))
        # Et at the ends of the atan factor, the larger first
        bend = np.sign(prm.QEZ4 + prm.QEZ5 * g) * (np.pi / 2)
        et = [aligning.trail_curvature(prm, dfz, dfz2, g, b, NUMPY) for b in (bend, -bend)]
        checks += [prm.QCZ1, dt, bt, 1 - et[0], 1 - et[1]]
    elif stage_name == "combined_fx":
        checks += [prm.RCX1, longitudinal.combined_slope_x(prm, g2), 1 - longitudinal.combined_curvature_x(prm, dfz)]
    elif stage_name == "combined_fy":
        checks += [prm.RCY1, lateral.combined_slope_y(prm, g2), 1 - lateral.combined_curvature_y(prm, dfz)]
    values = np.concatenate([np.ravel(np.asarray(c, dtype=float)) for c in checks]) if checks else np.zeros(0)
    return np.minimum(values, 0.0)
