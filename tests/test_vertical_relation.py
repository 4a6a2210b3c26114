"""The MF 6.2 loaded radius carries its load: property tests of the vertical relation Fz(Rl) = Fz.

Random loads (including the low loads where the camber deflection alone carries more than the load, and high loads
in turn-slip mode), speeds, pressures, cambers and forces on every MF 6.2 file at hand: wherever the relation has
a root the returned Rl satisfies it to 1e-9 relative (floor 1e-9 N); where it has none the loaded radius is the
free radius and no root exists on a fine grid up to R0 above it (a wheel lifted further is not in contact); a root
above the free radius is the first one. NumPy and CasADi alike; the CasADi derivative of Rl is the implicit one,
-(dF/dFz_target)/(dF/dRl). The solver's slopes against finite differences.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import mftyre
from mftyre.errors import InputClippedWarning
from mftyre.backend import NUMPY
from mftyre.formula import vertical

from conftest import MFEVAL_DIR, SHARED, TIR_FILES, require_shared

FILES = {
    "sample_swift": TIR_FILES / "car_205_60R15_mf62_swift.tir",
    "mfeval_mf62": MFEVAL_DIR / "MagicFormula62_Parameters.tir",
    "tno_mf62": SHARED / "reference" / "tir" / "TNO_car205_60R15.tir",
}


def _model(key):
    return mftyre.load_tir(require_shared(FILES[key]))


def _carried_or_no_root(model, fz, rl, omega, p, fx, fy, gamma):
    """Boolean per point: the relation holds at rl, or rl = R_omega and no root exists on a grid up to R0 above it."""
    prm = model.params
    back = model.vertical_force(rl, p=p, omega=omega, fx=fx, fy=fy, gamma=gamma)
    carried = np.abs(back - fz) <= 1e-9 * np.maximum(fz, 1.0)
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    ok = carried.copy()
    for j in np.nonzero(~carried)[0]:
        grid = r_omega[j] + np.linspace(0.0, prm.UNLOADED_RADIUS, 4001)
        f = model.vertical_force(grid, p=p[j], omega=omega[j], fx=fx[j], fy=fy[j], gamma=gamma[j]) - fz[j]
        ok[j] = rl[j] == r_omega[j] and np.all(f > 0)
    return ok, carried


@pytest.mark.parametrize("key", list(FILES))
def test_loaded_radius_carries_its_load(key):
    model = _model(key)
    prm = model.params
    rng = np.random.default_rng(7)
    n = 4000
    fz = rng.uniform(0.0, 4.0 * prm.FNOMIN, n)
    fz[:1500] = rng.uniform(0.0, 600.0, 1500)  # low loads: the camber deflection may carry more
    fz[1500:1700] = 0.0
    omega = rng.uniform(0.0, 250.0, n)
    p = rng.uniform(prm.PRESMIN, prm.PRESMAX, n)
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    fx, fy = rng.uniform(-1.2, 1.2, (2, n)) * fz
    rl, _ = model.loaded_radius(fz, p=p, omega=omega, fx=fx, fy=fy, gamma=gamma)
    ok, carried = _carried_or_no_root(model, fz, rl, omega, p, fx, fy, gamma)
    assert ok.all(), np.c_[fz, omega, gamma, fy, rl][~ok][:5]
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    assert np.all(rl[fz == 0] >= r_omega[fz == 0])
    # a lifted tyre's root is the first above R_omega (the one the reference evaluator reports): the load still
    # exceeds fz everywhere between R_omega and Rl
    lifted = np.nonzero(carried & (rl > r_omega))[0]
    between = r_omega[lifted, None] + np.linspace(0.0, 1.0, 400, endpoint=False) * (rl - r_omega)[lifted, None]
    load = model.vertical_force(between, p=p[lifted, None], omega=omega[lifted, None], fx=fx[lifted, None],
                                fy=fy[lifted, None], gamma=gamma[lifted, None])
    assert np.all(load > fz[lifted, None])
    if prm.Q_FCY != 0 and prm.Q_FYS3 != 0:  # the lifted roots exist and are found
        assert np.sum(carried & (rl > r_omega)) > 100


@pytest.mark.parametrize("key", ["mfeval_mf62", "tno_mf62"])
@pytest.mark.parametrize("turn_slip", [False, True])
def test_evaluate_loaded_radius_carries_load_with_its_own_forces(key, turn_slip):
    """The relation at the returned Rl, Fx, Fy, spin and pressure gives the load back, turn slip included, up to
    1.5 FZMAX (above FZMAX the loaded radius is that of the load as given, the forces those at FZMAX: MFeval's
    split, docs/model-input-policy.md)."""
    model = _model(key)
    prm = model.params
    rng = np.random.default_rng(11)
    n = 1500
    top = 1.45 * prm.FZMAX
    fz = np.r_[rng.uniform(0.0, 800.0, n // 3), rng.uniform(800.0, top, n - n // 3 - 1), top]
    kappa, alpha = rng.uniform(-0.4, 0.4, (2, n))
    gamma = rng.uniform(-0.2, 0.2, n)
    phit = rng.uniform(-0.05, 0.05, n)
    vx = rng.uniform(1.0, 60.0, n)
    p = rng.uniform(0.8, 1.2, n) * prm.NOMPRES
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputClippedWarning)  # the loads above FZMAX, named in the warning
        out = model.evaluate(fz, kappa, alpha, gamma, phit, vx=vx, p=p, turn_slip=turn_slip)
    gamma_used = np.clip(gamma, prm.CAMMIN, prm.CAMMAX)
    ok, _ = _carried_or_no_root(model, fz, out.rl, out.omega, out.p, out.fx, out.fy, gamma_used)
    assert ok.all(), np.c_[fz, gamma, out.rl][~ok][:5]


def test_lifted_root_at_zero_load_and_high_speed():
    """Fz = 0 at 31 m/s with camber on the MF 6.2 sample of the reference evaluator: Rl >= R_omega, and Fz(Rl) = 0
    (the old solver returned R_omega, where the relation gives hundreds of newtons)."""
    model = _model("mfeval_mf62")
    gamma = np.array([-0.05, -0.02, 0.03, 0.08, 0.1])
    out = model.evaluate(0.0, 0.0, 0.0, gamma, vx=31.0)
    r_omega = vertical.free_radius(model.params, out.omega, NUMPY)
    assert np.all(out.rl > r_omega)
    back = model.vertical_force(out.rl, omega=out.omega, fx=out.fx, fy=out.fy, gamma=gamma)
    np.testing.assert_allclose(back, 0.0, atol=1e-9)


@pytest.mark.parametrize("turn_slip", [False, True])
def test_casadi_loaded_radius_matches_numpy_and_implicit_derivative(turn_slip):
    import casadi as ca

    model = _model("mfeval_mf62")
    prm = model.params
    rng = np.random.default_rng(3)
    n = 40
    fz = np.r_[rng.uniform(0.0, 300.0, n // 2), rng.uniform(300.0, 15000.0, n - n // 2)]
    kappa, alpha = rng.uniform(-0.2, 0.2, (2, n))
    gamma = rng.uniform(-0.1, 0.1, n)
    vx = rng.uniform(2.0, 40.0, n)
    ins = ("fz", "kappa", "alpha", "gamma", "phit", "vx")
    f = model.casadi_function(ins, ("rl",), turn_slip=turn_slip)
    fz_sym = ca.SX.sym("fz")
    others = [ca.SX.sym(k) for k in ins[1:]]
    rl_sym = f(fz_sym, *others)
    drl = ca.Function("drl", [fz_sym, *others], [ca.jacobian(rl_sym, fz_sym)])
    out = model.evaluate(fz, kappa, alpha, gamma, 0.0, vx=vx, turn_slip=turn_slip)
    for j in range(n):
        args = (fz[j], kappa[j], alpha[j], gamma[j], 0.0, vx[j])
        assert abs(float(f(*args)) - out.rl[j]) <= 1e-9 * prm.UNLOADED_RADIUS
        slope = float(drl(*args))
        assert np.isfinite(slope)
        if fz[j] > 500:  # central difference of the NumPy model (forces and spin follow the load too)
            h = 1e-3 * fz[j]
            up, down = (model.evaluate(fz[j] + d, kappa[j], alpha[j], gamma[j], 0.0, vx=vx[j], turn_slip=turn_slip).rl
                        for d in (h, -h))
            assert slope == pytest.approx((up - down) / (2 * h), rel=1e-4, abs=1e-12)


@pytest.mark.parametrize("path", [TIR_FILES / "car_205_60R15_mf61.tir", TIR_FILES / "car_205_60R15_mf62_swift.tir"],
                         ids=["mf61", "mf62"])
def test_vertical_force_is_zero_above_the_free_radius(path):
    """A lifted tyre carries nothing: Fz(Rl > R_omega) = 0 (it was -6000 N at 0.35 m), NumPy and CasADi."""
    import casadi as ca

    from mftyre.backend import casadi_backend

    model = mftyre.load_tir(path)
    prm = model.params
    r_omega = vertical.free_radius(prm, 0.0, NUMPY)
    rl = np.array([r_omega, r_omega + 1e-6, 0.33, 0.35, 0.5, 1.0])
    np.testing.assert_array_equal(model.vertical_force(rl), 0.0)
    assert np.all(model.vertical_force(rl, fy=3000.0, fx=-2000.0, omega=80.0) >= 0.0)
    assert model.vertical_force(r_omega - 0.01) > 1000.0  # and a deflected one does
    x = ca.SX.sym("rl")
    be = casadi_backend()
    if prm.version == "62":
        fz = vertical.vertical_force_62(prm, x, r_omega, 0.0, 0.0, 0.0, 0.0, 0.0, be)
    else:
        fz = vertical.vertical_force_61(prm, r_omega - x, r_omega, 0.0, 0.0, 0.0, 0.0, be)
    f = ca.Function("fz", [x], [fz])
    assert [float(f(v)) for v in rl] == [0.0] * len(rl)


@pytest.mark.parametrize("key", [*FILES, "tno_without_lift_bound"])
def test_casadi_loaded_radius_carries_its_load_at_extreme_inputs(key):
    """The unrolled CasADi solver (7 safeguarded Newton steps; with 5 a lifted one of these 60,000 points falls short)
    against the relation itself at zero, few-newton and low loads up to 250 rad/s (the cambered tyre's root above
    R_omega), 15 kN with |Fx|, |Fy| up to 1.2 Fz, any pressure and camber in range: Rl carries the load to 1e-9
    relative wherever NumPy finds a root, and the two agree. Also with Q_CAM2 < 0, where the lifted roots are not
    bounded below R_omega + R0 (8 steps from there; 6 fall short)."""
    import casadi as ca
    from mftyre.backend import casadi_backend

    if key == "tno_without_lift_bound":
        prm = _model("tno_mf62").params.replace(Q_CAM2=-50.0)
        assert not vertical._lift_bound_applies(prm)
    else:
        prm = _model(key).params
    be = casadi_backend()
    symbols = [ca.SX.sym(n) for n in ("fz", "omega", "fx", "fy", "gamma", "dpi")]
    fz_s, omega_s, fx_s, fy_s, gamma_s, dpi_s = symbols
    rl_s, _ = vertical.loaded_radius_62(prm, fz_s, vertical.free_radius(prm, omega_s, be), omega_s, fx_s, fy_s,
                                        gamma_s, dpi_s, be)
    rng = np.random.default_rng(7)
    n = 60000
    fz = np.r_[np.zeros(n // 10), rng.uniform(0.0, 600.0, n // 3), np.full(n // 10, 15000.0),
               rng.uniform(0.0, 5.0, n // 10)]
    fz = np.r_[fz, rng.uniform(0.0, 4.0 * prm.FNOMIN, n - fz.size)]
    omega = rng.uniform(0.0, 250.0, n)
    dpi = rng.uniform(prm.PRESMIN, prm.PRESMAX, n) / prm.NOMPRES - 1.0
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    fx, fy = rng.uniform(-1.2, 1.2, (2, n)) * fz
    inputs = (fz, omega, fx, fy, gamma, dpi)
    rl = np.array(ca.Function("rl", symbols, [rl_s]).map(n)(*inputs)).ravel()
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    rl_numpy, _ = vertical.loaded_radius_62(prm, fz, r_omega, omega, fx, fy, gamma, dpi, NUMPY)

    def carried(r):
        back = vertical.vertical_force_62(prm, r, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
        return np.abs(back - fz) <= 1e-9 * np.maximum(fz, 1.0)

    has_root = carried(rl_numpy)
    assert has_root.sum() > 0.6 * n
    assert np.all(carried(rl)[has_root]), np.c_[inputs][has_root & ~carried(rl)][:5]
    np.testing.assert_array_equal(rl[~has_root], r_omega[~has_root])  # no root: the free radius
    np.testing.assert_allclose(rl, rl_numpy, rtol=0, atol=1e-9 * prm.UNLOADED_RADIUS)
    if prm.Q_FCY != 0 and prm.Q_FYS3 != 0:  # the lifted roots are among them
        assert np.sum(rl[has_root] > r_omega[has_root]) > 50


@pytest.mark.parametrize("key", list(FILES))
def test_relation_slopes_match_finite_differences(key):
    """The Newton solver's slopes: dFz/dRl written out term by term against central differences (in contact,
    in bottoming and above R_omega), and the lift slope against the Newton step on A - B (side-force term
    against what the load leaves) differentiated numerically."""
    prm = _model(key).params
    rng = np.random.default_rng(13)
    n = 3000
    fz = np.r_[rng.uniform(0.0, 600.0, n // 2), rng.uniform(0.0, 3.0 * prm.FNOMIN, n - n // 2)]
    omega = rng.uniform(0.0, 250.0, n)
    dpi = rng.uniform(prm.PRESMIN, prm.PRESMAX, n) / prm.NOMPRES - 1.0
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    fx, fy = rng.uniform(-1.2, 1.2, (2, n)) * fz
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    R0, Fz0 = prm.UNLOADED_RADIUS, prm.FNOMIN
    rl = r_omega + rng.uniform(-0.4, 1.0, n) * R0 * 0.5  # below the rim (bottoming) up to R0/2 above R_omega
    kinks = np.minimum(np.abs(rl - r_omega), np.abs(rl - prm.RIM_RADIUS - prm.BOTTOM_OFFST))
    rl = np.where(kinks < 1e-5, rl + 3e-5, rl)
    terms = vertical._relation_terms_62(prm, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
    value, slope, lift_slope = vertical._relation_62(prm, rl, terms, NUMPY, target=fz)
    h = 1e-7
    numeric = (vertical._relation_62(prm, rl + h, terms, NUMPY) - vertical._relation_62(prm, rl - h, terms, NUMPY))
    numeric /= 2 * h
    np.testing.assert_allclose(slope, numeric, rtol=1e-5, atol=1e-4 * Fz0)
    np.testing.assert_allclose(value, vertical._relation_62(prm, rl, terms, NUMPY) - fz, rtol=0, atol=0)
    if prm.Q_FCY == 0:
        np.testing.assert_array_equal(lift_slope, slope)
        return

    def a_minus_b(r):  # above R_omega: A = |x^Q_FCY2 Q_FCY (Fy - S_Fygamma)/Fz0|, B = sqrt(correction - fz/load);
        # Fz - fz = -(A + B) load (A - B) where B is real
        x = vertical.deflection_62(prm, r, r_omega, gamma, NUMPY) / R0
        ratio = r / r_omega
        s_fygamma = (prm.Q_FYS1 + prm.Q_FYS2 * ratio + prm.Q_FYS3 * ratio**2) * gamma
        a = np.abs(x**prm.Q_FCY2 * prm.Q_FCY * (fy - s_fygamma) / Fz0)
        load = terms[4] * (np.sqrt((prm.VERTICAL_STIFFNESS * R0 / Fz0) ** 2 - 4 * prm.Q_FZ2) * x + prm.Q_FZ2 * x**2)
        b_squared = terms[3] - fz / load
        return a - np.sqrt(np.maximum(b_squared, 0.0)), b_squared

    zeta, b_squared = a_minus_b(rl)
    zeta_slope = (a_minus_b(rl + h)[0] - a_minus_b(rl - h)[0]) / (2 * h)
    regular = (rl > r_omega) & (zeta != 0) & (np.abs(zeta_slope) > 1e-3) & (b_squared > 1e-6)
    np.testing.assert_allclose((value / lift_slope)[regular], (zeta / zeta_slope)[regular], rtol=1e-4, atol=1e-9)
    assert regular.sum() > n // 4


@pytest.mark.parametrize("key", ["mfeval_mf62", "tno_mf62"])
def test_casadi_loaded_radius_derivatives_are_implicit_ones(key):
    """dRl/d(Fz, Fy, gamma) of the unrolled CasADi solve against central differences of the NumPy solve, for
    tyres in contact and lifted ones (root above R_omega, where the Newton steps use the lift slope): the final
    Newton step makes them the implicit function's derivatives either way. And finite everywhere, also at extreme
    inputs (an unused branch's infinite partial derivative times zero gave NaN)."""
    import casadi as ca
    from mftyre.backend import casadi_backend

    prm = _model(key).params
    be = casadi_backend()
    symbols = [ca.SX.sym(n) for n in ("fz", "omega", "fx", "fy", "gamma", "dpi")]
    rl_s, _ = vertical.loaded_radius_62(prm, symbols[0], vertical.free_radius(prm, symbols[1], be), *symbols[1:], be)
    wrt = ca.vertcat(symbols[0], symbols[3], symbols[4])
    f = ca.Function("rl", symbols, [rl_s, ca.jacobian(rl_s, wrt)])
    rng = np.random.default_rng(17)
    n = 300
    fz = np.r_[rng.uniform(20.0, 400.0, n // 2), rng.uniform(1000.0, 12000.0, n - n // 2)]
    omega = rng.uniform(0.0, 200.0, n)
    dpi = rng.uniform(-0.2, 0.2, n)
    gamma = rng.choice([-1.0, 1.0], n) * rng.uniform(0.03, 0.1, n)
    fx, fy = rng.uniform(-0.8, 0.8, (2, n)) * fz
    rl, jac = (np.array(v) for v in f.map(n)(fz, omega, fx, fy, gamma, dpi))
    rl, jac = rl.ravel(), jac.reshape(n, 3).T
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    lifted = rl > r_omega
    assert 30 < lifted.sum() < n - 30

    def numpy_rl(fz, fy, gamma):
        return vertical.loaded_radius_62(prm, fz, r_omega, omega, fx, fy, gamma, dpi, NUMPY)[0]

    for k, (name, h) in enumerate([("fz", 1e-4 * fz), ("fy", 1e-2), ("gamma", 1e-6)]):
        step = [np.zeros(n)] * 3
        step[k] = h + np.zeros(n)
        numeric = (numpy_rl(fz + step[0], fy + step[1], gamma + step[2])
                   - numpy_rl(fz - step[0], fy - step[1], gamma - step[2])) / (2 * step[k])
        np.testing.assert_allclose(jac[k], numeric, rtol=1e-4, atol=1e-12, err_msg=f"d rl / d {name}")

    rng = np.random.default_rng(19)
    n = 20000
    fz = np.r_[np.zeros(n // 10), rng.uniform(0.0, 5.0, n // 10), rng.uniform(0.0, 600.0, n // 3),
               rng.uniform(0.0, 4.0 * prm.FNOMIN, n - n // 10 - n // 10 - n // 3)]
    omega = rng.uniform(0.0, 250.0, n)
    dpi = rng.uniform(prm.PRESMIN, prm.PRESMAX, n) / prm.NOMPRES - 1.0
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    fx, fy = rng.uniform(-1.2, 1.2, (2, n)) * fz
    everything = ca.Function("drl", symbols, [ca.jacobian(rl_s, ca.vertcat(*symbols))])
    assert np.all(np.isfinite(np.array(everything.map(n)(fz, omega, fx, fy, gamma, dpi))))


@pytest.mark.parametrize("key", list(FILES))
def test_numpy_loaded_radius_same_alone_in_a_batch_and_per_point(key):
    """NumPy's shortcuts (the relation at R_omega only where a load is not above what the free tyre carries without
    the side-force term, no lifted-tyre work where none is lifted, Newton on the few points left) decide per call:
    loads just above and below the free tyre's own load, alone, in a mixed batch and one by one, give one Rl."""
    prm = _model(key).params
    rng = np.random.default_rng(5)
    n = 600
    omega = rng.uniform(0.0, 250.0, n)
    dpi = rng.uniform(prm.PRESMIN, prm.PRESMAX, n) / prm.NOMPRES - 1.0
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    fy = rng.uniform(-1.0, 1.0, n) * prm.FNOMIN
    fx = rng.uniform(-0.5, 0.5, n) * prm.FNOMIN
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    free = vertical.vertical_force_62(prm, r_omega, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
    fz = free * rng.choice([1.0 - 1e-3, 1.0 - 1e-9, 1.0 + 1e-9, 1.0 + 1e-3, 1.5, 3.0], n)
    fz[: n // 3] = rng.uniform(0.5, 3.0, n // 3) * prm.FNOMIN  # in contact for sure
    args = (r_omega, omega, fx, fy, gamma, dpi)
    batch, _ = vertical.loaded_radius_62(prm, fz, *args, NUMPY)
    sure = np.arange(n // 3)
    alone, _ = vertical.loaded_radius_62(prm, fz[sure], *(v[sure] for v in args), NUMPY)
    assert alone.shape == sure.shape
    np.testing.assert_allclose(alone, batch[sure], rtol=0, atol=1e-12)
    single = [vertical.loaded_radius_62(prm, fz[j], *(v[j] for v in args), NUMPY)[0] for j in range(0, n, 3)]
    np.testing.assert_allclose(single, batch[::3], rtol=0, atol=1e-12)
    back = vertical.vertical_force_62(prm, batch, *args, NUMPY)
    assert np.all((np.abs(back - fz) <= 1e-9 * np.maximum(fz, 1.0)) | (batch == r_omega))


def test_numpy_solve_newton_keeps_given_and_converged_elements():
    """NumPy solve_newton iterates every element until few are left: elements given f = 0 still return x, and the
    others find their roots (cubic-perturbed line, roots known) to 1e-15 from starts near and far, by Newton steps
    or, where the slope at the start is not negative, by bisection; one point alone gives the same root."""
    n = 40
    root = np.linspace(0.05, 0.95, n)

    def fun(x, idx):
        r = root if idx is None else root[idx]
        return (r - x) * (1.0 + (r - x) ** 2), -(1.0 + 3.0 * (r - x) ** 2)

    x = np.full(n, 0.5)
    f, df = fun(x, None)
    f, df = f.copy(), df.copy()
    f[:5] = 0.0  # given f = 0: stay at x while the others iterate on
    df[5:8] = 1.0  # a slope that is not negative: bisection first
    out = NUMPY.solve_newton(fun, x, f, df, 0.0, 1.0, xtol=1e-15, ftol=1e-14)
    assert np.all(out[:5] == 0.5)
    np.testing.assert_allclose(out[5:], root[5:], rtol=0, atol=1e-15)
    j = 20
    one = NUMPY.solve_newton(lambda v, _: fun(np.array([v]), (np.array([j]),)), 0.5, f[j], df[j], 0.0, 1.0,
                             xtol=1e-15, ftol=1e-14)
    assert abs(float(np.squeeze(one)) - root[j]) <= 1e-15


@pytest.mark.parametrize("key", ["mfeval_mf62", "tno_mf62"])
def test_numpy_loaded_radius_converged_in_rl(key):
    """Rl itself is converged, not only the load: one more Newton step on the relation from the returned Rl moves it
    by less than 1e-13 m wherever it carries its load (low loads incl. lifted roots, where the slope is small and a
    stop estimated too early shows; an early stop left 1e-11 m)."""
    prm = _model(key).params
    rng = np.random.default_rng(13)
    n = 200000
    fz = np.r_[np.zeros(n // 10), rng.uniform(0.0, 600.0, n // 3), rng.uniform(0.0, 5.0, n // 10)]
    fz = np.r_[fz, rng.uniform(0.0, 4.0 * prm.FNOMIN, n - fz.size)]
    omega = rng.uniform(0.0, 250.0, n)
    dpi = rng.uniform(prm.PRESMIN, prm.PRESMAX, n) / prm.NOMPRES - 1.0
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    fx, fy = rng.uniform(-1.2, 1.2, (2, n)) * fz
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    rl, _ = vertical.loaded_radius_62(prm, fz, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
    terms = vertical._relation_terms_62(prm, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
    value, slope, _ = vertical._relation_62(prm, rl, terms, NUMPY, fz, lift=False)
    carried = (np.abs(value) <= 1e-9 * np.maximum(fz, 1.0)) & (slope != 0)
    assert carried.sum() > 0.9 * n
    assert np.max(np.abs(value / np.where(carried, slope, 1.0))[carried]) <= 1e-13


@pytest.mark.parametrize("key", list(FILES))
def test_loaded_radius_across_bottoming_onset_with_large_side_force(key, tmp_path):
    """Across the bottoming onset (Rl within 4 mm of RIM_RADIUS + BOTTOM_OFFST, where the slope of Fz(Rl) jumps
    by BOTTOM_STIFF) with |Fy| up to FZMAX, |Fx| up to FZMAX/2, any spin, pressure and camber in range: the load
    the relation gives at a chosen Rl is carried by the Rl that NumPy, CasADi and the compiled C return (1e-9
    relative), and the three agree with that Rl."""
    import casadi as ca

    from mftyre.backend import casadi_backend
    from mftyre.compiled import CompiledFunction, compile_function

    prm = _model(key).params
    rng = np.random.default_rng(11)
    n = 3000
    omega = rng.uniform(0.0, 250.0, n)
    dpi = rng.uniform(prm.PRESMIN, prm.PRESMAX, n) / prm.NOMPRES - 1.0
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    fy = rng.uniform(-1.0, 1.0, n) * prm.FZMAX
    fx = rng.uniform(-0.5, 0.5, n) * prm.FZMAX
    onset = prm.RIM_RADIUS + prm.BOTTOM_OFFST
    rl_chosen = onset + rng.uniform(-0.004, 0.004, n)
    r_omega = vertical.free_radius(prm, omega, NUMPY)
    fz = vertical.vertical_force_62(prm, rl_chosen, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
    keep = fz > 100.0  # (a side force far beyond the friction limit may leave the relation no load there)
    assert keep.sum() > 0.8 * n
    assert np.sum(rl_chosen[keep] < onset) > 0.3 * n and np.sum(rl_chosen[keep] > onset) > 0.3 * n
    fz, omega, dpi, gamma, fx, fy, rl_chosen, r_omega = (v[keep] for v in (fz, omega, dpi, gamma, fx, fy, rl_chosen,
                                                                          r_omega))
    inputs = (fz, omega, fx, fy, gamma, dpi)

    def carried(rl):
        back = vertical.vertical_force_62(prm, rl, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
        return np.abs(back - fz) <= 1e-9 * fz

    rl_numpy, _ = vertical.loaded_radius_62(prm, fz, r_omega, omega, fx, fy, gamma, dpi, NUMPY)
    be = casadi_backend()
    symbols = [ca.SX.sym(name) for name in ("fz", "omega", "fx", "fy", "gamma", "dpi")]
    rl_s, _ = vertical.loaded_radius_62(prm, symbols[0], vertical.free_radius(prm, symbols[1], be), *symbols[1:], be)
    function = ca.Function("rl", symbols, [rl_s], ["fz", "omega", "fx", "fy", "gamma", "dpi"], ["rl"])
    rl_casadi = np.array(function.map(fz.size)(*inputs)).ravel()
    library = compile_function(function, f"bottoming-onset-{key}", directory=tmp_path)
    (rl_c,) = CompiledFunction(library).batch(*inputs)
    for rl in (rl_numpy, rl_casadi, rl_c):
        assert carried(rl).all(), np.c_[inputs][~carried(rl)][:3]
        np.testing.assert_allclose(rl, rl_chosen, rtol=0, atol=1e-9 * prm.UNLOADED_RADIUS)


@pytest.mark.parametrize("turn_slip", [False, True])
def test_issue_points_in_bottoming_carry_the_load_at_the_camber_used(turn_slip):
    """The two points of issue #24 (15.5 and 15.8 kN, |Fy| ~ 11 kN, Rl in the bottoming region of the reference
    evaluator's MF 6.2 sample): with limits=True the camber is saturated to CAMMIN..CAMMAX, and the Rl returned
    carries the load with that camber, the spin, forces and pressure used (the 13.9 kN of the issue came from the
    unsaturated camber, which the relation was never solved for); with limits=False the root at the given camber."""
    model = _model("mfeval_mf62")
    points = [(15480.0, 0.0458, -0.6208, 0.1144, 25.02, 2.878e5), (15846.0, 0.0047, 0.3162, -0.1165, 12.47, 2.276e5)]
    onset = model.params.RIM_RADIUS + model.params.BOTTOM_OFFST
    for fz, kappa, alpha, gamma, vx, p in points:
        for limits in (True, False):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", mftyre.InputClippedWarning)
                out = model.evaluate(fz, kappa, alpha, gamma, 0.0, vx, p, limits=limits, turn_slip=turn_slip)
            used = model.used_input("gamma", gamma) if limits else gamma
            assert float(out.rl) < onset  # bottoming
            back = model.vertical_force(out.rl, p=out.p, omega=out.omega, fx=out.fx, fy=out.fy, gamma=used)
            assert float(back) == pytest.approx(fz, rel=1e-9)
