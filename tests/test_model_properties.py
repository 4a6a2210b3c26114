"""Properties the Magic Formula model must have, checked independently of any stored output.

Every check here compares the model with something it must satisfy by construction of the published equations
(mirror symmetry, odd symmetry of a shift-free tyre, finite differences against the analytic stiffnesses,
continuity of the low-speed model, inverse functions, broadcasting) or with the physical meaning of a
parameter sign (pressure trends). No snapshot of our own output is used.

Axes: ISO-W. A positive slip angle gives a negative side force (Kya < 0).
"""
from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest

import mftyre
from mftyre.backend import NUMPY
from mftyre.errors import ModelInputError
from mftyre.formula import OUTPUT_NAMES, Modes, steady_state
from mftyre.model import MFModel

from conftest import MFEVAL_DIR, TIR_FILES

SAMPLE_FILES = ("car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir")
REFERENCE_FILES = ("MagicFormula61_Parameters.tir", "MagicFormula62_Parameters.tir")

#: outputs that change sign when the tyre is mirrored (the echoed lateral inputs included)
LATERAL_OUTPUTS = ("fy", "mx", "mz", "mzr", "alpha", "gamma", "phit")
FORCES = ("fx", "fy", "fz")
MOMENTS = ("mx", "my", "mz", "mzr")


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # missing-parameter warnings are the subject of test_sample_tir_files
        return mftyre.load_tir(path)


def _sample(name):
    return _load(TIR_FILES / name)


def _reference(name):
    path = MFEVAL_DIR / name
    if not path.exists():
        pytest.skip(f"reference file {path} not found: the shared reference material lives in ../shared beside "
                    "the project (present in CI, absent in a user's clone)")
    return _load(path)


def _any_file(spec):
    kind, name = spec
    return _sample(name) if kind == "sample" else _reference(name)


ALL_FILES = [("sample", n) for n in SAMPLE_FILES] + [("reference", n) for n in REFERENCE_FILES]


def _tol(model, name):
    """Absolute tolerance scale of an output: forces ~ FNOMIN, moments ~ FNOMIN R0."""
    prm = model.params
    if name in FORCES:
        return prm.FNOMIN
    if name in MOMENTS:
        return prm.FNOMIN * prm.UNLOADED_RADIUS
    return 1.0


def _input_grid(model):
    """A mixed set of operating points (loads, slips, camber, turn slip, speeds incl. low and reverse)."""
    prm = model.params
    fz = np.array([500.0, 2000.0, 4000.0, 6500.0])
    kappa = np.array([-0.3, -0.02, 0.0, 0.01, 0.15])
    alpha = np.array([-0.25, -0.03, 0.0, 0.004, 0.12])
    gamma = np.array([-0.08, 0.0, 0.05])
    phit = np.array([-0.6, 0.0, 0.3])
    vx = np.array([-12.0, 0.5 * prm.VXLOW, prm.LONGVL, 30.0])
    grids = np.meshgrid(fz, kappa, alpha, gamma, phit, vx, indexing="ij")
    return dict(zip(("fz", "kappa", "alpha", "gamma", "phit", "vx"), (g.ravel() for g in grids)))


# ------------------------------------------------------------------------------------------------ mirror
@pytest.mark.parametrize("turn_slip", [False, True], ids=["no_turn_slip", "turn_slip"])
@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_mirror_symmetry_left_right(name, turn_slip):
    """with_side(other) is the mirror image: at mirrored inputs (alpha, gamma, phit negated) Fy, Mx, Mz, Mzr
    (and the echoed lateral inputs) are negated, every other output is identical."""
    model = _sample(name)
    other = "right" if model.side == "left" else "left"
    mirrored = model.with_side(other)
    assert mirrored.side == other and mirrored.mirrored and not model.mirrored
    x = _input_grid(model)
    xm = dict(x, alpha=-x["alpha"], gamma=-x["gamma"], phit=-x["phit"])
    for limits in (True, False):
        a = model.evaluate(**x, turn_slip=turn_slip, limits=limits)
        b = mirrored.evaluate(**xm, turn_slip=turn_slip, limits=limits)
        for out in OUTPUT_NAMES:
            expected = -a[out] if out in LATERAL_OUTPUTS else a[out]
            np.testing.assert_allclose(b[out], expected, rtol=1e-12, atol=1e-12 * _tol(model, out),
                                       err_msg=f"{name}: output {out} (limits={limits}) is not mirrored")
        # the lateral outputs are not trivially zero, so the sign flip above is a real check
        assert np.max(np.abs(a.fy)) > 0.1 * model.params.FNOMIN
        assert np.max(np.abs(a.mz)) > 1.0


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_file_side_evaluates_unmirrored_equations(name):
    """Both sample files say TYRESIDE = LEFT: evaluated as left, the model is the bare equations; the same
    parameters labelled RIGHT and mounted right give the same numbers; mounted left they give the mirror."""
    model = _sample(name)
    prm = model.params
    assert str(prm.TYRESIDE).strip("'\" ").upper() == "LEFT"
    left = model.with_side("left")
    assert not left.mirrored
    x = _input_grid(model)
    for turn_slip in (False, True):
        modes = Modes(limits=True, turn_slip=turn_slip)
        with np.errstate(all="ignore"):
            bare = steady_state(prm, x["fz"], x["kappa"], x["alpha"], x["gamma"], x["phit"], x["vx"],
                                np.full_like(x["fz"], prm.INFLPRES), np.zeros_like(x["fz"]), False, modes, NUMPY)
        out = left.evaluate(**x, turn_slip=turn_slip)
        relabelled = MFModel(prm.replace(TYRESIDE="RIGHT"), side="right").evaluate(**x, turn_slip=turn_slip)
        relabelled_left = MFModel(prm.replace(TYRESIDE="RIGHT"), side="left")
        mirror = relabelled_left.evaluate(fz=x["fz"], kappa=x["kappa"], alpha=-x["alpha"], gamma=-x["gamma"],
                                          phit=-x["phit"], vx=x["vx"], turn_slip=turn_slip)
        for k in OUTPUT_NAMES:
            ref = np.broadcast_to(np.asarray(bare[k], dtype=float), out[k].shape)
            np.testing.assert_allclose(out[k], ref, rtol=1e-13, atol=0, err_msg=f"{name}: {k} as left")
            np.testing.assert_allclose(relabelled[k], ref, rtol=1e-13, atol=0, err_msg=f"{name}: {k} relabelled")
            sign = -1.0 if k in LATERAL_OUTPUTS else 1.0
            np.testing.assert_allclose(mirror[k], sign * ref, rtol=1e-12, atol=1e-12 * _tol(model, k),
                                       err_msg=f"{name}: {k} relabelled RIGHT mounted left")


