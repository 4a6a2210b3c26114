"""The native FMU's variants and platforms (issue 35): one .fmu with Linux and Windows binaries, FMI 2.0 and 3.0,
co-simulation (CS) and model exchange (ME). Each variant is built once per test process (conftest ``built_fmu``)
and checked by importers we did not write (fmpy; the FMI Reference FMUs' fmusim when installed), by a plain C host
(tests/fmu_host.c) on linux64 and, cross-compiled with MinGW-w64, on the win64 binary under Wine, against the FMI 2
CS FMU (the variant the other test files check against the Python wheels) and against finite differences."""
from __future__ import annotations

import ctypes
import math
import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

from fmu import native_build  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TIR61 = ROOT / "tir_files" / "car_205_60R15_mf61.tir"
TIR62 = ROOT / "tir_files" / "car_205_60R15_mf62_swift.tir"
CLEAT = "cleat(x0=3.0, length=0.05, height=0.01)"  # test_fmu_native's road: its compiled objects are shared
HOST_C = Path(__file__).with_name("fmu_host.c")
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) to build native FMUs")

MODELS = {"steady": [TIR61], "transient": [TIR61, "--model", "transient"],
          "swift": [TIR62, "--model", "swift", "--road", CLEAT]}
#: (FMI version, interface, model): every variant the builder offers (SWIFT: co-simulation only).
VARIANTS = [(v, i, m) for v in (2, 3) for i in ("cs", "me") for m in MODELS if not (i == "me" and m == "swift")]
MINGW = shutil.which(native_build.MINGW)
WINE = shutil.which("wine64") or shutil.which("wine")


def _id(variant):
    return f"fmi{variant[0]}-{variant[1]}-{variant[2]}"


@pytest.fixture(scope="module")
def fmus(built_fmu):
    """variant -> path, built lazily (each once per process; FMI 2 CS as the other FMU test files build it)."""
    import warnings

    def get(version, interface, model):
        options = [] if (version, interface) == (2, "cs") else ["--interface", interface, "--fmi-version",
                                                                 str(version)]
        options += ["--platforms", "linux64,win64" if MINGW else "linux64"]  # conftest: linux64 alone by default
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return built_fmu(*MODELS[model], *options)
    return get


# ---------------------------------------------------------------------------------------- platforms, build
def test_one_fmu_holds_every_platform_it_could_build_and_its_sources(fmus):
    """The default build puts linux64 and (with MinGW-w64) win64 in one archive, FMI 3 under its platform tuples,
    with the C sources and buildDescription.xml."""
    for version, folders in ((2, ("linux64", "win64")), (3, ("x86_64-linux", "x86_64-windows"))):
        with zipfile.ZipFile(fmus(version, "cs", "transient")) as zf:
            names = set(zf.namelist())
        assert f"binaries/{folders[0]}/mftyre_transient.so" in names
        assert (f"binaries/{folders[1]}/mftyre_transient.dll" in names) == bool(MINGW), names
        assert {"sources/buildDescription.xml", "sources/tyre_model.c", "sources/tyre_start.c", "sources/fmi2_tyre.c"} <= names
        assert ("sources/fmi3_tyre.c" in names) == (version == 3)
        assert not any(n.startswith("binaries/aarch64") or n.startswith("binaries/darwin") for n in names)


def _build_cli(tmp_path, *args):
    from mftyre.cli import main

    return main(["fmu", "build", str(TIR61), "-o", str(tmp_path / "t.fmu"), *map(str, args)])


@pytest.fixture
def fake_compile(monkeypatch):
    """The compiler stubbed (what is tested is which binaries are asked for and what the build says)."""
    asked = []

    def compile_sources(sources, library):
        asked.append(library.relative_to(library.parents[2]).as_posix())
        library.parent.mkdir(parents=True, exist_ok=True)
        library.write_bytes(b"stub")

    monkeypatch.setattr(native_build, "compile_sources", compile_sources)
    return asked


