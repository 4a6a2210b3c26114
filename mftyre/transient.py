"""The tyre on a wheel, as a vehicle simulator drives it: steady Magic Formula, or the Magic Formula behind
first-order relaxation of the contact-point deflections (transient). One set of state equations, as CasADi
functions, evaluated here in Python and generated as C for the native FMU (:mod:`fmu.native`).

    import mftyre
    from mftyre.transient import WheelTyre
    tyre = WheelTyre(mftyre.load_tir("tir_files/car_205_60R15_mf61.tir"), "transient")
    tyre.set_inputs(vx=20.0, omega=20.0 / 0.3, z=0.29)
    tyre.initialise()
    for _ in range(1000):
        tyre.step(1e-3)
    tyre.outputs()["Fx"]

Axes and units: ISO-W (TYDEX W), SI. x is the wheel heading projected on the road, y to the left, z up; the MF
quantities act at the contact point C. ``vx``, ``vy``: wheel-centre velocity in these axes (road at rest).

Kinematics (both models)
  Re = the MF effective rolling radius at kappa = alpha = 0; slip speeds of the contact point
  Vsx = vx - omega Re, Vsy = vy.
Steady
  kappa = -Vsx / max(|vx|, VX_MIN) (ISO-W), alpha = atan2(Vsy, |vx|) and the MF with its own low-speed fade-out
  below VXLOW (no force at standstill).
Reversing (both models, and every importer of this tyre: :func:`mf_slip` is the one rule)
  The ISO-W slip -Vsx / |Vx| is > 0 when the contact point slips backwards relative to the road, and the road then
  pushes the tyre forwards: Fx has the sign of the ISO-W kappa in either direction of travel (a locked wheel,
  Omega = 0, brakes the motion both ways; a wheel spun forwards while the vehicle reverses pulls forwards). The
  MF (MFModel.evaluate, as MFeval; shared/reference/mfeval mf61_reverse) takes its slip relative to the direction
  of travel instead, kappa_MF = -Vsx / Vx with the signed speed (-1 = locked wheel either way), and turns Fx0 round
  for Vx < 0; so the MF gets kappa_MF = sign(Vx) kappa (ISO-W), which makes Fx(-Vx, -Omega) = -Fx(Vx, Omega).
  Output ``kappa``: the slip as given to the MF (kappa_MF; transient: of kappa').
Transient [Pacejka 2012 sec. 7.2 and 8.5 (contact-point deflections u, v with relaxation lengths
sigma_kappa, sigma_alpha); relaxation lengths the MF's ``sigmax``/``sigmay`` (PTX*, PTY*) at the current load]
  du/dt = -Vsx - |vx| u / sigma_kappa                (7.9 with the contact deflection u)
  dv/dt =  Vsy - |vx| v / sigma_alpha                (mftyre's alpha sign: tan(alpha) = Vsy / |vx|)
  kappa' = (u + tau du/dt) / sigma_kappa,  alpha' = atan((v + tau dv/dt) / sigma_alpha)
  F = MF(kappa', alpha', ...) evaluated at the speed max(|vx|, VXLOW) (the slip fade-out of the steady MF is
  replaced by the deflections: at standstill du/dt = -Vsx, the tyre is a spring C = C_kappa / sigma_kappa).
  tau = tau_vlow (1 + cos(pi |vx| / VXLOW)) / 2 below VXLOW, 0 above [chosen]: low-speed damping of the
  deflections (a damper tau C in parallel with the tyre spring), so a parked car on a slope comes to rest
  on the tyre spring without oscillating and without creep (at vx = 0 the deflections only integrate the slip
  speed). Default tau_vlow = 2 sqrt(m / C) with m = FNOMIN / g and C = C_kappa / sigma_kappa at FNOMIN: about
  critical damping for a quarter car at the nominal load [chosen].
  Integration: held inputs over a step make the deflection equations linear with constant coefficients; they
  are integrated exactly (exponential), so any step size is stable and a steady state is step-size independent.
  Initial state: the steady-state deflections u = -Vsx sigma / max(|vx|, VXLOW), v = Vsy sigma / max(|vx|, VXLOW).
  Model exchange (a host's integrator takes the states): ``deriv`` gives du/dt, dv/dt above; ``events`` one
  indicator per switch of the equations (vx: direction of travel; |vx| - VXLOW: low-speed fade; contact:
  R_omega - Rl in position mode, Fz_in with the load input), continuous across each.
Vertical
  ``position``: Fz = max(0, MF vertical force at the loaded radius Rl = (z - road_z) / cos(gamma - road_camber))
  while Rl < R_omega (else lifted off, Fz = 0). Where the .tir couples the vertical force to Fx and Fy (the
  published relation, MF 6.1 (A3.3) / MF 6.2, terms Q_FCX, Q_FCY) the load is the fixed point
  Fz = Fz(Rl, Fx(Fz), Fy(Fz)), from Fx = Fy = 0, by LOAD_PASSES passes.
  ``load``: the input ``Fz_in`` (negative = 0).
Wheel-centre loads: M_W = M_C + (C - W) x F with C -> W = Rl (0, -sin g, cos g):
  Mx_W = Mx + Rl (Fy cos g + Fz sin g),  My_W = My - Rl Fx cos g,  Mz_W = Mz - Rl Fx sin g.
Turn slip (option ``turn_slip``): input ``yaw_rate`` (ISO-W z up), phit = +yaw_rate / max(Vc, VXLOW), the MF with
its turn-slip equations; the turn slip acts without lag also in the transient model [chosen]. The sign: the tread
in the contact patch spins at yaw_rate + omega sin(gamma) about the road normal (rigid-body kinematics of a wheel
inclined by gamma about ISO-W x, spinning forwards about its axle), and the MF's spin phi = phit + (1 - eps_gamma)
omega sin(gamma) / Vc' (4.76 as :mod:`mftyre.formula.turnslip` reads it with the .tir's ISO-W camber) must see the
yaw rate with the sign of the camber spin. Pacejka's psi_dot = -phit Vc (4.75) is written in the book's own axes;
taken literally in ISO-W it turns the spin around: a wheel yawing to the left would get the side force and
moment of a wheel yawing to the right (force into the turn instead of out of it, the bore moment pushing the yaw on
instead of resisting it).
Road camber: the MF gets the inclination relative to the road, gamma - road_camber. Friction: ``mu_scale``
multiplies LMUX and LMUY of the .tir.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from .errors import ModelInputError
from .inputs import check_speed_limits, hard_limits
from .variables import WHEEL, pick

__all__ = ["StateFunctions", "WheelFunctions", "wheel_functions", "free_rolling_start", "start_inputs", "WheelTyre", "KINDS",
           "VERTICAL_MODES", "INPUT_MODES", "VX_MIN",
           "input_table", "OUTPUTS", "PARAMETERS", "default_tau_vlow", "kinematic_slips", "mf_slip", "slip_speeds",
           "wheel_vertical_force", "contact_load", "vertical_couples_forces",
           "wheel_centre_moments", "EVALUATORS", "wheel_key", "point_function", "LOAD_PASSES"]

KINDS = ("steady", "transient")
VERTICAL_MODES = ("position", "load")
#: vehicle: the wheel-centre motion and spin are the inputs; rig: the load and the slips (steady only).
INPUT_MODES = ("vehicle", "rig")
#: Below this |vx| [m/s] the steady kinematic slip uses VX_MIN in the denominator (finite at standstill).
VX_MIN = 1e-3
#: Floor of the relaxation lengths [m] (they vanish with the load).
SIGMA_MIN = 1e-4
#: Fixed-point passes of the load in position mode where the .tir couples Fz to Fx and Fy (module notes,
#: Vertical); each pass contracts the error by roughly 2 (Q_FCX Fx / FNOMIN)^2 + 2 (Q_FCY Fy / FNOMIN)^2. Measured
#: on the public TNO_car205_60R15 (MF 6.2) and MFeval MagicFormula61 files, kappa to +-0.5, vy to 5 m/s, deflection
#: to 10 % of R0: 12 passes leave at most 4e-8 FNOMIN to the converged load (8 passes: 6e-6).
LOAD_PASSES = 12

#: Outputs: name -> Variable (mftyre.variables). Forces/moments at the wheel centre, ISO-W axes.
OUTPUTS = pick(
    "output", "Fx", "Fy", "Fz", "Mx", "My", "Mz", "Mx_c", "My_c", "Mz_c", "kappa", "alpha", "Rl", "Re", "rho",
    "contact_length", "trail", "mux", "muy", "u_x", "u_y", "Vsx", "Vsy", "omega_used", "contact_width",
    describe={"Fz": "vertical force on the tyre at the wheel centre, ISO-W z (up), >= 0",
              "My": "moment about ISO-W y at the wheel centre (-Rl Fx + rolling resistance)",
              "kappa": "longitudinal slip given to the MF (transient: kappa')",
              "alpha": "slip angle given to the MF (transient: alpha')",
              "Vsx": "longitudinal slip speed of the slips given to the MF, -kappa vx",
              "Vsy": "lateral slip speed of the slips given to the MF, tan(alpha) |vx|",
              "omega_used": "spin speed used (the input; rig mode: estimated by the MF from kappa and vx)"})

#: Parameters: name -> Variable (start: NaN, computed from the tyre by :func:`default_tau_vlow`).
PARAMETERS = pick("parameter", "tau_vlow")


def input_table(vertical: str, turn_slip: bool = False, input_mode: str = "vehicle") -> dict:
    """Inputs: name -> Variable (mftyre.variables), in the order of the input vector."""
    if input_mode == "rig":  # the slips and the load imposed, as on a test rig (module notes)
        return pick("input", "vx", "gamma", "road_camber", "p", "mu_scale", "Fz_in", "kappa_in", "alpha_in")
    names = ["vx", "vy", "omega", "gamma", "road_camber", "p", "mu_scale"]
    names += ["z", "road_z"] if vertical == "position" else ["Fz_in"]
    return pick("input", *names, *(["yaw_rate"] if turn_slip else []))


def free_rolling_start(model, vx: float) -> tuple[float, float]:
    """(omega, z): the spin [rad/s] of free rolling at ``vx`` [m/s] (omega R_e = vx, R_e of the MF at FNOMIN and
    INFLPRES, which depends on the spin through R_omega: fixed-point passes) and the loaded radius [m] at FNOMIN:
    the start inputs of the FMUs, so that a tyre with no inputs set rolls freely under its nominal load."""
    prm = model.params
    omega = vx / prm.UNLOADED_RADIUS
    for _ in range(4):
        omega = vx / float(model.evaluate(prm.FNOMIN, 0.0, 0.0, vx=vx, p=prm.INFLPRES, omega=omega).re)
    rl, _ = model.loaded_radius(prm.FNOMIN, p=prm.INFLPRES, omega=omega)
    return omega, float(rl)


def start_inputs(model) -> dict:
    """The start values of the inputs that depend on the file (both FMU backends and every kind): free rolling at
    the start speed of ``WHEEL["vx"]`` under FNOMIN at INFLPRES (spin ``omega``, axle height ``z``)."""
    prm = model.params
    omega, z = free_rolling_start(model, WHEEL["vx"].start)
    return {"p": float(prm.INFLPRES), "omega": omega, "z": z, "Fz_in": float(prm.FNOMIN)}


def default_tau_vlow(model) -> float:
    """2 sqrt(m / C), m = FNOMIN / g, C = C_kappa / sigma_kappa at FNOMIN (module notes)."""
    prm = model.params
    o = model.evaluate(prm.FNOMIN, 0.0, 0.0, 0.0, 0.0, max(prm.VXLOW, 1.0))
    c = float(o.kxk) / max(float(o.sigmax), SIGMA_MIN)
    return 2.0 * math.sqrt(prm.FNOMIN / 9.81 / c)


# ------------------------------------------------------------------------------ the wheel's equations
# Backend-neutral (``be``: mftyre.backend), shared by the wheel model below and the pythonfmu FMU's steady tyre.
def _atan2(be):
    return np.arctan2 if be.name == "numpy" else be.ca.atan2


def kinematic_slips(vx, vy, omega, re, be):
    """Steady kinematic slips, ISO-W (module notes): kappa = -Vsx / max(|vx|, VX_MIN) with Vsx = vx - omega Re, and
    alpha = atan2(Vsy, |vx|) with Vsy = vy. The MF takes ``mf_slip(kappa, vx, be)`` and alpha."""
    vsx, vsy = vx - omega * re, vy
    return -vsx / be.fmax(be.abs(vx), VX_MIN), _atan2(be)(vsy, be.abs(vx))


def mf_slip(kappa, vx, be):
    """The longitudinal slip the MF takes at the speed ``vx`` (module notes, Reversing) from the ISO-W slip
    ``kappa`` = -Vsx / |vx| (kinematic or transient): kappa_MF = -Vsx / Vx = sign(vx) kappa (+ at vx = 0)."""
    return be.where(vx < 0, -kappa, kappa)


def slip_speeds(kappa, alpha, vx, be):
    """The contact point's slip speeds (Vsx, Vsy) = (-kappa vx, tan(alpha) |vx|) of the slips given to the MF at
    the speed ``vx`` (kappa_MF = -Vsx / Vx, :func:`mf_slip`)."""
    return -kappa * vx, be.tan(alpha) * be.abs(vx)


def wheel_vertical_force(model, rl, p, omega, fx, fy, gamma, be):
    """(Fz, R_omega): the .tir's vertical force at the loaded radius ``rl`` (MF 6.1 (A3.3) with rho = R_omega -
    Rl, or the MF 6.2 relation with camber and Fx/Fy terms) on the mounted side, as MFModel.vertical_force, and the
    free radius R_omega at the spin; see :func:`contact_load` for the lift-off."""
    from .formula import vertical as vert

    prm = model.params
    fy, gamma = (-fy, -gamma) if model.mirrored else (fy, gamma)
    r_omega, dpi = vert.free_radius(prm, omega, be), vert.pressure_increment(prm, p)
    return vert.vertical_force(prm, rl, r_omega, omega, fx, fy, gamma, dpi, be), r_omega


def contact_load(fz, rl, r_omega, be):
    """The load on the road: the vertical force, >= 0, while Rl < R_omega; 0 above (the wheel has lifted off)."""
    return be.where(rl < r_omega, be.fmax(fz, 0.0), 0.0)


def vertical_couples_forces(prm) -> bool:
    """Whether the .tir's vertical force depends on Fx and Fy (Q_FCX, Q_FCY non-zero; true when it has no such
    parameters to say otherwise)."""
    return bool(prm["Q_FCX"] != 0 or prm["Q_FCY"] != 0) if "Q_FCX" in prm else True


def wheel_centre_moments(fx, fy, fz, mx, my, mz, rl, gamma, be):
    """Moments about the wheel centre W of the loads at the contact point C (module notes): M_W = M_C + (C - W) x F
    with C -> W = Rl (0, -sin g, cos g), ISO-W components."""
    cg, sg = be.cos(gamma), be.sin(gamma)
    return mx + rl * (fy * cg + fz * sg), my - rl * fx * cg, mz - rl * fx * sg


@dataclass(frozen=True)
class StateFunctions:
    """A tyre with state as CasADi functions, the one definition both FMU backends and the Python steppers drive:
    ``init``, ``step``, ``out`` (their arguments in the subclasses), the state names, and the variables
    (:class:`mftyre.variables.Variable`, in the order of the vectors the functions take): inputs u, parameters q,
    outputs y (start values as the wheel computed them for this tyre)."""

    init: object
    step: object
    out: object
    state_names: tuple
    inputs: tuple
    parameters: tuple
    outputs: tuple

    @property
    def input_names(self) -> tuple:
        return tuple(v.name for v in self.inputs)

    @property
    def input_starts(self) -> tuple:
        return tuple(v.start for v in self.inputs)

    @property
    def parameter_names(self) -> tuple:
        return tuple(v.name for v in self.parameters)

    @property
    def parameter_starts(self) -> tuple:
        return tuple(v.start for v in self.parameters)

    @property
    def output_names(self) -> tuple:
        return tuple(v.name for v in self.outputs)


@dataclass(frozen=True)
class WheelFunctions(StateFunctions):
    """The wheel's state equations (x: state, u: inputs, q: parameters, all column vectors):
    ``init(u, q) -> x``, ``step(x, u, q, h) -> x_next`` (inputs held over h), ``out(x, u, q) -> y``."""

    kind: str
    vertical: str
    input_mode: str = "vehicle"
    #: ``deriv(x, u, q) -> dx/dt`` (the state equations a host's integrator can take: Model Exchange) and
    #: ``events(x, u, q) -> z``: one value per switch of the equations (sign of vx, |vx| = VXLOW, contact), zero where
    #: a branch changes (event indicators)
    deriv: object = None
    events: object = None
    event_names: tuple = ()
    #: the .tir parameters the functions take at run time, the entries of q after :attr:`parameters`
    #: (``run_time`` of :func:`wheel_functions`; empty: the model's values are numbers in the graph)
    run_time: tuple = ()


def wheel_functions(model, kind: str = "steady", vertical: str = "position",
                    tau_vlow: float | None = None, turn_slip: bool = False,
                    input_mode: str = "vehicle", run_time=()) -> WheelFunctions:
    """CasADi functions of the ``kind`` ("steady" or "transient") tyre with the ``vertical`` input mode;
    ``turn_slip``: the MF with turn slip (input ``yaw_rate``, module notes); ``input_mode`` "rig": the steady tyre
    with the load ``Fz_in`` and the slips ``kappa_in`` (relative to the direction of travel, as the MF takes it),
    ``alpha_in`` imposed, the spin estimated by the MF from kappa and vx (``vertical`` is then "load").
    ``run_time``: names of .tir parameters made entries of ``q`` after the wheel's own
    (:attr:`WheelFunctions.run_time`; real, non-zero, none that selects a form of the equations: see
    :func:`mftyre.model.run_time_parameter_names`), so the functions serve every model of the same structure
    (:func:`mftyre.model.structure_of`), each with its values in q; the input and parameter starts stay
    ``model``'s."""
    import casadi as ca

    from .backend import casadi_backend
    from .model import ParametricModel, run_time_parameter_names

    if kind not in KINDS:
        raise ModelInputError(f"model must be one of {', '.join(KINDS)}; got {kind!r}")
    if input_mode not in INPUT_MODES:
        raise ModelInputError(f"input mode must be one of {', '.join(INPUT_MODES)}; got {input_mode!r}")
    rig = input_mode == "rig"
    if rig and (kind != "steady" or turn_slip):
        raise ModelInputError("rig mode (slips and load imposed) is a mode of the steady tyre without turn slip: the "
                              "transient tyre and turn slip take the wheel's motion")
    vertical = "load" if rig else vertical
    if vertical not in VERTICAL_MODES:
        raise ModelInputError(f"vertical input must be one of {', '.join(VERTICAL_MODES)}; got {vertical!r}")
    prm = model.params
    be = casadi_backend()
    table = input_table(vertical, turn_slip, input_mode)
    computed = start_inputs(model)
    inputs = tuple(v.but(start=computed[n]) if n in computed else v for n, v in table.items())
    u = ca.SX.sym("u", len(table))
    U = {n: u[i] for i, n in enumerate(table)}
    parameters = ()
    if kind == "transient":
        tau_start = default_tau_vlow(model) if tau_vlow is None else float(tau_vlow)
        parameters = (PARAMETERS["tau_vlow"].but(start=tau_start),)
    names = list(run_time)
    bad = [n for n in names if n not in run_time_parameter_names(model.params)]
    if bad:
        raise ModelInputError(f"run-time parameter(s) {bad} of the wheel must be real, non-zero .tir parameters that "
                              f"select no form of the equations")
    q = ca.SX.sym("q", len(parameters) + len(names))
    couples = vertical_couples_forces(prm)  # (a form of the equations: from the numbers)
    if names:  # the equations read the run-time parameters as the entries of q after the wheel's own
        model = ParametricModel(model, names, [q[len(parameters) + i] for i in range(len(names))])
        prm = model.params
    nx = 2 if kind == "transient" else 0
    x = ca.SX.sym("x", nx)
    h = ca.SX.sym("h")

    mf_in = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p", "omega")
    mf_out = ("fx", "fy", "mx", "my", "mz", "re", "rho", "rl", "a", "b", "t", "mux", "muy")
    mf = model.casadi_function(inputs=mf_in, outputs=mf_out, parameters=("LMUX", "LMUY"), turn_slip=turn_slip,
                               name="mf")
    free = model.casadi_function(inputs=("fz", "gamma", "vx", "p", "omega"),
                                 outputs=("re", "sigmax", "sigmay"), fixed=dict(kappa=0.0, alpha=0.0),
                                 parameters=("LMUX", "LMUY"), name="free_rolling")
    vx, p = U["vx"], U["p"]
    gamma = U["gamma"] - U["road_camber"]
    lmux, lmuy = prm.LMUX * U["mu_scale"], prm.LMUY * U["mu_scale"]
    if rig:
        return _rig_functions(model, u, U, q, x, h, gamma, lmux, lmuy, inputs, parameters, tuple(names))
    vy, omega = U["vy"], U["omega"]

    # turn slip: phit = +psi_dot / Vc', Vc' = max(Vc, VXLOW) (module notes: the sign of the camber spin in ISO-W);
    # not relaxed in the transient model [chosen]
    phit = U["yaw_rate"] / be.fmax(be.sqrt(vx**2 + vy**2), prm.VXLOW) if turn_slip else 0.0 * vx

    def tyre_at(fz, start=False):
        """The tyre under the load ``fz``: (slips and state expressions, MF outputs); ``start``: with the
        deflections of the initial state (transient) instead of the state x."""
        re, sigx, sigy = free(fz, gamma, vx, p, omega, lmux, lmuy)
        vsx, vsy = vx - omega * re, vy
        if kind == "steady":
            kappa, alpha = kinematic_slips(vx, vy, omega, re, be)
            vx_mf = vx
            ux = uy = 0.0 * vx
            x0 = x_next = xdot = ca.SX(0, 1)
        else:
            sigx, sigy = be.fmax(sigx, SIGMA_MIN), be.fmax(sigy, SIGMA_MIN)
            speed = be.abs(vx)
            ref = be.fmax(speed, prm.VXLOW)
            x0 = ca.vertcat(-vsx * sigx / ref, vsy * sigy / ref)
            ux, uy = (x0[0], x0[1]) if start else (x[0], x[1])
            dux = -vsx - speed * ux / sigx                                       # (7.9), contact deflection u
            duy = vsy - speed * uy / sigy
            fade = be.where(speed < prm.VXLOW, 0.5 * (1.0 + be.cos(be.pi * speed / prm.VXLOW)), 0.0)
            tau = q[0] * fade
            kappa = (ux + tau * dux) / sigx
            alpha = be.atan((uy + tau * duy) / sigy)
            vx_mf = be.where(vx >= 0, be.fmax(vx, prm.VXLOW), be.fmin(vx, -prm.VXLOW))

            # exact solution over h of du/dt = -lam u + f (lam, f held): u e^{-lam h} + f (1 - e^{-lam h}) / lam
            def relax(dev, lam, forcing):
                lh = lam * h
                gain = be.where(lh > 1e-8, (1.0 - be.exp(-lh)) / be.fmax(lam, 1e-300), h * (1.0 - lh / 2))
                return dev * be.exp(-lh) + forcing * gain
            x_next = ca.vertcat(relax(ux, speed / sigx, -vsx), relax(uy, speed / sigy, vsy))
            xdot = ca.vertcat(dux, duy)
        kappa = mf_slip(kappa, vx_mf, be)  # the MF's slip is relative to the direction of travel (module notes)
        return (re, kappa, alpha, ux, uy, x0, x_next, xdot), mf(fz, kappa, alpha, gamma, phit, vx_mf, p, omega, lmux,
                                                                 lmuy)

    # vertical load
    if vertical == "position":
        rl_geo = (U["z"] - U["road_z"]) / be.cos(gamma)

        def road_load(fx, fy):
            fz_v, r_omega = wheel_vertical_force(model, rl_geo, p, omega, fx, fy, gamma, be)
            return contact_load(fz_v, rl_geo, r_omega, be), r_omega

        def coupled_load(start):  # Fz = Fz(Rl, Fx(Fz), Fy(Fz)) (A3.3 with Q_FCX, Q_FCY): LOAD_PASSES passes
            fz, r_omega = road_load(0.0, 0.0)
            for _ in range(LOAD_PASSES if couples else 0):
                fx_k, fy_k = tyre_at(fz, start)[1][:2]
                fz, r_omega = road_load(fx_k, fy_k)
            return fz, r_omega

        fz, ro = coupled_load(False)
        fz_start = coupled_load(True)[0] if kind == "transient" and couples else fz
        contact = ro - rl_geo  # > 0 in contact (contact_load)
    else:
        fz = fz_start = be.fmax(U["Fz_in"], 0.0)
        contact = U["Fz_in"]
    (re, kappa, alpha, ux, uy, _, x_next, xdot), mf_values = tyre_at(fz)
    x0 = tyre_at(fz_start, start=True)[0][5]
    fx, fy, mx, my, mz, _, rho, rl_mf, a, b, t, mux, muy = mf_values
    rl = rl_geo if vertical == "position" else rl_mf
    mx_w, my_w, mz_w = wheel_centre_moments(fx, fy, fz, mx, my, mz, rl, gamma, be)
    y = {"Fx": fx, "Fy": fy, "Fz": fz, "Mx": mx_w, "My": my_w, "Mz": mz_w,
         "Mx_c": mx, "My_c": my, "Mz_c": mz, "kappa": kappa, "alpha": alpha, "Rl": rl, "Re": re,
         "rho": rho if vertical == "load" else be.where(fz > 0, ro - rl_geo, 0.0),
         "contact_length": 2.0 * a, "trail": t, "mux": mux, "muy": muy, "u_x": ux, "u_y": uy,
         "omega_used": omega, "contact_width": 2.0 * b}
    y["Vsx"], y["Vsy"] = slip_speeds(kappa, alpha, vx, be)
    # the switches: direction of travel (mf_slip, vx_mf), the low-speed fade at VXLOW (the transient's damping; the
    # steady MF's own fade-out), the contact (lift-off)
    events = {"vx": vx, "low_speed": be.abs(vx) - prm.VXLOW, "contact": contact}
    return _wheel(x, u, q, h, x0, x_next, y, inputs, parameters, xdot, events, kind=kind, vertical=vertical,
                  run_time=tuple(names))