# -------------------------------------------------------------------------------------- odd symmetry
#: Parameters that make the pure-slip characteristics asymmetric at zero camber (reasoning per group):
#: - PHX1, PHX2 (SHx), PVX1, PVX2 (SVx): shifts of Fx0 (4.E17, 4.E18).
#: - PEX4: Ex = ... (1 - PEX4 sign(kappa_x)) (4.E14) makes the curvature differ for braking and driving.
#: - PHY1, PHY2 (SHy), PVY1, PVY2 (SVy): shifts of Fy0 (4.E27, 4.E29). PVY3/PVY4/PKY6/PKY7 multiply gamma*,
#:   inert at gamma = 0, so they stay (and are used in the joint (alpha, gamma) check below).
#: - PEY3: Ey = ... (1 + PEY5 g^2 - (PEY3 + PEY4 g) sign(alpha_y)) (4.E24); PEY4 g is odd in gamma, so
#:   (PEY4 g) sign(alpha_y) is invariant under (alpha, gamma) -> (-alpha, -gamma) and stays.
#: - QHZ1, QHZ2: trail shift SHt (4.E35) at gamma = 0; QHZ3, QHZ4 multiply gamma and stay.
#: - QEZ4: Et ~ (1 + QEZ4 (2/pi) atan(Bt Ct alpha_t)) (4.E44) is not even in alpha_t -> t not even.
#: - QDZ6, QDZ7: the residual torque Dr (4.E47) at gamma = 0 is even in alpha (cos(alpha*)), so Mzr would
#:   add an even part to Mz; QDZ8..QDZ11 multiply gamma and are inert at gamma = 0.
#: Left non-zero on purpose, because pure slip must not see them: RHX1 (Gxa(alpha = 0) = 1, 4.E51),
#: RHY1, RHY2 (Gyk(kappa = 0) = 1, 4.E59), RVY1..RVY6 (SVyk(kappa = 0) = 0, 4.E66), SSZ1, SSZ2 (multiply Fx,
#: which is 0 at kappa = 0 once SVx = 0). QSX* concern Mx only, which is not checked here.
ASYMMETRY_PARAMETERS = ("PHX1", "PHX2", "PVX1", "PVX2", "PEX4", "PHY1", "PHY2", "PVY1", "PVY2", "PEY3",
                        "QHZ1", "QHZ2", "QEZ4", "QDZ6", "QDZ7")


