"""Linear modes of the rigid-ring tyre rolling steadily on a flat road: eigenvalues of the CasADi Jacobian of the
right-hand side (:meth:`swift.simulate.SwiftTyre.jacobian`) at the static equilibrium
(:meth:`swift.simulate.SwiftTyre.initial_state`).

    from swift import Flat, SwiftTyre
    from swift.modes import modes, scan
    tyre = SwiftTyre(model, Flat(), axle="height", rim="torque", x_range=(0.0, 3.0))
    table = modes(tyre, vx=7.0, fz=4000.0)       # Modes: eigenvalues, frequencies [Hz], damping ratios
    rows = scan(tyre, speeds, loads, pressures)  # one Modes per operating point

The operating point: axle height fixed at the loaded radius of the steady-state model at ``fz`` (pressure ``p``),
rim free to spin (``rim="torque"`` with no torque: the rim and belt spin settle to free rolling) or imposed
(``rim="speed"``), no slip, camber or yaw. States whose derivative does not depend on the state (the axle x
position, imposed axle height, the stored contact solution) give eigenvalues that are exactly zero; they are not
modes and are left out (``|lambda| <= ZERO``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .simulate import StepInputs, SwiftTyre

__all__ = ["Modes", "modes", "scan", "ZERO"]

#: Eigenvalues below this magnitude [1/s] are the structural zeros of the state (not modes).
ZERO = 1e-9


@dataclass(frozen=True)
class Modes:
    """The linear modes at one operating point: ``eigenvalues`` (the structural zeros left out), oscillatory modes
    as ``frequency`` [Hz] (damped, |Im lambda| / 2 pi) with ``damping`` ratio -Re lambda / |lambda|, and the real
    ``rates`` [1/s] of the non-oscillatory modes (negative: decaying)."""

    vx: float
    fz: float
    p: float
    eigenvalues: np.ndarray
    frequency: np.ndarray
    damping: np.ndarray
    rates: np.ndarray

    @property
    def max_real(self) -> float:
        """Largest real part [1/s] of any mode: negative = every mode damped."""
        return float(np.max(self.eigenvalues.real))


def modes(tyre: SwiftTyre, vx: float, fz: float, p: float | None = None, x: float = 1.0) -> Modes:
    """The modes of ``tyre`` (on a flat road) rolling at ``vx`` [m/s] with axle height at the loaded radius for
    ``fz`` [N] and pressure ``p`` [Pa] (default: the file's INFLPRES)."""
    model = tyre.model
    p = float(model.params.INFLPRES if p is None else p)
    rl, _ = model.loaded_radius(fz, p=p)
    re = float(model.evaluate(fz, 0.0, 0.0, vx=abs(vx) if vx else None, p=p).re)
    u = StepInputs(x=x, vx=vx, z=float(rl), omega=vx / re, p=p)
    ev = np.linalg.eigvals(tyre.jacobian(tyre.initial_state(u), u))
    ev = ev[np.abs(ev) > ZERO]
    osc = ev[ev.imag > 0]
    return Modes(vx, fz, p, ev, osc.imag / (2 * np.pi), -osc.real / np.abs(osc), np.sort(ev[ev.imag == 0].real))


def scan(tyre: SwiftTyre, speeds, loads, pressures) -> list[Modes]:
    """:func:`modes` at every combination of ``speeds`` [m/s], ``loads`` [N] and ``pressures`` [Pa]."""
    return [modes(tyre, v, fz, p) for p in pressures for fz in loads for v in speeds]
