"""Evaluation modes: which optional parts of the model are switched on."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Modes", "TURN_SLIP_FORMS", "SMOOTH_LIMITS_SLOPE", "SMOOTH_LIMITS_MARGIN"]

#: With ``limits="smooth"``, the share of an input's change far beyond its .tir range that still reaches the
#: equations.
SMOOTH_LIMITS_SLOPE = 0.01
#: With ``limits="smooth"``, the width (a share of the range, of FZMAX for Fz) over which the slope beyond a bound
#: falls from 1 to SMOOTH_LIMITS_SLOPE: the input used goes at most about this far beyond the range (plus 1 % of
#: the excursion).
SMOOTH_LIMITS_MARGIN = 0.01

#: Forms of the turn-slip equations (see :mod:`mftyre.formula.turnslip`):
#: "published": Pacejka (2012) as printed: the spin (4.76) with its leading minus sign, K_zgamma,r0 (4.99),
#:              the residual spin torque D_rphi driven by the spin phi; the trail's F'y at gamma = phi = 0;
#:              singularity protection Vc' >= VXLOW.
#: "mfeval":    the reference evaluator MFeval 4.3.1: (4.76) without the minus sign, K_zgamma,r0 =
#:              Fz R0 (QDZ8 QDZ9 dfz + QDZ10 + QDZ11 dfz |gamma|) LKZC, D_rphi driven by the turn slip phit,
#:              the trail's F'y with S_Hyphi,
#:              Vc' = VXLOW sign(Vx) below VXLOW, and Cr = (2/pi) acos(Mz90/|D_rphi|) (4.104) complex where the
#:              ratio leaves [-1, 1] (MATLAB's acos), Mzr its real part (see mftyre.formula.aligning).
TURN_SLIP_FORMS = ("published", "mfeval")


@dataclass(frozen=True)
class Modes:
    """Switches of one evaluation.

    limits:     True: saturate the inputs to the .tir ranges, low-speed model below VXLOW, cap the curvature
                factors E at 1 (the reference evaluator's use mode 1xx). The saturation makes every derivative
                with respect to a saturated input exactly zero beyond its range (and a load Fz <= 0 gives zero
                forces and zero derivatives: the wheel has left the road).
                At a bound itself the slope is the full one from inside (one-sided).
                "smooth", for optimisers (decision variables such as the pressure bounded by PRESMIN..PRESMAX):
                the identity inside the ranges, as True, and beyond a bound a soft saturation, twice continuously
                differentiable at the bound: at a distance d beyond it the input used is the bound plus
                (1 - s) m tanh(d/m) + s d (s = SMOOTH_LIMITS_SLOPE = 1 %, m = SMOOTH_LIMITS_MARGIN = 1 % of the
                range, of FZMAX for Fz). A point a hair outside (an interior-point solver's bound relaxation)
                sees the full slope, so an optimum at a bound gets its true multiplier, and far outside 1 % of
                the slope still points back into the range (outputs beyond the ranges differ from True).
                False: the equations at the inputs as given (use mode 2xx).
    alpha_star: alpha* = tan(alpha) sign(Vx), gamma* = sin(gamma) (4.E3, 4.E4); otherwise alpha* = alpha.
    turn_slip:  turn slip and camber spin through the zeta factors (4.76-4.106).
    turn_slip_form: "published" or "mfeval", see :data:`TURN_SLIP_FORMS`.
    low_speed:  with limits, the low-speed model below VXLOW; False: the caller keeps |Vx| >= VXLOW (SWIFT's slip
                model at max(|V|, VXLOW)), where its factors are 1, and a symbolic graph leaves it out.
    """

    limits: bool = True
    alpha_star: bool = False
    turn_slip: bool = False
    turn_slip_form: str = "published"
    low_speed: bool = True

    def __post_init__(self):
        if self.limits not in (True, False, "smooth"):
            raise ValueError(f"limits must be True, False or 'smooth', got {self.limits!r}")
        if self.turn_slip_form not in TURN_SLIP_FORMS:
            raise ValueError(f"turn_slip_form must be one of {TURN_SLIP_FORMS}, got {self.turn_slip_form!r}")

    @classmethod
    def from_use_mode(cls, use_mode: int, turn_slip_form: str = "published") -> "Modes":
        """The reference evaluator's three-digit use mode: hundreds 1/2 = limits on/off, tens 1/2 = alpha*
        off/on, units 1/2 = turn slip off/on."""
        digits = str(int(use_mode))
        if len(digits) != 3 or any(d not in "12" for d in digits):
            raise ValueError(f"use mode must have three digits, each 1 or 2 (e.g. 111, 212); got {use_mode!r}")
        return cls(limits=digits[0] == "1", alpha_star=digits[1] == "2", turn_slip=digits[2] == "2",
                   turn_slip_form=turn_slip_form)