def _symmetric(model):
    return model.with_params(**{n: 0.0 for n in ASYMMETRY_PARAMETERS})


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_pure_slip_odd_symmetry_without_shifts(name):
    base = _sample(name)
    prm = base.params
    # the test must have something to remove: the files do carry asymmetries
    assert any(prm[n] != 0 for n in ASYMMETRY_PARAMETERS)
    assert prm.RHX1 != 0 and prm.RHY1 != 0 and prm.RVY1 != 0
    model = _symmetric(base)
    fz = np.array([1500.0, 4000.0, 7000.0])[:, None]
    p = np.array([prm.PRESMIN, prm.NOMPRES, prm.PRESMAX])[:, None, None]
    slip = np.array([1e-4, 0.003, 0.02, 0.08, 0.2, 0.5])
    for limits in (False, True):
        # Fx0(-kappa) = -Fx0(kappa) at alpha = 0
        fp = model.evaluate(fz=fz, kappa=slip, alpha=0.0, p=p, limits=limits)
        fm = model.evaluate(fz=fz, kappa=-slip, alpha=0.0, p=p, limits=limits)
        np.testing.assert_allclose(fm.fx, -fp.fx, rtol=1e-10, atol=1e-9 * prm.FNOMIN)
        assert np.all(fp.fx > 0)
        # Fy(-alpha) = -Fy(alpha), Mz(-alpha) = -Mz(alpha) at kappa = 0, gamma = 0
        fp = model.evaluate(fz=fz, kappa=0.0, alpha=slip, p=p, limits=limits)
        fm = model.evaluate(fz=fz, kappa=0.0, alpha=-slip, p=p, limits=limits)
        np.testing.assert_allclose(fm.fy, -fp.fy, rtol=1e-10, atol=1e-9 * prm.FNOMIN)
        np.testing.assert_allclose(fm.mz, -fp.mz, rtol=1e-10, atol=1e-9 * prm.FNOMIN * prm.UNLOADED_RADIUS)
        assert np.all(fp.fy < 0)  # ISO-W: positive slip angle, negative side force
        # and at zero slip nothing is left
        f0 = model.evaluate(fz=fz, kappa=0.0, alpha=0.0, p=p, limits=limits)
        for k in ("fx", "fy", "mz"):
            np.testing.assert_allclose(f0[k], 0.0, atol=1e-9 * prm.FNOMIN)
    # the unmodified tyre is not odd (otherwise the checks above prove nothing about the shifts)
    fp = base.evaluate(fz=4000.0, kappa=0.0, alpha=0.003, limits=False)
    fm = base.evaluate(fz=4000.0, kappa=0.0, alpha=-0.003, limits=False)
    assert abs(fp.fy + fm.fy) > 1.0


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_lateral_force_odd_in_joint_alpha_gamma(name):
    """With the non-camber shifts removed, the camber terms (PVY3, PVY4, PKY6, PKY7, PEY4, PKY3, PKY5, PDY3)
    are odd or even in gamma such that Fy(-alpha, -gamma) = -Fy(alpha, gamma) (4.E19-4.E30)."""
    model = _symmetric(_sample(name))
    fz = np.array([2000.0, 4000.0, 6000.0])[:, None, None]
    alpha = np.array([0.0, 0.002, 0.02, 0.1, 0.3])[:, None]
    gamma = np.array([-0.09, -0.02, 0.03, 0.1])
    for turn_slip in (False,):
        a = model.evaluate(fz=fz, kappa=0.0, alpha=alpha, gamma=gamma, limits=False, turn_slip=turn_slip)
        b = model.evaluate(fz=fz, kappa=0.0, alpha=-alpha, gamma=-gamma, limits=False, turn_slip=turn_slip)
        np.testing.assert_allclose(b.fy, -a.fy, rtol=1e-10, atol=1e-9 * model.params.FNOMIN)
        # camber does act: at alpha = 0 there is a camber thrust
        assert np.min(np.abs(a.fy[:, 0, :])) > 1.0


#: Further asymmetries that act under combined slip only: RHX1 (4.E57, Gxa not even in alpha), RHY1, RHY2
#: (4.E65, Gyk not even in kappa), RVY1, RVY2 (4.E66/67: SVyk is even in alpha, so it is an offset of Fy),
#: RBY3 (4.E62, Byk not even in alpha), SSZ1 (paper A56: s Fx with a constant arm is even in alpha).
COMBINED_ASYMMETRY_PARAMETERS = ("RHX1", "RHY1", "RHY2", "RVY1", "RVY2", "RBY3", "SSZ1")


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_symmetric_tyre_same_on_both_sides(name):
    """A tyre without asymmetries at zero camber and turn slip gives the same Fx, Fy, Mz on either side,
    under combined slip too."""
    model = _symmetric(_sample(name)).with_params(**{n: 0.0 for n in COMBINED_ASYMMETRY_PARAMETERS})
    other = model.with_side("right" if model.side == "left" else "left")
    kw = dict(fz=np.array([2500.0, 5000.0])[:, None], kappa=np.array([0.0, 0.05, -0.1])[:, None, None],
              alpha=np.array([-0.2, -0.01, 0.0, 0.03]), limits=False)
    a, b = model.evaluate(**kw), other.evaluate(**kw)
    for k in ("fx", "fy", "mz"):
        np.testing.assert_allclose(b[k], a[k], rtol=1e-10, atol=1e-9 * model.params.FNOMIN, err_msg=k)


