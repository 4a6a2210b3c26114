"""The tyre FMU in swift mode (model=swift: the SWIFT rigid ring, swift.fmu_model.SwiftWheel), run with fmpy.

Evidence used: ``swift.SwiftTyre.step`` driven directly with ``StepInputs`` built here from the FMU's documented
input mapping (same road, same table step; agreement ~1e-8 of FNOMIN: the FMU runs swift_functions' step as
CasADi-generated C, the reference SwiftTyre's own compiled step with the parameters at run time, on a table of
another origin: round-off, amplified at the cleat's edges, up to 5e-9 FNOMIN in Fz_c, 7e-11 m in road_w, 4e-10 m in
contact_length), ``MFModel.evaluate`` at the contact-patch state for
the outputs the ring does not report, splitting of communication steps (a 2 ms step = two 1 ms steps), RK4
convergence for step sizes that are not multiples, FMI call sequences (reset, rejected inputs, bad parameters),
fmpy's validator, and time/memory over a long run.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("pythonfmu")
fmpy = pytest.importorskip("fmpy")

from swift import Cleat, Flat, StepInputs, SwiftTyre  # noqa: E402
from swift.fmu_model import SUBSTEPS  # noqa: E402  (the FMUs' RK4 substeps: one stepping rule)
from swift.ring import STATE_NAMES  # noqa: E402

from conftest import SWIFT_SAMPLE  # noqa: E402
from test_fmu import TIR61, TIR62, Slave, _build, assert_no_time_drift, run_long  # noqa: E402

S = {n: i for i, n in enumerate(STATE_NAMES)}
CLEAT = "cleat(x0=1.0, length=0.05, height=0.01)"
# FMU output -> SwiftTyre.step output (the documented mapping; Rl, Vsx, Vsy and the MF extras checked apart)
MAPPED = {"Fx": "fx", "Fy": "fy", "Fz": "fz", "Mx": "mx", "My": "my", "Mz": "mz", "Mz_c": "mz_c", "Fz_c": "fz_c",
          "kappa": "kappa", "alpha": "alpha", "rho": "rho", "Re": "re", "road_slope": "beta"}
OUT = ("Fx", "Fy", "Fz", "Mx", "My", "Mz", "Mx_c", "My_c", "Mz_c", "kappa", "alpha", "Vsx", "Vsy", "omega_used",
       "rho", "Rl", "Re", "contact_length", "contact_width", "trail", "mux", "muy", "Fz_c", "road_w", "road_slope",
       "x_road")


@pytest.fixture(scope="module")
def model(sample):
    """The SWIFT FMU's file as a model (conftest's ``sample``: TIR62 is that file)."""
    assert TIR62.resolve() == SWIFT_SAMPLE.resolve()
    return sample


@pytest.fixture(scope="module")
def swift_fmu(built_fmu):
    return built_fmu(TIR62, "--backend", "pythonfmu", "--model", "swift", "--vertical", "position")


def _scale(model, name):
    prm = model.params
    F, L = prm.FNOMIN, prm.UNLOADED_RADIUS
    if name.startswith("F"):
        return F
    if name.startswith("M"):
        return F * L
    return {"kappa": 1.0, "alpha": 1.0, "road_slope": 1.0, "omega_used": 100.0}.get(name, L)


def _assert_close(model, fmu_out, ref_out, names, rel=2e-8, where="", same=False):
    """FMU outputs against SwiftTyre outputs (MAPPED names), or against FMU outputs (same=True)."""
    for name in names:
        key = name if same else MAPPED[name]
        assert fmu_out[name] == pytest.approx(float(ref_out[key]), abs=rel * _scale(model, name)), f"{name} {where}"


def _check_mf_extras(model, out, ref_out, ref_state, gamma, p):
    """Mx_c, My_c, contact width, trail, mu: the MF at the contact-patch state of the reference (its slip
    -Vsx/|Vcx| given to the MF relative to the direction of travel, (omega Re - Vcx)/Vcx: sign(Vcx) kappa)."""
    vcx = float(ref_out["vcx"])
    mf = model.evaluate(max(float(ref_out["fz_c"]), 1e-3), math.copysign(1.0, vcx) * float(ref_out["kappa"]),
                        float(ref_out["alpha"]), gamma, 0.0, vcx, p, float(ref_state[S["omb"]]))
    for name, key, factor in (("Mx_c", "mx", 1), ("My_c", "my", 1), ("Mz_c", "mz", 1), ("contact_width", "b", 2),
                              ("trail", "t", 1), ("mux", "mux", 1), ("muy", "muy", 1)):
        assert out[name] == pytest.approx(factor * float(mf[key]), rel=1e-8, abs=1e-9 * _scale(model, name)), name


def test_swift_fmu_validates_and_describes(swift_fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(swift_fmu)) == []
    md = fmpy.read_model_description(swift_fmu)
    start = {v.name: v.start for v in md.modelVariables}
    assert start["model"] == "swift" and start["vertical_input"] == "position" and start["rim"] == "speed"
    units = {v.name: v.unit for v in md.modelVariables}
    assert units["torque"] == "N.m" and units["max_step"] == "s" and units["axle_mass"] == "kg"


def test_cli_swift_needs_swift_parameters(tmp_path, capsys):
    text = TIR61.read_text(encoding="latin-1").splitlines()
    text = [("FREQ_LONG = 0.0" if ln.startswith("FREQ_LONG") else ln) for ln in text]  # no ring frequency
    (tmp_path / "noring.tir").write_text("\n".join(text), encoding="latin-1")
    assert _build([tmp_path / "noring.tir", "-o", tmp_path / "s.fmu", "--model", "swift"]) == 1
    assert "no usable SWIFT parameters" in capsys.readouterr().err
    assert not (tmp_path / "s.fmu").exists()


def test_position_mode_over_cleat_equals_swift_step(model, swift_fmu, tmp_path):
    """Axle height imposed (moving with vz), spin imposed, lateral speed and camber, over a cleat and far past it
    (where the FMU moves the wheel back into its road table): the FMU = SwiftTyre.step on the same inputs."""
    vx, vy, omega, gamma, p, z0, vz = 10.0, 0.3, 10.0 / 0.305, 0.02, 2.3e5, 0.288, 0.004
    fmu = Slave(swift_fmu, tmp_path, start={"road": CLEAT, "vx": vx, "vy": vy, "omega": omega, "gamma": gamma,
                                           "p": p, "z": z0, "vz": vz, "road_z": 0.0})
    assert fmu.status() == 0, fmu.messages
    ref = SwiftTyre(model, Cleat(x0=1.0, length=0.05, height=0.01), axle="height", rim="speed", substeps=SUBSTEPS,
                    x_range=(-2.0, 8.0))

    def u(t):
        return StepInputs(x=vx * t, vx=vx, z=z0 + vz * t, vz=vz, omega=omega, p=p, y=vy * t, vy=vy, gamma=gamma)

    state = ref.initial_state(u(0.0))
    state, r = ref.step(state, u(0.0), 0.0)
    out = fmu.get(*OUT)
    _assert_close(model, out, r, MAPPED, where="after initialisation")
    h, n = 1e-3, 600  # 6 m: over the cleat at 1 m and beyond 2.6 m, where the FMU re-bases x
    fz_max = 0.0
    for k in range(n):
        fmu.set(z=z0 + vz * k * h)
        fmu.fmu.doStep(k * h, h)
        state, r = ref.step(state, u(k * h), h)
        out = fmu.get(*OUT)
        _assert_close(model, out, r, MAPPED, where=f"step {k}")
        fz_max = max(fz_max, out["Fz"])
        if k % 50 == 0:
            _check_mf_extras(model, out, r, state, gamma, p)
        assert out["road_w"] == pytest.approx(float(r["w"]), abs=1e-9)
        assert out["x_road"] == pytest.approx(vx * (k + 1) * h, abs=1e-9)
        assert out["Rl"] == pytest.approx((z0 + vz * (k + 1) * h - r["w"]) * math.cos(r["beta"]), abs=1e-9)
        assert out["contact_length"] == pytest.approx(2 * float(r["a"]), abs=1e-9)
        assert out["Vsx"] == pytest.approx(-out["kappa"] * abs(r["vcx"]), abs=1e-9)
    assert fz_max > 1.3 * out["Fz"]  # the cleat was felt
    assert fmu.status() == 0
    fmu.close()


def test_load_mode_torque_and_road_height_equal_swift_step(model, swift_fmu, tmp_path):
    """Axle load (axle mass), drive torque, the road lifted by road_z: = SwiftTyre on Flat(road_z)."""
    vx, load, torque, p, road_z = 15.0, 3800.0, 150.0, 2.1e5, 0.05
    start = {"vertical_input": "load", "rim": "torque", "axle_mass": 25.0, "vx": vx, "Fz_in": load,
             "torque": torque, "omega": vx / 0.305, "p": p, "road_z": road_z, "x_start": 3.0}
    fmu = Slave(swift_fmu, tmp_path, start=start)
    assert fmu.status() == 0, fmu.messages
    ref = SwiftTyre(model, Flat(road_z), axle="load", rim="torque", axle_mass=25.0, substeps=SUBSTEPS,
                    x_range=(2.0, 8.0))
    u = lambda t: StepInputs(x=3.0 + vx * t, vx=vx, load=load, torque=torque, omega=vx / 0.305, p=p)  # noqa: E731
    state = ref.initial_state(u(0.0))
    state, r = ref.step(state, u(0.0), 0.0)
    _assert_close(model, fmu.get(*OUT), r, MAPPED, where="after initialisation")
    h = 2e-3
    for k in range(150):
        fmu.fmu.doStep(k * h, h)
        for j in range(2):  # the FMU splits 2 ms into two 1 ms steps
            state, r = ref.step(state, u(k * h + j * h / 2), h / 2)
        out = fmu.get(*OUT)
        _assert_close(model, out, r, MAPPED, where=f"step {k}")
        assert out["omega_used"] == pytest.approx(state[S["oma"]], rel=1e-12)
        assert out["road_w"] == pytest.approx(road_z, abs=1e-12)
        assert out["Rl"] == pytest.approx((state[S["za"]] - r["w"]) * math.cos(r["beta"]), abs=1e-9)
    assert out["Fx"] > 0 and out["omega_used"] > vx / 0.305  # driven: spins up, pushes forwards
    fmu.close()


def test_reversing_mf_extras_follow_the_wheel_rule(swift_fmu, tmp_path):
    """Reversing at 10 m/s (load mode, spin imposed): a locked wheel brakes the motion (Fx > 0) and, as forwards,
    has no rolling-resistance moment (My_c = 0: the MF's extras get the slip relative to the direction of travel,
    -1 = locked, as the steady FMUs; it was 10 N m with the ring's -Vsx/|Vcx| = +1 given at the signed speed); a
    free-rolling wheel's My_c opposes the motion (minus the forward one), Mx_c as forwards."""
    out = {}
    for vx in (10.0, -10.0):
        for spin in (0.0, 1.0):
            start = {"vertical_input": "load", "rim": "speed", "axle_mass": 25.0, "vx": vx, "Fz_in": 4000.0,
                     "omega": spin * vx / 0.305}
            fmu = Slave(swift_fmu, tmp_path, start=start)
            for k in range(200):
                fmu.fmu.doStep(k * 1e-3, 1e-3)
            out[vx, spin] = fmu.get(*OUT)
            assert fmu.status() == 0, fmu.messages
            fmu.close()
    back, fwd = out[-10.0, 0.0], out[10.0, 0.0]
    assert back["Fx"] > 0.5 * back["Fz"] and back["Fx"] == pytest.approx(-fwd["Fx"], rel=1e-3)
    assert back["Vsx"] == pytest.approx(-10.0, rel=1e-6) and fwd["Vsx"] == pytest.approx(10.0, rel=1e-6)
    for spin in (0.0, 1.0):
        back, fwd = out[-10.0, spin], out[10.0, spin]
        assert abs(back["My_c"] + fwd["My_c"]) < 1e-3 * max(abs(fwd["My_c"]), 1.0), spin
        assert back["Mx_c"] == pytest.approx(fwd["Mx_c"], rel=1e-3), spin
    assert out[10.0, 1.0]["My_c"] < -1.0 < 1.0 < out[-10.0, 1.0]["My_c"]


def _run(fmu, steps, inputs=lambda t: {}):
    t, rows = 0.0, []
    for h in steps:
        fmu.set(**inputs(t))
        fmu.fmu.doStep(t, h)
        t += h
        rows.append((t, fmu.get(*OUT)))
    return rows


def test_varying_communication_steps(swift_fmu, tmp_path, model):
    """Steps that are multiples of max_step give the same internal steps (equal to 1e-9); other sizes converge
    (RK4) to the same history. max_step 0.5 ms: RK4 steps of 0.5 ms (the FMUs' rule, swift.fmu_model.internal_steps;
    the default 1 ms steps keep Fz over this cleat within 8.5 % of its swing at 0.65-0.7 ms steps)."""
    start = {"road": CLEAT, "vx": 12.0, "omega": 12.0 / 0.305, "z": 0.288, "vertical_input": "position",
             "max_step": 5e-4}
    base = _run(Slave(swift_fmu, tmp_path, start=start), [1e-3] * 300)
    at = {round(t, 9): o for t, o in base}
    rng = np.random.default_rng(5)
    mixed = _run(Slave(swift_fmu, tmp_path, start=start), list(rng.choice([1e-3, 2e-3, 4e-3], 120)))
    n = 0
    for t, o in mixed:
        if round(t, 9) in at:
            _assert_close(model, o, at[round(t, 9)], OUT, where=f"t={t}", same=True, rel=1e-9)
            n += 1
    assert n > 50
    # steps of 0.7 ms and 1.3 ms (split into 2 of 0.65 ms) against 1 ms: the same history within the RK4 error
    odd = _run(Slave(swift_fmu, tmp_path, start=start), [7e-4, 1.3e-3] * 150)
    fz_range = max(o["Fz"] for _, o in base) - min(o["Fz"] for _, o in base)
    t_odd = np.array([t for t, _ in odd])
    for name in ("Fx", "Fz", "My"):
        y_odd = np.interp([t for t, _ in base], t_odd, [o[name] for _, o in odd])
        dev = np.max(np.abs(y_odd - [o[name] for _, o in base])[50:])  # after the first 50 ms
        assert dev < 0.03 * fz_range, name
    assert abs(odd[-1][1]["Fz"] - base[-1][1]["Fz"]) < 1e-4 * fz_range  # settled after the cleat


def test_reset_and_reinitialise(swift_fmu, tmp_path):
    start = {"road": CLEAT, "vx": 10.0, "omega": 10.0 / 0.305, "z": 0.29}
    fmu = Slave(swift_fmu, tmp_path, start=start)
    first = fmu.get(*OUT)
    run1 = _run(fmu, [1e-3] * 150)
    fmu.fmu.reset()
    fmu.initialise(start)
    assert fmu.get(*OUT) == first
    run2 = _run(fmu, [1e-3] * 150)
    assert [o for _, o in run2] == [o for _, o in run1]
    # a rejected step leaves the state as it was: the run continues as if it had not been tried
    fmu.fmu.reset()
    fmu.initialise(start)
    from fmpy.fmi1 import FMICallException

    head = _run(fmu, [1e-3] * 50)
    fmu.set(vx=float("nan"))
    with pytest.raises(FMICallException, match="discard"):
        fmu.fmu.doStep(0.05, 1e-3)
    assert fmu.status() == 1 and fmu.get(*OUT) == head[-1][1]
    assert "input rejected" in fmu.messages[-1][1]
    fmu.set(vx=10.0)
    rest = _run(fmu, [1e-3] * 100)
    assert [o for _, o in head + rest] == [o for _, o in run1]
    assert fmu.status() == 0
    fmu.close()


@pytest.mark.parametrize("params, text", [
    ({"road": "cleat(x0=1.0)"}, "cleat needs length, height"),
    ({"road": "__import__('os').system('true')"}, "each term must be one of"),
    ({"road": "sine(amplitude=0.01, wavelength=1.0)"}, "sine needs x_end"),
    ({"road": "csv('missing_profile.csv')"}, "file not found: expected an existing road profile CSV"),
    ({"rim": "free"}, "rim must be"),
    ({"input_mode": "rig"}, "for model='steady' only"),
    ({"max_step": -1.0}, "max_step must be positive"),
])
def test_configuration_errors(swift_fmu, tmp_path, params, text):
    from fmpy.fmi1 import FMICallException

    fmu = Slave(swift_fmu, tmp_path, initialise=False)
    with pytest.raises(FMICallException) as exc:  # a failure, never OK (pythonfmu: fmi2Fatal)
        fmu.initialise(params)
    assert exc.value.status >= 3
    # logged as the native FMU does: "initialisation failed: <cause>", no traceback for a user's error
    assert any(status == 3 and msg.startswith("initialisation failed: ") and text in msg and "Traceback" not in msg
               for status, msg in fmu.messages), fmu.messages


def test_sampled_profiles(swift_fmu, tmp_path, model):
    """A CSV profile and the same points inline give the same run; a sum of obstacles is accepted."""
    xs = np.linspace(0.0, 3.0, 61)
    zs = 0.008 * np.sin(np.pi * xs / 3.0) ** 2
    csv = tmp_path / "profile.csv"
    np.savetxt(csv, np.column_stack([xs, zs]), delimiter=",", header="x,z", comments="")
    inline = "points([" + ", ".join(f"[{float(a)!r}, {float(b)!r}]" for a, b in zip(xs, zs)) + "])"
    runs = []
    for road in (f"csv({str(csv)!r})", inline):
        fmu = Slave(swift_fmu, tmp_path, start={"road": road, "vx": 20.0, "omega": 20.0 / 0.305, "z": 0.288,
                                               "x_start": -0.5})
        assert fmu.status() == 0, fmu.messages
        runs.append(_run(fmu, [1e-3] * 200))
        fmu.close()
    assert [o for _, o in runs[0]] == [o for _, o in runs[1]]
    assert max(o["road_w"] for _, o in runs[0]) > 0.005
    fmu = Slave(swift_fmu, tmp_path, start={"road": "step(x0=1, height=0.01) + bump(2.0, 0.2, 0.01)"})
    assert fmu.status() == 0, fmu.messages
    fmu.close()


def test_long_run_no_drift_in_memory_or_time(swift_fmu, tmp_path):
    """100,000 steps of 1 ms (2 km at 20 m/s: the road table stays small), varying inputs, road height and cleat."""
    fmu = Slave(swift_fmu, tmp_path, start={"road": "cleat(x0=2.0, length=0.05, height=0.01)", "vx": 20.0,
                                           "omega": 20.0 / 0.305, "z": 0.29})
    h = 1e-3

    def inputs_at(k):
        s = h * k
        return [20.0 + math.sin(s), 0.3 * math.sin(3 * s), (20.0 + math.sin(s)) / 0.305, 0.01,
                0.29 + 0.003 * math.sin(7 * s), 0.021 * math.cos(7 * s), 0.002 * math.sin(0.5 * s), 2.2e5]

    times, rss, out = run_long(fmu, ("vx", "vy", "omega", "gamma", "z", "vz", "road_z", "p"),
                               ("Fx", "Fy", "Fz", "Mx", "My", "Mz", "x_road"), inputs_at, h)
    assert fmu.status() == 0 and all(math.isfinite(v) for v in out)
    assert out[-1] > 1900.0  # x_road: ~2 km travelled
    fmu.close()
    print(f"swift: time per step {[round(x * 1e6, 1) for x in times]} us; RSS {[r >> 20 for r in rss]} MiB")
    assert_no_time_drift(times)
    assert rss[-1] - rss[0] < 8 << 20


def test_replay_after_restoring_the_whole_state(swift_fmu, tmp_path):
    """fmi2GetFMUstate holds the ring state (not only the FMI variables): a replay equals the first run."""
    fmu = Slave(swift_fmu, tmp_path, start={"road": CLEAT, "vx": 10.0, "omega": 10.0 / 0.305, "z": 0.29})
    _run(fmu, [1e-3] * 60)
    state = fmu.fmu.getFMUstate()
    blob = fmu.fmu.serializeFMUstate(state)
    first = _run(fmu, [1e-3] * 80, lambda t: {"vy": 0.2 * math.sin(30 * t)})
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(blob))
    replay = _run(fmu, [1e-3] * 80, lambda t: {"vy": 0.2 * math.sin(30 * t)})
    for (_, a), (_, b) in zip(first, replay):
        for name in ("Fx", "Fz", "My", "x_road"):
            assert abs(a[name] - b[name]) <= 1e-12 * max(1.0, abs(a[name])), name
    fmu.close()