def _wheel(x, u, q, h, x0, x_next, y: dict, inputs, parameters, xdot, events: dict, **mode) -> WheelFunctions:
    """The functions of a wheel from its expressions: initial state ``x0``, state after a step ``x_next``,
    outputs ``y`` (by name, :data:`OUTPUTS`), state derivatives ``xdot``, event indicators ``events`` (by name)."""
    import casadi as ca

    init = ca.Function("tyre_init", [u, q], [x0], ["u", "q"], ["x0"])
    step = ca.Function("tyre_step", [x, u, q, h], [x_next], ["x", "u", "q", "h"], ["x_next"])
    out = ca.Function("tyre_out", [x, u, q], [ca.vertcat(*(y[n] for n in OUTPUTS))], ["x", "u", "q"], ["y"])
    deriv = ca.Function("tyre_deriv", [x, u, q], [xdot], ["x", "u", "q"], ["xdot"])
    ev = ca.Function("tyre_events", [x, u, q], [ca.vertcat(*events.values())], ["x", "u", "q"], ["z"])
    return WheelFunctions(init=init, step=step, out=out, state_names=("u_x", "u_y")[:x.numel()], inputs=inputs,
                          parameters=parameters, outputs=tuple(OUTPUTS.values()), deriv=deriv, events=ev,
                          event_names=tuple(events), **mode)


