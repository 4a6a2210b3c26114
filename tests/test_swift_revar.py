"""Effective rolling radius variation over the curved effective road (issue 13, swift.ring module notes):
zero on the flat, the closed form on a road of constant curvature, the documented direction of its Fx over a
cleat, exact and finite derivatives."""
from __future__ import annotations

import numpy as np
import pytest

import mftyre
from swift import CircularBump, Cleat, Flat, Sampled, StepInputs, SwiftTyre
from swift.ring import OUTPUT_NAMES, STATE_NAMES

from conftest import TIR_FILES

S = {n: i for i, n in enumerate(STATE_NAMES)}
pytestmark = pytest.mark.filterwarnings("ignore:Q_BV", "ignore:ELLIPS_NLENGTH", "ignore:road height range")


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")


def _switched(model, on):
    return mftyre.MFModel(model.params.replace(SWIFT_REVAR=1.0 if on else 0.0))


def test_default_is_on(model):
    """The project's own parameter: absent from the file, default 1 (the belt-band kinematics)."""
    assert "SWIFT_REVAR" in model.params.missing and "SWIFT_REVAR" not in model.params.missing_reported
    assert model.params.SWIFT_REVAR == 1.0


def test_flat_road_no_variation_and_results_unchanged(model):
    """Flat road, braking torque on a free rim (transient slip, wind-up): Delta r_e = 0 exactly, the filtered slope
    0 to the initial Newton's last digits, and every output equals the run with the term switched off."""
    rl, _ = model.loaded_radius(4000.0)
    u = StepInputs(x=1.0, vx=15.0, z=float(rl), omega=15.0 / 0.3044, torque=-300.0)
    res = {on: SwiftTyre(_switched(model, on), Flat(), rim="torque", x_range=(0.0, 4.0)).run(0.2, u)
           for on in (True, False)}
    assert np.all(res[True]["dre"] == 0.0) and np.all(np.abs(res[True].states[:, S["betaf"]]) < 1e-20)
    assert abs(res[True]["fx"][-1]) > 500.0  # the torque is carried through the slip
    for name in OUTPUT_NAMES:  # to round-off (the two are compiled apart)
        np.testing.assert_allclose(res[True][name], res[False][name], rtol=1e-12, atol=1e-12, err_msg=name)


def test_constant_grade_no_variation(model):
    """A 10 % grade, axle load and free rim at 36 km/h: no curvature, Delta r_e and the forces as without the term
    to round-off."""
    road = Sampled([-5.0, 10.0], [-0.5, 1.0])
    u = StepInputs(x=1.0, vx=10.0, load=4000.0, omega=10.0 / 0.3044)
    res = {on: SwiftTyre(_switched(model, on), road, axle="load", rim="torque", x_range=(0.0, 3.0)).run(0.2, u)
           for on in (True, False)}
    assert np.all(res[True]["beta"] == pytest.approx(np.arctan(0.1), abs=1e-9))
    assert np.max(np.abs(res[True]["dre"])) < 1e-12
    for name in ("fx", "fz", "my", "kappa"):
        np.testing.assert_allclose(res[True][name], res[False][name], rtol=1e-9, atol=1e-9, err_msg=name)


@pytest.mark.parametrize("V", [5.0, -5.0])
def test_constant_curvature_gives_the_closed_form(model, V):
    """A circular hump of radius 11.3 m (>> the tyre), rolled over at 5 m/s forwards and backwards with the axle
    height following the road and a free rim: at the crest the free-rolling radius V_cx/Omega_b is R_e + Delta r_e,
    Delta r_e = R_e t/(1 - t), t = kappa (R_e - r_c) with kappa = -1/R (convex), against the same run without
    the term; the reported dre is that value (the tandem under the belt centre turns at kappa V_cx; with the tandem
    at the foot of the normal it was R_e kappa (R_e - r_c)/(1 - R_e kappa), 3 % smaller)."""
    hump = CircularBump(1.0, 3.0, 0.1)
    kappa = -1.0 / hump.radius
    rl, _ = model.loaded_radius(4000.0)
    dt, x0 = 1e-3, (0.3 if V > 0 else 4.7)
    crest = {}
    for on in (True, False):
        tyre = SwiftTyre(_switched(model, on), hump, rim="torque", x_range=(0.0, 5.0))
        inputs = lambda t: StepInputs(x=x0 + V * t, vx=V, z=float(rl + hump.height(x0 + V * t)),  # noqa: E731
                                      vz=float(V * (hump.height(x0 + V * t + 1e-6) - hump.height(x0 + V * t)) / 1e-6),
                                      omega=V / 0.3044)
        res = tyre.run((hump.x0 + hump.length / 2 - x0) / V, inputs, dt=dt)
        crest[on] = {n: res[n][-1] for n in ("vcx", "re", "rl", "dre", "curvature")}
        crest[on]["omb"] = res.states[-1, S["omb"]]
    on, off = crest[True], crest[False]
    # the effective road is the road (long wavelength), to the secant slopes of the 1 mm cam-height table
    assert on["curvature"] == pytest.approx(kappa, rel=1e-2)
    re, rc = on["re"], on["rl"]
    expected = re * kappa * (re - rc) / (1.0 - kappa * (re - rc))
    assert expected < -2e-4  # r_e drops on a crest by a measurable amount (0.3 mm)
    measured = on["vcx"] / on["omb"] - off["vcx"] / off["omb"]
    assert measured == pytest.approx(expected, rel=0.03)
    assert on["dre"] == pytest.approx(expected, rel=0.015)
    assert off["dre"] == 0.0