# ------------------------------------------------------------------------------ stiffness vs slope
def _central_slope(f, x0, h):
    return (f(x0 + h) - f(x0 - h)) / (2.0 * h)


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_slip_stiffness_equals_slope_at_zero_slip(name):
    """Kya = dFy/dalpha and Kxk = dFx/dkappa at zero slip once the shifts are removed (4.E25, 4.E15 are the
    slopes B C D of the Magic Formula at its origin), at several loads and pressures."""
    model = _symmetric(_sample(name))
    prm = model.params
    fz = np.array([800.0, 2500.0, 4000.0, 6000.0, 8000.0])[:, None]
    p = np.array([prm.PRESMIN, 2.0e5, prm.NOMPRES, prm.PRESMAX])
    h = 1e-6
    for limits in (False, True):
        at0 = model.evaluate(fz=fz, kappa=0.0, alpha=0.0, p=p, limits=limits)
        dfy = _central_slope(lambda a: model.evaluate(fz=fz, kappa=0.0, alpha=a, p=p, limits=limits).fy, 0.0, h)
        dfx = _central_slope(lambda k: model.evaluate(fz=fz, kappa=k, alpha=0.0, p=p, limits=limits).fx, 0.0, h)
        np.testing.assert_allclose(at0.kya, dfy, rtol=1e-6, err_msg="Kya vs dFy/dalpha")
        np.testing.assert_allclose(at0.kxk, dfx, rtol=1e-6, err_msg="Kxk vs dFx/dkappa")
        assert np.all(at0.kya < 0) and np.all(at0.kxk > 0)
        # the stiffnesses do depend on load and pressure, so the grid is a real test
        assert np.ptp(at0.kya[:, 0]) > 0.1 * np.max(np.abs(at0.kya))
        assert np.ptp(at0.kxk[2, :]) > 1e-3 * np.max(np.abs(at0.kxk))


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_slip_stiffness_equals_slope_at_shifted_origin(name):
    """With the file's shifts present, the Magic Formula origin is at alpha = -SHy, kappa = -SHx; at zero
    camber SHy = (PHY1 + PHY2 dfz) LHY (4.E27: the camber and SVyg terms vanish) and SHx = (PHX1 + PHX2 dfz)
    LHX (4.E17). The slope there is Kya (Kxk): the curvature factor E, which jumps with sign(alpha_y) (PEY3) or
    sign(kappa_x) (PEX4), multiplies a term of third order and does not change the slope."""
    model = _sample(name)
    prm = model.params
    assert prm.PHY1 != 0 and prm.PHX1 != 0
    fz = np.array([1500.0, 4000.0, 7000.0])
    dfz = (fz - prm.LFZO * prm.FNOMIN) / (prm.LFZO * prm.FNOMIN)
    shy = (prm.PHY1 + prm.PHY2 * dfz) * prm.LHY
    shx = (prm.PHX1 + prm.PHX2 * dfz) * prm.LHX
    h = 1e-7
    kya = model.evaluate(fz=fz, kappa=0.0, alpha=-shy, limits=False).kya
    kxk = model.evaluate(fz=fz, kappa=-shx, alpha=0.0, limits=False).kxk
    dfy = _central_slope(lambda a: model.evaluate(fz=fz, kappa=0.0, alpha=a, limits=False).fy, -shy, h)
    dfx = _central_slope(lambda k: model.evaluate(fz=fz, kappa=k, alpha=0.0, limits=False).fx, -shx, h)
    np.testing.assert_allclose(kya, dfy, rtol=1e-6)
    np.testing.assert_allclose(kxk, dfx, rtol=1e-6)


# -------------------------------------------------------------------------------------- low speed
@pytest.mark.parametrize("turn_slip", [False, True], ids=["no_turn_slip", "turn_slip"])
@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_continuity_across_vxlow(name, turn_slip):
    """With limits on, the low-speed model joins the normal model without a step at |Vx| = VXLOW."""
    model = _sample(name)
    prm = model.params
    grid = np.meshgrid([1000.0, 4000.0, 7000.0], [-0.2, -0.01, 0.0, 0.05], [-0.1, 0.0, 0.02, 0.3],
                       [0.0, 0.06], [0.0, 0.4], indexing="ij")
    x = dict(zip(("fz", "kappa", "alpha", "gamma", "phit"), (g.ravel() for g in grid)))
    jumps = []
    for sign in (1.0, -1.0):
        lo = model.evaluate(**x, vx=sign * prm.VXLOW * (1 - 1e-9), turn_slip=turn_slip)
        hi = model.evaluate(**x, vx=sign * prm.VXLOW * (1 + 1e-9), turn_slip=turn_slip)
        for k in OUTPUT_NAMES:
            atol = 1e-6 * _tol(model, k) if (k in FORCES or k in MOMENTS) else 1e-9
            bad = ~(np.abs(lo[k] - hi[k]) <= atol + 1e-6 * np.abs(hi[k]))
            if np.any(bad):
                i = np.argmax(np.where(bad, np.abs(lo[k] - hi[k]), -1.0))
                point = {n: float(v[i]) for n, v in x.items()}
                jumps.append(f"{k} at Vx = {sign:+.0f} VXLOW: {bad.sum()} points, largest step "
                             f"{lo[k][i] - hi[k][i]:.6g} (below {lo[k][i]:.6g}, above {hi[k][i]:.6g}) at {point}")
    assert not jumps, f"{name}: outputs jump across VXLOW\n" + "\n".join(jumps)


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_low_speed_forces_fade_smoothly_to_zero(name):
    """Below VXLOW the slip (and the shifts) fade out: F(Vx) goes to 0 at Vx = 0, with increments no larger
    than the linear-range slope K slip / VXLOW allows; without shifts, monotonically for small slip (with the
    file's shifts |F| may dip slightly just below VXLOW where the slip is no longer reduced but the shifts
    still fade in)."""
    base = _sample(name)
    prm = base.params
    vx = np.linspace(0.0, 2.0 * prm.VXLOW, 4001)
    dv = vx[1] - vx[0]
    low = vx <= prm.VXLOW
    fz = 4000.0
    kappa, alpha = 0.02, 0.02
    for model, shifts in ((base, True), (_symmetric(base), False)):
        for sign in (1.0, -1.0):
            fx = model.evaluate(fz=fz, kappa=kappa, alpha=0.0, vx=sign * vx).fx
            fy = model.evaluate(fz=fz, kappa=0.0, alpha=alpha, vx=sign * vx).fy
            nominal = model.evaluate(fz=fz, kappa=0.0, alpha=0.0)
            for force, k_slip, label in ((fx, nominal.kxk * kappa * sign, "Fx"), (fy, nominal.kya * alpha, "Fy")):
                label = f"{label} (shifts={shifts}, sign(Vx)={sign:+.0f})"
                assert force[0] == pytest.approx(0.0, abs=1e-9 * prm.FNOMIN), f"{label} at Vx = 0"
                assert abs(force[-1]) > 0.1 * abs(k_slip), f"{label} above VXLOW should carry the slip"
                steps = np.abs(np.diff(force))
                assert np.max(steps) <= 1.5 * abs(k_slip) / prm.VXLOW * dv + 1e-6 * prm.FNOMIN, f"{label} steps"
                assert np.all(np.sign(force[1:]) == np.sign(k_slip)), f"{label} sign"
                if not shifts:
                    assert np.all(np.diff(np.abs(force[low])) >= -1e-9 * prm.FNOMIN), f"{label} not monotone"
    # at exactly Vx = 0 the aligning moment is gone too
    at0 = model.evaluate(fz=fz, kappa=0.1, alpha=0.1, vx=0.0)
    assert at0.mz == pytest.approx(0.0, abs=1e-9 * prm.FNOMIN * prm.UNLOADED_RADIUS)