def _rig_functions(model, u, U, q, x, h, gamma, lmux, lmuy, inputs, parameters, run_time) -> WheelFunctions:
    """The steady tyre on a rig: the MF at the imposed load and slips (kappa_in relative to the direction of
    travel, as MFModel.evaluate takes it), its spin estimated from kappa and vx; Rl, rho and Re the MF's."""
    import casadi as ca

    from .backend import casadi_backend

    be = casadi_backend()
    mf = model.casadi_function(inputs=("fz", "kappa", "alpha", "gamma", "vx", "p"),
                               outputs=("fx", "fy", "mx", "my", "mz", "omega", "re", "rho", "rl", "a", "b", "t", "mux",
                                        "muy"), parameters=("LMUX", "LMUY"), name="mf_rig")
    fz, kappa, alpha = be.fmax(U["Fz_in"], 0.0), U["kappa_in"], U["alpha_in"]
    fx, fy, mx, my, mz, omega, re, rho, rl, a, b, t, mux, muy = mf(fz, kappa, alpha, gamma, U["vx"], U["p"], lmux,
                                                                   lmuy)
    mx_w, my_w, mz_w = wheel_centre_moments(fx, fy, fz, mx, my, mz, rl, gamma, be)
    none = 0.0 * U["vx"]
    y = {"Fx": fx, "Fy": fy, "Fz": fz, "Mx": mx_w, "My": my_w, "Mz": mz_w, "Mx_c": mx, "My_c": my, "Mz_c": mz,
         "kappa": kappa, "alpha": alpha, "Rl": rl, "Re": re, "rho": rho, "contact_length": 2.0 * a, "trail": t,
         "mux": mux, "muy": muy, "u_x": none, "u_y": none, "omega_used": omega, "contact_width": 2.0 * b}
    y["Vsx"], y["Vsy"] = slip_speeds(kappa, alpha, U["vx"], be)
    return _wheel(x, u, q, h, ca.SX(0, 1), ca.SX(0, 1), y, inputs, parameters, ca.SX(0, 1), {"contact": U["Fz_in"]},
                  kind="steady", vertical="load", input_mode="rig", run_time=run_time)


