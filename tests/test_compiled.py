"""mftyre.compiled: thread safety, input validation, the disk cache, and compiled derivatives for NLPs."""
from __future__ import annotations

import os
import subprocess
import sys
import threading
import warnings

import numpy as np
import pytest

import mftyre
from conftest import PROJECT, SHARED, TIR_FILES, require_shared
from mftyre.compiled import CacheSecurityError, CompiledFunction, compile_external, compile_model
from mftyre.errors import InputClippedWarning, MFTyreError, ModelInputError

FILES = {"mf61": "car_205_60R15_mf61.tir", "mf62": "car_205_60R15_mf62_swift.tir"}
INPUTS = ("fz", "kappa", "alpha", "gamma", "phit", "vx", "p")


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    """Every output of both sample tyres, compiled once for the module."""
    directory = tmp_path_factory.mktemp("cache")
    result = {}
    for tag, name in FILES.items():
        model = mftyre.load_tir(TIR_FILES / name)
        result[tag] = model, compile_model(model, directory=directory)
    return result


@pytest.fixture(scope="module")
def tno_compiled(tmp_path_factory):
    """The public TNO MF 6.2 file (its vertical relation uses the side-force term), compiled once."""
    path = require_shared(SHARED / "reference" / "tir" / "TNO_car205_60R15.tir")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(path)
    return model, compile_model(model, directory=tmp_path_factory.mktemp("tno"))


def _points(model, n, seed):
    prm = model.params
    rng = np.random.default_rng(seed)
    return [rng.uniform(0.3, 1.8, n) * prm.FNOMIN, rng.uniform(-0.2, 0.2, n), rng.uniform(-0.2, 0.2, n),
            rng.uniform(-0.05, 0.05, n), 0.0, rng.uniform(5, 35, n), rng.uniform(0.9, 1.1, n) * prm.NOMPRES]