# ------------------------------------------------------------------------------------ finite outputs
EXTREME_CASES = {
    "zero_load": dict(fz=0.0, kappa=0.1, alpha=0.1),
    "standstill": dict(fz=4000.0, kappa=0.1, alpha=0.1, vx=0.0),
    "wheel_lock": dict(fz=4000.0, kappa=-1.0, alpha=0.05),
    "alpha_plus_90deg": dict(fz=4000.0, kappa=0.0, alpha=np.pi / 2),
    "alpha_minus_90deg": dict(fz=4000.0, kappa=0.0, alpha=-np.pi / 2),
    "large_camber": dict(fz=4000.0, kappa=0.05, alpha=0.1, gamma=0.6),
    "reverse": dict(fz=4000.0, kappa=0.05, alpha=0.1, vx=-10.0),
    "reverse_slow": dict(fz=4000.0, kappa=0.05, alpha=0.1, vx=-0.3),
    "phit_zero": dict(fz=4000.0, kappa=0.05, alpha=0.1, phit=0.0),
    "phit_large": dict(fz=4000.0, kappa=0.05, alpha=0.1, phit=40.0),
    "phit_large_negative": dict(fz=4000.0, kappa=0.05, alpha=0.1, phit=-40.0),
}


@pytest.mark.parametrize("case", list(EXTREME_CASES))
@pytest.mark.parametrize("spec", ALL_FILES, ids=[n for _, n in ALL_FILES])
def test_outputs_finite_at_extremes(spec, case):
    model = _any_file(spec)
    failures = []
    for limits, turn_slip, alpha_star in itertools.product((True, False), repeat=3):
        out = model.evaluate(**EXTREME_CASES[case], limits=limits, turn_slip=turn_slip, alpha_star=alpha_star)
        bad = [k for k in OUTPUT_NAMES if not np.all(np.isfinite(out[k]))]
        if bad:
            failures.append(f"limits={limits} turn_slip={turn_slip} alpha_star={alpha_star}: {bad}")
    assert not failures, f"{spec[1]} {case}: non-finite outputs\n" + "\n".join(failures)


# --------------------------------------------------------------------------------------- input errors
@pytest.mark.parametrize("which", ["fz", "kappa", "alpha", "gamma", "phit", "vx", "p", "omega"])
def test_nan_input_raises(which):
    model = _sample(SAMPLE_FILES[0])
    kw = dict(fz=4000.0, kappa=0.0, alpha=0.0, gamma=0.0, phit=0.0, vx=10.0, p=2.2e5, omega=30.0)
    kw[which] = np.array([1.0, np.nan])
    with pytest.raises(ModelInputError, match=which):
        model.evaluate(**kw)


@pytest.mark.parametrize("p", [0.0, -1.0e5, np.array([2.2e5, 0.0])])
def test_nonpositive_pressure_raises(p):
    model = _sample(SAMPLE_FILES[0])
    with pytest.raises(ModelInputError, match="pressure"):
        model.evaluate(4000.0, 0.0, 0.0, p=p)
    with pytest.raises(ModelInputError, match="pressure"):
        model.loaded_radius(4000.0, p=p)
    with pytest.raises(ModelInputError, match="pressure"):
        model.vertical_force(0.3, p=p)


def test_non_broadcastable_raises():
    model = _sample(SAMPLE_FILES[0])
    with pytest.raises(ModelInputError, match="broadcast"):
        model.evaluate(np.ones(3) * 4000.0, np.zeros(4), 0.0)
    with pytest.raises(ModelInputError, match="broadcast"):
        model.evaluate(4000.0, 0.0, np.zeros((2, 3)), gamma=np.zeros(2))


@pytest.mark.parametrize("value", ["abc", "0.1x", object(), [0.1, "a"], {"a": 1}])
def test_non_numeric_raises(value):
    model = _sample(SAMPLE_FILES[0])
    with pytest.raises(ModelInputError):
        model.evaluate(4000.0, value, 0.0)