class StepError(ModelInputError):
    """A step or input the tyre cannot take (non-finite input, step size not positive and finite)."""


#: How WheelTyre evaluates the outputs: compiled C (mftyre.compiled, cached), CasADi's virtual machine, or auto
#: (compiled, else CasADi with a warning).
EVALUATORS = ("auto", "compiled", "casadi")


def wheel_key(model, **mode) -> str:
    """Identifies the compiled outputs of a wheel: the .tir's parameters, the side, the mode, the versions of
    mftyre and CasADi (the key of :func:`mftyre.compiled.compile_function`)."""
    import hashlib
    import json

    import casadi as ca

    from . import __version__

    prm = model.params
    payload = {"parameters": {k: repr(prm[k]) for k in prm}, "side": model.side, "mode": mode,
               "mftyre": __version__, "casadi": ca.__version__}
    return "wheel_" + hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:24]


def point_function(functions: StateFunctions):
    """``out`` as a function of scalars, for compiling: (state, inputs, parameters, each by name) -> outputs."""
    import casadi as ca

    x, u, q = (ca.SX.sym(n, k) for n, k in (("x", len(functions.state_names)), ("u", len(functions.inputs)),
                                              ("q", len(functions.parameters))))
    y = functions.out(x, u, q)
    args = [*ca.vertsplit(x), *ca.vertsplit(u), *ca.vertsplit(q)]
    names = [*functions.state_names, *functions.input_names, *functions.parameter_names]
    return ca.Function("wheel_out", args, ca.vertsplit(y), names, list(functions.output_names))


