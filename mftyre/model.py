"""MFModel: the public face of the steady-state Magic Formula.

    >>> import mftyre
    >>> model = mftyre.load_tir("tir_files/car_205_60R15_mf61.tir")
    >>> out = model.evaluate(fz=4000, kappa=0.0, alpha=np.linspace(-0.2, 0.2, 41))
    >>> out.fy, out.mz, out.to_frame()

Axes and units: ISO-W (TYDEX W) contact-point axes, SI units (N, N m, rad, m, m/s, Pa, rad/s).

Tyre side. ``TYRESIDE`` in a .tir file names the side on which the tyre was measured. A model mounted on the
other side (``side=`` of :func:`load_tir` / :class:`MFModel`) is the mirror image of the measured tyre in the
wheel's x-z plane: the lateral inputs alpha, gamma and phit change sign before the equations, and the lateral
outputs Fy, Mx, Mz and Mzr change sign after them. Everything else (Fx, Fz, My, radii, patch, friction,
stiffnesses, trail, relaxation lengths) is unchanged: mirroring turns the tyre's own asymmetries (ply steer,
conicity, the camber-induced shifts) into their mirror images and keeps the symmetric behaviour as it is.
"""
from __future__ import annotations

import functools

import numpy as np

from .errors import ModelInputError
from .inputs import LoadFactorCheck, PressureFactorCheck, check_finite, check_finite_outputs, check_limits, \
    check_pressure, check_tyre_outputs, hard_limits, input_ranges, saturate, warn_outside
from .formula import OUTPUT_NAMES, Modes, steady_state, vertical
from .backend import NUMPY, NUMPY_FOLDING
from .params import SELECTS_FORM
from .variables import MF_OUTPUTS, unit_table

__all__ = ["MFModel", "MFOutputs", "load_tir", "OUTPUT_UNITS", "SymbolicParameters", "ParametricModel",
           "FORM_PARAMETERS", "run_time_parameter_names", "structure_of"]

#: Unit and meaning of every output (the table :data:`mftyre.variables.MF_OUTPUTS`).
OUTPUT_UNITS = unit_table(MF_OUTPUTS)
assert tuple(OUTPUT_UNITS) == OUTPUT_NAMES

_INPUT_ORDER = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p", "omega")
#: points per chunk of a large batch (see MFModel._evaluate_arrays). Measured (bench_casadi.py, 1e5 points, one core):
#: 6 000 to 34 000 points per chunk take the same time within the noise; smaller chunks pay the ~0.5 ms of Python and
#: NumPy call overhead of the ~830 array operations of one evaluation more often (2 048: +40 %), larger ones leave
#: the cache (50 000: +10 %; unchunked 1e5 MF 6.2: +40 %). 16 384 also keeps a 1e4 batch in a single call.
_CHUNK = 16384
#: from this many points on, array evaluations fold the .tir coefficients that are exactly 0 or 1 (see
#: mftyre.backend.ExactCoefficient). Measured (one core, MF 6.1 sample file): 1e3 points +5 %, 3e3 -2 %, 1e5 -12 %:
#: below it the Python dispatch of the folding costs more than the array operations it saves.
_FOLD_POINTS = 2048
_MIRRORED_INPUTS = ("alpha", "gamma", "phit")
_MIRRORED_OUTPUTS = ("fy", "mx", "mz", "mzr", "alpha", "gamma", "phit")
_SIDES = ("left", "right")


class MFOutputs:
    """Every output of one evaluation as named NumPy arrays (see :data:`OUTPUT_UNITS`). No array shares memory with
    another or with an input; those of a batch above 16 384 points are rows of one block (keeping one array keeps
    the block: ``out.fx.copy()`` keeps Fx alone)."""

    __slots__ = OUTPUT_NAMES

    def __init__(self, **values):
        for name in OUTPUT_NAMES:
            setattr(self, name, values[name])

    def __getitem__(self, name):
        if name not in OUTPUT_NAMES:
            raise KeyError(f"no output {name!r}; outputs are {', '.join(OUTPUT_NAMES)}")
        return getattr(self, name)

    def keys(self):
        return OUTPUT_NAMES

    def as_dict(self) -> dict:
        return {name: getattr(self, name) for name in OUTPUT_NAMES}

    def to_frame(self):
        """A pandas DataFrame, one row per evaluated point, one column per output (SI)."""
        import pandas as pd

        cols = {name: np.ravel(np.broadcast_to(getattr(self, name), np.shape(self.fx))) for name in OUTPUT_NAMES}
        return pd.DataFrame(cols)

    def __repr__(self):
        return f"MFOutputs(shape={np.shape(self.fx)}, outputs={', '.join(OUTPUT_NAMES)})"