# ------------------------------------------------------------------------------------ pressure trends
def test_pressure_trends_mf61():
    """205/60R15 MF 6.1 file: signs of the published pressure parameters imply the trends.

    Kya (4.E25) = PKY1 Fz0' (1 + PPY1 dpi) sin(PKY4 atan(Fz/(Fz0' PKY2 (1 + PPY2 dpi)))) ...; the relative
    change with dpi is PPY1/(1 + PPY1 dpi) - g PPY2/(1 + PPY2 dpi) with |g| <= 1 below the load of peak Kya,
    so with |PPY1| > |PPY2| the sign of PPY1 decides: PPY1 < 0 -> |Kya| falls as pressure rises.
    Cz = Cz0 (1 + PFZ1 dpi) (paper (5)): PFZ1 > 0 -> stiffer. Contact length a (paper (9)) grows with
    Fz/Cz, so it shrinks with pressure; the deflection shrinks, so the loaded radius grows.
    """
    model = _sample("car_205_60R15_mf61.tir")
    prm = model.params
    assert prm.PPY1 < 0 and abs(prm.PPY1) > abs(prm.PPY2)
    assert prm.PFZ1 > 0
    p = np.linspace(prm.PRESMIN, prm.PRESMAX, 8)
    fz = np.array([1500.0, 3000.0, 4000.0, 5500.0])[:, None]
    peak_load = prm.FNOMIN * prm.LFZO * prm.PKY2 * np.tan(np.pi / (2 * prm.PKY4)) * (1 + prm.PPY2 * 0.2)
    assert np.all(fz < 0.95 * peak_load)
    out = model.evaluate(fz=fz, kappa=0.0, alpha=0.0, p=p)
    np.testing.assert_array_equal(out.p, np.broadcast_to(p, out.p.shape))  # inside the range: not clipped
    assert np.all(np.diff(np.abs(out.kya), axis=1) < 0), "|Kya| should fall with pressure (PPY1 < 0)"
    assert np.all(np.diff(out.cz, axis=1) > 0), "Cz should rise with pressure (PFZ1 > 0)"
    assert np.all(np.diff(out.a, axis=1) < 0), "contact half length should fall with pressure"
    assert np.all(np.diff(out.rl, axis=1) > 0), "loaded radius should rise with pressure"
    assert np.all(np.diff(out.rho, axis=1) < 0), "deflection should fall with pressure"
    rl, _ = model.loaded_radius(fz, p=p)
    assert np.all(np.diff(rl, axis=1) > 0)
    # magnitude: Cz at the nominal load follows Cz0 (1 + PFZ1 dpi) to within the non-linearity Q_FZ2
    # and by about the factor (1 + PFZ1 dpi) (exactly so for a linear tyre; Q_FZ2 bends it a little)
    dpi = (p - prm.NOMPRES) / prm.NOMPRES
    cz0 = model.evaluate(fz=fz, kappa=0.0, alpha=0.0, p=prm.NOMPRES).cz
    np.testing.assert_allclose(out.cz / cz0, np.broadcast_to(1 + prm.PFZ1 * dpi, out.cz.shape), rtol=0.03)


# ------------------------------------------------------------------------------ loaded radius <-> Fz
VERTICAL_FILES = [("sample", n) for n in SAMPLE_FILES] + [("reference", n) for n in REFERENCE_FILES]


@pytest.mark.parametrize("spec", VERTICAL_FILES, ids=[n for _, n in VERTICAL_FILES])
def test_loaded_radius_and_vertical_force_are_inverse(spec):
    model = _any_file(spec)
    prm = model.params
    fz = np.array([300.0, 2000.0, 4000.0, 6500.0, 9000.0])[:, None, None, None]
    p = np.array([prm.PRESMIN, prm.NOMPRES, prm.PRESMAX])[:, None, None]
    gamma = np.array([-0.08, 0.0, 0.05])[:, None]
    fy = np.array([-3000.0, 0.0, 2500.0])
    omega = 40.0
    for m in (model, model.with_side("right" if model.side == "left" else "left")):
        rl, rho = m.loaded_radius(fz, p=p, omega=omega, fx=500.0, fy=fy, gamma=gamma)
        assert rl.shape == (5, 3, 3, 3)
        assert np.all(np.isfinite(rl)) and np.all(rl > 0) and np.all(rho > 0)
        back = m.vertical_force(rl, p=p, omega=omega, fx=500.0, fy=fy, gamma=gamma)
        # MF 6.2: a cambered tyre touching the road with its shoulder already carries a load at Rl = R_omega
        # (the camber deflection); smaller loads have their root above R_omega (wheel lifted) or none (Rl = R_omega)
        r_omega = prm.UNLOADED_RADIUS * (prm.Q_RE0 + prm.Q_V1 * (omega * prm.UNLOADED_RADIUS / prm.LONGVL) ** 2)
        f_top = m.vertical_force(r_omega, p=p, omega=omega, fx=500.0, fy=fy, gamma=gamma)
        reachable = np.broadcast_to(fz, back.shape) > f_top
        if prm.version == "61":
            assert np.all(reachable)
        assert np.mean(reachable) > 0.9
        np.testing.assert_allclose(back[reachable], np.broadcast_to(fz, back.shape)[reachable], rtol=1e-9, atol=1e-6)
        lifted = ~reachable & (rl > r_omega)
        np.testing.assert_allclose(back[lifted], np.broadcast_to(fz, back.shape)[lifted], rtol=1e-9)
        np.testing.assert_allclose(rl[~reachable & ~lifted], r_omega, rtol=0, atol=1e-12)
        # and the other way round, from radii
        rls = np.linspace(prm.UNLOADED_RADIUS - 0.04, prm.UNLOADED_RADIUS - 0.005, 5)[:, None, None, None]
        f = m.vertical_force(rls, p=p, omega=omega, fx=500.0, fy=fy, gamma=gamma)
        rl2, _ = m.loaded_radius(f, p=p, omega=omega, fx=500.0, fy=fy, gamma=gamma)
        np.testing.assert_allclose(rl2, np.broadcast_to(rls, rl2.shape), rtol=0, atol=1e-9)


