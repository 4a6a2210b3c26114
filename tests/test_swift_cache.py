"""The SWIFT step library goes through mftyre.compiled's verified cache (cached_library): damaged libraries are
rebuilt, libraries others could write are refused, every change of what defines the code gives a new library,
concurrent builds all succeed; separate tyres sharing one library step from threads at once."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import threading
import warnings

import numpy as np
import pytest

import mftyre
from mftyre.compiled import CacheSecurityError
from swift import Cleat, StepInputs, SwiftTyre
from swift import simulate

from conftest import TIR_FILES

V = 40 / 3.6


@pytest.fixture(scope="module")
def model():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the sample file's unmodelled parameters
        return mftyre.load_tir(TIR_FILES / "car_205_60R15_mf62_swift.tir")


@pytest.fixture(scope="module")
def base_library(model, tmp_path_factory):
    """The sample file's SWIFT step library (the one most tests here use), built once into a cache of its own."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MFTYRE_CACHE", str(tmp_path_factory.mktemp("seed") / "cache"))
        return _build(_tyre(model))


@pytest.fixture
def empty_cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("MFTYRE_CACHE", str(folder))
    return folder


@pytest.fixture
def cache(empty_cache, base_library):
    """A fresh cache holding a copy of :func:`base_library` (and its description): what a test does to its files
    stays in the test; a test that must see a library compiled takes :func:`empty_cache`."""
    empty_cache.mkdir(mode=0o700)
    for source in (base_library, base_library.with_suffix(".json")):
        shutil.copyfile(source, empty_cache / source.name)
        (empty_cache / source.name).chmod(0o644)
    return empty_cache


def _tyre(model, compiled=False, **kwargs):  # compiled=False: nothing loaded into this process
    return SwiftTyre(model, Cleat(0.3, 0.05, 0.01), x_range=(0.0, 3.0), compiled=compiled, **kwargs)


def _build(tyre):
    return simulate._library(tyre, tyre._key("step"))


def _intact(library):
    meta = json.loads(library.with_suffix(".json").read_text())
    data = library.read_bytes()
    return len(data) == meta["size"] and hashlib.sha256(data).hexdigest() == meta["sha256"]


def _steps(tyre, vx=V, n=40):
    u = StepInputs(x=0.0, vx=vx, z=0.2915, omega=vx / 0.3044)
    s = tyre.initial_state(u)
    for k in range(n):
        s, out = tyre.step(s, StepInputs(x=vx * k * 1e-3, vx=vx, z=0.2915, omega=vx / 0.3044), 1e-3)
    return np.array(s), dict(out)


