"""CasADi path: agreement with NumPy on the reference grids, exact derivatives, smoothing, compiled C."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import mftyre
from conftest import MFEVAL_DIR, TIR_FILES, require_shared
from mftyre.formula import OUTPUT_NAMES, Modes

casadi = pytest.importorskip("casadi")

REFERENCE_TIR = {"mf61": "MagicFormula61_Parameters.tir", "mf62": "MagicFormula62_Parameters.tir",
                 "mf52": "MagicFormula52_Parameters.tir"}
MOMENTS = {"mx", "my", "mz", "mzr"}
FORCES = {"fx", "fy", "fz"}


def _floor(prm, name):
    """Absolute floor of the relative comparison: near zero crossings a relative error is meaningless."""
    if name in FORCES:
        return prm.FNOMIN
    if name in MOMENTS:
        return prm.FNOMIN * prm.UNLOADED_RADIUS
    return 1e-300


@pytest.mark.parametrize("table", ["mf61_random", "mf61_turnslip_random", "mf61_lowspeed", "mf61_reverse",
                                   "mf61_modes", "mf61_omega_input", "mf62_random", "mf62_modes", "mf62_load",
                                   "mf62_pure_lat", "mf52_random"])
def test_casadi_agrees_with_numpy_on_reference_grids(table):
    """1e-12 relative (floors FNOMIN N, FNOMIN R0 N m) on the inputs of the shared MFeval tables."""
    require_shared(MFEVAL_DIR)
    model = mftyre.load_tir(MFEVAL_DIR / REFERENCE_TIR[table.split("_")[0]])
    prm = model.params
    df = pd.read_csv(MFEVAL_DIR / f"{table}.csv")
    for mode, rows in df.groupby("useMode"):
        modes = Modes.from_use_mode(mode)
        given = bool((rows["in_omega"] != 0).all())
        names = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p") + (("omega",) if given else ())
        columns = ["in_Fz", "in_kappa", "in_alpha", "in_gamma", "in_phit", "in_Vx", "in_P"] + (["in_omega"] if given else [])
        x = [rows[c].to_numpy(float) for c in columns]
        f = model.casadi_function(names, turn_slip=modes.turn_slip, alpha_star=modes.alpha_star, limits=modes.limits)
        values = f.map(len(rows))(*[v[None, :] for v in x])
        ref = model.evaluate(*x[:5], vx=x[5], p=x[6], omega=x[7] if given else None, turn_slip=modes.turn_slip,
                             alpha_star=modes.alpha_star, limits=modes.limits)
        for name, value in zip(OUTPUT_NAMES, values):
            ours, expected = np.asarray(value).ravel(), ref[name]
            bound = 1e-12 * np.maximum(np.abs(expected), _floor(prm, name))
            assert np.all(np.abs(ours - expected) <= bound), (table, mode, name)


def _zero_shift_model(name):
    """The sample tyre with the horizontal/vertical shifts of Fx0 and Fy0 removed: zero slip is the origin."""
    model = mftyre.load_tir(TIR_FILES / name)
    return model.with_params(PHX1=0.0, PHX2=0.0, PVX1=0.0, PVX2=0.0, PHY1=0.0, PHY2=0.0, PVY1=0.0, PVY2=0.0)


@pytest.mark.parametrize("tir", ["car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir"])
def test_slopes_at_zero_slip_equal_kya_and_kxk(tir):
    model = _zero_shift_model(tir)
    f = model.casadi_function(("fz", "kappa", "alpha", "p"), ("fx", "fy", "kxk", "kya"))
    fz, kappa, alpha, p = (casadi.SX.sym(n) for n in ("fz", "kappa", "alpha", "p"))
    fx, fy, kxk, kya = f(fz, kappa, alpha, p)
    slopes = casadi.Function("s", [fz, kappa, alpha, p],
                             [casadi.jacobian(fx, kappa), casadi.jacobian(fy, alpha), kxk, kya])
    for load in (0.5, 1.0, 1.8):
        for pressure in (1.8e5, 2.2e5, 2.6e5):
            dfx, dfy, k_x, k_y = (float(v) for v in slopes(load * model.params.FNOMIN, 0.0, 0.0, pressure))
            assert dfx == pytest.approx(k_x, rel=1e-9)
            assert dfy == pytest.approx(k_y, rel=1e-9)


@pytest.mark.parametrize("tir", ["car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir"])
@pytest.mark.parametrize("turn_slip", [False, True])
def test_jacobian_matches_central_differences(tir, turn_slip):
    """Exact Jacobian of every output w.r.t. every input against central differences of the NumPy model."""
    model = mftyre.load_tir(TIR_FILES / tir)
    prm = model.params
    names = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p")
    outputs = ("fx", "fy", "mz", "mx", "my", "re", "rl", "rho", "t", "mzr", "a", "sigmax", "sigmay")
    f = model.casadi_function(names, outputs, turn_slip=turn_slip)
    jac = f.jacobian()
    rng = np.random.default_rng(3)
    scales = dict(fz=prm.FNOMIN, kappa=0.1, alpha=0.1, gamma=0.05, phit=0.2, vx=20.0, p=prm.NOMPRES)
    for _ in range(6):
        x = dict(fz=rng.uniform(0.4, 1.6) * prm.FNOMIN, kappa=rng.uniform(-0.15, 0.15),
                 alpha=rng.uniform(-0.15, 0.15), gamma=rng.uniform(-0.05, 0.05),
                 phit=rng.uniform(-0.3, 0.3) if turn_slip else 0.0, vx=rng.uniform(8, 30),
                 p=rng.uniform(0.85, 1.15) * prm.NOMPRES)
        args = [x[n] for n in names]
        blocks = jac(*args, *f(*args))
        for j, name in enumerate(names):
            if name == "phit" and not turn_slip:
                continue
            h = 1e-5 * scales[name]
            plus, minus = dict(x), dict(x)
            plus[name] += h
            minus[name] -= h
            op = model.evaluate(**plus, turn_slip=turn_slip)
            om = model.evaluate(**minus, turn_slip=turn_slip)
            for i, out in enumerate(outputs):
                exact = float(blocks[i * len(names) + j])
                fd = (float(op[out]) - float(om[out])) / (2 * h)
                size = abs(float(model.evaluate(**x, turn_slip=turn_slip)[out])) / scales[name]
                assert exact == pytest.approx(fd, rel=1e-6, abs=1e-7 * size + 1e-12), (out, name, x)


@pytest.mark.parametrize("eps", [1e-4, 1e-6])
def test_smooth_model_stays_within_bound_of_exact(eps):
    """smooth=eps changes the outputs by O(eps): here at most 20 eps relative to the output scale."""
    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    prm = model.params
    outputs = ("fx", "fy", "mz", "mx", "my")
    exact = model.casadi_function(outputs=outputs)
    smooth = model.casadi_function(outputs=outputs, smooth=eps)
    rng = np.random.default_rng(5)
    n = 2000
    x = [rng.uniform(0.2, 2.0, n) * prm.FNOMIN, rng.uniform(-0.5, 0.5, n), rng.uniform(-0.4, 0.4, n),
         rng.choice([0.0, 1e-7, -1e-7, 0.03], n), np.zeros(n), rng.uniform(5, 30, n),
         rng.uniform(0.9, 1.1, n) * prm.NOMPRES]
    x[1][:50] = 0.0  # exactly on the kinks of sign(kappa) and |gamma|
    x[2][50:100] = 0.0
    a = exact.map(n)(*[v[None, :] for v in x])
    b = smooth.map(n)(*[v[None, :] for v in x])
    for name, va, vb in zip(outputs, a, b):
        va, vb = np.asarray(va).ravel(), np.asarray(vb).ravel()
        scale = prm.FNOMIN * (prm.UNLOADED_RADIUS if name.startswith("m") else 1.0)
        assert np.max(np.abs(va - vb)) <= 20 * eps * scale, name
        assert np.max(np.abs(va - vb)) > 0  # the smoothing is really applied
    # smooth and differentiable at the kink: the derivative of |gamma| terms exists at gamma = 0
    g = casadi.SX.sym("g")
    mz = model.casadi_function(("gamma",), ("mz",), fixed=dict(fz=4000.0, kappa=0.0, alpha=0.02), smooth=eps)(g)
    d2 = casadi.Function("d2", [g], [casadi.jacobian(casadi.jacobian(mz, g), g)])
    assert np.isfinite(float(d2(0.0)))


def test_compiled_model_matches_and_is_cached(tmp_path):
    from mftyre.compiled import compile_model

    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")
    compiled = compile_model(model, directory=tmp_path)
    libraries = list(tmp_path.glob("*.so"))
    assert len(libraries) == 1
    stamp = libraries[0].stat().st_mtime_ns
    again = compile_model(model, directory=tmp_path)  # cached: no recompilation
    assert libraries[0].stat().st_mtime_ns == stamp and again.library == compiled.library
    other = compile_model(model.with_params(LMUY=0.9), directory=tmp_path)  # new parameters, new library
    assert other.library != compiled.library

    point = (4500.0, -0.04, 0.06, 0.02, 0.0, 22.0, 2.0e5)
    ref = model.evaluate(*point[:5], vx=point[5], p=point[6])
    for name, value in zip(compiled.outputs, compiled(*point)):
        assert value == pytest.approx(float(ref[name]), rel=1e-11, abs=1e-11 * _floor(model.params, name)), name
    rng = np.random.default_rng(2)
    n = 700  # not a multiple of the batch size
    x = [rng.uniform(1000, 8000, n), rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n), 0.01, 0.0, 20.0, 2.2e5]
    batch = compiled.batch(*x)
    ref = model.evaluate(*x[:5], vx=x[5], p=x[6])
    for name, value in zip(compiled.outputs, batch):
        np.testing.assert_allclose(value, ref[name], rtol=1e-11, atol=1e-11 * min(_floor(model.params, name), 1e6),
                                   err_msg=name)
    assert model.with_params(LMUY=0.9).evaluate(4000.0, 0.0, 0.1).fy == pytest.approx(
        other(4000.0, 0.0, 0.1, 0.0, 0.0, model.params.LONGVL, model.params.INFLPRES)[1], rel=1e-11)


@pytest.mark.parametrize("tir", ["car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir"])
def test_symbolic_parameters_match_with_params_and_differences(tir):
    """.tir parameters as symbols: same values as the NumPy model with those values; exact sensitivities."""
    model = mftyre.load_tir(TIR_FILES / tir)
    prm = model.params
    names = ("LMUY", "PKY1", "VERTICAL_STIFFNESS", "PFZ1", "QDZ1")
    f = model.casadi_function(("fz", "kappa", "alpha", "p"), ("fy", "mz", "rl"), parameters=names)
    point = (4500.0, 0.03, 0.06, 2.0e5)
    values = [prm[n] * 1.1 for n in names]
    changed = model.with_params(**dict(zip(names, values))).evaluate(*point[:3], p=point[3])
    for out, name in zip(f(*point, *values), ("fy", "mz", "rl")):
        assert float(out) == pytest.approx(float(changed[name]), rel=1e-12), name
    jac = f.jacobian()
    blocks = jac(*point, *values, *f(*point, *values))
    n_in = 4 + len(names)
    for j, name in enumerate(names):
        h = 1e-6 * abs(values[j])
        plus = model.with_params(**{**dict(zip(names, values)), name: values[j] + h}).evaluate(*point[:3], p=point[3])
        minus = model.with_params(**{**dict(zip(names, values)), name: values[j] - h}).evaluate(*point[:3], p=point[3])
        for i, out in enumerate(("fy", "mz", "rl")):
            fd = (float(plus[out]) - float(minus[out])) / (2 * h)
            exact = float(blocks[i * n_in + 4 + j])
            assert exact == pytest.approx(fd, rel=1e-5, abs=1e-9 * abs(float(changed[out])) / abs(values[j])), (out, name)


def test_structural_parameters_cannot_be_symbolic():
    from mftyre.errors import ModelInputError

    model = mftyre.load_tir(TIR_FILES / "car_205_60R15_mf61.tir")
    with pytest.raises(ModelInputError, match="form of the equations"):
        model.casadi_function(parameters=("QSX1",))