def test_build_says_which_platforms_it_built_and_why_others_are_missing(tmp_path, capsys, fake_compile, monkeypatch):
    monkeypatch.setenv(native_build.PLATFORMS_ENV, "linux64")  # the default of --platforms from the environment
    assert _build_cli(tmp_path) == 0
    assert "binaries for linux64\n" in capsys.readouterr().out and fake_compile == ["binaries/linux64/mftyre_steady.so"]
    monkeypatch.delenv(native_build.PLATFORMS_ENV)  # the default: every platform this machine can build
    fake_compile.clear()
    assert _build_cli(tmp_path, "--overwrite") == 0
    out = capsys.readouterr().out
    assert "binaries for linux64" + (", win64" if MINGW else "") in out
    assert "no darwin64 binary: not cross-compiled here" in out
    assert "no aarch64-linux binary: FMI 2.0 has no platform name for it" in out
    assert fake_compile == ["binaries/linux64/mftyre_steady.so"] + (["binaries/win64/mftyre_steady.dll"] if MINGW
                                                                     else [])
    # without the cross compiler: linux64 only, and the reason with the package to install
    which = shutil.which
    monkeypatch.setattr(native_build.shutil, "which", lambda name, *a, **k: None if "mingw" in name else
                        which(name, *a, **k))
    fake_compile.clear()
    assert _build_cli(tmp_path, "--overwrite") == 0
    assert "no win64 binary: no MinGW-w64 cross compiler (x86_64-w64-mingw32-gcc; Debian/Ubuntu: apt-get install " \
           "gcc-mingw-w64-x86-64)" in capsys.readouterr().out
    assert fake_compile == ["binaries/linux64/mftyre_steady.so"]
    # asked for explicitly, it is an error naming the cause; FMI 3 names ARM 64 (aarch64 is not linux64)
    assert _build_cli(tmp_path, "--overwrite", "--platforms", "linux64,win64") == 1
    assert "--platforms win64: cannot build it here: no MinGW-w64 cross compiler" in capsys.readouterr().err
    assert _build_cli(tmp_path, "--overwrite", "--platforms", "aarch64-linux", "--fmi-version", "3") == 1
    assert "not cross-compiled here (build it on aarch64-linux from the FMU's sources/)" in capsys.readouterr().err
    assert _build_cli(tmp_path, "--overwrite", "--platforms", "linux32") == 1
    assert "unknown platform 'linux32'" in capsys.readouterr().err
    fake_compile.clear()
    assert _build_cli(tmp_path, "--overwrite", "--platforms", "x86_64-linux", "--fmi-version", "3") == 0
    assert fake_compile == ["binaries/x86_64-linux/mftyre_steady.so"]


def test_swift_model_exchange_is_refused_with_the_reason(tmp_path, capsys):
    from mftyre.cli import main

    assert main(["fmu", "build", str(TIR62), "-o", str(tmp_path / "s.fmu"), "--model", "swift",
                 "--interface", "me"]) == 1
    err = capsys.readouterr().err
    assert "--interface me is not offered for --model swift" in err and "contact solution" in err
    assert not (tmp_path / "s.fmu").exists()


def test_the_pythonfmu_backend_refuses_the_native_options(tmp_path, capsys):
    from mftyre.cli import main

    assert main(["fmu", "build", str(TIR61), "-o", str(tmp_path / "p.fmu"), "--backend", "pythonfmu",
                 "--fmi-version", "3"]) == 1
    assert "options of --backend native" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------- fmpy
@pytest.mark.parametrize("variant", VARIANTS, ids=_id)
def test_fmpy_validates_every_variant(fmus, variant):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmus(*variant))) == []