def test_obstacle_met_where_it_is_for_far_starts(swift_fmu, tmp_path):
    """x_start 2.6 m further back meets the cleat (x0 = 1 m) 0.26 s later at 10 m/s (the wheel used to be moved
    forward at initialisation)."""
    peaks = []
    for xs in (0.0, -2.6):
        fmu = Slave(swift_fmu, tmp_path, start={"road": CLEAT, "vx": 10.0, "omega": 10.0 / 0.305, "z": 0.29,
                                               "x_start": xs})
        rows = _run(fmu, [1e-3] * 400)
        i = int(np.argmax([o["Fz"] for _, o in rows]))
        peaks.append(rows[i][0])
        assert rows[i][1]["x_road"] == pytest.approx(xs + 10.0 * rows[i][0], abs=1e-9)
        fmu.close()
    assert peaks[1] - peaks[0] == pytest.approx(0.26, abs=1.5e-3)


def test_standstill_start_and_rest(model, swift_fmu, tmp_path):
    """vx = 0, omega = 0, 5 ms communication steps for 1 s: the FMU starts from SwiftTyre.initial_state's static
    state, equals SwiftTyre.step and does not move (Fz, Fx constant)."""
    z = 0.29
    fmu = Slave(swift_fmu, tmp_path, start={"road": CLEAT, "vx": 0.0, "omega": 0.0, "z": z})
    assert fmu.status() == 0, fmu.messages
    ref = SwiftTyre(model, Cleat(x0=1.0, length=0.05, height=0.01), axle="height", rim="speed", substeps=SUBSTEPS,
                    x_range=(-2.0, 8.0))
    u = StepInputs(x=0.0, vx=0.0, z=z, omega=0.0)
    state = ref.initial_state(u)
    _assert_close(model, fmu.get(*OUT), ref.step(state, u, 0.0)[1], MAPPED, where="after initialisation")
    rows = _run(fmu, [5e-3] * 200)
    for _ in range(200):
        state, r = ref.step(state, u, 5e-3)
    _assert_close(model, rows[-1][1], r, MAPPED, where="after 1 s")
    fz = [o["Fz"] for _, o in rows]
    assert np.ptp(fz) < 1e-6 and fz[0] > 0.8 * float(model.vertical_force(z))
    assert np.ptp([o["Fx"] for _, o in rows]) < 1e-6 and rows[-1][1]["x_road"] == 0.0
    fmu.close()


