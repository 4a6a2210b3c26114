"""One vocabulary for every variable that leaves the library: a :class:`Variable` (name, unit, causality, start,
description) per input, output and parameter of the wheels (:mod:`mftyre.transient`, :mod:`swift.fmu_model`) and
of both FMU backends (:mod:`fmu`). A name means one quantity in one unit wherever it appears; a wheel picks the
names it has from :data:`WHEEL` (:func:`pick`) and may say more about one in its own description.

    from mftyre.variables import WHEEL, pick
    outputs = pick("output", "Fx", "Fy", "Fz", describe={"Fz": "vertical force at the wheel centre, >= 0"})

Imports nothing of ours (ground floor, beside :mod:`mftyre.errors`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

__all__ = ["Variable", "CAUSALITIES", "UNIT_BASES", "WHEEL", "MF_OUTPUTS", "SOIL_OUTPUTS", "pick", "table", "unit_table"]

CAUSALITIES = ("parameter", "input", "output")

#: The SI base-unit exponents of the FMI units of :data:`WHEEL` (an FMU's <UnitDefinitions>); "1": dimensionless.
UNIT_BASES = {
    "N": dict(kg=1, m=1, s=-2), "N.m": dict(kg=1, m=2, s=-2), "m": dict(m=1), "m/s": dict(m=1, s=-1),
    "rad": dict(rad=1), "rad/s": dict(rad=1, s=-1), "Pa": dict(kg=1, m=-1, s=-2), "s": dict(s=1),
    "kg": dict(kg=1), "N/m": dict(kg=1, s=-2), "1/m": dict(m=-1),
}


@dataclass(frozen=True)
class Variable:
    """One named quantity: ``unit`` (SI, as FMI spells it: "N.m", "1" for dimensionless), ``causality``
    ("parameter", "input" or "output"), ``start`` (inputs and parameters: the start value, NaN where the wheel
    computes it from the tyre, e.g. free rolling; outputs: None) and a ``description`` for people."""

    name: str
    unit: str
    causality: str
    start: float | None = None
    description: str = ""

    def __post_init__(self):
        if self.causality not in CAUSALITIES:
            raise ValueError(f"variable {self.name}: causality must be one of {', '.join(CAUSALITIES)}, got "
                             f"{self.causality!r}")

    def but(self, **changes) -> "Variable":
        """This variable with some fields changed (``start``, ``description``)."""
        return dataclasses.replace(self, **changes)


def table(*variables: Variable) -> dict[str, Variable]:
    """name -> Variable in the given order; a name given twice is an error."""
    out: dict[str, Variable] = {}
    for v in variables:
        if v.name in out:
            raise ValueError(f"variable {v.name} is listed twice")
        out[v.name] = v
    return out


_NAN = math.nan
_P, _I, _O = "parameter", "input", "output"

#: Every variable of the wheels and the FMUs: each name once, with its unit.
WHEEL = table(
    # parameters (fixed)
    Variable("tau_vlow", "s", _P, _NAN, "transient: low-speed damping time constant of the contact deflections "
             "(mftyre.transient notes)"),
    Variable("x_start", "m", _P, 0.0, "wheel-centre position on the road profile at the start"),
    Variable("max_step", "s", _P, 1e-3, "longest internal RK4 step (steps are never longer than "
             "swift.simulate.MAX_RK4_STEP = 1 ms, the longest a parked tyre is stable with)"),
    Variable("axle_mass", "kg", _P, 30.0, "swift, vertical load: the mass of the axle that Fz_in pushes down"),
    # inputs (continuous; ISO-W axes: x the wheel heading on the road, y left, z up)
    Variable("vx", "m/s", _I, 10.0, "wheel-centre velocity along ISO-W x (wheel heading projected on the road)"),
    Variable("vy", "m/s", _I, 0.0, "wheel-centre velocity along ISO-W y (to the left)"),
    Variable("omega", "rad/s", _I, _NAN, "wheel spin speed about the axle (positive rolling forwards; start: free "
             "rolling at the start vx under FNOMIN)"),
    Variable("gamma", "rad", _I, 0.0, "inclination (camber) of the wheel plane about ISO-W x"),
    Variable("road_camber", "rad", _I, 0.0, "road camber (banking) about ISO-W x, > 0 rising to the left"),
    Variable("p", "Pa", _I, _NAN, "inflation pressure (start: the .tir INFLPRES)"),
    Variable("mu_scale", "1", _I, 1.0, "friction scaling: multiplies LMUX and LMUY of the .tir"),
    Variable("z", "m", _I, _NAN, "wheel-centre height, ISO-W z (same datum as road_z; start: the loaded radius at "
             "FNOMIN)"),
    Variable("vz", "m/s", _I, 0.0, "wheel-centre vertical velocity (z moves with it within a step)"),
    Variable("road_z", "m", _I, 0.0, "road height under the wheel, ISO-W z"),
    Variable("Fz_in", "N", _I, _NAN, "vertical load on the tyre (negative = no contact; start: FNOMIN)"),
    Variable("yaw_rate", "rad/s", _I, 0.0, "yaw velocity of the wheel about ISO-W z (vehicle yaw rate + steer rate); "
             "turn slip phit = +yaw_rate / max(Vc, VXLOW) (mftyre.transient notes)"),
    Variable("kappa_in", "1", _I, 0.0, "rig: longitudinal slip relative to the direction of travel, (omega Re - vx)"
             " / vx (-1 = locked)"),
    Variable("alpha_in", "rad", _I, 0.0, "rig: slip angle"),
    Variable("torque", "N.m", _I, 0.0, "drive (> 0) or brake (< 0) torque on the rim about its axle"),
    # outputs (continuous, calculated)
    Variable("Fx", "N", _O, None, "longitudinal force on the tyre at the wheel centre, ISO-W x"),
    Variable("Fy", "N", _O, None, "lateral force on the tyre at the wheel centre, ISO-W y"),
    Variable("Fz", "N", _O, None, "vertical force on the tyre at the wheel centre, ISO-W z (up)"),
    Variable("Mx", "N.m", _O, None, "moment about ISO-W x at the wheel centre"),
    Variable("My", "N.m", _O, None, "moment about ISO-W y at the wheel centre"),
    Variable("Mz", "N.m", _O, None, "moment about ISO-W z at the wheel centre"),
    Variable("Mx_c", "N.m", _O, None, "overturning moment at the contact point (MF)"),
    Variable("My_c", "N.m", _O, None, "rolling-resistance moment at the contact point (MF)"),
    Variable("Mz_c", "N.m", _O, None, "self-aligning moment at the contact point"),
    Variable("Fx_c", "N", _O, None, "longitudinal contact force in the effective road plane"),
    Variable("Fy_c", "N", _O, None, "lateral contact force"),
    Variable("Fz_c", "N", _O, None, "normal contact force (normal to the effective road plane)"),
    Variable("kappa", "1", _O, None, "longitudinal slip given to the MF"),
    Variable("alpha", "rad", _O, None, "slip angle given to the MF"),
    Variable("Vsx", "m/s", _O, None, "longitudinal slip speed of the contact point"),
    Variable("Vsy", "m/s", _O, None, "lateral slip speed of the contact point"),
    Variable("omega_used", "rad/s", _O, None, "spin speed used"),
    Variable("rho", "m", _O, None, "vertical tyre deflection"),
    Variable("Rl", "m", _O, None, "loaded radius (wheel centre to contact point, in the wheel plane)"),
    Variable("Re", "m", _O, None, "effective rolling radius"),
    Variable("contact_length", "m", _O, None, "contact patch length 2a"),
    Variable("contact_width", "m", _O, None, "contact patch width 2b"),
    Variable("trail", "m", _O, None, "pneumatic trail"),
    Variable("mux", "1", _O, None, "longitudinal friction coefficient"),
    Variable("muy", "1", _O, None, "lateral friction coefficient"),
    Variable("u_x", "m", _O, None, "longitudinal contact-point deflection (transient; 0 for steady)"),
    Variable("u_y", "m", _O, None, "lateral contact-point deflection (transient; 0 for steady)"),
    Variable("road_w", "m", _O, None, "effective road height under the wheel"),
    Variable("road_slope", "rad", _O, None, "effective forward road slope beta_y (> 0 rising ahead)"),
    Variable("road_curvature", "1/m", _O, None, "effective road curvature d beta_y / dx"),
    Variable("Re_variation", "m", _O, None, "effective rolling radius variation over the curved effective road "
             "(free-rolling steady value; 0 on a flat road or a grade)"),
    Variable("road_camber_eff", "rad", _O, None, "effective road camber beta_x: the profile's multi-track camber "
             "plus road_camber"),
    Variable("x_contact", "m", _O, None, "contact centre on the road (x_road plus the forward shift to the foot of "
             "the normal)"),
    Variable("x_road", "m", _O, None, "wheel-centre position on the road: x_start + integral of vx dt"),
)


#: The outputs of MFModel.evaluate (MFOutputs; units as ``mftyre eval`` prints them).
MF_OUTPUTS = table(
    Variable("fx", "N", _O, None, "longitudinal force"),
    Variable("fy", "N", _O, None, "lateral force"),
    Variable("fz", "N", _O, None, "vertical load (input, negative values set to 0)"),
    Variable("mx", "N m", _O, None, "overturning moment"),
    Variable("my", "N m", _O, None, "rolling-resistance moment (negative rolling forwards)"),
    Variable("mz", "N m", _O, None, "self-aligning moment"),
    Variable("kappa", "-", _O, None, "longitudinal slip as used (low-speed scaled, not saturated)"),
    Variable("alpha", "rad", _O, None, "slip angle as used (0 at standstill, not saturated)"),
    Variable("gamma", "rad", _O, None, "inclination angle (input)"),
    Variable("phit", "1/m", _O, None, "turn slip as used"),
    Variable("vx", "m/s", _O, None, "longitudinal speed of the wheel centre"),
    Variable("p", "Pa", _O, None, "inflation pressure as used (saturated to the .tir range with limits)"),
    Variable("omega", "rad/s", _O, None, "wheel spin (input or estimated from kappa and Vx)"),
    Variable("re", "m", _O, None, "effective rolling radius"),
    Variable("rho", "m", _O, None, "vertical deflection"),
    Variable("rl", "m", _O, None, "loaded radius"),
    Variable("a", "m", _O, None, "contact patch half length"),
    Variable("b", "m", _O, None, "contact patch half width"),
    Variable("t", "m", _O, None, "pneumatic trail"),
    Variable("mzr", "N m", _O, None, "residual aligning moment"),
    Variable("mux", "-", _O, None, "longitudinal friction coefficient"),
    Variable("muy", "-", _O, None, "lateral friction coefficient"),
    Variable("cx", "N/m", _O, None, "longitudinal carcass stiffness"),
    Variable("cy", "N/m", _O, None, "lateral carcass stiffness"),
    Variable("cz", "N/m", _O, None, "vertical stiffness Fz/rho"),
    Variable("kya", "N/rad", _O, None, "cornering stiffness (negative in ISO-W)"),
    Variable("kxk", "N", _O, None, "longitudinal slip stiffness"),
    Variable("sigmax", "m", _O, None, "longitudinal relaxation length"),
    Variable("sigmay", "m", _O, None, "lateral relaxation length"),
)

#: The outputs of the soft-soil tyre (mftyre.soil).
SOIL_OUTPUTS = table(
    Variable("sinkage", "m", _O, None, "depth z of the rut below the soil surface"),
    Variable("contact_length", "m", _O, None, "projected length of the soil contact (front arc + flat part)"),
    Variable("flat_length", "m", _O, None, "length 2 a_t of the flat part (the .tir's contact length at the load "
        "F_t)"),
    Variable("contact_width", "m", _O, None, "width B of the soil contact (arc and flat part): the section width "
        "WIDTH"),
    Variable("ground_pressure", "Pa", _O, None, "normal stress under the flat part, F_t / (2 a_t B) = k z_0^n"),
    Variable("flat_load", "N", _O, None, "load F_t carried by the flat part (the rest by the front arc)"),
    Variable("carcass_pressure", "Pa", _O, None, "carcass stiffness pressure p_c = max(Fz / (4 a_h b_h) - p_i, 0) on "
        "hard ground at "
        "this load (see carcass_pressure)"),
    Variable("deflection", "m", _O, None, "tyre deflection: the .tir's Fz(rho, p) at the flat load F_t"),
    Variable("rolling_radius", "m", _O, None, "radius r_f of the tread speed omega r_f on the flat part (.tir's Re "
        "at F_t)"),
    Variable("compaction_resistance", "N", _O, None, "compaction resistance R_c (horizontal part of the arc's normal "
        "stress)"),
    Variable("bulldozing_resistance", "N", _O, None, "bulldozing resistance R_b (0 unless the bulldozing option is "
        "on)"),
    Variable("motion_resistance", "N", _O, None, "soil motion resistance R_c + R_b"),
    Variable("gross_traction", "N", _O, None, "gross traction (thrust) H from the shear"),
    Variable("drawbar_pull", "N", _O, None, "drawbar pull DP = H - R_c - R_b (net longitudinal force)"),
    Variable("hysteresis_moment", "N m", _O, None, "tyre hysteresis moment M_h = -My of the .tir at the flat load "
        "(>= 0 forward)"),
    Variable("torque", "N m", _O, None, "driving torque on the wheel: the shear at each tread's speed plus M_h"),
    Variable("fy", "N", _O, None, "lateral force (ISO-W, shear only)"),
    Variable("omega", "rad/s", _O, None, "wheel spin V / ((1 - i) Re)"),
    Variable("power", "W", _O, None, "wheel input power T omega"),
    Variable("slip_power", "W", _O, None, "shear-slip loss: the shear stress times the slip velocity of the tread, "
        "over the contact"),
    Variable("efficiency", "-", _O, None, "tractive efficiency DP V / (T omega); NaN where T omega <= 1e-9 Fz V (not "
        "driven)"),
    Variable("slip", "-", _O, None, "slip i = 1 - V / (omega Re), Re the hard-ground rolling radius (input)"),
)


def unit_table(variables: dict) -> dict[str, tuple[str, str]]:
    """name -> (unit, description) of a table of variables (the form the result tables and plots take)."""
    return {name: (v.unit, v.description) for name, v in variables.items()}


def pick(causality: str, *names: str, describe: dict | None = None) -> dict[str, Variable]:
    """The :data:`WHEEL` variables ``names`` in that order, all of ``causality``: name -> Variable; ``describe``:
    {name: description} where a wheel says more about a variable than the vocabulary."""
    describe = dict(describe or {})
    chosen = []
    for name in names:
        if name not in WHEEL:
            raise KeyError(f"{name!r} is not in the wheel vocabulary (mftyre.variables.WHEEL)")
        v = WHEEL[name]
        if v.causality != causality:
            raise ValueError(f"variable {name} is an {v.causality}, not an {causality}")
        chosen.append(v.but(description=describe.pop(name)) if name in describe else v)
    if describe:
        raise KeyError(f"described but not picked: {', '.join(describe)}")
    return table(*chosen)


assert {v.unit for v in WHEEL.values()} <= {*UNIT_BASES, "1"}, "a WHEEL unit without its SI base units"