@pytest.mark.parametrize("tag", FILES)
def test_eight_threads_give_the_serial_results(compiled, tag):
    model, f = compiled[tag]
    data = [_points(model, 2000 + 700 * k, seed=k) for k in range(8)]  # packed (<= 4096) and strided calls
    serial_batch = [f.batch(*x) for x in data]
    serial_point = [[f(*(float(np.broadcast_to(v, x[0].shape)[i]) for v in x)) for i in range(40)] for x in data]
    failures = []

    def work(k):
        x = data[k]
        try:
            for _ in range(4):
                for got, want in zip(f.batch(*x), serial_batch[k]):
                    if not np.array_equal(got, want):
                        failures.append(("batch", k))
                for i in range(40):
                    if f(*(float(np.broadcast_to(v, x[0].shape)[i]) for v in x)) != serial_point[k][i]:
                        failures.append(("point", k, i))
        except Exception as exc:  # noqa: BLE001  (reported below)
            failures.append(repr(exc))

    threads = [threading.Thread(target=work, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not failures, failures[:5]
    # the threaded batch option (4 threads over 20,000 points) gives the same numbers
    x = _points(model, 20_000, seed=9)
    for got, want in zip(f.batch(*x, threads=4), f.batch(*x)):
        np.testing.assert_array_equal(got, want)



def test_batch_outputs_are_named(compiled):
    """batch returns one array per output, by position (as before) and by name, and pickles with its names."""
    import pickle

    model, f = compiled["mf61"]
    out = f.batch(np.array([3000.0, 5000.0]), 0.02, 0.05, 0.0, 0.0, 20.0, 2.1e5)
    ref = model.evaluate(np.array([3000.0, 5000.0]), 0.02, 0.05, vx=20.0, p=2.1e5)
    assert len(out) == len(f.outputs) and isinstance(out, tuple)
    np.testing.assert_allclose(out.fy, ref.fy, rtol=1e-10)
    np.testing.assert_allclose(out.mz, out[f.outputs.index("mz")])
    assert list(out.to_dict()) == list(f.outputs)
    back = pickle.loads(pickle.dumps(out))
    assert back.names == out.names and np.array_equal(back.fx, out.fx)
    with pytest.raises(AttributeError, match="no output 'fyy'"):
        out.fyy


def test_results_match_numpy_and_broadcast(compiled):
    model, f = compiled["mf61"]
    fz = np.array([[3000.0], [5000.0], [7000.0]])  # (3, 1) against (4,): a (3, 4) grid
    alpha = np.array([-0.1, 0.0, 0.05, 0.1])
    out = f.batch(fz, 0.02, alpha, 0.01, 0.0, 20.0, 2.1e5)
    ref = model.evaluate(fz, 0.02, alpha, 0.01, 0.0, vx=20.0, p=2.1e5)
    for name, value in zip(f.outputs, out):
        assert value.shape == (3, 4)
        np.testing.assert_allclose(value, ref[name], rtol=1e-10, atol=1e-6, err_msg=name)
    # the integer dtype is accepted; the previous call's values are never reused
    assert f.batch(np.array([4000]), 0, 0, 0, 0, 20, 200000)[1][0] == pytest.approx(
        float(model.evaluate(4000.0, 0.0, 0.0, vx=20.0, p=2e5).fy), rel=1e-12, abs=1e-9)


@pytest.mark.parametrize("threads", [-1, 1.5, "2", None, True])
def test_batch_refuses_a_thread_count_that_is_not_a_count(compiled, threads):
    """threads=-1 ran silently on one thread before; only 0 (every core) and positive integers are counts."""
    _, f = compiled["mf61"]
    with pytest.raises(ModelInputError, match=r"threads must be 0 .* or a positive integer, got"):
        f.batch(*([np.full(3, v) for v in (4000.0, 0.0, 0.0, 0.0, 0.0, 10.0, 2.2e5)]), threads=threads)


def test_batch_validates_arity_shapes_and_types(compiled):
    model, f = compiled["mf61"]
    x = _points(model, 10, 0)
    f.batch(*x)
    with pytest.raises(ModelInputError, match=r"got 5.*missing vx, p"):
        f.batch(*x[:5])
    with pytest.raises(ModelInputError, match="got 8"):
        f.batch(*x, 1.0)
    with pytest.raises(ModelInputError, match=r"broadcast.*fz \(10,\).*kappa \(3,\)"):
        f.batch(x[0], np.zeros(3), *x[2:])
    with pytest.raises(ModelInputError, match="'alpha' must be real numbers"):
        f.batch(x[0], x[1], np.array(["a"] * 10), *x[3:])
    with pytest.raises(ModelInputError, match="'kappa' must be real numbers"):
        f.batch(x[0], x[1] + 0j, *x[2:])
    with pytest.raises(ModelInputError, match=r"expected 7 inputs.*got 3"):
        f(4000.0, 0.0, 0.0)
    with pytest.raises(ModelInputError, match="'gamma' must be a real number"):
        f(4000.0, 0.0, 0.0, "0.1", 0.0, 20.0, 2e5)  # a numeric string is not a number


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_inputs_raise(compiled, bad):
    model, f = compiled["mf61"]
    x = _points(model, 50, 1)
    x[2] = x[2].copy()
    x[2][7] = bad
    with pytest.raises(ModelInputError, match="'alpha' must be finite; 1 of 50"):
        f.batch(*x)
    with pytest.raises(ModelInputError, match="'vx' must be finite"):
        f(4000.0, 0.0, 0.0, 0.0, 0.0, bad, 2e5)


@pytest.mark.parametrize("p", [0.0, -1e5, np.nan])
def test_pressure_must_be_positive_not_clipped_to_presmin(compiled, p):
    model, f = compiled["mf61"]
    with pytest.raises(ModelInputError, match="'p' must be"):
        f(4000.0, 0.0, 0.05, 0.0, 0.0, 20.0, p)
    with pytest.raises(ModelInputError, match="'p' must be"):
        f.batch(np.full(5, 4000.0), 0.0, 0.05, 0.0, 0.0, 20.0, np.array([2e5, 2e5, p, 2e5, 2e5]))


def test_values_outside_the_ranges_warn_like_numpy(compiled, tmp_path):
    model, f = compiled["mf61"]
    prm = model.params
    alpha = np.array([0.0, 0.1, prm.ALPMAX + 0.1, prm.ALPMIN - 0.2])
    p = np.array([prm.NOMPRES, prm.PRESMIN * 0.9, prm.NOMPRES, prm.NOMPRES])
    with pytest.warns(InputClippedWarning) as record:
        out = f.batch(4000.0, 0.0, alpha, 0.0, 0.0, 20.0, p)
    message = str(record[0].message)
    assert len(record) == 1
    assert "alpha outside ALPMIN..ALPMAX" in message and "at 2 of 4" in message
    assert "p outside PRESMIN..PRESMAX" in message and "at 1 of 4" in message
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = model.evaluate(4000.0, 0.0, alpha, 0.0, 0.0, vx=20.0, p=p)
    np.testing.assert_allclose(out[f.outputs.index("fy")], ref.fy, rtol=1e-11)
    with pytest.warns(InputClippedWarning, match="gamma outside CAMMIN..CAMMAX"):
        f(4000.0, 0.0, 0.0, prm.CAMMAX + 0.1, 0.0, 20.0, prm.NOMPRES)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f(4000.0, 0.0, 0.05, 0.0, 0.0, 20.0, prm.NOMPRES)  # inside: no warning
        free = compile_model(model, outputs=("fy",), directory=tmp_path, limits=False)
        fy = free.batch(4000.0, 0.0, alpha, 0.0, 0.0, 20.0, prm.NOMPRES)[0]  # limits off: no warning
    assert fy[2] == pytest.approx(float(model.evaluate(4000.0, 0.0, alpha[2], limits=False, vx=20.0).fy), rel=1e-11)


def test_mirrored_tyre_checks_the_mirrored_range(tmp_path):
    model = mftyre.load_tir(TIR_FILES / FILES["mf61"])
    prm = model.params
    other = model.with_side("left" if model.side == "right" else "right")
    f = compile_model(other, outputs=("fy",), directory=tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f(4000.0, 0.0, -prm.ALPMAX + 1e-3, 0.0, 0.0, 20.0, prm.NOMPRES)
    with pytest.warns(InputClippedWarning, match="alpha"):
        f(4000.0, 0.0, -prm.ALPMAX - 1e-3, 0.0, 0.0, 20.0, prm.NOMPRES)
    with pytest.raises(ModelInputError, match="'p'"):
        compile_model(model, inputs=("fz", "kappa", "alpha"), outputs=("fy",), directory=tmp_path, fixed={"p": 0.0})


# --------------------------------------------------------------------------------------------------- cache
def _compile_in_subprocess(directory, tir, outputs="fx,fy"):
    code = ("import sys, warnings; warnings.simplefilter('ignore'); import mftyre; "
            "from mftyre.compiled import compile_model; "
            f"f = compile_model(mftyre.load_tir({str(tir)!r}), outputs={outputs.split(',')!r}, "
            f"directory={str(directory)!r}); print(f.library, f(4000.0, 0.02, 0.03, 0, 0, 20.0, 2.2e5)[1])")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(PROJECT)})


def test_truncated_library_is_rebuilt_not_loaded(tmp_path):
    tir = TIR_FILES / FILES["mf61"]
    first = _compile_in_subprocess(tmp_path, tir)
    assert first.returncode == 0, first.stderr
    library = next(tmp_path.glob("*.so"))
    size = library.stat().st_size
    with open(library, "r+b") as fh:  # a library cut short (disk full, a killed copy...)
        fh.truncate(size // 3)
    with pytest.raises(MFTyreError, match="damaged"):
        CompiledFunction(library)
    model = mftyre.load_tir(tir)
    f = compile_model(model, outputs=("fx", "fy"), directory=tmp_path)  # rebuilt, no crash
    assert f.library.stat().st_size == size
    assert f(4000.0, 0.02, 0.03, 0.0, 0.0, 20.0, 2.2e5)[1] == pytest.approx(
        float(model.evaluate(4000.0, 0.02, 0.03, vx=20.0, p=2.2e5).fy), rel=1e-12)
    library.with_suffix(".json").write_text("{not json")  # a damaged description is rebuilt too
    assert compile_model(model, outputs=("fx", "fy"), directory=tmp_path)(4000.0, 0, 0, 0, 0, 20.0, 2.2e5)


def test_libraries_others_could_write_are_refused(tmp_path, monkeypatch):
    model = mftyre.load_tir(TIR_FILES / FILES["mf61"])
    cache = tmp_path / "cache"
    f = compile_model(model, outputs=("fy",), directory=cache)
    library = f.library
    library.chmod(0o666)  # planted or altered by someone else: world-writable
    with pytest.raises(CacheSecurityError, match="writable by group or others"):
        CompiledFunction(library)
    with pytest.raises(CacheSecurityError):
        compile_model(model, outputs=("fy",), directory=cache)
    library.chmod(0o644)
    cache.chmod(0o777)
    monkeypatch.setenv("MFTYRE_CACHE", str(cache))
    with pytest.raises(CacheSecurityError, match="the folder"):
        compile_model(model, outputs=("fy",))
    cache.chmod(0o700)
    assert compile_model(model, outputs=("fy",)).library == library
    if os.geteuid() == 0:  # root's own files are trusted: give the library to another user
        os.chown(library, 4243, -1)
    else:  # pretend to be another user
        real_uid = os.geteuid()
        monkeypatch.setattr(os, "geteuid", lambda: real_uid + 12345)
    with pytest.raises(CacheSecurityError, match="belongs to user id"):
        CompiledFunction(library)


def test_concurrent_compilation_in_threads_and_processes(tmp_path):
    tir = TIR_FILES / FILES["mf61"]
    model = mftyre.load_tir(tir)
    results, errors = [], []

    def work():
        try:
            results.append(compile_model(model, outputs=("fx", "fy"), directory=tmp_path / "threads"))
        except Exception as exc:  # noqa: BLE001
            errors.append(repr(exc))

    threads = [threading.Thread(target=work) for _ in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and len(results) == 6
    values = {r(4000.0, 0.02, 0.03, 0.0, 0.0, 20.0, 2.2e5) for r in results}
    assert len(values) == 1
    assert not list((tmp_path / "threads").glob(".*"))  # no temporary files left
    # the same compilation started in two processes at once
    code = ("import subprocess, sys; cmd = [sys.executable, '-c', sys.argv[1]]; "
            "ps = [subprocess.Popen(cmd) for _ in range(2)]; sys.exit(sum(p.wait() for p in ps))")
    inner = ("import warnings; warnings.simplefilter('ignore'); import mftyre; "
             "from mftyre.compiled import compile_model; "
             f"f = compile_model(mftyre.load_tir({str(tir)!r}), outputs=['fx', 'fy'], "
             f"directory={str(tmp_path / 'procs')!r}); assert abs(f(4000.0, 0, 0.03, 0, 0, 20.0, 2.2e5)[1]) > 0")
    run = subprocess.run([sys.executable, "-c", code, inner], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONPATH": str(PROJECT)})
    assert run.returncode == 0, run.stderr
    assert len(list((tmp_path / "procs").glob("*.so"))) >= 1


# --------------------------------------------------------------------------------------------- derivatives
def test_external_derivatives_equal_casadi_and_differences(tmp_path):
    import casadi as ca

    model = mftyre.load_tir(TIR_FILES / FILES["mf61"])
    inputs, outputs = ("fz", "kappa", "alpha"), ("fx", "fy", "mz")
    ext = compile_external(model, inputs, outputs, hessian=True, directory=tmp_path, name="tyre")
    sym = model.casadi_function(inputs, outputs)
    x = ca.SX.sym("x", 3)
    jac = {k: ca.Function("j", [x], [ca.jacobian(ca.vertcat(*f(x[0], x[1], x[2])), x)]) for k, f in
           (("ext", ext), ("sym", sym))}
    hess = {k: ca.Function("h", [x], [ca.hessian(f(x[0], x[1], x[2])[1], x)[0]]) for k, f in
            (("ext", ext), ("sym", sym))}
    for point in ([4000.0, 0.05, 0.1], [6500.0, -0.1, -0.04], [2500.0, 0.0, 0.2]):
        j_ext, j_sym = np.array(jac["ext"](point)), np.array(jac["sym"](point))
        np.testing.assert_allclose(j_ext, j_sym, rtol=1e-12, atol=1e-9)
        # central differences of the NumPy model
        steps = np.array([1.0, 1e-6, 1e-6])
        for i in range(3):
            hi, lo = np.array(point), np.array(point)
            hi[i] += steps[i]
            lo[i] -= steps[i]
            f_hi, f_lo = (model.evaluate(*v, vx=model.params.LONGVL) for v in (hi, lo))
            fd = [(f_hi[n] - f_lo[n]) / (2 * steps[i]) for n in outputs]
            np.testing.assert_allclose(j_ext[:, i], np.ravel(fd), rtol=1e-5, atol=1e-3 * steps[i] ** -1 * 1e-6)
        np.testing.assert_allclose(np.array(hess["ext"](point)), np.array(hess["sym"](point)), rtol=1e-10,
                                   atol=1e-6)
    # the compiled library holds the tyre and its derivatives only: small, and cached
    assert len(list(tmp_path.glob("*.so"))) == 1
    assert next(tmp_path.glob("*.so")).stat().st_size < 2_000_000
    again = compile_external(model, inputs, outputs, hessian=True, directory=tmp_path, name="tyre")
    assert len(list(tmp_path.glob("*.so"))) == 1 and float(again(4000, 0.05, 0.1)[1]) == float(ext(4000, 0.05, 0.1)[1])


def test_external_function_inside_ipopt(tmp_path):
    import casadi as ca

    model = mftyre.load_tir(TIR_FILES / FILES["mf61"])
    ext = compile_external(model, ("kappa", "alpha"), ("fx", "fy"), hessian=True, directory=tmp_path,
                           fixed={"fz": 4000.0}, name="tyre4k")
    # the combined-slip operating point that gives Fx = 1500 N and Fy = -2500 N with least slip
    w = ca.MX.sym("w", 2)
    fx, fy = ext(w[0], w[1])
    solver = ca.nlpsol("s", "ipopt", {"x": w, "f": w[0] ** 2 + w[1] ** 2, "g": ca.vertcat(fx - 1500.0, fy + 2500.0)},
                       {"ipopt.print_level": 0, "print_time": 0, "ipopt.hessian_approximation": "exact"})
    sol = solver(x0=[0.01, 0.01], lbg=0, ubg=0, lbx=[-0.2, -0.2], ubx=[0.2, 0.2])
    assert solver.stats()["success"]
    kappa, alpha = np.array(sol["x"]).ravel()
    out = model.evaluate(4000.0, kappa, alpha)
    assert float(out.fx) == pytest.approx(1500.0, abs=1e-6) and float(out.fy) == pytest.approx(-2500.0, abs=1e-6)


@pytest.mark.parametrize("hessian, approximation", [(True, "exact"), (False, "exact"), (False, "limited-memory")])
def test_external_function_with_or_without_hessian_inside_ipopt(tmp_path, hessian, approximation):
    """compile_external(hessian=False) works in IPOPT's exact-Hessian mode (second derivatives by differences of the
    compiled Jacobian; it failed at construction: 'Failed to create nlp_hess_l') and with its limited-memory
    quasi-Newton, and reaches the optimum of hessian=True (which carries the Jacobian of the adjoint, the
    Hessian of the Lagrangian, exact)."""
    import casadi as ca

    model = mftyre.load_tir(TIR_FILES / FILES["mf61"])
    ext = compile_external(model, ("kappa", "alpha"), ("fx", "fy"), hessian=hessian, directory=tmp_path,
                           fixed={"fz": 4000.0}, name="tyre4k")
    w = ca.MX.sym("w", 2)
    fx, fy = ext(w[0], w[1])
    solver = ca.nlpsol("s", "ipopt", {"x": w, "f": w[0] ** 2 + w[1] ** 2, "g": ca.vertcat(fx - 1500.0, fy + 2500.0)},
                       {"ipopt.print_level": 0, "print_time": 0, "ipopt.hessian_approximation": approximation})
    sol = solver(x0=[0.01, 0.01], lbg=0, ubg=0, lbx=[-0.2, -0.2], ubx=[0.2, 0.2])
    assert solver.stats()["success"]
    kappa, alpha = np.array(sol["x"]).ravel()
    out = model.evaluate(4000.0, kappa, alpha)
    assert float(out.fx) == pytest.approx(1500.0, abs=1e-5) and float(out.fy) == pytest.approx(-2500.0, abs=1e-5)
    # the same point as the exact-derivative route of the SX function
    f = model.casadi_function(("kappa", "alpha"), ("fx", "fy"), fixed={"fz": 4000.0})
    fx_s, fy_s = f(w[0], w[1])
    exact = ca.nlpsol("e", "ipopt", {"x": w, "f": w[0] ** 2 + w[1] ** 2, "g": ca.vertcat(fx_s - 1500.0, fy_s + 2500.0)},
                      {"ipopt.print_level": 0, "print_time": 0})
    np.testing.assert_allclose(np.array(sol["x"]).ravel(),
                               np.array(exact(x0=[0.01, 0.01], lbg=0, ubg=0, lbx=[-0.2, -0.2], ubx=[0.2, 0.2])["x"]).ravel(),
                               rtol=1e-7, atol=1e-10)


def test_external_without_hessian_keeps_exact_first_derivatives(tmp_path):
    """compile_external(hessian=False): the Jacobian CasADi takes of it in a graph (an MX Jacobian, as IPOPT's
    constraint Jacobian) is the compiled exact one, equal to hessian=True's to rounding; only the second derivatives
    are differences (they were differences of differences: the first derivatives were differenced too, ~1e-6 off)."""
    import casadi as ca

    model = mftyre.load_tir(TIR_FILES / FILES["mf61"])
    inputs, outputs = ("fz", "kappa", "alpha"), ("fx", "fy")
    exact = compile_external(model, inputs, outputs, hessian=True, directory=tmp_path, name="tyre_h")
    no_hessian = compile_external(model, inputs, outputs, hessian=False, directory=tmp_path, name="tyre_j")
    x = ca.MX.sym("x", 3)
    jac = {k: ca.Function("j", [x], [ca.jacobian(ca.vertcat(*f(x[0], x[1], x[2])), x)]) for k, f in
           (("exact", exact), ("no_hessian", no_hessian))}
    for point in ([4000.0, 0.05, 0.1], [6500.0, -0.1, -0.04], [2500.0, 0.0, 0.2]):
        a, b = np.array(jac["no_hessian"](point)), np.array(jac["exact"](point))
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-13 * np.abs(b).max())
    # its second derivatives exist (differences of that Jacobian) and are close to the exact ones
    hess = {k: ca.Function("h", [x], [ca.hessian(f(x[0], x[1], x[2])[1], x)[0]]) for k, f in
            (("exact", exact), ("no_hessian", no_hessian))}
    h_fd, h_exact = np.array(hess["no_hessian"]([4000.0, 0.05, 0.1])), np.array(hess["exact"]([4000.0, 0.05, 0.1]))
    np.testing.assert_allclose(h_fd, h_exact, rtol=1e-3, atol=1e-4 * np.abs(h_exact).max())


@pytest.mark.parametrize("table, tir", [("mf61_random", "MagicFormula61_Parameters.tir"),
                                        ("mf62_random", "MagicFormula62_Parameters.tir")])
def test_compiled_reproduces_reference_tables(mfeval_dir, tmp_path, table, tir):
    """The vectorised C (vector maths library, no fast-math) against MFeval at the tolerances of
    tests/test_reference_mfeval.py: 1e-9 relative, floors 1e-9 FNOMIN N, FNOMIN R0 N m, R0 m; MF 6.2 Rl 1e-7 m."""
    import pandas as pd

    model = mftyre.load_tir(mfeval_dir / tir)
    prm = model.params
    df = pd.read_csv(mfeval_dir / f"{table}.csv")
    assert set(df["useMode"]) == {111} and (df["in_omega"] == 0).all()  # limits on, spin estimated
    outputs = ("fx", "fy", "mx", "my", "mz", "re", "rl", "kya", "kxk", "mux", "muy")
    f = compile_model(model, outputs=outputs, directory=tmp_path)
    p = np.where(df["in_P"] == 0, prm.INFLPRES, df["in_P"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputClippedWarning)
        ours = dict(zip(outputs, f.batch(*(df[f"in_{c}"].to_numpy() for c in
                                            ("Fz", "kappa", "alpha", "gamma", "phit", "Vx")), p)))
    Fz0, R0 = prm.FNOMIN, prm.UNLOADED_RADIUS
    columns = {"fx": ("Fx", Fz0), "fy": ("Fy", Fz0), "mx": ("Mx", Fz0 * R0), "my": ("My", Fz0 * R0),
               "mz": ("Mz", Fz0 * R0), "re": ("Re", R0), "kya": ("Kya", Fz0), "kxk": ("Kxk", Fz0),
               "mux": ("mux", 1.0), "muy": ("muy", 1.0)}
    for name, (col, floor) in columns.items():
        ref = df[col].to_numpy()
        ok = np.isfinite(ref)
        np.testing.assert_allclose(ours[name][ok], ref[ok], rtol=1e-9, atol=1e-9 * floor, err_msg=name)
    ok = np.isfinite(df["Rl"].to_numpy())
    atol = 1e-7 if "62" in table else 1e-9 * R0
    np.testing.assert_allclose(ours["rl"][ok], df["Rl"].to_numpy()[ok], rtol=0, atol=atol)


def test_compile_c_from_threads_into_one_library(tmp_path):
    """compile_c (also used by swift) writes under a unique temporary name: no collision between threads."""
    import ctypes

    from mftyre.compiled import compile_c

    source = tmp_path / "twice.c"
    source.write_text("double twice(double x) { return 2.0 * x; }\n")
    library = tmp_path / "twice.so"
    errors = []

    def work():
        try:
            compile_c(source, library)
        except Exception as exc:  # noqa: BLE001
            errors.append(repr(exc))

    threads = [threading.Thread(target=work) for _ in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert sorted(p.name for p in tmp_path.iterdir()) == ["twice.c", "twice.so"]  # no temporary files left
    twice = ctypes.CDLL(str(library)).twice
    twice.restype, twice.argtypes = ctypes.c_double, [ctypes.c_double]
    assert twice(1.25) == 2.5


def test_shared_range_check_gives_the_compiled_warning(compiled):
    """mftyre.inputs counts and words the warning of MFModel.evaluate exactly as the compiled C does."""
    from mftyre.inputs import input_ranges, saturate, warn_outside

    model, f = compiled["mf61"]
    prm = model.params
    x = dict(fz=np.array([4000.0, prm.FZMAX + 1.0, 3000.0]), kappa=np.array([0.0, prm.KPUMAX + 0.5, prm.KPUMIN - 1]),
             alpha=0.0, gamma=0.0, phit=0.0, vx=20.0, p=np.array([prm.NOMPRES, prm.PRESMAX * 2, prm.NOMPRES]))
    with pytest.warns(InputClippedWarning) as compiled_warning:
        f.batch(*x.values())
    ranges = input_ranges(prm, model.mirrored)
    arrays = {k: np.broadcast_to(v, (3,)) for k, v in x.items()}
    counts = {name: saturate(arrays[name], ranges[name])[1] for name in ranges}
    assert counts == {"fz": 1, "kappa": 2, "alpha": 0, "gamma": 0, "p": 1}
    with pytest.warns(InputClippedWarning) as shared_warning:
        warn_outside(counts, 3, ranges)
    assert str(shared_warning[0].message) == str(compiled_warning[0].message)
    with pytest.warns(InputClippedWarning) as numpy_warning:
        model.evaluate(**x)
    assert [str(w.message) for w in numpy_warning] == [str(compiled_warning[0].message)]


@pytest.mark.parametrize("tag", [*FILES, "mf62_fy_term"])
def test_gcc_vectorises_the_kernel_loop(tag, tmp_path):
    """The batch kernel runs SIMD: gcc reports its loop vectorised (with the default flags gcc 12 left the MF 6.2
    kernel scalar, 3.5x slower: the unrolled loaded-radius solver's masks defeated the vectoriser). Also on the
    shared MF 6.2 file whose vertical relation uses the side-force term (x^Q_FCY2 in every solver step)."""
    from mftyre.compiled import _toolchain, generate_c

    flags, _, kind = _toolchain()
    version = subprocess.run([os.environ.get("CC", "cc"), "--version"], capture_output=True, text=True).stdout
    if kind != "libmvec" or "Free Software Foundation" not in version:  # gcc
        pytest.skip("checks gcc with libmvec (the vectorised build); this toolchain builds the scalar kernel")
    path = (require_shared(SHARED / "reference" / "tir" / "TNO_car205_60R15.tir") if tag == "mf62_fy_term"
            else TIR_FILES / FILES[tag])
    model = mftyre.load_tir(path)
    source = tmp_path / "kernel.c"
    source.write_text(generate_c(model.casadi_function(INPUTS), point_function=model.casadi_function(
        INPUTS, early_stop=True)))  # as compile_model builds it
    lines = source.read_text().split("\n")
    loop = range(lines.index("  for (i = 0; i < m; ++i) {") + 1, lines.index("static void kernel_point(const double "
                                                                            "*const *in, double *const *out)"))
    run = subprocess.run([os.environ.get("CC", "cc"), *[f for f in flags if f not in ("-shared", "-Wl,--no-undefined")],
                          "-c", "-fopt-info-vec-optimized", str(source), "-o", str(tmp_path / "kernel.o")],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    vectorised = [int(line.split("kernel.c:")[1].split(":")[0]) for line in run.stderr.splitlines()
                  if "loop vectorized" in line]
    assert any(number in loop for number in vectorised), run.stderr[-2000:]


def test_mf62_with_side_force_term_matches_numpy_at_low_loads(tno_compiled):
    """The compiled MF 6.2 loaded-radius solve (fixed Newton steps) on a file whose vertical relation uses the
    side-force term, at low loads where a cambered tyre's root lies above the free radius and up to twice the
    nominal load: every output equals NumPy's (adaptive iteration) at the tolerances above."""
    from mftyre.backend import NUMPY
    from mftyre.formula import vertical

    model, f = tno_compiled
    prm = model.params
    rng = np.random.default_rng(21)
    n = 3000
    fz = np.r_[np.zeros(100), rng.uniform(0.0, 600.0, n // 2), rng.uniform(600.0, 2.0 * prm.FNOMIN, n // 2 - 100)]
    kappa, alpha = rng.uniform(-0.2, 0.2, (2, n))
    gamma = rng.uniform(prm.CAMMIN, prm.CAMMAX, n)
    vx = rng.uniform(1.0, 50.0, n)
    p = rng.uniform(prm.PRESMIN, prm.PRESMAX, n)
    out = f.batch(fz, kappa, alpha, gamma, 0.0, vx, p)
    ref = model.evaluate(fz, kappa, alpha, gamma, 0.0, vx=vx, p=p)
    r_omega = vertical.free_radius(prm, ref.omega, NUMPY)
    assert np.sum(ref.rl > r_omega) > 200  # lifted roots among them
    for name, value in zip(f.outputs, out):
        np.testing.assert_allclose(value, ref[name], rtol=1e-10, atol=1e-6, err_msg=name)


def test_one_point_with_non_finite_output_raises_or_returns_it(tmp_path):
    """The single-point entry flags a non-finite output in C (bit 48): with ``finite_outputs`` the call raises the
    error of MFModel.evaluate naming the output and the inputs, without it the value is returned; finite outputs
    pass unflagged, also beside an input outside its range (only warned)."""
    import casadi as ca

    from mftyre.compiled import compile_function

    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    function = ca.Function("f", [x, y], [ca.sqrt(x) + y, x / y], ["x", "y"], ["root", "ratio"])
    library = compile_function(function, "non-finite-output", directory=tmp_path,
                               checks=[{"range": [-1.0, 4.0]}, {}])
    strict, lenient = CompiledFunction(library, finite_outputs=True), CompiledFunction(library)
    assert strict(4.0, 2.0) == (4.0, 2.0)
    with pytest.raises(ModelInputError, match=r"non-finite root at 1 of 1 point.*x=-1, y=1"):
        strict(-1.0, 1.0)
    with pytest.raises(ModelInputError, match=r"non-finite ratio"):
        strict(1.0, 0.0)
    root, ratio = lenient(-1.0, 0.0)
    assert np.isnan(root) and np.isinf(ratio)
    with pytest.warns(InputClippedWarning):
        assert strict(9.0, 1.0) == (4.0, 9.0)


def test_jacobian_of_adjoint_equals_casadis_and_is_cheaper():
    """compile_external's second derivatives (symmetric Hessian of lambda^T f and J^T) equal CasADi's own Jacobian
    of the adjoint, block for block with the same names and sparsity, in fewer operations (lane-change tyre)."""
    import casadi as ca

    from mftyre.compiled import _jacobian_of_adjoint

    model = mftyre.load_tir(TIR_FILES / FILES["mf61"])
    f = model.casadi_function(("fz", "kappa", "alpha", "vx", "p"), ("fx", "fy", "mz"), limits="smooth", smooth=True)
    sx = f.sx_in()
    f = ca.Function("tyre", sx, f.call(sx), f.name_in(), f.name_out(), {"cse": True})
    ours, casadis = _jacobian_of_adjoint(f), f.reverse(1).jacobian()
    assert ours.name() == casadis.name() and ours.name_in() == casadis.name_in()
    assert ours.name_out() == casadis.name_out()
    assert all(ours.sparsity_out(k) == casadis.sparsity_out(k) for k in range(ours.n_out()))
    assert ours.n_instructions() < 0.85 * casadis.n_instructions()
    for point in ([4000.0, 0.05, 0.1, 20.0, 2.2e5], [6500.0, -0.1, -0.04, 35.0, 1.9e5], [2500.0, 0.0, 0.2, 8.0, 2.6e5]):
        args = point + [0.0] * 3 + [1.3, -0.7, 0.4] + [0.0] * 5
        a = np.array([float(v) for v in ours(*args)])
        b = np.array([float(v) for v in casadis(*args)])
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12 * np.abs(b).max())


# ------------------------------------------------------------------------------ one point: C entry and ctypes
def _outcome(call, args):
    """What one call does: its value or its error (type and message), and its warnings (category, message and
    the line they are attributed to)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = ("value", call(*args))
        except Exception as exc:  # noqa: BLE001  (compared below)
            result = ("error", type(exc), str(exc))
    return repr(result), [(w.category, str(w.message), w.filename, w.lineno) for w in caught]


def _one_point(model, seed):
    return [float(np.atleast_1d(v)[0]) for v in _points(model, 1, seed)]


def _awkward_points(model, n, seed):
    """Random points inside the .tir ranges, a third pushed outside one range, some with a non-finite input or a
    pressure <= 0, some given as ints, NumPy scalars, 0-d arrays, a string, too few or too many values."""
    prm = model.params
    rng = np.random.default_rng(seed)
    outside = {0: prm.FZMAX * 1.2, 1: prm.KPUMAX + 0.1, 2: prm.ALPMIN - 0.1, 3: prm.CAMMAX + 0.05,
               6: prm.PRESMIN * 0.9}
    points = []
    for i in range(n):
        x = _one_point(model, seed * 1000 + i)
        kind = rng.integers(12)
        if kind < 4:
            k = int(rng.choice(list(outside)))
            x[k] = outside[k]
        elif kind == 4:
            x[rng.integers(7)] = float(rng.choice([np.nan, np.inf, -np.inf]))
        elif kind == 5:
            x[6] = float(rng.choice([0.0, -1e5]))
        elif kind == 6:
            x[0], x[4] = int(x[0]), 0
        elif kind == 7:
            x[1], x[5] = np.float32(x[1]), np.array(x[5])
        elif kind == 8:
            x[2] = np.float64(x[2])
        elif kind == 9:
            x = x[: rng.integers(7)] if rng.integers(2) else [*x, 1.0]
        elif kind == 10:
            x[3] = "0.01"
        points.append(x)
    return points


@pytest.mark.parametrize("tag", [*FILES, "tno"])
def test_one_point_c_entry_equals_the_ctypes_route(compiled, tno_compiled, tag):
    """Where CPython's headers are found the library's own C entry evaluates one point (fast_point); on random
    points (inside and outside the ranges, non-finite, p <= 0, other number types, wrong arity, a string) it
    returns exactly the ctypes route's outputs, raises the same errors and gives the same warnings at the same
    line, for the two sample files and the TNO MF 6.2 file."""
    from mftyre.compiled import _python_extension_flags

    model, f = tno_compiled if tag == "tno" else compiled[tag]
    assert f.fast_point == bool(_python_extension_flags())
    points = _awkward_points(model, 240, seed={"mf61": 1, "mf62": 2, "tno": 3}[tag])
    kinds = {"value": 0, "error": 0, "warned": 0}
    for x in points:
        fast, ctypes_route = _outcome(f, x), _outcome(f._call_ctypes, x)
        assert fast == ctypes_route, x
        kinds["value" if fast[0].startswith("('value'") else "error"] += 1
        kinds["warned"] += bool(fast[1])
    assert min(kinds.values()) >= 20, kinds  # every kind of outcome was compared
    inside = _one_point(model, 5)
    with pytest.raises(TypeError, match="unexpected keyword"):
        f(*inside[:6], p=inside[6])


def test_one_point_c_entry_from_four_threads(compiled):
    """Four threads calling one point at once (the C entry holds the GIL, its buffers on the stack): each gets
    its serial results, and the errors of non-finite inputs, unmixed."""
    model, f = compiled["mf62"]
    data = [[_one_point(model, 100 * k + i) for i in range(300)] for k in range(4)]
    for k, points in enumerate(data):
        for i in range(k, 300, 7):
            points[i][1 + k] = np.nan  # kappa, alpha, gamma or phit
    serial = [[_outcome(f, x) for x in points] for points in data]
    failures = []

    def work(k):
        for _ in range(3):
            for x, want in zip(data[k], serial[k]):
                try:
                    got = repr(("value", f(*x)))
                except ModelInputError as exc:
                    got = repr(("error", ModelInputError, str(exc)))
                if got != want[0]:
                    failures.append((k, x, got))

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not failures, failures[:3]
    assert sum("error" in s[0] for points in serial for s in points) >= 4 * 40


def test_without_python_headers_one_point_goes_through_ctypes(tmp_path, monkeypatch):
    """Without CPython's headers the library is built without the C entry, silently (an optimisation, not a
    requirement), and one point goes through ctypes with the same results; a library built for another
    interpreter's ABI is not entered from this one."""
    import casadi as ca

    from mftyre import compiled as module

    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    function = ca.Function("f", [x, y], [ca.sqrt(x) + y, x / y], ["x", "y"], ["root", "ratio"])
    checks = [{"range": [-1.0, 4.0]}, {}]
    headers = bool(module._python_extension_flags())
    with_entry = CompiledFunction(module.compile_function(function, "entry", tmp_path, checks=checks),
                                  finite_outputs=True)
    monkeypatch.setattr(module, "_python_extension_flags", lambda: ())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        library = module.compile_function(function, "entry", tmp_path, checks=checks)
        plain = CompiledFunction(library, finite_outputs=True)
    assert library != with_entry.library and not plain.fast_point
    assert not hasattr(plain._lib, "mft_python_function")
    assert with_entry.fast_point == headers
    for args in [(4.0, 2.0), (2, 3), (-1.0, 1.0), (9.0, 1.0), (1.0, 0.0), (np.nan, 1.0), (1.0,), ("1", 2.0)]:
        assert _outcome(plain, args) == _outcome(with_entry, args), args
    monkeypatch.setattr(module, "_PYTHON_ABI", ".cpython-0-other.so")
    other = CompiledFunction(with_entry.library, finite_outputs=True)
    assert not other.fast_point and other(4.0, 2.0) == (4.0, 2.0)


def test_headers_that_do_not_compile_fall_back_to_ctypes(tmp_path, monkeypatch):
    """Python.h present but unusable (another interpreter's, a broken install): the library is built without the C
    entry instead of failing, and later builds of the process skip the entry; a failure that is not the entry's
    (no compiler) is still raised."""
    import casadi as ca

    from mftyre import compiled as module

    broken = tmp_path / "include"
    broken.mkdir()
    (broken / "Python.h").write_text("#error not these headers\n")
    monkeypatch.setattr(module, "_PYTHON_ABI", module._PYTHON_ABI or ".cpython-0-test.so")
    monkeypatch.setattr(module, "_python_headers", lambda: ("-DMFT_PYTHON", f"-I{broken}"))
    monkeypatch.setattr(module, "_PYTHON_ENTRY_BUILDS", {True})
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    function = ca.Function("g", [x, y], [x * y], ["x", "y"], ["product"])
    plain = CompiledFunction(module.compile_function(function, "broken-headers", tmp_path / "cache"))
    assert not plain.fast_point and plain(3.0, 2.0) == (6.0,)
    assert not module._PYTHON_ENTRY_BUILDS and module._python_extension_flags() == ()
    flags, libraries, tag = module._toolchain()
    monkeypatch.setattr(module, "_toolchain", lambda: ((*flags, "--no-such-compiler-option"), libraries, tag))
    monkeypatch.setattr(module, "_PYTHON_ENTRY_BUILDS", {True})
    with pytest.raises(MFTyreError, match="no-such-compiler-option"):
        module.compile_function(function, "other-key", tmp_path / "cache")


# ------------------------------------------------------------- one point: the loaded-radius steps stop early
def _extreme_points(model, n, seed):
    """Loads from none (lifted roots with camber) to 4x nominal (the rim's bottoming region), large slips and
    side forces, camber at and beyond its range, speeds and pressures across and beyond their ranges."""
    prm = model.params
    rng = np.random.default_rng(seed)
    fz = np.r_[rng.uniform(0.0, 600.0, n // 4), rng.uniform(0.0, 3.0 * prm.FNOMIN, n // 2),
               rng.uniform(2.0 * prm.FNOMIN, 4.0 * prm.FNOMIN, n - n // 4 - n // 2)]
    gamma = rng.choice([prm.CAMMIN, prm.CAMMAX, 0.0], n) * rng.uniform(0.5, 1.5, n)
    return [fz, rng.uniform(-0.5, 0.5, n), rng.uniform(-0.7, 0.7, n), gamma, np.zeros(n), rng.uniform(0.5, 60.0, n),
            rng.uniform(0.6 * prm.PRESMIN, 1.2 * prm.PRESMAX, n)]


@pytest.mark.parametrize("path", [TIR_FILES / FILES["mf62"], SHARED / "reference" / "tir" / "TNO_car205_60R15.tir",
                                  SHARED / "reference" / "mfeval" / "MagicFormula62_Parameters.tir"],
                         ids=["mf62", "tno", "mfeval62"])
def test_early_stop_stays_within_1e12_of_every_newton_step(path):
    """``early_stop`` (what compile_model builds): the MF 6.2 loaded-radius Newton steps stay put once the NumPy
    solver's stopping tests hold; on extreme points (no load to 4x nominal, in and beyond the ranges) the results
    are those of all the unrolled steps to 1e-12 relative (CasADi's own evaluation of both graphs)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mftyre.load_tir(require_shared(path))
    x = _extreme_points(model, 4000, seed=31)
    outputs = ("rl", "rho", "re", "fx", "fy", "mz", "my")
    results = {}
    for early_stop in (False, True):
        f = model.casadi_function(INPUTS, outputs, limits=False, early_stop=early_stop).map(len(x[0]))
        results[early_stop] = [np.array(v).ravel() for v in f(*x)]
    prm = model.params
    rl = results[False][0]
    assert np.sum(rl < prm.RIM_RADIUS + prm.BOTTOM_OFFST) > 50 or path.name == FILES["mf62"]  # bottoming reached
    for name, full, early in zip(outputs, results[False], results[True]):
        assert np.all(np.isfinite(early)), name
        np.testing.assert_allclose(early, full, rtol=1e-12, atol=1e-300, err_msg=name)


def test_one_point_skips_the_steps_after_convergence_with_the_batch_results(tno_compiled):
    """The one-point C runs the branches of if_else not taken inside ``if`` (the loaded-radius steps once
    converged): on extreme points inside the ranges (the batch kernel computes every step) each point gives the
    batch's results; the kernel of the TNO file has such branches, at least one per unrolled Newton step."""
    import casadi as ca

    from mftyre.compiled import _operations, _point_body
    from mftyre.formula import vertical

    model, f = tno_compiled
    graph = model.casadi_function(INPUTS, early_stop=True)
    lines = _point_body(ca.Function("k", graph.sx_in(), graph.call(graph.sx_in()), {"cse": True}), _operations())
    assert sum(line.lstrip().startswith("if (v") for line in lines) >= vertical._NEWTON_STEPS
    prm = model.params
    x = _extreme_points(model, 1500, seed=32)
    x[2] = np.clip(x[2], prm.ALPMIN, prm.ALPMAX)
    x[3] = np.clip(x[3], prm.CAMMIN, prm.CAMMAX)
    x[6] = np.clip(x[6], prm.PRESMIN, prm.PRESMAX)
    x[0] = np.clip(x[0], 0.0, prm.FZMAX)
    batch = np.array(f.batch(*x))
    points = np.array([f(*(float(v[i]) for v in x)) for i in range(len(x[0]))]).T
    np.testing.assert_allclose(points, batch, rtol=1e-10, atol=1e-6)