@pytest.mark.parametrize("h", [1e-3, 5e-3])
def test_steady_cornering_equals_magic_formula(model, swift_fmu, tmp_path, h):
    """Constant lateral axle speed (4 and 10 deg, kappa 0 and 0.1), imposed spin, flat road: the pythonfmu SWIFT
    FMU's rim forces equal the MF at its own Fz_c, slip angle and spin within 1 % at 1 and 5 ms steps."""
    from test_swift_steady import V, _spin, assert_magic_formula

    rl, _ = model.loaded_radius(4000.0)
    for deg, kappa in ((4.0, 0.0), (10.0, 0.1)):
        vy, omega = -V * math.tan(math.radians(deg)), _spin(model, kappa)
        fmu = Slave(swift_fmu, tmp_path, start={"vx": V, "vy": vy, "omega": omega, "z": float(rl)})
        for k in range(int(round(0.3 / h))):
            fmu.fmu.doStep(k * h, h)
        out = fmu.get("Fx", "Fy", "Fz_c", "Re")
        assert_magic_formula(model, out["Fx"], out["Fy"], out["Fz_c"], out["Re"], vy, omega, f"{deg} deg {kappa}")
        assert fmu.status() == 0
        fmu.close()


def test_default_inputs_roll_freely(swift_fmu, tmp_path):
    """No inputs set: the pythonfmu SWIFT FMU rolls freely under the nominal load (slip ~0, |Fx| < 1 % of Fz)."""
    fmu = Slave(swift_fmu, tmp_path)
    for k in range(50):
        fmu.fmu.doStep(k * 1e-3, 1e-3)
    out = fmu.get("Fx", "Fz", "kappa")
    assert abs(out["kappa"]) < 1e-4 and abs(out["Fx"]) < 0.01 * out["Fz"]
    assert out["Fz"] == pytest.approx(4000.0, rel=0.05)
    fmu.close()


def test_swift_evaluators_agree(swift_fmu, tmp_path, model):
    """evaluator=compiled (swift_functions' step and outputs as C, shipped) and evaluator=casadi (the same functions
    on CasADi's virtual machine) give the same outputs over the cleat; the log names the path taken."""
    rows = {}
    for evaluator in ("compiled", "casadi"):
        fmu = Slave(swift_fmu, tmp_path, start={"road": "cleat(x0=0.3, length=0.05, height=0.01)", "vx": 10.0,
                                               "omega": 10.0 / 0.305, "z": 0.29, "evaluator": evaluator})
        assert fmu.status() == 0, fmu.messages
        assert any(f"step {evaluator}" in m for _, m in fmu.messages), fmu.messages
        rows[evaluator] = _run(fmu, [1e-3] * 40)
        fmu.close()
    for (_, a), (_, b) in zip(rows["compiled"], rows["casadi"]):
        _assert_close(model, a, b, OUT, rel=1e-9, same=True)