@pytest.mark.parametrize("spec", VERTICAL_FILES, ids=[n for _, n in VERTICAL_FILES])
def test_evaluate_rl_matches_loaded_radius(spec):
    """evaluate(...).rl is the loaded radius at the evaluated Fx, Fy and spin (inputs inside the .tir ranges)."""
    model = _any_file(spec)
    prm = model.params
    fz = np.array([1500.0, 4000.0, 7000.0])[:, None, None]
    alpha = np.array([-0.15, 0.0, 0.05])[:, None]
    kappa = np.array([-0.1, 0.0, 0.08])
    gamma = 0.04
    p = 0.5 * (prm.PRESMIN + prm.PRESMAX)
    for m in (model, model.with_side("right" if model.side == "left" else "left")):
        for omega in (None, 50.0):
            out = m.evaluate(fz=fz, kappa=kappa, alpha=alpha, gamma=gamma, vx=20.0, p=p, omega=omega)
            rl, rho = m.loaded_radius(fz, p=p, omega=out.omega, fx=out.fx, fy=out.fy, gamma=gamma)
            np.testing.assert_allclose(out.rl, rl, rtol=0, atol=1e-9)
            np.testing.assert_allclose(out.rho, rho, rtol=0, atol=1e-9)


# ------------------------------------------------------------------------------------- alpha* mode
@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_alpha_star_reverse_running(name):
    """alpha* = tan(alpha) sign(Vx) (4.E3) and Fy0 negated for Vx < 0: running backwards is the point
    reflection of the forward characteristic, Fy(alpha, gamma, -V) = -Fy(-alpha, gamma, V) (pure side slip;
    above VXLOW, LMUV = 0 so |Vs| plays no role). For a tyre without shifts (odd Fy0) this means the force keeps
    the sign it has forwards: alpha is defined with |Vx| (Vsy = tan(alpha) |Vx|), so the same alpha is the same
    sliding direction and the force must still oppose it."""
    model = _sample(name)
    prm = model.params
    assert prm.LMUV == 0
    fz = np.array([2000.0, 4000.0, 6500.0])[:, None, None]
    alpha = np.array([-0.3, -0.05, -0.004, 0.0, 0.01, 0.1, 0.5])[:, None]
    gamma = np.array([-0.05, 0.0, 0.08])
    v = 15.0
    for limits in (True, False):
        back = model.evaluate(fz=fz, kappa=0.0, alpha=alpha, gamma=gamma, vx=-v, alpha_star=True, limits=limits)
        fwd = model.evaluate(fz=fz, kappa=0.0, alpha=-alpha, gamma=gamma, vx=v, alpha_star=True, limits=limits)
        np.testing.assert_allclose(back.fy, -fwd.fy, rtol=1e-10, atol=1e-9 * prm.FNOMIN)
        # with the file's shifts the characteristic is not odd, so the reflection is not a trivial identity
        same = model.evaluate(fz=fz, kappa=0.0, alpha=alpha, gamma=gamma, vx=v, alpha_star=True, limits=limits)
        assert np.max(np.abs(back.fy - same.fy)) > 1.0
    sym = _symmetric(model)
    back = sym.evaluate(fz=fz, kappa=0.0, alpha=alpha, gamma=0.0, vx=-v, alpha_star=True, limits=False)
    fwd = sym.evaluate(fz=fz, kappa=0.0, alpha=alpha, gamma=0.0, vx=v, alpha_star=True, limits=False)
    np.testing.assert_allclose(back.fy, fwd.fy, rtol=1e-10, atol=1e-9 * prm.FNOMIN)
    nz = np.broadcast_to(alpha != 0, back.fy.shape)
    assert np.all(np.sign(back.fy[nz]) == -np.sign(np.broadcast_to(alpha, back.fy.shape)[nz]))


