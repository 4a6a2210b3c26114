"""Tandem-cam enveloping and the quasi-static tyre: analytic limits, closed forms and the pressure trends of
Schmeitz et al. (2005), figs 17-20 (higher pressure: shorter response, larger forces)."""
from __future__ import annotations

import numpy as np
import pytest

import mftyre
from swift import Cams, Cleat, Flat, Sampled, Sine, Step, TwoTrack, cam_height, effective_road, \
    effective_road_3d, quasi_static, tandem_base
from swift.road import CircularBump, Road, Trapezoid

from conftest import TIR_FILES


@pytest.fixture(scope="module")
def model():
    return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")


@pytest.fixture(scope="module")
def cams(model):
    return Cams.from_params(model.params)


def test_cam_size_from_tir(model, cams):
    prm = model.params
    assert cams.ae == pytest.approx(prm.ELLIPS_LENGTH * prm.UNLOADED_RADIUS)
    assert cams.be == pytest.approx(prm.ELLIPS_HEIGHT * prm.UNLOADED_RADIUS)
    # the contour reaches b_e at the end of the semi-axis, 0 at the lowest point
    assert cams.contour(0.0) == 0.0 and cams.contour(cams.ae) == pytest.approx(cams.be)


@pytest.mark.filterwarnings("ignore:road height range")
def test_flat_road_and_grade(cams):
    x = np.linspace(-1, 1, 201)
    eff = effective_road(Flat(0.02), x, 0.1, cams)
    assert np.allclose(eff.w, 0.02) and np.allclose(eff.beta, 0.0) and np.allclose(eff.curvature, 0.0)
    s = 0.05  # constant grade: slope exact, no curvature, w offset by max(s xi - z_c(xi))
    grade = Sampled([-10.0, 10.0], [-10 * s, 10 * s])
    eff = effective_road(grade, x, 0.1, cams)
    assert np.allclose(eff.beta, np.arctan(s), atol=1e-9) and np.allclose(eff.curvature, 0.0, atol=1e-6)
    xi = np.linspace(-cams.ae, cams.ae, 200001)
    offset = np.max(s * xi - cams.contour(xi))
    assert np.allclose(eff.w - s * x, offset, atol=2e-6)


def test_long_wavelength_passes_unchanged(cams):
    road = Sine(0.005, 2.0)
    x = np.linspace(1.0, 3.0, 401)
    eff = effective_road(road, x, 0.11, cams)
    assert np.max(np.abs(eff.w - road.height(x))) < 1e-4  # < 0.1 mm of 5 mm
    slope = np.arctan(0.005 * 2 * np.pi / 2.0 * np.cos(2 * np.pi * x / 2.0))
    assert np.max(np.abs(eff.beta - slope)) < np.radians(0.02)
    # a short wavelength is filtered
    short = effective_road(Sine(0.005, 0.2), np.linspace(1.0, 1.2, 201), 0.11, cams)
    assert np.ptp(short.w) < 0.5 * 0.01


def test_step_basic_function_and_smoothness(cams):
    H, ls = 0.01, 0.11
    x = np.linspace(-0.3, 0.3, 6001)
    h = cam_height(Step(0.0, H), x, cams)
    rise = x[(h > 1e-12) & (h < H - 1e-12)]
    assert rise[-1] - rise[0] == pytest.approx(cams.basic_length(H), abs=2e-4)
    eff = effective_road(Step(0.0, H), x, ls, cams)
    assert np.all(np.diff(eff.w) >= -1e-12) and eff.w[0] == 0 and eff.w[-1] == pytest.approx(H)
    assert np.all(eff.beta >= 0)
    assert np.trapezoid(np.tan(eff.beta), x) == pytest.approx(H, rel=1e-3)  # two-point follower identity
    assert np.max(np.abs(np.diff(eff.w))) < 0.05 * H  # no jump: the response is spread over l_b + l_s


def test_cleat_enveloped_closed_forms(cams):
    H, L, ls = 0.01, 0.05, 0.11
    x = np.linspace(-0.2, 0.25, 4501)
    eff = effective_road(Cleat(0.0, L, H), x, ls, cams)
    centre = np.argmin(np.abs(x - L / 2))
    assert eff.w[centre] == pytest.approx(max(0.0, H - cams.contour((ls - L) / 2)), abs=1e-6)
    assert eff.w.max() < H
    assert np.max(np.abs(eff.beta)) == pytest.approx(np.arctan(H / ls), abs=1e-9)
    touched = x[eff.w > 1e-12]
    assert touched[-1] - touched[0] == pytest.approx(2 * cams.basic_length(H) + ls + L, abs=3e-4)
    # symmetric obstacle: w symmetric, slope antisymmetric about the cleat centre
    xm = L / 2 + np.linspace(-0.15, 0.15, 301)
    e1, e2 = effective_road(Cleat(0.0, L, H), xm, ls, cams), effective_road(Cleat(0.0, L, H), xm[::-1], ls, cams)
    assert np.allclose(e1.w, e2.w, atol=1e-9) and np.allclose(e1.beta, -e2.beta, atol=1e-9)


