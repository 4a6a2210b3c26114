"""The tandem cams under the wheel centre (issue 19 item 5): the cams move only vertically (seed 002, Schmeitz et
al. 2005 sec. 3.1), so the contact solution does not fold. Old: the tandem moved with the foot of the normal and
the solution jumped where a cam met an edge (Fz +364 N within 0.5 mm at the first touch of a 20 mm step or a
20 x 20 mm cleat, in the quasi-static and the dynamic model alike), creep differed from the quasi-static model by
10 % of the peak at the jump, and at 2 m/s over a 10 x 20 mm cleat Fx changed sign five times."""
from __future__ import annotations

import numpy as np
import pytest

import mftyre
from swift import Cleat, Step, StepInputs, SwiftTyre, quasi_static

from conftest import SHARED, TIR_FILES, require_shared

pytestmark = pytest.mark.filterwarnings("ignore:Q_BV", "ignore:road height range", "ignore:ELLIPS_NLENGTH")

ROADS = {"step 20 mm": Step(0.4, 0.02), "cleat 20 x 20 mm": Cleat(0.4, 0.02, 0.02),
         "cleat 10 x 20 mm": Cleat(0.4, 0.01, 0.02)}
FILES = {"sample": lambda: TIR_FILES / "car_205_60R15_mf62_swift.tir",
         "tno": lambda: require_shared(SHARED / "reference" / "tir" / "TNO_car205_60R15.tir")}


def _creep(model, road):
    """0.1 m/s from x = 0.15 m over 0.55 m, fixed axle at 4 kN, free rim, 2 ms steps (0.2 mm of travel each):
    the dynamic run and the quasi-static model at its positions."""
    rl, _ = model.loaded_radius(4000.0)
    tyre = SwiftTyre(model, road, rim="torque", x_range=(-0.5, 1.2))
    res = tyre.run(5.5, StepInputs(x=0.15, vx=0.1, z=float(rl), omega=0.1 / model.params.UNLOADED_RADIUS), dt=2e-3)
    return res, quasi_static(model, road, res.x, 4000.0)


@pytest.mark.parametrize("road", ["step 20 mm", "cleat 20 x 20 mm"])
def test_no_jump_at_first_touch(road):
    """Quasi-static Fz changes by at most 2 % of its peak per 0.5 mm of travel (old: 364 N, 8 % / 16 %); the
    dynamic creep by at most 1 % per 0.2 mm (old: 310 N)."""
    model = mftyre.load_tir(FILES["sample"]())
    x = np.arange(0.1, 0.75, 5e-4)
    qs = quasi_static(model, ROADS[road], x, 4000.0)
    peak = np.max(qs.fz - qs.fz[0])
    assert peak > 2000.0
    assert np.max(np.abs(np.diff(qs.fz))) < 0.02 * peak
    res, _ = _creep(model, ROADS[road])
    assert np.max(np.abs(np.diff(res["fz"]))) < 0.01 * peak


@pytest.mark.parametrize("name", list(FILES))
def test_creep_equals_quasi_static_everywhere(name):
    """10 x 20 mm cleat: creep equals the quasi-static model within 5 % of the peak everywhere (Fz change; Fx within
    5 % of its range; the issue asks 15 %; old: 10 % at the jump), l_s within 1 mm."""
    model = mftyre.load_tir(FILES[name]())
    res, qs = _creep(model, ROADS["cleat 10 x 20 mm"])
    peak = np.max(qs.fz - qs.fz[0])
    assert peak > 2000.0
    assert np.max(np.abs((res["fz"] - res["fz"][0]) - (qs.fz - qs.fz[0]))) < 0.05 * peak
    assert np.max(np.abs((res["fx"] - res["fx"][0]) - (qs.fx - qs.fx[0]))) < 0.05 * np.ptp(qs.fx)
    assert np.max(np.abs(res["ls"] - qs.ls)) < 1e-3


@pytest.mark.parametrize("name", list(FILES))
def test_fx_first_negative_then_positive_at_2_m_per_s(name):
    """2 m/s over a 10 x 20 mm cleat, fixed axle, free rim: the change of Fx is first negative (the cleat ahead
    tilts the plane back), then positive, each beyond 30 % of its peak, and never changes sign in between by more
    than 10 % of the peak (old: -, +, -, +, -)."""
    model = mftyre.load_tir(FILES[name]())
    rl, _ = model.loaded_radius(4000.0)
    tyre = SwiftTyre(model, ROADS["cleat 10 x 20 mm"], rim="torque", x_range=(-0.5, 1.2))
    V = 2.0
    res = tyre.run(0.35, StepInputs(x=0.1, vx=V, z=float(rl), omega=V / float(model.evaluate(4000.0, 0, 0, vx=V).re)),
                   dt=1e-3)
    fx = res["fx"] - res["fx"][0]
    peak = np.max(np.abs(fx))
    big = fx[np.abs(fx) > 0.1 * peak]
    signs = [big[0] > 0] + [b > 0 for a, b in zip(big[:-1], big[1:]) if (a > 0) != (b > 0)]
    assert signs == [False, True]
    assert fx.min() < -0.3 * peak and fx.max() > 0.3 * peak
    assert np.argmin(fx) < np.argmax(fx)