def _scenario(name, md, t_end=0.6):
    """Inputs (structured array for fmpy, rows for a CSV) of the cornering, braking and cleat runs: ramps over the
    first 0.25 s, then held (both hosts interpolate linearly between the 1 ms samples)."""
    start = {v.name: float(v.start) for v in md.modelVariables if v.causality == "input"}
    t = np.round(np.arange(0.0, t_end + 5e-4, 1e-3), 6)
    ramp = np.minimum(t / 0.25, 1.0)
    vy = 0.8 * ramp if name == "cornering" else np.zeros_like(t)
    omega = start["omega"] * (1.0 - 0.12 * ramp) if name == "braking" else np.full_like(t, start["omega"])
    if name == "cleat":
        vy = np.full_like(t, 0.2)
    signals = np.zeros(t.size, dtype=[("time", float), ("vy", float), ("omega", float)])
    signals["time"], signals["vy"], signals["omega"] = t, vy, omega
    return signals


SCENARIOS = {"steady": ("cornering", "braking"), "transient": ("cornering", "braking"),
             "swift": ("cornering", "braking", "cleat")}
COMPARED = ("Fx", "Fy", "Fz", "Mz", "My")


def _fmpy_run(path, signals, interface):
    return fmpy.simulate_fmu(str(path), stop_time=float(signals["time"][-1]), output_interval=1e-3, input=signals,
                             fmi_type="ModelExchange" if interface == "me" else "CoSimulation",
                             relative_tolerance=1e-8, output=list(COMPARED))


#: ME against CS, as fractions of the load (_assert_like_cs): the transient while the inputs ramp (the host
#: integrates with the inputs interpolated where CS holds them over each 1 ms step) and 0.25 s after the ramps end.
ME_TOLERANCE = {"steady": (1e-12, 1e-12), "transient": (2e-4, 5e-5)}
#: fmusim's CVode run of the transient ME FMU while the inputs ramp (measured: 7.8e-4 of the load cornering,
#: 1.9e-3 braking; fmpy's: 8e-5 and 7e-5); once the inputs are held it agrees as fmpy's (ME_TOLERANCE)
FMUSIM_ME_RAMPING = 3e-3


def _assert_like_cs(got, ref, interface, model, where, ramping=None):
    """``got`` (a run of a variant) equals ``ref`` (the FMI 2 CS FMU's): CS to 1e-12. ME: the CS outputs at t + h
    are those of the inputs at t, held over the step, the ME outputs at t those of the inputs at t: the steady
    ME outputs are the CS ones one step earlier; the transient's states, integrated by the host with the inputs
    interpolated, lag the CS states (inputs held) by half a step, so its outputs at t are the mean of the CS outputs
    at t and t + h; once the inputs are held, outputs at the same times agree (ME_TOLERANCE)."""
    scale = np.max(np.abs(ref["Fz"]))  # the load: the scale of the forces (and, times the radius, the moments)
    for out in COMPARED:
        if interface == "cs":
            np.testing.assert_allclose(got[out], ref[out], rtol=1e-12, atol=1e-12 * scale, err_msg=f"{where} {out}")
            continue
        ramps, held = ME_TOLERANCE[model]
        ramps = ramps if ramping is None or model == "steady" else ramping
        cs = ref[out][1:] if model == "steady" else 0.5 * (ref[out][1:] + ref[out][:-1])
        np.testing.assert_allclose(got[out][:-1], cs, rtol=0, atol=ramps * scale, err_msg=f"{where} {out}")
        late = ref["time"] >= 0.5
        np.testing.assert_allclose(got[out][late], ref[out][late], rtol=0, atol=held * scale,
                                   err_msg=f"{where} {out} (inputs held)")


@pytest.fixture(scope="module")
def reference(fmus):
    """(model, scenario) -> (inputs, fmpy's run of the FMI 2 CS FMU), each run once."""
    runs = {}

    def get(model, name):
        if (model, name) not in runs:
            signals = _scenario(name, fmpy.read_model_description(str(fmus(2, "cs", model))))
            runs[model, name] = signals, _fmpy_run(fmus(2, "cs", model), signals, "cs")
        return runs[model, name]
    return get