@pytest.mark.parametrize("kmh", [30.0, 60.0])
def test_cleat_fx_changes_in_the_documented_direction(model, kmh):
    """10 x 20 mm cleat, fixed axle, free rim: at the crest of the effective road (most negative curvature) the
    rolling radius drops, the wheel cannot spin up at once, so the contact force brakes more with the term on
    (by more than 50 N: -193 / -59 N at 30 / 60 km/h with the slope filtered over the contact half-length a,
    issue 19; more than 200 N with the old numerical 4 mm filter, whose value set the result); the wheel-centre
    Fx response changes by more than 20 % of its range."""
    rl, _ = model.loaded_radius(4000.0)
    V = kmh / 3.6
    res = {on: SwiftTyre(_switched(model, on), Cleat(0.4, 0.02, 0.01), rim="torque", x_range=(0.0, 1.2)).run(
        0.6 / V, StepInputs(x=0.1, vx=V, z=float(rl), omega=V / 0.3044)) for on in (True, False)}
    crest = np.argmin(res[True]["curvature"])
    assert res[True]["dre"][crest] < -3e-3
    assert res[True]["fx_c"][crest] - res[False]["fx_c"][crest] < -50.0
    assert np.max(np.abs(res[True]["fx"] - res[False]["fx"])) > 0.2 * np.ptp(res[False]["fx"])
    assert np.all(np.isfinite(res[True]["fx"]))


def test_exact_derivatives_at_a_cleat_point_match_finite_differences(model):
    """The CasADi right-hand side and outputs at a state on the cleat (30 km/h, term on): finite, and their exact
    Jacobians with respect to the state equal central differences."""
    import casadi as ca

    rl, _ = model.loaded_radius(4000.0)
    V = 30 / 3.6
    tyre = SwiftTyre(model, Cleat(0.4, 0.02, 0.01), rim="torque", x_range=(0.0, 1.2))
    u = StepInputs(x=0.1, vx=V, z=float(rl), omega=V / 0.3044)
    res = tyre.run(0.31 / V, u)
    state = res.states[-1]
    assert abs(res["curvature"][-1]) > 0.5 and abs(state[S["betaf"]] - res["beta"][-1]) > 1e-3  # turning plane
    uvec = tyre._u(StepInputs(x=state[S["xa"]], vx=V, z=float(rl), omega=V / 0.3044))
    x0w, grid, hw, _ = tyre._rhs_args(state)
    xs = ca.MX.sym("x", len(STATE_NAMES))
    dx, out = tyre.rhs_function(xs, uvec, x0w, grid, hw, 0.0)
    both = ca.Function("f", [xs], [ca.vertcat(dx, out)])
    jac = np.asarray(ca.Function("j", [xs], [ca.jacobian(ca.vertcat(dx, out), xs)])(state))
    value = np.asarray(both(state)).ravel()
    assert np.all(np.isfinite(value)) and np.all(np.isfinite(jac))
    fd = np.empty_like(jac)
    for j in range(len(STATE_NAMES)):
        e = np.zeros_like(state)
        e[j] = 1e-7 * max(1.0, abs(state[j]))
        fd[:, j] = (np.asarray(both(state + e)).ravel() - np.asarray(both(state - e)).ravel()) / (2 * e[j])
    row_scale = np.max(np.abs(jac), axis=1, keepdims=True) + 1e-9
    bad = np.abs(fd - jac) > 1e-6 * row_scale + 1e-4 * np.abs(jac)
    names = list(STATE_NAMES) + list(OUTPUT_NAMES)
    assert not bad.any(), [(names[i], STATE_NAMES[j]) for i, j in zip(*np.nonzero(bad))]
    assert np.any(jac[len(STATE_NAMES) + OUTPUT_NAMES.index("dre")] != 0.0)
    assert jac[S["kappa"], S["betaf"]] != 0.0  # the filtered slope drives the slip


def test_radius_variation_does_not_depend_on_the_step(model):
    """The slope rate in the slip is the slope filtered over the contact half-length a (a physical length, issue
    19), not over max(4 mm, half a step's travel): the cleat response at 60 km/h is the same at 2 ms and 0.25 ms
    steps (old: the filter length followed the step above 57 km/h at 1 ms, and the term's Fx contribution at
    60 km/h was +238 / +151 / -74 N with a 4 / 8 / 16 mm filter)."""
    rl, _ = model.loaded_radius(4000.0)
    V = 60 / 3.6
    tyre = SwiftTyre(model, Cleat(0.4, 0.02, 0.01), rim="torque", x_range=(0.0, 1.2))
    u = StepInputs(x=0.1, vx=V, z=float(rl), omega=V / 0.3044)
    coarse, fine = tyre.run(0.036, u, 2e-3), tyre.run(0.036, u, 2.5e-4)
    assert np.max(np.abs(coarse["fx"] - fine["fx"][::8])) < 0.015 * np.ptp(fine["fx"])
    assert np.ptp(fine["fx"]) > 300.0  # the cleat was met