def load_tir(path, *, side: str | None = None, strict: bool = False) -> "MFModel":
    """Read a .tir property file and return its :class:`MFModel` (mounted on ``side``, default the file's)."""
    from .tir import read_tir

    return MFModel(read_tir(path, strict=strict), side=side)


class MFModel:
    """A steady-state Magic Formula tyre defined by a parameter set.

    ``side``: 'left' or 'right', the side the tyre is mounted on; default: the file's TYRESIDE (no mirroring).
    """

    def __init__(self, params, *, side: str | None = None):
        self._params = params
        file_side = str(params["TYRESIDE"]).strip().strip("'\"").lower() if "TYRESIDE" in params else "right"
        if file_side not in _SIDES:
            raise ModelInputError(f"TYRESIDE must be 'LEFT' or 'RIGHT', got {params['TYRESIDE']!r}")
        if side is None:
            side = file_side
        side = str(side).lower()
        if side not in _SIDES:
            raise ModelInputError(f"side must be 'left' or 'right', got {side!r}")
        self.side = side
        self.mirrored = side != file_side
        self._plain = _PlainParameters(params)
        self._plain_folding = _PlainParameters(params, exact=True)  # for NUMPY_FOLDING (large arrays)

    @property
    def params(self):
        """The :class:`mftyre.params.TyreParameters` (SI) of this model."""
        return self._params

    def with_params(self, **changes) -> "MFModel":
        """A new model with some parameters changed, e.g. ``model.with_params(INFLPRES=2.0e5, LMUY=0.9)``; TirError
        naming the parameter when a value is one no tyre can have (the check of :func:`mftyre.tir.read_tir`)."""
        from .tir import validate_params

        params = self._params.replace(**changes)
        return MFModel(validate_params(params, "with_params"), side=self.side)

    def with_side(self, side: str) -> "MFModel":
        """The same tyre mounted on ``side``."""
        return MFModel(self._params, side=side)

    # ------------------------------------------------------------------------------------------ evaluation
    def evaluate(self, fz, kappa, alpha, gamma=0.0, phit=0.0, vx=None, p=None, omega=None, *,
                 turn_slip: bool = False, alpha_star: bool = False, limits: bool | str = True,
                 turn_slip_form: str = "published") -> MFOutputs:
        """Evaluate every output; inputs broadcast like NumPy.

        fz [N], kappa [-], alpha [rad], gamma [rad], phit [1/m], vx [m/s] (default LONGVL), p [Pa] (default
        INFLPRES), omega [rad/s] (default: estimated from kappa and vx). Keywords switch turn slip, alpha*
        (4.E3-4.E4), the .tir limits and low-speed model, and the form of the turn-slip K_zgamma,r0
        ('published' (4.99) or 'mfeval').

        Slips: alpha is ISO-W's atan(Vsy / |Vx|); kappa is the slip relative to the direction of travel,
        -Vsx / Vx = (omega Re - vx) / vx with the signed speed, as MFeval: -1 is a locked wheel and > 0 a wheel
        driven in the direction of travel, also for vx < 0 (rolling backwards), where Fx0 turns round with vx:
        Fx(-vx, kappa) = -Fx(vx, kappa), so a locked wheel brakes the motion either way (Fx > 0 reversing). The
        ISO-W slip -Vsx / |Vx| is sign(vx) kappa; a wheel model converts it with :func:`mftyre.transient.mf_slip`
        (both FMUs do). The omega estimated is (1 + kappa) vx / Re.

        ``limits=True`` (default) saturates kappa, alpha, gamma, p and Fz to the .tir ranges (KPUMIN/KPUMAX,
        ALPMIN/ALPMAX, CAMMIN/CAMMAX, PRESMIN/PRESMAX, FZMAX; FZMIN is no bound of the input, it raises the load
        in the aligning torque and the MF 6.1 deflection only, without a warning, see :mod:`mftyre.inputs`) and
        switches on the low-speed model below VXLOW; one :class:`mftyre.InputClippedWarning` per call names every
        input outside its range, the range and how many points were outside it (as MFeval reports them, the
        output p is the pressure used, kappa and alpha the low-speed-scaled slips before saturation, gamma and
        fz as given: see OUTPUT_UNITS; ``mftyre eval``'s NAME_used columns show the saturated values). ``limits=False`` evaluates the equations at the inputs as given,
        extrapolating beyond the fitted ranges, with no low-speed model. ``limits="smooth"`` (for decision
        variables of optimisers) is the identity inside the ranges and saturates softly beyond them, with the full
        slope a hair outside and 1 % left far outside (see :class:`mftyre.formula.Modes`).
        """
        modes = Modes(limits=limits, alpha_star=alpha_star, turn_slip=turn_slip, turn_slip_form=turn_slip_form)
        prm = self._params
        inputs = dict(fz=fz, kappa=kappa, alpha=alpha, gamma=gamma, phit=phit,
                      vx=prm.LONGVL if vx is None else vx, p=prm.INFLPRES if p is None else p,
                      omega=0.0 if omega is None else omega)
        arrays = as_float_arrays(inputs, copy=False)
        self._check_pressure(arrays["p"])
        check_limits(prm, arrays, limits, omega is not None, self._hard_limits)
        p_min, p_max = float(np.min(arrays["p"])), float(np.max(arrays["p"]))
        fz_min, fz_max = float(np.min(arrays["fz"])), float(np.max(arrays["fz"]))
        if limits:
            ranges = self._input_ranges
            counts = {name: saturate(arrays[name], ranges[name])[1] for name in ranges}
            warn_outside(counts, arrays["fz"].size, ranges)
            p_min, p_max = (min(max(v, ranges["p"][0]), ranges["p"][1]) for v in (p_min, p_max))
            fz_min, fz_max = (min(max(v, ranges["fz"][0]), ranges["fz"][1]) for v in (fz_min, fz_max))
        self.pressure_factors(p_min, p_max)
        self.load_factors(fz_min, fz_max, p_min, p_max)
        out = self._evaluate_arrays(arrays, omega is not None, modes, check_finite=True)
        check_tyre_outputs(out, arrays, prm, self._hard_limits)
        return MFOutputs(**out)

    def evaluate_chunked(self, fz, kappa, alpha, gamma=0.0, phit=0.0, vx=None, p=None, *,
                         outputs=("fx", "fy", "mz"), chunks=2**20, **options) -> dict:
        """Very large inputs (10^8 points: a driving simulator's look-up table) as ``dask.array`` chunks: output
        name -> a lazy dask array of the broadcast shape, each chunk evaluated by the compiled kernel
        (:func:`mftyre.compiled.compile_model` of these ``outputs`` and ``options``: turn_slip, alpha_star, limits,
        turn_slip_form), which checks its inputs as :meth:`evaluate` does (non-finite inputs or p <= 0 raise
        ModelInputError, values outside the .tir ranges warn) when computed. Inputs: numbers, NumPy or dask
        arrays (``chunks``: points per chunk of those that are not dask arrays yet, rounded up to a multiple of
        :data:`mftyre.compiled.BLOCK_POINTS`, so that the bits do not depend on it); omega is estimated from
        kappa and vx. Compute with ``dask.compute(*out.values())``: on the threads of this process (the kernel
        releases the GIL), or on the workers of a :class:`mftyre.runner.Runner` while its client is active; a
        chunk carries only the parameters and its inputs, each worker builds (or loads from the compile cache)
        the kernel once. The results agree with :meth:`evaluate` to about 3e-11 relative (the C's vector maths)
        and do not depend on the chunks (of a multiple of BLOCK_POINTS points)."""
        import dask.array as da

        from .compiled import BLOCK_POINTS

        chunks = -(-int(chunks) // BLOCK_POINTS) * BLOCK_POINTS
        prm = self._params
        values = [fz, kappa, alpha, gamma, phit, prm.LONGVL if vx is None else vx, prm.INFLPRES if p is None else p]
        shape = np.broadcast_shapes(*(np.shape(v) for v in values))
        arrays = da.broadcast_arrays(*(v if isinstance(v, da.Array) else
                                       da.from_array(np.asarray(v, dtype=float), chunks=chunks) for v in values))
        arrays = [a.reshape(-1) for a in arrays]
        arrays = da.unify_chunks(*(x for a in arrays for x in (a, "i")))[1]
        outputs = tuple(outputs)
        block = da.map_blocks(_compiled_block, *arrays, params=prm, side=self.side, outputs=outputs,
                              options=dict(options), dtype=float, new_axis=0,
                              chunks=((len(outputs),), arrays[0].chunks[0]), meta=np.empty((0, 0)))
        return {name: block[i].reshape(shape) for i, name in enumerate(outputs)}

    @functools.cached_property
    def pressure_factors(self) -> PressureFactorCheck:
        """Warns once per factor where the model is used at a pressure at which a pressure factor of the file has
        changed sign (:class:`mftyre.inputs.PressureFactorCheck`); call with the least and greatest pressure used."""
        return PressureFactorCheck(self._params)

    @functools.cached_property
    def load_factors(self) -> LoadFactorCheck:
        """Warns once per factor where the model is used at a load beyond which a slip stiffness of the file has the
        opposite sign to the one at FNOMIN (:class:`mftyre.inputs.LoadFactorCheck`); call with the least and
        greatest load and pressure used."""
        return LoadFactorCheck(self._params)

    def input_range(self, name: str) -> tuple[float, float]:
        """(lo, hi) that ``limits=True`` saturates input ``name`` to (:mod:`mftyre.inputs`), in the mounted side's
        axes (a mirrored model's alpha and gamma ranges are mirrored too); Fz: (-inf, FZMAX)."""
        return self._input_ranges[name][:2]

    @functools.cached_property
    def _hard_limits(self) -> dict:
        return hard_limits(self._params)

    @functools.cached_property
    def _input_ranges(self) -> dict:
        return input_ranges(self._params, self.mirrored)

    def used_input(self, name: str, values):
        """The values of input ``name`` that ``limits=True`` evaluates (saturated to :meth:`input_range`)."""
        return saturate(values, self.input_range(name))[0]

    def _evaluate_arrays(self, arrays: dict, omega_given, modes: Modes, check_finite: bool = False) -> dict:
        """Evaluate float arrays of one shape (no validation of the inputs; broadcast views are fine, they are only
        read). ``omega_given``: bool or boolean array. ``check_finite``: raise where the outputs are not finite
        (see :func:`_check_finite_outputs`).

        Batches larger than :data:`_CHUNK` points are evaluated chunk by chunk (the equations make hundreds of
        temporary arrays; a chunk's stay small and in the cache) into one block holding every output: one
        allocation per call (29 separate output arrays of a 1e5 batch cost ~110 ns/point in page faults), checked
        for non-finite values chunk by chunk while still in the cache."""
        shape = arrays["fz"].shape
        flat = {k: v.reshape(-1) for k, v in arrays.items()}
        if not isinstance(omega_given, bool):
            omega_given = np.broadcast_to(omega_given, shape).reshape(-1)
        n = flat["fz"].size
        if n == 1:  # one point: NumPy scalars (operations on them cost a fraction of those on arrays)
            given = omega_given if isinstance(omega_given, bool) else omega_given[0]
            point = [-flat[k][0] if self._mirrored_input(k) else flat[k][0] for k in _INPUT_ORDER]
            with np.errstate(all="ignore"):
                values = steady_state(self._plain, *point, given, modes, NUMPY)
            out = {k: np.array(v, dtype=float).reshape(1) for k, v in values.items()}
            self._mirror_outputs(out, slice(None))
        elif n <= _CHUNK:  # one chunk: the results are the outputs (no copy)
            chunk = self._chunk_inputs(flat, slice(None))
            prm, be = (self._plain_folding, NUMPY_FOLDING) if n >= _FOLD_POINTS else (self._plain, NUMPY)
            with np.errstate(all="ignore"):
                values = steady_state(prm, *chunk, omega_given, modes, be)
            out = _own_arrays(values, n, chunk)
            self._mirror_outputs(out, slice(None))
        else:
            block = np.empty((len(OUTPUT_NAMES), n))
            out = dict(zip(OUTPUT_NAMES, block))  # rows of one block: no output overlaps another
            finite = True
            chunks = -(-n // _CHUNK)
            size = -(-n // chunks)  # chunks of equal size (none much smaller than the others)
            for start in range(0, n, size):
                part = slice(start, min(start + size, n))
                given = omega_given if isinstance(omega_given, bool) else omega_given[part]
                with np.errstate(all="ignore"):
                    values = steady_state(self._plain_folding, *self._chunk_inputs(flat, part), given, modes,
                                          NUMPY_FOLDING)
                for k, v in values.items():
                    out[k][part] = v
                self._mirror_outputs(out, part)
                finite = finite and bool(np.isfinite(block[:, part]).all())
            check_finite = check_finite and not finite
        out = {k: v.reshape(shape) for k, v in out.items()}
        if check_finite:
            check_finite_outputs(out, arrays)
        return out

    def _mirrored_input(self, name: str) -> bool:
        return self.mirrored and name in _MIRRORED_INPUTS

    def _chunk_inputs(self, flat: dict, part: slice) -> list:
        """The inputs of the points ``part`` in equation order, contiguous, on the measured side's axes."""
        return [-flat[k][part] if self._mirrored_input(k) else np.ascontiguousarray(flat[k][part])
                for k in _INPUT_ORDER]

    def _mirror_outputs(self, out: dict, part: slice) -> None:
        """Lateral outputs of the points ``part`` to the mounted side's axes, in place (arrays owned by ``out``)."""
        if self.mirrored:
            for k in _MIRRORED_OUTPUTS:
                np.negative(out[k][part], out=out[k][part])

    # ------------------------------------------------------------------------------------------ casadi
    def casadi_function(self, inputs=("fz", "kappa", "alpha", "gamma", "phit", "vx", "p"), outputs=OUTPUT_NAMES,
                        *, turn_slip: bool = False, alpha_star: bool = False, limits: bool | str = True,
                        turn_slip_form: str = "published", fixed: dict | None = None, parameters=(),
                        smooth: float | bool | dict | None = None, name: str = "mftyre", early_stop: bool = False,
                        low_speed: bool = True):
        """A ``casadi.Function`` of the same equations, built from ``casadi.SX`` scalars.

        ``inputs``: the symbolic inputs, any of fz kappa alpha gamma phit vx p omega, as the first arguments in
        the order given. Inputs not listed take the value in ``fixed`` or their default (gamma = phit = 0,
        vx = LONGVL, p = INFLPRES; omega estimated from kappa and vx with 8 unrolled fixed-point steps, which
        converge to machine precision: the contraction factor is about 2 Q_V1 (omega R0 / V0)^2 < 1e-2).
        ``parameters``: .tir parameter names made symbolic too (further arguments, after the inputs), e.g.
        ``("LMUY", "PKY1")`` for identification or design studies; parameters that select a form of the
        equations (FITTYP, FZMIN, QSX1-QSX14, Q_CAM1, Q_CAM2, Q_A1, Q_A2, PHYP4, TYRESIDE) must stay numbers.
        ``outputs``: any of :data:`OUTPUT_NAMES`; the echoed inputs are named ``kappa_used``, ``alpha_used``...
        in the function (CasADi needs distinct input and output names).
        ``smooth``: None for the exact model; True rounds every kink over a width of its own quantity
        (:data:`mftyre.backend.SMOOTH_WIDTHS`: force 1 N (the contact at Fz = 0), speed 0.01 m/s (|Vx| and the
        low-speed switch at VXLOW), angle and slip 1e-4, other 1e-6), a mapping overrides some widths
        (``{"force": 10.0}``), a number is one width for all (see :class:`mftyre.backend.CasadiBackend`); outputs
        stay finite at any finite input, a negative Fz included.
        ``limits``: True saturates the inputs to the .tir ranges: the full derivative up to and at a bound
        (one-sided), exactly zero beyond it (and at Fz <= 0 the forces and their derivatives are zero: no
        contact); decision variables of an optimiser (a pressure bounded by PRESMIN..PRESMAX: an interior-point
        solver ends a hair outside an active bound) need ``limits="smooth"``: the full slope a hair outside, a
        soft saturation fading to 1 % further out (:class:`mftyre.formula.Modes`); False extrapolates.
        The MF 6.2 loaded radius is solved with up to 8 bracket-widening and 16 Dekker steps and a final
        Newton step, so its derivatives are those of the implicit function. ``early_stop``: the MF 6.2
        loaded-radius Newton steps stay put once converged (the NumPy solver's stopping tests; results within
        1e-12 relative of the full steps), which the compiled one-point C uses to skip the remaining steps
        (:func:`mftyre.compiled.compile_model` sets it there; ~15 % more operations in the graph, no gain
        elsewhere). ``low_speed=False`` (with limits): the caller keeps |vx| >= VXLOW, where the low-speed factors
        are 1, and the graph leaves the low-speed model out (SWIFT's slip model; below VXLOW it would be missing).
        Evaluate many points with ``f.map(n)``; :mod:`mftyre.compiled` compiles the function to C.
        """
        import casadi as ca
        from .backend import casadi_backend

        allowed = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p", "omega")
        unknown = [n for n in (*inputs, *(fixed or {})) if n not in allowed]
        if unknown:
            raise ModelInputError(f"unknown input(s) {unknown}; inputs are {', '.join(allowed)}")
        bad = [n for n in outputs if n not in OUTPUT_NAMES]
        if bad:
            raise ModelInputError(f"unknown output(s) {bad}; outputs are {', '.join(OUTPUT_NAMES)}")
        prm = self._params
        values = dict(gamma=0.0, phit=0.0, vx=prm.LONGVL, p=prm.INFLPRES, omega=0.0)
        for fixed_name, value in (fixed or {}).items():
            if not isinstance(value, ca.SX | ca.MX):
                check_finite(fixed_name, value)
        values.update(fixed or {})
        symbols = {n: ca.SX.sym(n) for n in inputs}
        values.update(symbols)
        missing = [n for n in ("fz", "kappa", "alpha") if n not in values]
        if missing:
            raise ModelInputError(f"input(s) {missing} must be symbolic or given in `fixed`")
        if self.mirrored:
            values = {k: (-v if k in _MIRRORED_INPUTS else v) for k, v in values.items()}
        parameter_symbols = {n: ca.SX.sym(n) for n in parameters}
        equations_prm = SymbolicParameters(prm, parameter_symbols) if parameters else prm
        modes = Modes(limits=limits, alpha_star=alpha_star, turn_slip=turn_slip, turn_slip_form=turn_slip_form,
                      low_speed=low_speed)
        omega_given = "omega" in inputs or "omega" in (fixed or {})
        out = steady_state(equations_prm, values["fz"], values["kappa"], values["alpha"], values["gamma"],
                           values["phit"], values["vx"], values["p"], values["omega"], omega_given, modes,
                           casadi_backend(smooth, early_stop), outputs=outputs)
        sign = {k: (-1.0 if self.mirrored and k in _MIRRORED_OUTPUTS else 1.0) for k in outputs}
        out_names = [f"{k}_used" if k in allowed else k for k in outputs]
        return ca.Function(name, [symbols[n] for n in inputs] + list(parameter_symbols.values()),
                           [sign[k] * ca.SX(out[k]) for k in outputs], list(inputs) + list(parameters), out_names)

    # ---------------------------------------------------------------------------------------- vertical
    def vertical_force(self, rl, p=None, omega=0.0, fx=0.0, fy=0.0, gamma=0.0):
        """Fz [N] at loaded radius ``rl`` [m]: the MF 6.1 load-deflection relation (A3.3) with rho = R_omega -
        Rl, or for FITTYP 62 the MF 6.2 relation with camber, Fx/Fy and speed terms; bottoming included. No
        limits apply: to check the ``rl`` of :meth:`evaluate` pass the inputs it used (``p``, ``omega``, forces
        from its outputs; gamma saturated, ``used_input("gamma", gamma)``, as limits=True evaluates it)."""
        a, dpi, r_omega = self._vertical_inputs(rl=rl, p=p, omega=omega, fx=fx, fy=fy, gamma=gamma)
        prm = self._params
        with np.errstate(all="ignore"):
            return vertical.vertical_force(prm, a["rl"], r_omega, a["omega"], a["fx"], a["fy"], a["gamma"], dpi, NUMPY)

    def loaded_radius(self, fz, p=None, omega=0.0, fx=0.0, fy=0.0, gamma=0.0):
        """(Rl, rho) [m] carrying the load ``fz`` [N]: the inverse of :meth:`vertical_force` (no limits applied)."""
        a, dpi, r_omega = self._vertical_inputs(fz=fz, p=p, omega=omega, fx=fx, fy=fy, gamma=gamma)
        prm = self._params
        fz_pos = np.maximum(a["fz"], 0.0)
        with np.errstate(all="ignore"):
            rl, rho = vertical.loaded_radius(prm, fz_pos, r_omega, a["omega"], a["fx"], a["fy"], a["gamma"], dpi, NUMPY)
            return rl.reshape(fz_pos.shape), rho.reshape(fz_pos.shape)

    def _vertical_inputs(self, p, **inputs):
        """Validated, broadcast, side-mirrored inputs of the vertical relations, dpi and R_omega."""
        a = as_float_arrays(dict(inputs, p=self._params.INFLPRES if p is None else p))
        self._check_pressure(a["p"])
        if self.mirrored:
            a["fy"], a["gamma"] = -a["fy"], -a["gamma"]
        dpi = vertical.pressure_increment(self._params, a["p"])
        return a, dpi, vertical.free_radius(self._params, a["omega"], NUMPY)

    @staticmethod
    def _check_pressure(p):
        check_pressure(p)

    def __repr__(self):
        src = getattr(self._params, "source", None)
        return f"MFModel(FITTYP={self._params.fittyp}, side={self.side!r}, source={src!r})"


#: Compiled kernels of this process for :meth:`MFModel.evaluate_chunked` (a digest of the parameters, side, outputs
#: and options -> CompiledFunction): each worker builds or loads a kernel once, whatever the number of chunks.
_KERNELS: dict = {}


def _compiled_block(*inputs, params, side, outputs, options):
    """One chunk of :meth:`MFModel.evaluate_chunked`: (outputs, points)."""
    import hashlib
    import pickle

    from .compiled import compile_model

    key = hashlib.sha256(pickle.dumps((params, side, outputs, sorted(options.items())))).hexdigest()
    kernel = _KERNELS.get(key)
    if kernel is None:
        kernel = _KERNELS[key] = compile_model(MFModel(params, side=side), outputs=outputs, **options)
    return np.array(kernel.batch(*inputs)).reshape(len(outputs), -1)


class _PlainParameters:
    """The values of a parameter set as plain attributes (the equations read hundreds of them per evaluation;
    TyreParameters' mapping lookup costs more than a single-point evaluation's arithmetic)."""

    def __init__(self, params, exact: bool = False):
        values = params.to_dict()
        self.__dict__.update(NUMPY.known_coefficients(values) if exact else values)
        self.version, self.fittyp = params.version, params.fittyp

    def __getitem__(self, name):
        return self.__dict__[name]


class SymbolicParameters:
    """A parameter set in which some parameters are CasADi symbols (for :meth:`MFModel.casadi_function` and the
    SWIFT graph with run-time parameters); the forms of the equations must stay numbers."""

    def __init__(self, params, symbols: dict):
        form = SELECTS_FORM | (vertical.MF62_SOLVER_FORM_PARAMETERS if params.version == "62" else frozenset())
        fixed = sorted(set(symbols) & form)  # (Python branches: they cannot be symbolic)
        if fixed:
            raise ModelInputError(f"parameter(s) {fixed} select the form of the equations and must stay numbers")
        unknown = sorted(n for n in symbols if n not in params)
        if unknown:
            raise ModelInputError(f"unknown parameter(s) {unknown}")
        self._params, self._symbols = params, symbols
        self.version, self.fittyp, self.missing = params.version, params.fittyp, params.missing

    def __getattr__(self, name):
        symbols = self.__dict__["_symbols"]
        return symbols[name] if name in symbols else getattr(self.__dict__["_params"], name)

    def __getitem__(self, name):
        return self._symbols[name] if name in self._symbols else self._params[name]

    def __contains__(self, name):
        return name in self._params

    def __iter__(self):
        return iter(self._params)


#: Parameters whose values choose a form of the equations (Python branches): numbers in any graph built with
#: run-time parameters (:data:`mftyre.params.SELECTS_FORM` and those the MF 6.2 loaded-radius solver branches on).
FORM_PARAMETERS = SELECTS_FORM | vertical.MF62_SOLVER_FORM_PARAMETERS


def run_time_parameter_names(params) -> list:
    """The .tir parameters a graph built with run-time parameters takes as inputs (in the file's order): every real
    number except those that select a form of the equations (:data:`FORM_PARAMETERS`) and those at 0. A parameter
    at 0 switches its effect off (the equations test some for 0, e.g. Q_FCY, and a compiler drops the terms they
    multiply), so which are 0 is part of the graph's structure (:func:`structure_of`)."""
    return [n for n in params if isinstance(params[n], float) and params[n] != 0.0 and n not in FORM_PARAMETERS]


def structure_of(model, names) -> dict:
    """What shapes a graph of ``model`` built with the run-time parameters ``names``: the values of the others, the
    absent ones, the version and the mounted side (a JSON-able mapping; equal mappings, one graph)."""
    prm = model.params
    return {"fixed": {k: repr(prm[k]) for k in prm if k not in names}, "run_time": list(names),
            "missing": sorted(prm.missing), "version": prm.version, "side": model.side}


class ParametricModel:
    """Stands in for an MFModel while a graph is built with run-time parameters: ``params`` the model's parameters
    with those of ``names`` as the CasADi ``symbols`` (:class:`SymbolicParameters`), ``casadi_function`` the model's
    with those parameters bound to the same symbols; the side as the model's."""

    def __init__(self, model, names, symbols):
        self._model, self._names, self._symbols = model, list(names), list(symbols)
        self.side, self.mirrored = model.side, model.mirrored
        self.params = SymbolicParameters(model.params, dict(zip(self._names, self._symbols)))

    def casadi_function(self, *, parameters=(), **options):
        """The model's function of its inputs and ``parameters`` (further symbolic parameters, after the inputs as
        :meth:`MFModel.casadi_function` takes them), the other run-time parameters bound to their symbols."""
        bound = [(n, symbol) for n, symbol in zip(self._names, self._symbols) if n not in parameters]
        function = self._model.casadi_function(parameters=(*parameters, *(n for n, _ in bound)), **options)
        return lambda *arguments: function(*arguments, *(symbol for _, symbol in bound))


def _own_arrays(values: dict, n: int, inputs: list) -> dict:
    """The outputs as arrays of n elements that share memory with no input and no other output: an array the
    equations made (it owns its memory) is kept, anything else (an input passed through, a view, a scalar) copied."""
    out, seen = {}, set(map(id, inputs))
    for k, v in values.items():
        if (type(v) is not np.ndarray or v.shape != (n,) or v.dtype != np.float64 or v.base is not None
                or id(v) in seen):
            v, value = np.empty(n), v
            v[...] = value
        seen.add(id(v))
        out[k] = v
    return out


def as_float_arrays(inputs: dict, copy: bool = True) -> dict:
    """Broadcast the inputs to one shape as float arrays (writable copies, or with ``copy=False`` read-only
    broadcast views); NaN, +-inf, numbers beyond binary64 (an int such as 10**400) or non-numeric ->
    ModelInputError naming the input."""
    arrays = {}
    for name, value in inputs.items():
        try:
            arr = np.asarray(value, dtype=float)
        except OverflowError as exc:
            raise ModelInputError(f"input {name!r} must be finite; got a number beyond the largest float "
                                  f"(~1.8e308): {_short(value)}") from exc
        except (TypeError, ValueError) as exc:
            raise ModelInputError(f"input {name!r} must be numeric, got {value!r}") from exc
        check_finite(name, arr)
        arrays[name] = arr
    try:
        broadcast = np.broadcast_arrays(*arrays.values())
    except ValueError as exc:
        shapes = {k: v.shape for k, v in arrays.items()}
        raise ModelInputError(f"inputs cannot be broadcast to one shape: {shapes}") from exc
    return {k: np.array(v) if copy else v for k, v in zip(arrays, broadcast)}


def _short(value) -> str:
    """``value`` as text for an error message, at most 60 characters (a 400-digit int is shortened)."""
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:28]}...{text[-28:]} ({len(text)} characters)"