@pytest.mark.parametrize("variant", [v for v in VARIANTS if v[:2] != (2, "cs")], ids=_id)
def test_fmpy_runs_every_variant_like_the_fmi2_cs_fmu(fmus, reference, variant):
    """Cornering, braking (and SWIFT over the cleat) in fmpy: every variant gives the FMI 2 CS FMU's numbers (ME:
    integrated by fmpy's CVode, _assert_like_cs)."""
    version, interface, model = variant
    for name in SCENARIOS[model]:
        signals, ref = reference(model, name)
        got = _fmpy_run(fmus(*variant), signals, interface)
        np.testing.assert_array_equal(got["time"], ref["time"])
        _assert_like_cs(got, ref, interface, model, f"fmpy {name}")
        assert np.ptp(ref["Fy" if name == "cornering" else "Fx" if name == "braking" else "Fz"]) > 100.0, name


# ------------------------------------------------------------------------------------ model exchange calls
class Model:
    """One FMI 2 ME instance through fmpy's FMU2Model, driven call by call."""

    def __init__(self, path, tmp_path):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Model

        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.nx, self.nz = self.md.numberOfContinuousStates, self.md.numberOfEventIndicators
        self.fmu = FMU2Model(guid=self.md.guid, unzipDirectory=extract(str(path), unzipdir=str(tmp_path / "me")),
                             modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName="tyre")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.fmu.newDiscreteStates()
        self.fmu.enterContinuousTimeMode()

    def set(self, **values):
        self.fmu.setReal([self.vr[k] for k in values], list(values.values()))

    def states(self, x=None):
        buf = (ctypes.c_double * max(self.nx, 1))(*(x if x is not None else []))
        if x is not None:
            self.fmu.setContinuousStates(buf, self.nx)
        else:
            self.fmu.getContinuousStates(buf, self.nx)
        return np.array(buf[:self.nx])

    def derivatives(self):
        buf = (ctypes.c_double * max(self.nx, 1))()
        self.fmu.getDerivatives(buf, self.nx)
        return np.array(buf[:self.nx])

    def events(self):
        buf = (ctypes.c_double * max(self.nz, 1))()
        self.fmu.getEventIndicators(buf, self.nz)
        return np.array(buf[:self.nz])


def test_me_derivatives_are_the_rate_of_the_cs_step_and_its_jacobian_the_finite_differences(fmus, tmp_path):
    """The transient ME FMU's derivatives equal (x(h) - x(0)) / h of the wheel's exactly integrated step as h -> 0,
    and its directional derivatives (states and inputs to derivatives and outputs) the finite differences of
    fmi2GetDerivatives / fmi2GetReal; fmi2GetFMUstate/SetFMUstate restore the state the host had set."""
    import mftyre
    from mftyre.transient import WheelTyre

    m = Model(fmus(2, "me", "transient"), tmp_path)
    m.set(vx=12.0, vy=0.4, omega=12.0 / 0.305 * 0.95)
    x = np.array([0.004, 0.01])
    m.states(x)
    xdot = m.derivatives()
    wheel = WheelTyre(mftyre.load_tir(TIR61), "transient")
    wheel.set_inputs(vx=12.0, vy=0.4, omega=12.0 / 0.305 * 0.95)
    h = 1e-7
    wheel.state = x.copy()
    wheel.step(h)
    np.testing.assert_allclose(xdot, (wheel.state - x) / h, rtol=1e-5)
    assert np.all(np.abs(xdot) > 0.1)
    state = m.fmu.getFMUstate()
    names = ["u_x", "u_y", "vy", "omega"]
    unknowns = ["der(u_x)", "der(u_y)", "Fx", "Fy", "Mz"]
    for k, known in enumerate(names):
        dd = m.fmu.getDirectionalDerivative([m.vr[n] for n in unknowns], [m.vr[known]], [1.0])
        step = 1e-6 * (1.0 if known.startswith("u_") else 1e2)
        values = []
        for sign in (1, -1):
            if known.startswith("u_"):
                m.states(x + sign * step * np.eye(2)[k])
            else:
                m.fmu.setFMUstate(state)
                m.set(**{known: {"vy": 0.4, "omega": 12.0 / 0.305 * 0.95}[known] + sign * step})
            values.append(np.concatenate([m.derivatives(), m.fmu.getReal([m.vr[n] for n in unknowns[2:]])]))
        m.fmu.setFMUstate(state)
        fd = (values[0] - values[1]) / (2 * step)
        np.testing.assert_allclose(dd, fd, rtol=1e-5, atol=1e-6 * np.max(np.abs(fd)), err_msg=known)
    np.testing.assert_array_equal(m.states(), x)
    np.testing.assert_array_equal(m.derivatives(), xdot)


