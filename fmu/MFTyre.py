"""FMI 2.0 co-simulation slave of the mftyre Magic Formula tyre (pythonfmu).

Built by ``mftyre fmu build FILE.tir -o tyre.fmu --backend pythonfmu`` (see build.py and README.md here); not meant to be run
directly. The FMU's resources hold this script, ``config.json`` (what
was built), ``tyre.tir`` (the embedded property file), ``functions/`` (for the build platform, the compiled
libraries of the wheels) and ``vendor/mftyre`` (a copy of the mftyre package used
when the host's Python has none installed).

FMI behaviour
-------------
* Parameters are read when initialisation ends; the outputs are computed then from the inputs' current values,
  so they are valid right after fmi2ExitInitializationMode, and after every fmi2DoStep. model=steady has no
  state: the outputs are those of the inputs at the end of the step, whatever the step size. model=swift holds
  the state of the rigid-ring tyre (``swift.fmu_model.SwiftWheel``, the native FMU's functions): it starts in
  static equilibrium at the initial inputs and is advanced over each communication step (any step size; split
  into internal steps of at most ``max_step``).
* A failed initialisation (bad parameter, unreadable .tir, bad road) is logged with status fmi2Error (category
  logStatusError) as "initialisation failed: <cause>", the cause naming the parameter or file as the native FMU
  does (a traceback follows only for unexpected errors), and raised, so fmi2ExitInitializationMode fails instead
  of claiming OK. Its status is fmi2Fatal, not the fmi2Error the native FMU returns and FMI 2.0 intends for a
  user error: pythonfmu's binary (0.7.0, PySlaveInstance::handle_py_exception) turns every Python exception into
  fmi2Fatal and has no other failure status for this call. During stepping no exception leaves this class: a
  non-finite input, p <= 0 or a step size that is not positive and finite makes fmi2DoStep return fmi2Discard and
  leaves the outputs (and the swift state) at their last valid values; the ``status`` output says why (0 ok, 1
  input or step rejected).
* fmi2GetFMUstate/fmi2SetFMUstate/serialise hold the whole state: the variables, x_road and the SWIFT ring state
  (``_get_fmu_state``).
* fmi2Reset returns the instance to the state after instantiation (pythonfmu re-creates the object).
"""
import json
import math
import os
import sys
import traceback
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status

#: Inputs (Real): name -> what this FMU's modes make of it; units from mftyre.variables.WHEEL, start values from
#: config.json.
_INPUTS = {
    "vx": "wheel-centre velocity along the wheel heading x (ISO-W); rig mode: the rig speed",
    "vy": "vehicle mode: wheel-centre velocity along y (ISO-W, to the left)",
    "omega": "vehicle mode: wheel spin speed (positive rolling forwards)",
    "gamma": "inclination (camber) angle, ISO-W",
    "z": "vehicle mode, vertical_input=position: wheel-centre height (same reference as road_z)",
    "road_z": "vehicle mode, vertical_input=position: road height under the wheel",
    "vz": "swift, vertical_input=position: wheel-centre vertical speed (z moves with it inside the step)",
    "Fz_in": "vertical load (vertical_input=load, and rig mode; swift: downward force on the axle)",
    "p": "inflation pressure (may change during the run)",
    "road_camber": "road camber angle about ISO-W x (steady: the MF takes gamma - road_camber; swift: the ring's)",
    "mu_scale": "steady: friction scale, multiplies LMUX and LMUY of the .tir (swift: must stay 1)",
    "kappa_in": "rig mode: longitudinal slip",
    "alpha_in": "rig mode: slip angle (ISO-W)",
    "torque": "swift, rim=torque: drive (+) or brake (-) torque on the rim about its axle",
}
#: The input of an FMU built with turn slip (config.json ``turn_slip``, as the native FMU's ``--turn-slip``).
_TURN_SLIP_INPUTS = {
    "yaw_rate": "turn slip, model=steady: yaw velocity of the wheel about ISO-W z (vehicle yaw rate + steer rate), "
                "phit = +yaw_rate / max(Vc, VXLOW); swift: must stay 0 (the wheel frame does not yaw: the ring's turn "
                "slip is the contact patch's yaw relative to the rim)",
}

