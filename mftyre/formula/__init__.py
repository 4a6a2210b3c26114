"""The Magic Formula 6.1/6.2 (and 5.2) steady-state equations.

Pure functions of ``(prm, state, be)``: ``prm`` is a :class:`mftyre.params.TyreParameters` (SI floats),
``state`` a :class:`types.SimpleNamespace` carrying the conditioned inputs and the intermediate quantities
that later equations need, ``be`` a backend from :mod:`mftyre.backend`. Nothing here knows about files,
plots or fitting.

Equation numbers in comments refer to Pacejka, *Tire and Vehicle Dynamics*, 3rd ed. (2012), Chapter 4
("4.Exx", "4.xx") and Appendix 3 ("A3.x"), and to Besselink, Schmeitz & Pacejka, *An improved Magic
Formula/Swift tyre model that can handle inflation pressure changes*, VSD 48 (2010) ("paper Ann" for its
appendix, "paper (n)" for the numbered equations of its body).

Modules, in the order the evaluation uses them:

========================  ===========================================================================
``normalisation``         input conditioning (limits, low speed), load/pressure increments, alpha*, lambdas
``vertical``              free and effective rolling radius, spin estimate, Fz(rho, p), loaded radius, patch
``turnslip``              spin slip phi and the zeta reduction factors
``longitudinal``          pure and combined Fx
``lateral``               pure and combined Fy
``aligning``              pneumatic trail, residual torque, Mz
``moments``               overturning Mx and rolling resistance My
``derived``               carcass stiffnesses and relaxation lengths
``steady_state``          the orchestration: inputs -> every output
========================  ===========================================================================
"""
from .options import Modes
from .steady_state import steady_state, OUTPUT_NAMES

__all__ = ["Modes", "steady_state", "OUTPUT_NAMES"]
