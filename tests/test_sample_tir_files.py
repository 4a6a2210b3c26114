"""The sample property files in tir_files/: complete, documented, and physically plausible.

The plausibility bounds are general knowledge about passenger-car tyres (friction 0.8-1.5 on dry road,
cornering stiffness 10-30 per radian of load, longitudinal slip stiffness 10-40 per unit slip of load),
not values taken from our own output.

Signs in ISO-W (TYDEX W) axes, x forward, z up, y to the left, moments right-handed about the axes:
* a positive slip angle alpha means the contact point slides towards +y (Vsy = tan(alpha) |Vx| > 0), so the
  road pushes the tyre towards -y: Fy < 0, i.e. the cornering stiffness Kya = dFy/dalpha is negative;
* the side force acts a pneumatic trail t > 0 behind the contact centre, at x = -t, so its moment about z is
  Mz = x Fy = -t Fy > 0 for small positive alpha. A positive Mz turns the wheel's x axis towards +y, i.e.
  towards the velocity (which lies at +alpha from the x axis): it reduces the slip angle, a restoring,
  "self-aligning" torque. Hence Mz > 0 for small alpha > 0 and dMz/dalpha > 0 at alpha = 0;
* a wheel rolling forwards spins about +y (omega x (0, 0, R) = (omega R, 0, 0) moves the centre to +x);
  the rolling-resistance moment opposes that spin: My < 0 forwards, My > 0 rolling backwards.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import mftyre
from mftyre.params import MissingParameterWarning

from conftest import TIR_FILES

TIR_PATHS = sorted(TIR_FILES.glob("*.tir"))
IDS = [p.name for p in TIR_PATHS]


def _load_recording(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = mftyre.load_tir(path)
    missing = [w for w in caught if issubclass(w.category, MissingParameterWarning)]
    return model, missing


def _load(path):
    return _load_recording(path)[0]


def test_sample_files_exist():
    names = {p.name for p in TIR_PATHS}
    assert {"car_205_60R15_mf61.tir", "car_205_60R15_mf62_swift.tir"} <= names


@pytest.mark.parametrize("path", TIR_PATHS, ids=IDS)
def test_loads_without_missing_parameter_warnings(path):
    """A sample file should be complete for its model version: no parameter filled in by default."""
    model, missing = _load_recording(path)
    assert model.params.fittyp in (61, 62)
    reported = list(model.params.missing_reported)
    assert not missing and not reported, (
        f"{path.name}: MissingParameterWarning for {reported}: "
        + " | ".join(str(w.message) for w in missing))


@pytest.mark.parametrize("path", TIR_PATHS, ids=IDS)
def test_header_names_source(path):
    """Each file starts with a '!' comment header saying what it is and where its values come from."""
    lines = path.read_text().splitlines()
    header = []
    for line in lines:
        if not line.startswith("!"):
            break
        header.append(line)
    assert len(header) >= 5, f"{path.name}: no comment header at the top"
    text = "\n".join(header)
    assert path.name in text, "the header should name the file"
    assert "SOURCE" in text.upper()
    # a citable source: author/title/year of the publication the values come from
    assert "Pacejka" in text and "2012" in text
    assert "Appendix 3" in text or "App. 3" in text
    # and the file is listed in the README of the directory
    assert path.name in (TIR_FILES / "README.md").read_text()


def test_mf61_and_mf62_files_carry_the_same_fit():
    """README: the two files carry the same published fit and differ only in FITTYP and MF 6.2 terms."""
    a = _load(TIR_FILES / "car_205_60R15_mf61.tir").params
    b = _load(TIR_FILES / "car_205_60R15_mf62_swift.tir").params
    mf62_only = {"FITTYP", "Q_CAM1", "Q_CAM2", "Q_CAM3", "Q_FCY2", "Q_FYS1", "Q_FYS2", "Q_FYS3", "ENV_C1", "ENV_C2"}
    differ = sorted(k for k in a if a[k] != b[k] and k not in mf62_only)
    assert not differ, f"parameters differ between the MF 6.1 and MF 6.2 sample files: {differ}"
    # at zero camber, no Fx/Fy and no spin the MF 6.2 vertical relation reduces to MF 6.1
    fz = np.array([1000.0, 4000.0, 8000.0])
    ra, _ = mftyre.MFModel(a).loaded_radius(fz)
    rb, _ = mftyre.MFModel(b).loaded_radius(fz)
    np.testing.assert_allclose(rb, ra, rtol=0, atol=1e-9)


@pytest.mark.parametrize("path", TIR_PATHS, ids=IDS)
def test_plausible_physics_at_nominal_conditions(path):
    model = _load(path)
    prm = model.params
    fz = prm.FNOMIN
    nominal = model.evaluate(fz=fz, kappa=0.0, alpha=0.0)
    # friction
    assert 0.8 <= float(nominal.mux) <= 1.5
    assert 0.8 <= float(nominal.muy) <= 1.5
    # cornering stiffness: negative in ISO-W, 10..30 /rad of the load
    kya = float(nominal.kya)
    assert kya < 0
    assert 10.0 <= abs(kya) / fz <= 30.0
    # longitudinal slip stiffness: positive, 10..40 per unit slip of the load
    kxk = float(nominal.kxk)
    assert 10.0 <= kxk / fz <= 40.0
    # a driving slip gives a forward force, a positive slip angle a negative side force
    assert float(model.evaluate(fz=fz, kappa=0.05, alpha=0.0).fx) > 0
    assert float(model.evaluate(fz=fz, kappa=-0.05, alpha=0.0).fx) < 0
    assert float(model.evaluate(fz=fz, kappa=0.0, alpha=0.03).fy) < 0
    assert float(model.evaluate(fz=fz, kappa=0.0, alpha=-0.03).fy) > 0
    # self-aligning torque (see the module docstring): Mz > 0 at small positive alpha, < 0 at small negative,
    # restoring slope at zero slip, and a positive pneumatic trail of a few centimetres
    small = np.array([0.01, 0.02, 0.04])
    assert np.all(model.evaluate(fz=fz, kappa=0.0, alpha=small).mz > 0)
    assert np.all(model.evaluate(fz=fz, kappa=0.0, alpha=-small).mz < 0)
    h = 1e-5
    dmz = (model.evaluate(fz=fz, kappa=0.0, alpha=h).mz - model.evaluate(fz=fz, kappa=0.0, alpha=-h).mz) / (2 * h)
    assert float(dmz) > 0
    assert 0.005 < float(nominal.t) < 0.1
    # effective rolling radius between rim and unloaded radius; loaded radius below the effective radius
    assert prm.RIM_RADIUS < float(nominal.re) < prm.UNLOADED_RADIUS
    assert prm.RIM_RADIUS < float(nominal.rl) < float(nominal.re)
    # rolling resistance opposes the rolling: My < 0 forwards, > 0 backwards; coefficient 0.005..0.02
    assert float(nominal.my) < 0
    crr = -float(nominal.my) / (fz * prm.UNLOADED_RADIUS)
    assert 0.005 <= crr <= 0.02
    backwards = model.evaluate(fz=fz, kappa=0.0, alpha=0.0, vx=-prm.LONGVL)
    assert float(backwards.my) > 0
    # vertical stiffness at nominal load near the file's VERTICAL_STIFFNESS (same order, within 30 %)
    assert 0.7 < float(nominal.cz) / prm.VERTICAL_STIFFNESS < 1.3
    # peak friction reached within the slip ranges the file declares
    kappa = np.linspace(0.0, 0.3, 301)
    fx = model.evaluate(fz=fz, kappa=kappa, alpha=0.0).fx
    assert 0.8 * fz <= np.max(fx) <= 1.5 * fz
    alpha = np.linspace(0.0, 0.3, 301)
    fy = model.evaluate(fz=fz, kappa=0.0, alpha=alpha).fy
    assert 0.8 * fz <= -np.min(fy) <= 1.5 * fz