@pytest.mark.parametrize("model", ["steady", "transient"])
def test_event_indicators_change_sign_where_the_equations_switch(fmus, tmp_path, model):
    """One indicator per switch: the direction of travel (vx), the low-speed fade (|vx| = VXLOW) and the contact
    (the wheel centre above the free radius: lift-off)."""
    m = Model(fmus(2, "me", model), tmp_path)
    vxlow = mftyre_params()["VXLOW"]
    z0 = m.fmu.getReal([m.vr["z"]])[0]
    signs = {}
    for vx in (5.0, 0.5 * vxlow, -0.5 * vxlow, -5.0):
        m.set(vx=vx, omega=vx / 0.3)
        signs[vx] = np.sign(m.events()[:2])
    assert [list(s) for s in signs.values()] == [[1, 1], [1, -1], [-1, -1], [-1, 1]]
    m.set(vx=5.0, omega=5.0 / 0.3)
    assert m.events()[2] > 0 and m.fmu.getReal([m.vr["Fz"]])[0] > 1000
    m.set(z=z0 + 0.05)
    assert m.events()[2] < 0 and m.fmu.getReal([m.vr["Fz"]])[0] == 0.0
    assert m.md.numberOfEventIndicators == 3


def mftyre_params():
    import mftyre

    return mftyre.load_tir(TIR61).params


# ------------------------------------------------------------------------------------------ the C host
def _host_args(path, tmp_path, platform_dir):
    """(library, arguments) of tests/fmu_host.c for the FMU at ``path``."""
    from fmpy import extract

    md = fmpy.read_model_description(str(path))
    ident = (md.coSimulation or md.modelExchange).modelIdentifier
    interface = "cs" if md.coSimulation else "me"
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = ["Fx"] + [v.name for v in md.modelVariables if v.causality == "output" and v.name != "Fx"]
    folder = Path(extract(str(path), unzipdir=str(tmp_path / f"{path.stem}_{md.fmiVersion}_{interface}")))
    suffix = ".dll" if "win" in platform_dir else ".so"
    nz = md.numberOfEventIndicators if interface == "me" else 0
    return folder / "binaries" / platform_dir / f"{ident}{suffix}", [
        md.fmiVersion[0], interface, md.guid, 4, 10000, 1, md.numberOfContinuousStates, nz,
        vr["vx"], vr["vy"], vr["omega"], len(outputs), *(vr[n] for n in outputs)]


def _parse(stdout):
    rows = [line.split() for line in stdout.splitlines() if line.startswith("instance")]
    return np.array([[float(r[3]), *map(float, r[5:])] for r in rows])


@pytest.fixture(scope="module")
def hosts(tmp_path_factory):
    """The C host compiled for linux64 and (with MinGW-w64) for win64."""
    out = tmp_path_factory.mktemp("host")
    headers = Path(fmpy.__file__).parent / "c-code"
    built = {"linux64": out / "host"}
    subprocess.run(["cc", "-O2", "-I", str(headers), str(HOST_C), "-o", str(built["linux64"]), "-ldl", "-lm"],
                   check=True)
    if MINGW:
        built["win64"] = out / "host.exe"
        subprocess.run([MINGW, "-O2", "-I", str(headers), str(HOST_C), "-o", str(built["win64"]), "-static"],
                       check=True)
    return built


def _wine_env():
    from mftyre.compiled import cache_dir

    env = dict(os.environ, WINEDEBUG="-all")
    env.setdefault("WINEPREFIX", str(cache_dir() / "wine64"))  # created once (slow: the first start of Wine)
    return env