def test_truncated_or_altered_swift_library_is_rebuilt_not_loaded(model, cache):
    """(old: any file of the library's name was loaded as it was)"""
    tyre = _tyre(model)
    library = _build(tyre)
    original = library.read_bytes()
    assert _intact(library) and len(list(cache.glob("swift_*.so"))) == 1
    with open(library, "r+b") as fh:  # cut short (disk full, a killed copy)
        fh.truncate(len(original) // 3)
    rebuilt = _build(tyre)
    assert _intact(rebuilt) and rebuilt.stat().st_size > len(original) // 3
    data = bytearray(rebuilt.read_bytes())  # altered, same size
    data[len(data) // 2] ^= 0xFF
    rebuilt.write_bytes(bytes(data))
    again = _build(tyre)
    assert _intact(again) and again.read_bytes() != bytes(data)
    # the rebuilt library is the one loaded, and it steps as the CasADi virtual machine does
    state, out = _steps(_tyre(model, compiled=True), n=5)
    ref_state, ref_out = _steps(tyre, n=5)
    np.testing.assert_allclose(state, ref_state, rtol=1e-9, atol=1e-12)
    assert out["fz"] == pytest.approx(ref_out["fz"], rel=1e-9)


def test_swift_library_others_could_write_is_refused(model, cache, monkeypatch):
    library = _build(_tyre(model))
    library.chmod(0o666)
    with pytest.raises(CacheSecurityError, match="writable by group or others"):
        _tyre(model, compiled=True)
    library.chmod(0o644)
    cache.chmod(0o777)
    with pytest.raises(CacheSecurityError, match="the folder"):
        _tyre(model, compiled=True)
    cache.chmod(0o700)
    if os.geteuid() == 0:  # root's own files are trusted: give the library to another user
        os.chown(library, 4243, -1)
    else:  # pretend to be another user
        real_uid = os.geteuid()
        monkeypatch.setattr(os, "geteuid", lambda: real_uid + 12345)
    with pytest.raises(CacheSecurityError, match="belongs to user id"):
        _tyre(model, compiled=True)


def test_every_change_of_the_code_gives_a_new_swift_library(model, cache, monkeypatch):
    base = _build(_tyre(model))
    # the structure: a parameter that selects a form of the equations, one moved away from 0 (its terms come back)
    assert model.params.Q_A1 != 0.5 and model.params.PCFX3 == 0.0
    form = _build(_tyre(model.with_params(Q_A1=0.5)))
    switched_on = _build(_tyre(model.with_params(PCFX3=0.1)))
    monkeypatch.setattr(simulate, "_SOURCE_HASH", hashlib.sha256(b"edited ring.py").hexdigest())
    edited = _build(_tyre(model))
    assert len({base, form, switched_on, edited}) == 4
    assert all(_intact(p) for p in (base, form, switched_on, edited))
    monkeypatch.undo()
    monkeypatch.setenv("MFTYRE_CACHE", str(cache))
    assert _build(_tyre(model)) == base  # unchanged: found again, not rebuilt


def test_new_parameter_values_reuse_the_library_and_step_as_the_virtual_machine(model, cache):
    """The parameters are a run-time input of the compiled step: a refit's trial values compile nothing and add
    nothing to the cache, and the shared library steps each model as the CasADi VM does with that model's values in
    its graph (old: one library per parameter set, ~0.5 s and 83 kB each)."""
    trials = [model, model.with_params(VERTICAL_STIFFNESS=1.1 * model.params.VERTICAL_STIFFNESS,
                                       FREQ_LONG=0.9 * model.params.FREQ_LONG, Q_RA1=1.2 * model.params.Q_RA1,
                                       BELT_MASS=1.1 * model.params.BELT_MASS, PCX1=1.05 * model.params.PCX1)]
    tyres = [_tyre(m, compiled=True) for m in trials]
    assert len(list(cache.glob("swift_*.so"))) == 1
    assert len({t._compiled._lib._name for t in tyres}) == 1
    results = [_steps(t, n=60) for t in tyres]
    assert results[0][1]["fz"] != pytest.approx(results[1][1]["fz"], rel=1e-3)  # the values do reach the step
    for m, (state, out) in zip(trials, results):
        ref_state, ref_out = _steps(_tyre(m), n=60)
        np.testing.assert_allclose(state, ref_state, rtol=1e-9, atol=1e-12)
        for name in ("fx", "fz", "my"):
            assert out[name] == pytest.approx(ref_out[name], rel=1e-9, abs=1e-9)


def test_a_banked_road_gets_its_own_library_and_steps_as_the_virtual_machine(model, cache):
    """The library of a road without road camber leaves the cams' road-camber slope out (a 2-D road: 0); a banked
    road of the same model and modes gets a library of its own, built after the flat one in this process, whose
    beta_x and forces are the virtual machine's (which always looks the camber up)."""
    from swift import Flat, TwoTrack

    bank = 0.05  # 5 cm over a 1 m track spacing: beta_x = atan(0.05)
    flat, banked = (SwiftTyre(model, road, x_range=(0.0, 3.0), compiled=compiled)
                    for road, compiled in ((Flat(0.0), True), (TwoTrack(Flat(bank / 2), Flat(-bank / 2), 1.0), True)))
    assert flat._compiled._lib._name != banked._compiled._lib._name
    state, out = _steps(banked, n=20)
    ref_state, ref_out = _steps(SwiftTyre(model, banked.table, x_range=(0.0, 3.0), compiled=False), n=20)
    assert out["beta_x"] == pytest.approx(np.arctan(bank), rel=1e-3) and _steps(flat, n=2)[1]["beta_x"] == 0.0
    np.testing.assert_allclose(state, ref_state, rtol=1e-9, atol=1e-12)
    for name in ("fy", "fz", "mx"):
        assert out[name] == pytest.approx(ref_out[name], rel=1e-9, abs=1e-9)


def test_two_threads_building_one_swift_model_both_succeed(model, empty_cache):
    """Compiled into one library at once; and the CasADi graphs built at once, three times over (old: CasADi's
    shared nodes were corrupted now and then, a crash)."""
    barrier, results, errors = threading.Barrier(2), [None, None], []

    def work(i):
        try:
            barrier.wait()
            results[i] = _steps(_tyre(model, compiled=True))[0]
            for _ in range(3):
                barrier.wait()
                _tyre(model).output_function
        except Exception as exc:  # noqa: BLE001  (reported below)
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    np.testing.assert_array_equal(results[0], results[1])
    libraries = list(empty_cache.glob("swift_*.so"))
    assert libraries and all(_intact(p) for p in libraries)
    assert not [p for p in empty_cache.iterdir() if p.name.startswith(".") or p.is_dir()]  # no temporary leftovers


def test_separate_tyres_sharing_one_library_step_from_threads_at_once(model, cache):
    """Each SwiftTyre has its own buffers; the C releases the GIL, so the threads really run together."""
    speeds = (V, 0.5 * V, 1.5 * V, 0.8 * V)
    tyres = [_tyre(model, compiled=True) for _ in speeds]
    assert len({t._compiled._lib._name for t in tyres}) == 1
    expected = [_steps(_tyre(model, compiled=True), vx, 200) for vx in speeds]
    results = [None] * len(speeds)

    def work(i):
        results[i] = _steps(tyres[i], speeds[i], 200)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(speeds))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for (s, out), (s_ref, out_ref) in zip(results, expected):
        np.testing.assert_array_equal(s, s_ref)
        assert out == out_ref


def test_libraries_shipped_in_an_fmu_are_installed_verified_and_loaded_without_a_compiler(model, tmp_path,
                                                                                          monkeypatch):
    from mftyre import compiled
    from fmu.build import export_swift_libraries
    from swift.fmu_model import SwiftWheel

    monkeypatch.setenv("MFTYRE_CACHE", str(tmp_path / "build"))
    shipped = tmp_path / "fmu" / "swift"
    entry = export_swift_libraries(model, shipped)
    assert sorted(p.suffix for p in shipped.iterdir()) == [".json"] * 4 + [".so"] * 4  # each with its description
    for p in shipped.iterdir():
        p.chmod(0o666)  # as unpacked by some tool: the installed copies must still be private
    monkeypatch.setenv("MFTYRE_CACHE", str(tmp_path / "user"))
    assert compiled.install_libraries(shipped, entry) == 8

    def no_compiler(*args, **kwargs):
        raise AssertionError("compiled instead of loading the shipped library")

    real_compiler = compiled.compile_c
    monkeypatch.setattr(compiled, "compile_c", no_compiler)
    from swift.fmu_model import SUBSTEPS, TABLE_DX, WINDOW

    grid = dict(table_dx=TABLE_DX, window=WINDOW, substeps=SUBSTEPS)
    wheel = SwiftWheel(model, "flat()", axle="load", rim="torque", compiled=True)  # the shipped library, loaded
    wheel.initialise()
    wheel.step(1e-3)
    assert wheel.outputs()["Fz"] > 3000.0
    other = _tyre(model, axle="load", rim="torque", **grid)  # nothing loaded: its library may be damaged here
    monkeypatch.setattr(compiled, "compile_c", real_compiler)
    library = _build(other)
    monkeypatch.setattr(compiled, "compile_c", no_compiler)
    library.write_bytes(library.read_bytes()[:1000])  # a damaged installed copy is refused and rebuilt
    with pytest.raises(AssertionError, match="compiled instead"):
        _build(other)


def test_fmu_swift_wheel_compiled_equals_its_casadi_functions(model):
    """swift.fmu_model.SwiftWheel(compiled=True) (the pythonfmu SWIFT tyre: swift_functions' step and outputs as
    CasADi-generated C) = the same functions on CasADi's virtual machine, over a cleat, load mode and rim torque."""
    from swift.fmu_model import SwiftWheel

    wheels = [SwiftWheel(model, "cleat(x0=0.3, length=0.05, height=0.01)", axle="load", rim="torque", compiled=c)
              for c in (False, True)]
    assert wheels[0].library is None and wheels[1].library is not None
    for w in wheels:
        w.set_inputs(vx=10.0, omega=10.0 / 0.3, Fz_in=4000.0, torque=50.0)
        w.initialise()
    for _ in range(50):  # 5 cm of cleat at 10 m/s and beyond
        for w in wheels:
            w.step(1e-3)
        a, b = (w.outputs() for w in wheels)
        for name in a:
            assert b[name] == pytest.approx(a[name], rel=1e-9, abs=1e-9), name
    assert max(a["Fz"], b["Fz"]) > 0