_PARAMETERS = {  # name -> description; start values come from config.json
    "tir_file": "property file: empty = the .tir embedded in the FMU (resources/tyre.tir), else a path",
    "model": "tyre model: steady (Magic Formula, no states) or swift (rigid ring with tandem-cam enveloping)",
    "side": "side the tyre is mounted on: left or right (mirrors the lateral behaviour)",
    "input_mode": "vehicle (wheel-centre velocities, spin, vertical position or load) or rig (kappa, alpha, Fz)",
    "vertical_input": "vehicle mode: load (Fz_in is the load) or position (Fz from z - road_z)",
    "evaluator": "auto (compiled C, else CasADi VM), compiled or casadi",
    "road": "swift: road profile, e.g. cleat(x0=2, length=0.05, height=0.01); empty = flat (see documentation)",
    "rim": "swift: speed (the omega input is imposed) or torque (the torque input drives the rim)",
}

#: Outputs the FMU adds to the wheel's (mftyre.transient.OUTPUTS), in every mode (the SWIFT wheel's).
EXTRA_OUTPUTS = ("Fz_c", "road_w", "road_slope", "x_road", "Fx_c", "Fy_c", "road_curvature", "Re_variation",
                 "road_camber_eff", "x_contact")
#: What the pythonfmu FMU says more about some outputs than the vocabulary (its modes: steady vehicle/rig, swift).
OUTPUT_NOTES = {
    "Fz": "vertical force on the tyre, >= 0 (at the wheel centre, ISO-W axes)",
    "My": "moment about y at the wheel centre, ISO-W axes (-Rl Fx + rolling resistance)",
    "kappa": "longitudinal slip given to the MF, -Vsx / Vx (kinematic or the rig input: relative to the direction of "
             "travel, -1 = locked wheel; swift: the transient slip -Vsx / |Vcx|, its MF runs at |Vcx|)",
    "alpha": "slip angle given to the MF (kinematic, or the rig input)",
    "Vsx": "longitudinal slip speed of the contact point, -kappa vx (swift: -kappa |Vcx|)",
    "Vsy": "lateral slip speed of the contact point, tan(alpha) |vx|",
    "omega_used": "spin speed used (the input; in rig mode estimated from kappa and vx)",
    "Fz_c": "normal contact force (swift: normal to the effective road plane; steady: = Fz)",
    "road_w": "effective road height under the wheel (swift: tandem cams + road_z; steady: road_z, or 0 with "
              "vertical_input=load)",
    "road_slope": "effective forward road slope beta_y (swift; 0 in steady mode)",
}


def _outputs():
    """The outputs: name -> Variable (needs mftyre importable: the host's or the FMU's vendored copy)."""
    from mftyre.transient import OUTPUTS
    from mftyre.variables import pick

    return pick("output", *OUTPUTS, *EXTRA_OUTPUTS, describe=OUTPUT_NOTES)


#: Real parameters: name -> description; units and defaults from mftyre.variables.WHEEL.
_REAL_PARAMETERS = {
    "x_start": "swift: wheel-centre position on the road profile at the start",
    "max_step": "swift: longest internal step (a communication step is split into equal steps)",
    "axle_mass": "swift, vertical_input=load: mass of the axle the Fz_in input pushes down",
}


def _user_error(exc) -> bool:
    """A problem of the parameters or the .tir file that the user can mend (logged without a traceback)."""
    kind = getattr(sys.modules.get("mftyre.errors"), "MFTyreError", None)
    return isinstance(exc, (ValueError, *((kind,) if kind is not None else ())))


