"""Evaluation modes: which optional parts of the model are switched on."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Modes", "KZGR0_FORMS"]

#: Forms of the turn-slip camber-torque stiffness K_zgamma,r0 (used in the turn-slip residual torque):
#: "published": (4.99)  Fz R0 (QDZ8 + QDZ9 dfz + (QDZ10 + QDZ11 dfz)|gamma|) LKZC
#: "mfeval":    the reference evaluator's  Fz R0 (QDZ8 QDZ9 dfz + QDZ10 + QDZ11 dfz |gamma|) LKZC
KZGR0_FORMS = ("published", "mfeval")


@dataclass(frozen=True)
class Modes:
    """Switches of one evaluation.

    limits:     saturate the inputs to the .tir ranges, low-speed model below VXLOW, cap the curvature
                factors E at 1 (the reference evaluator's use mode 1xx).
    alpha_star: alpha* = tan(alpha) sign(Vx), gamma* = sin(gamma) (4.E3, 4.E4); otherwise alpha* = alpha.
    turn_slip:  turn slip and camber spin through the zeta factors (4.76-4.106).
    kzgr0:      the form of K_zgamma,r0, see :data:`KZGR0_FORMS`.
    """

    limits: bool = True
    alpha_star: bool = False
    turn_slip: bool = False
    kzgr0: str = "published"

    def __post_init__(self):
        if self.kzgr0 not in KZGR0_FORMS:
            raise ValueError(f"kzgr0 must be one of {KZGR0_FORMS}, got {self.kzgr0!r}")

    @classmethod
    def from_use_mode(cls, use_mode: int, kzgr0: str = "published") -> "Modes":
        """The reference evaluator's three-digit use mode: hundreds 1/2 = limits on/off, tens 1/2 = alpha*
        off/on, units 1/2 = turn slip off/on."""
        digits = str(int(use_mode))
        if len(digits) != 3 or any(d not in "12" for d in digits):
            raise ValueError(f"use mode must have three digits, each 1 or 2 (e.g. 111, 212); got {use_mode!r}")
        return cls(limits=digits[0] == "1", alpha_star=digits[1] == "2", turn_slip=digits[2] == "2", kzgr0=kzgr0)