@pytest.mark.parametrize("road", [
    Step(1.0, 0.02), Step(1.0, -0.02), Cleat(2.0, 0.02, 0.015), Trapezoid(1.0, 0.1, -0.03, 0.05),
    Trapezoid(1.0, 0.0, 0.03, 0.05), CircularBump(1.2, 0.3, 0.02), Sine(0.01, 0.5, 1.0, 3.0), Sine(0.01, 0.5, 1.0),
    Sampled([0, 1, 1.5, 2, 2.5, 3], [0, 0, 0.01, 0.01, 0.01, 0]), Flat(0.003) + Cleat(1.0, 0.05, 0.01) + Step(2.5, 0.02),
    TwoTrack(Cleat(1, 0.02, 0.01), Flat() + Step(2, 0.01), 1.5)], ids=lambda road: type(road).__name__)
def test_skipping_the_search_on_level_spans_changes_no_bit(road, cams, monkeypatch):
    """On a level part of the road the cam rests at that level; elsewhere it searches. The heights equal the search
    everywhere (the spans switched off) bit for bit, and the level parts are skipped."""
    x = np.linspace(-1.0, 5.0, 12001)
    ys = (-0.3, 0.1) if road.varies_with_y else (0.0,)
    skipped = np.asarray(road.level_spans()).reshape(-1, 2)
    assert skipped.size and np.all(skipped[:, 1] > skipped[:, 0]) and np.all(skipped[1:, 0] >= skipped[:-1, 1])
    fast = [cam_height(road, x, cams, y=y) for y in ys]
    monkeypatch.setattr(type(road), "level_spans", Road.level_spans)
    searched = [cam_height(road, x, cams, y=y) for y in ys]
    for a, b in zip(fast, searched):
        assert np.array_equal(a.view(np.int64), b.view(np.int64))


def test_point_cams_are_two_point_follower():
    point = Cams(ae=0.0, be=0.3, ce=1.5, shift=0.8)
    road = Sine(0.005, 0.3) + Cleat(0.4, 0.05, 0.01)
    x = np.linspace(0.0, 1.0, 301)
    eff = effective_road(road, x, 0.1, point)
    assert np.allclose(eff.w, (road.height(x + 0.05) + road.height(x - 0.05)) / 2, atol=1e-12)


def test_road_camber_from_two_tracks(cams):
    bank = 0.02  # left side 2 cm higher over 1 m
    road = TwoTrack(Flat(bank / 2), Flat(-bank / 2), spacing=1.0)
    eff = effective_road_3d(road, np.linspace(0, 1, 11), 0.1, 0.07, cams)
    assert np.allclose(eff.beta_x, np.arctan(bank / 1.0)) and np.allclose(eff.w, 0.0, atol=1e-12)


def test_sampled_csv(tmp_path):
    path = tmp_path / "road.csv"
    path.write_text("x,z\n0,0\n1,0.01\n2,0\n")
    road = Sampled.from_csv(path)
    assert road.height([0.5, 1.5, 3.0]) == pytest.approx([0.005, 0.005, 0.0])
    with pytest.raises(mftyre.errors.DataError):
        Sampled.from_csv(path, z_column="height")


def test_tandem_base_shortens_with_pressure(model):
    prm = model.params
    ls = tandem_base(prm, 4000.0, (np.array([1.8e5, 2.2e5, 2.6e5]) - prm.NOMPRES) / prm.NOMPRES)
    assert np.all(np.diff(ls) < 0)


@pytest.mark.parametrize("mode", ["fixed_axle", "constant_load"])
def test_pressure_trend_quasi_static(model, mode):
    """Schmeitz et al. 2005 figs 17-20: higher pressure -> shorter response and larger forces."""
    x = np.linspace(-0.25, 0.3, 1101)
    peaks, lengths, lifts = [], [], []
    for p in (1.8e5, 2.2e5, 2.6e5):
        q = quasi_static(model, Cleat(0.0, 0.05, 0.01), x, 4000.0, p=p, mode=mode)
        touched = x[q.road.w > 1e-9]
        lengths.append(touched[-1] - touched[0])
        peaks.append((np.max(q.fz - q.fz[0]), np.max(np.abs(q.fx))))
        lifts.append(q.dz.max())
        if mode == "constant_load":  # |Fx| = Fz tan(beta) (free rolling), vertical force constant
            i = np.argmax(np.abs(q.fx))
            assert np.allclose(q.fz, 4000.0) and abs(q.fx[i]) == pytest.approx(4000.0 * 0.01 / q.ls[i], rel=1e-6)
    peaks = np.array(peaks)
    assert np.all(np.diff(lengths) < 0)
    assert np.all(np.diff(peaks[:, 1]) > 0)
    if mode == "fixed_axle":
        assert np.all(np.diff(peaks[:, 0]) > 0)
        assert peaks[:, 0].max() < 2 * 4000  # enveloped: far below a point follower on a 10 mm cleat
    else:
        assert np.all(np.diff(lifts) > 0) and max(lifts) < 0.01