class MFTyre(Fmi2Slave):
    """Magic Formula 6.1/6.2 tyre (mftyre), steady or SWIFT rigid ring: forces and moments at the wheel centre,
    slips, radii, contact patch."""

    author = "mftyre developers"
    description = ("Magic Formula 6.1/6.2 tyre from a .tir file (mftyre): steady state, or the SWIFT rigid ring "
                   "with tandem-cam enveloping (model=swift); ISO-W axes, SI units. "
                   "Needs Python with numpy and casadi (see documentation).")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._config = self._read_config()
        cfg = self._config
        params = cfg.get("parameters", {})
        self._turn_slip = bool(cfg.get("turn_slip", False))  # fixed at build time: it adds the input yaw_rate
        inputs = {**_INPUTS, **(_TURN_SLIP_INPUTS if self._turn_slip else {})}
        for name in _PARAMETERS:
            setattr(self, name, str(params.get(name, "")))
        self._import_mftyre(self.resources or ".")
        import mftyre
        from mftyre.variables import WHEEL

        starts = cfg.get("inputs", {})
        for name in inputs:
            start = WHEEL[name].start
            setattr(self, name, float(starts.get(name, start if math.isfinite(start) else 0.0)))
        self.version = mftyre.__version__  # the one version string (pyproject reads it too)
        outputs = _outputs()
        for name in _REAL_PARAMETERS:
            setattr(self, name, float(params.get(name, WHEEL[name].start)))
        self._units = {v.name: v.unit for v in outputs.values()}
        self._units.update({n: WHEEL[n].unit for n in (*inputs, *_REAL_PARAMETERS)})
        for name in outputs:
            setattr(self, name, 0.0)
        self.status = 0
        self._core = None
        self._mode = None
        self._problem = None  # configuration error message, once found
        self._x_road = 0.0  # steady mode: x_start + integral of vx

        for name, description in _PARAMETERS.items():
            self.register_variable(String(name, causality=Fmi2Causality.parameter,
                                          variability=Fmi2Variability.fixed, description=description))
        for name, description in _REAL_PARAMETERS.items():
            self.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                        description=description))
        for name, description in inputs.items():
            self.register_variable(Real(name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                                        description=description))
        for v in outputs.values():
            self.register_variable(Real(v.name, causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                                        initial=Fmi2Initial.calculated, description=v.description))
        self.register_variable(Integer("status", causality=Fmi2Causality.output, variability=Fmi2Variability.discrete,
                                       initial=Fmi2Initial.calculated,
                                       description="0 ok; 1 last input rejected (non-finite), outputs held; "
                                                   "2 configuration error (see log), outputs invalid"))

    # ------------------------------------------------------------------------------------------ model description
    def to_xml(self, model_options=dict()):
        """pythonfmu's description plus units and the InitialUnknowns that FMI 2.0 requires for the outputs."""
        options = dict(model_options)
        options.update(canGetAndSetFMUstate=True, canSerializeFMUstate=True)  # the whole state: _get_fmu_state
        root = super().to_xml(options)
        units = {k: u for k, u in self._units.items() if u != "1"}
        from mftyre.variables import UNIT_BASES

        defs = Element("UnitDefinitions")
        for unit in sorted(set(units.values())):
            SubElement(SubElement(defs, "Unit", name=unit), "BaseUnit",
                       {k: str(v) for k, v in UNIT_BASES[unit].items()})
        position = list(root).index(root.find("CoSimulation")) + 1
        root.insert(position, defs)
        outputs = []
        for i, sv in enumerate(root.find("ModelVariables"), start=1):
            name = sv.get("name")
            real = sv.find("Real")
            if real is not None and name in units:
                real.set("unit", units[name])
            if sv.get("causality") == "output":
                outputs.append(i)
        structure = root.find("ModelStructure")
        initial = SubElement(structure, "InitialUnknowns")
        for i in outputs:
            SubElement(initial, "Unknown", index=str(i))
        return root

    def _read_config(self):
        try:
            with open(os.path.join(self.resources or ".", "config.json"), encoding="utf-8") as fh:
                return json.load(fh)
        except Exception:  # building without a config: generic start values
            return {}

    # ------------------------------------------------------------------------------------------------- logging
    def _error(self, message):
        self.log(message, Fmi2Status.error)

    # -------------------------------------------------------------------------------------------------- set-up
    def exit_initialization_mode(self):
        try:
            import warnings

            with warnings.catch_warnings(record=True) as caught:  # model warnings go to the FMI log
                warnings.simplefilter("always")
                self._setup()
                self._compute()
            for w in caught:
                self.log(f"{w.category.__name__}: {w.message}", Fmi2Status.warning)
        except Exception as exc:  # logged with its cause (as the native FMU words it), then raised: see the notes
            detail = "" if _user_error(exc) else "\n" + traceback.format_exc(limit=3)
            self._fail(f"initialisation failed: {exc}{detail}")
            raise RuntimeError(f"initialisation failed: {exc}") from None

    def _fail(self, message):
        self._problem = message
        self.status = 2
        self._error(message)

    def _setup(self):
        cfg = self._config
        self._problem = None
        model_name = self.model.strip().lower()
        if model_name not in ("steady", "swift"):
            raise ValueError(f"parameter model must be 'steady' or 'swift', got {self.model!r}")
        mode = self.input_mode.strip().lower()
        if mode not in ("vehicle", "rig"):
            raise ValueError(f"parameter input_mode must be 'vehicle' or 'rig', got {self.input_mode!r}")
        vertical = self.vertical_input.strip().lower()
        if vertical not in ("load", "position"):
            raise ValueError(f"parameter vertical_input must be 'load' or 'position', got {self.vertical_input!r}")
        side = self.side.strip().lower() or None
        if side not in (None, "left", "right"):
            raise ValueError(f"parameter side must be 'left' or 'right', got {self.side!r}")
        rim = self.rim.strip().lower() or "speed"
        if model_name == "swift":
            if mode == "rig":
                raise ValueError("parameter input_mode='rig' is for model='steady' only: the SWIFT model needs the "
                                 "wheel-centre motion (input_mode='vehicle')")
            if rim not in ("speed", "torque"):
                raise ValueError(f"parameter rim must be 'speed' or 'torque', got {self.rim!r}")
        elif mode == "rig" and self._turn_slip:
            raise ValueError("parameter input_mode='rig' has no turn slip (the slips and the load are imposed) and "
                             "this FMU was built with turn slip: use input_mode='vehicle'")
        resources = self.resources or "."
        self._import_mftyre(resources, swift=model_name == "swift")
        import mftyre
        from mftyre.transient import WheelTyre
        from mftyre.compiled import install_libraries

        tir = self.tir_file.strip()
        embedded = not tir
        path = os.path.join(resources, cfg.get("tir", "tyre.tir")) if embedded else tir
        if not os.path.exists(path):  # a FIFO or device exists: load_tir refuses it as not a regular file
            raise ValueError(f"parameter tir_file: no such file {path!r}")
        model = mftyre.load_tir(path, side=side)
        shipped = embedded and model.side == cfg.get("side")
        functions_dir = os.path.join(resources, "functions") if shipped else None
        index = cfg.get("functions") if shipped else None
        evaluator = self.evaluator.strip().lower() or "auto"
        if evaluator not in ("auto", "compiled", "casadi"):
            raise ValueError(f"parameter evaluator must be one of auto, compiled, casadi; got {self.evaluator!r}")
        warn = lambda m: self.log(m, Fmi2Status.warning)  # noqa: E731
        self._x_road = float(self.x_start)
        if model_name == "swift":
            self._core, step = self._swift_wheel(model, vertical, rim, evaluator, functions_dir, index, warn)
            self._mode = "swift"
            detail = (f"model swift (rim {rim}, road {self.road.strip() or 'flat'}), vertical_input {vertical}, "
                      f"step {step}")
        else:
            if functions_dir is not None and index and index.get("wheel"):  # the compiled wheels shipped
                try:
                    install_libraries(os.path.join(functions_dir, "wheel"), index["wheel"])
                except Exception as exc:  # read-only cache...: compiled now instead
                    warn(f"shipped wheel libraries not installed: {exc}")
            self._core = WheelTyre(model, "steady", vertical, turn_slip=self._turn_slip, input_mode=mode,
                                   evaluator=evaluator)
            self._mode = "rig" if mode == "rig" else vertical
            detail = (f"input_mode {mode}{'' if mode == 'rig' else ', vertical_input ' + vertical}, "
                      f"evaluator {self._core.evaluator}")
        self.log(f"{cfg.get('tir_name', os.path.basename(path)) if embedded else path}: FITTYP "
                 f"{model.params.fittyp}, mounted {model.side}, {detail}{', turn slip' if self._turn_slip else ''}",
                 Fmi2Status.ok)

    def _swift_wheel(self, model, vertical, rim, evaluator, functions_dir, index, warn):
        """(swift.fmu_model.SwiftWheel of the parameters, "compiled" or "casadi")."""
        from swift.fmu_model import SwiftWheel
        from swift.road import parse_road
        from mftyre.compiled import install_libraries

        for name in ("max_step", "axle_mass"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"parameter {name} must be positive, got {value!r}")
        if not math.isfinite(float(self.x_start)):
            raise ValueError(f"parameter x_start must be finite, got {self.x_start!r}")
        road = parse_road(self.road, os.getcwd())
        if functions_dir is not None and index and index.get("swift"):  # the compiled SWIFT wheels shipped
            try:
                install_libraries(os.path.join(functions_dir, "swift"), index["swift"])
            except Exception as exc:  # read-only cache...: compiled now instead
                warn(f"shipped SWIFT libraries not installed: {exc}")
        options = dict(x_start=float(self.x_start), rim=rim, axle="load" if vertical == "load" else "height",
                       axle_mass=float(self.axle_mass), turn_slip=self._turn_slip)
        wheel = None
        if evaluator in ("auto", "compiled"):
            try:
                wheel = SwiftWheel(model, road, compiled=True, **options)
            except Exception as exc:  # no C compiler...
                if evaluator == "compiled":
                    raise ValueError(f"compiled SWIFT wheel unavailable: {exc}") from None
                warn(f"compiled SWIFT wheel unavailable ({exc}); using CasADi's virtual machine (slow)")
        if wheel is None:
            wheel = SwiftWheel(model, road, compiled=False, **options)
        wheel.set_parameters(x_start=float(self.x_start), max_step=float(self.max_step))
        return wheel, "compiled" if wheel.library is not None else "casadi"

    @staticmethod
    def _import_mftyre(resources, swift=False):
        vendor = os.path.join(resources, "vendor")
        for name in ("mftyre",) + (("swift",) if swift else ()):
            try:
                __import__(name)  # the host's installed package
            except ImportError:
                if vendor not in sys.path:
                    sys.path.append(vendor)
                __import__(name)

    # ---------------------------------------------------------------------------------------------- FMU state
    def _get_fmu_state(self):
        """The whole state: the FMI variables, and the tyre's internal state (SWIFT ring, road frames, x_road)."""
        state = {"variables": super()._get_fmu_state(), "x_road": self._x_road, "problem": self._problem}
        core = self._core
        if core is not None and getattr(core, "state", None) is not None:
            state["swift"] = {"state": [float(v) for v in core.state]}
        return state

    def _set_fmu_state(self, state):
        if not isinstance(state, dict) or "variables" not in state:
            raise ValueError("not a state of this FMU")
        if "swift" in state and (self._core is None or self._mode != "swift"):
            raise ValueError("a SWIFT state cannot be restored into an instance that is not initialised as SWIFT")
        super()._set_fmu_state(state["variables"])
        self._x_road, self._problem = state["x_road"], state["problem"]
        if "swift" in state:
            import numpy as np

            sw = state["swift"]
            self._core.state = np.array(sw["state"], dtype=float)

    # ------------------------------------------------------------------------------------------------- stepping
    def do_step(self, current_time, step_size):
        try:
            if self._problem is not None or self._core is None:
                self._error("the tyre is not usable: " + (self._problem or "initialisation did not complete"))
                return False
            if not (math.isfinite(step_size) and step_size > 0):
                self._error(f"step at t={current_time}: step size {step_size!r} rejected (must be positive and "
                            "finite); outputs and state keep their last valid values")
                self.status = 1
                return False
            return self._compute(step_size)
        except Exception as exc:
            self._error(f"step at t={current_time}: {exc}")
            self.status = 1
            return False

    def _compute(self, step_size=None):
        """Outputs from the current inputs: at initialisation (step_size None) or after a step of step_size."""
        core = self._core
        mode = self._mode
        if mode == "swift":
            return self._compute_swift(step_size)
        names = core.functions.input_names  # the wheel's inputs in this mode (mftyre.transient.input_table)
        values = [getattr(self, n) for n in names]
        bad = [f"{n}={v!r}" for n, v in zip(names, values) if not math.isfinite(v)]
        if not bad and not values[names.index("p")] > 0:
            bad = [f"p={values[names.index('p')]!r} (the inflation pressure must be positive)"]
        if bad:
            self._error(f"input rejected: {', '.join(bad)}; outputs keep their last valid values")
            self.status = 1
            return False
        core.set_inputs(**dict(zip(names, values)))
        out = core.outputs()
        if not all(math.isfinite(v) for v in out.values()):
            self._error(f"the model returned non-finite outputs for {dict(zip(names, values))}; outputs held")
            self.status = 1
            return False
        if step_size is not None:
            self._x_road += self.vx * step_size
        out["Fz_c"] = out["Fz"]
        out["road_w"] = self.road_z if mode == "position" else 0.0
        out["road_slope"] = 0.0
        out["x_road"] = self._x_road
        for k, v in out.items():
            setattr(self, k, v)
        self.status = 0
        return True

    def _compute_swift(self, step_size):
        core = self._core
        u = {n: getattr(self, n) for n in core.functions.input_names}  # this mode's (swift.fmu_model.input_table)
        bad = [f"{n}={v!r}" for n, v in u.items() if not math.isfinite(v)]
        if not bad and not u["p"] > 0:
            bad = [f"p={u['p']!r} (the inflation pressure must be positive)"]
        if not bad and self.mu_scale != 1.0:
            bad = [f"mu_scale={self.mu_scale!r} (the SWIFT model has no friction scale: leave it at 1)"]
        if not bad and self._turn_slip and self.yaw_rate != 0.0:
            bad = [f"yaw_rate={self.yaw_rate!r} (the SWIFT wheel frame does not yaw; its turn slip is the contact "
                   "patch's yaw relative to the rim: leave it at 0)"]
        if not bad and step_size is not None and not step_size >= 0:
            bad = [f"communication step size {step_size!r}"]
        if bad:
            self._error(f"input rejected: {', '.join(bad)}; outputs and state keep their last valid values")
            self.status = 1
            return False
        try:
            core.set_inputs(**u)
            if step_size is None:
                core.initialise()
            else:
                core.step(step_size)
            out = core.outputs()
            if not all(math.isfinite(v) for v in out.values()):
                raise ArithmeticError("non-finite outputs")
        except Exception as exc:
            if step_size is None:
                raise
            self._error(f"SWIFT step rejected ({exc}); outputs and state keep their last valid values")
            self.status = 1
            return False
        for k, v in out.items():
            setattr(self, k, v)
        self.status = 0
        return True