@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_longitudinal_slip_is_relative_to_the_direction_of_travel(name):
    """evaluate's kappa is -Vsx / Vx with the signed speed (as MFeval, whose mf61_reverse table the reference
    tests hold): the spin it estimates is omega = (1 + kappa) Vx / Re (kappa = -1: omega = 0, locked, also
    reversing), and Fx0 turns round with Vx, so running backwards is the fore-aft reflection
    Fx(-Vx, kappa) = -Fx(Vx, kappa): a locked wheel brakes the motion in both directions (Fx > 0 for Vx < 0),
    a wheel driven in the direction of travel (kappa > 0) pulls backwards. A wheel model gives it the ISO-W slip
    -Vsx / |Vx| times sign(Vx) (mftyre.transient.mf_slip)."""
    model = _sample(name)
    kappa = np.array([-1.0, -0.3, -0.05, 0.0, 0.05, 0.3, 1.0])
    for limits in (True, False):
        back = model.evaluate(4000.0, kappa, 0.0, vx=-12.0, limits=limits)
        fwd = model.evaluate(4000.0, kappa, 0.0, vx=12.0, limits=limits)
        np.testing.assert_allclose(back.fx, -fwd.fx, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose((back.omega * back.re + 12.0) / -12.0, kappa, atol=1e-6)
        assert back.omega[0] == pytest.approx(0.0, abs=1e-6) and back.fx[0] > 0.5 * 4000.0
        assert np.all(np.sign(back.fx[[0, 1, 2, 4, 5, 6]]) == -np.sign(kappa[[0, 1, 2, 4, 5, 6]]))
        # the spin given: the locked wheel, and a wheel spinning forwards while the car reverses (ISO-W slip > 1)
        given = model.evaluate(4000.0, (np.array([0.0, 5.0]) * back.re[3] + 12.0) / -12.0, 0.0, vx=-12.0,
                               omega=np.array([0.0, 5.0]), limits=limits)
        assert np.all(given.fx > 0.5 * 4000.0)


# ------------------------------------------------------------------------------------- broadcasting
@pytest.mark.parametrize("name", SAMPLE_FILES)
def test_broadcasting_matches_scalar_evaluation(name):
    model = _sample(name)
    fz = np.array([1500.0, 4500.0])[:, None, None]  # (2, 1, 1)
    kappa = np.array([-0.05, 0.0, 0.1])[:, None]  # (3, 1)
    alpha = np.array([-0.1, 0.02, 0.0, 0.2])  # (4,)
    gamma = 0.03
    vx = np.array([[5.0], [25.0], [-8.0]])  # (3, 1)
    p = 2.0e5
    for turn_slip in (False, True):
        out = model.evaluate(fz, kappa, alpha, gamma=gamma, phit=0.1, vx=vx, p=p, turn_slip=turn_slip)
        shape = np.broadcast_shapes(fz.shape, kappa.shape, alpha.shape, vx.shape)
        assert shape == (2, 3, 4)
        for k in OUTPUT_NAMES:
            assert np.shape(out[k]) == shape, k
        full = np.broadcast_arrays(fz, kappa, alpha, vx)
        grid = model.evaluate(*full[:3], gamma=np.full(shape, gamma), phit=0.1, vx=full[3], p=np.full(shape, p),
                              turn_slip=turn_slip)
        flat = model.evaluate(*(a.ravel() for a in full[:3]), gamma=gamma, phit=0.1, vx=full[3].ravel(), p=p,
                              turn_slip=turn_slip)
        for idx in np.ndindex(shape):
            one = model.evaluate(float(full[0][idx]), float(full[1][idx]), float(full[2][idx]), gamma=gamma,
                                 phit=0.1, vx=float(full[3][idx]), p=p, turn_slip=turn_slip)
            for k in OUTPUT_NAMES:
                assert np.shape(one[k]) == ()
                scale = 1e-11 * max(_tol(model, k), abs(float(one[k])))
                assert abs(out[k][idx] - one[k]) <= scale, (k, idx, out[k][idx], one[k])
        for k in OUTPUT_NAMES:
            np.testing.assert_allclose(grid[k], out[k], rtol=1e-12, atol=1e-12 * _tol(model, k))
            np.testing.assert_allclose(flat[k].reshape(shape), out[k], rtol=1e-12, atol=1e-12 * _tol(model, k))


def test_broadcasting_shapes_of_vertical_helpers():
    model = _sample(SAMPLE_FILES[1])
    rl, rho = model.loaded_radius(np.array([2000.0, 4000.0])[:, None], p=np.array([2.0e5, 2.2e5, 2.4e5]))
    assert rl.shape == rho.shape == (2, 3)
    f = model.vertical_force(rl, fy=np.zeros((4, 1, 1)))
    assert f.shape == (4, 2, 3)
    rl0, _ = model.loaded_radius(4000.0)
    assert np.shape(rl0) in ((), (1,))
    assert float(np.ravel(rl0)[0]) == pytest.approx(float(rl[1, 1]), abs=1e-12)


def test_parameters_without_a_finite_solution_raise_instead_of_returning_nan():
    """Q_V1 = -1433, Q_V2 = 480 (written by an old fit) make the free radius vanish: evaluate returned NaN radii
    and spin silently; now a ModelInputError names the input, its value and the limit (the free radius would
    change by more than 10 % at any rim speed above 0.14 m/s)."""
    from conftest import TIR_FILES

    # values no tyre can have: with_params refuses them, the unchecked replace() does not
    bad = mftyre.MFModel(mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir").params.replace(Q_V1=-1433.0, Q_V2=480.0))
    with pytest.raises(ModelInputError, match=r"vx = 40 .*beyond the limit.*Q_V1 = -1433"):
        bad.evaluate(4000.0, 0.0, 0.0, vx=40.0)