@pytest.mark.parametrize("variant", VARIANTS, ids=_id)
def test_c_host_runs_four_instances_on_linux64_and_win64_under_wine_alike(fmus, hosts, tmp_path, variant):
    """4 instances x 10 000 steps of 1 ms in the C host, every output after the last step and the sum of Fx over
    the run: on linux64, and on the win64 DLL under Wine (the host cross-compiled with MinGW-w64) equal to 1e-12
    relative. The instances differ (each its own memory), and the C host agrees with fmpy's FMI 2 CS run."""
    lib, args = _host_args(fmus(*variant), tmp_path, "linux64" if variant[0] == 2 else "x86_64-linux")
    res = subprocess.run([str(hosts["linux64"]), str(lib), *map(str, args)], capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    linux = _parse(res.stdout)
    assert linux.shape[0] == 4 and np.all(np.isfinite(linux))
    assert len({row[1] for row in linux}) == 4  # Fx differs between the instances (their own inputs)
    if not (MINGW and WINE):
        pytest.skip(f"the win64 run needs MinGW-w64 ({native_build.MINGW}: {'found' if MINGW else 'missing'}) and "
                    f"Wine (wine64: {'found' if WINE else 'missing'}); Debian: apt-get install gcc-mingw-w64-x86-64 "
                    "wine64")
    lib, args = _host_args(fmus(*variant), tmp_path, "win64" if variant[0] == 2 else "x86_64-windows")
    res = subprocess.run([WINE, str(hosts["win64"]), str(lib), *map(str, args)], capture_output=True, text=True,
                         timeout=600, env=_wine_env())
    assert res.returncode == 0, res.stdout + res.stderr
    windows = _parse(res.stdout)
    np.testing.assert_allclose(windows, linux, rtol=1e-12, atol=1e-12 * np.max(np.abs(linux)))


# ------------------------------------------------------------------------------------------------- fmusim
def _fmusim():
    return os.environ.get("FMUSIM") or shutil.which("fmusim")


@pytest.mark.parametrize("variant", [v for v in VARIANTS if v[0] == 3], ids=_id)
def test_fmusim_runs_the_fmi3_variants_like_the_fmi2_cs_fmu(fmus, reference, tmp_path, variant):
    """The FMI Reference FMUs' fmusim (an importer we did not write; set FMUSIM or put fmusim on PATH) runs each
    FMI 3 variant over the cornering, braking (and cleat) runs: CS gives fmpy's FMI 2 CS numbers, ME (fmusim's
    CVode) the same once the inputs are held."""
    fmusim = _fmusim()
    if not fmusim:
        pytest.skip("fmusim not found (build it from modelica/Reference-FMUs with CMake, see docs/fmu-variants.md, "
                    "and set FMUSIM=/path/to/fmusim)")
    _, interface, model = variant
    for name in SCENARIOS[model]:
        signals, ref = reference(model, name)
        csv = tmp_path / f"{name}.csv"
        np.savetxt(csv, np.column_stack([signals[n] for n in signals.dtype.names]), delimiter=",",
                   header=",".join(f'"{n}"' for n in signals.dtype.names), comments="", fmt="%.17g")
        out = tmp_path / f"{name}_out.csv"
        cmd = [fmusim, "--interface-type", interface, "--stop-time", repr(float(signals["time"][-1])),
               "--output-interval", "0.001", "--input-file", str(csv), "--output-file", str(out),
               "--tolerance", "1e-8", *(a for o in COMPARED for a in ("--output-variable", o)), str(fmus(*variant))]
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        assert res.returncode == 0, res.stdout + res.stderr
        got = np.genfromtxt(out, delimiter=",", names=True)
        last = np.append(got["time"][1:] != got["time"][:-1], True)  # at an event time: the row after the event
        got = got[last]
        np.testing.assert_allclose(got["time"], ref["time"], atol=1e-9)
        _assert_like_cs(got, ref, interface, model, f"fmusim {name}", FMUSIM_ME_RAMPING)