class WheelTyre:
    """The steady or transient tyre in Python: the same CasADi functions the native FMU runs as C.

    ``set_inputs(**values)``, ``initialise()``, ``step(h)``, ``outputs()`` (dict), ``state`` (array; get/set).
    Inputs are held over a step; a rejected step (StepError) leaves state and outputs as they were.
    ``evaluator`` (:data:`EVALUATORS`): how ``outputs`` evaluates ``out``; the one used is ``self.evaluator``."""

    def __init__(self, model, kind: str = "steady", vertical: str = "position", tau_vlow: float | None = None,
                 turn_slip: bool = False, input_mode: str = "vehicle", evaluator: str = "casadi"):
        if evaluator not in EVALUATORS:
            raise ModelInputError(f"evaluator must be one of {', '.join(EVALUATORS)}; got {evaluator!r}")
        self.functions = f = wheel_functions(model, kind, vertical, tau_vlow, turn_slip, input_mode)
        self._params, self._limits = model.params, hard_limits(model.params)
        self.u = np.array(f.input_starts, dtype=float)
        self.q = np.array(f.parameter_starts, dtype=float)
        self.state = np.zeros(len(f.state_names))
        self._compiled = None
        self.evaluator = "casadi"
        if evaluator != "casadi":
            from .compiled import CompiledFunction, compile_function

            key = wheel_key(model, kind=kind, vertical=f.vertical, turn_slip=turn_slip, input_mode=input_mode)
            try:
                self._compiled = CompiledFunction(compile_function(lambda: point_function(f), key))
                self.evaluator = "compiled"
            except Exception as exc:  # no C compiler...
                if evaluator == "compiled":
                    raise ModelInputError(f"compiled evaluator unavailable: {exc}") from None
                warnings.warn(f"compiled evaluator unavailable ({exc}); using CasADi's virtual machine",
                              stacklevel=2)

    def set_inputs(self, **values):
        names = self.functions.input_names
        for k, v in values.items():
            if k not in names:
                raise ModelInputError(f"unknown input {k!r}; inputs are {', '.join(names)}")
            if not math.isfinite(v):
                raise StepError(f"input {k} must be finite, got {v!r}")
            self.u[names.index(k)] = v

    def set_parameters(self, **values):
        names = self.functions.parameter_names
        for k, v in values.items():
            if k not in names:
                raise ModelInputError(f"unknown parameter {k!r}; parameters are {', '.join(names) or 'none'}")
            self.q[names.index(k)] = v

    def _check_limits(self, error):
        """The input policy's speed limits (:func:`mftyre.inputs.check_limits`; the native FMU's TYRE_LIMITS, from
        :func:`mftyre.inputs.point_limit_checks`): vx, and the rim speed of the input spin (rig mode: vx only, the
        spin follows from kappa_in), raised as ``error``."""
        U = dict(zip(self.functions.input_names, self.u))
        try:
            check_speed_limits(self._params, U["vx"], U.get("omega"), lim=self._limits)
        except ModelInputError as exc:
            raise error(str(exc)) from None

    def initialise(self):
        self._check_limits(ModelInputError)
        self.state = np.asarray(self.functions.init(self.u, self.q), dtype=float).ravel()

    def step(self, h: float):
        if not (math.isfinite(h) and h > 0):
            raise StepError(f"step size must be positive and finite, got {h!r}")
        self._check_limits(StepError)
        if self.state.size:
            self.state = np.asarray(self.functions.step(self.state, self.u, self.q, h), dtype=float).ravel()

    def outputs(self) -> dict:
        if self._compiled is not None:
            return dict(zip(self.functions.output_names, self._compiled(*self.state, *self.u, *self.q)))
        y = np.asarray(self.functions.out(self.state, self.u, self.q), dtype=float).ravel()
        return dict(zip(self.functions.output_names, y))
