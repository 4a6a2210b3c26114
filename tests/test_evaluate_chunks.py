"""MFModel.evaluate on large batches works chunk by chunk (mftyre.model._CHUNK points at a time, results written
into one block): the chunking must not show. Chunked results equal those of one whole-batch evaluation, the
clipping warning and the non-finite-output error speak of the whole call (totals, original indices), and threads
sharing one model get what a serial caller gets. The chunk size is shrunk here so that small batches straddle it.
"""
from __future__ import annotations

import threading
import warnings

import numpy as np
import pytest

import mftyre
import mftyre.model as model_module
from mftyre import ModelInputError
from mftyre.errors import InputClippedWarning
from mftyre.formula import Modes
from mftyre.model import as_float_arrays

from conftest import TIR_FILES

CHUNK = 50
FILES = [TIR_FILES / "car_205_60R15_mf61.tir", TIR_FILES / "car_205_60R15_mf62_swift.tir"]


def _inputs(model, n, seed=0):
    prm = model.params
    rng = np.random.default_rng(seed)
    return dict(fz=rng.uniform(0.0, 2.0, n) * prm.FNOMIN, kappa=rng.uniform(-0.3, 0.3, n),
                alpha=rng.uniform(-0.3, 0.3, n), gamma=rng.uniform(-0.05, 0.05, n), phit=rng.uniform(-0.2, 0.2, n),
                vx=rng.uniform(-5.0, 35.0, n), p=rng.uniform(0.9, 1.1, n) * prm.NOMPRES,
                omega=rng.uniform(0.0, 100.0, n))


def _evaluate(model, chunk, monkeypatch, *args, **kwargs):
    monkeypatch.setattr(model_module, "_CHUNK", chunk)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputClippedWarning)
        return model.evaluate(*args, **kwargs)


def _assert_same(chunked, whole):
    for name in mftyre.MFOutputs.__slots__:
        a, b = chunked[name], whole[name]
        assert a.shape == b.shape and a.dtype == b.dtype == np.float64, name
        np.testing.assert_array_equal(a, b, err_msg=name)


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
@pytest.mark.parametrize("n", [CHUNK - 1, CHUNK, CHUNK + 1, 3 * CHUNK + 7])
@pytest.mark.parametrize("side", ["left", "right"])
def test_chunked_equals_whole_batch(path, n, side, monkeypatch):
    model = mftyre.load_tir(path, side=side)
    x = _inputs(model, n)
    cases = [
        (dict(x), {}),  # every input an array
        (dict(fz=4000.0, kappa=x["kappa"], alpha=0.05, vx=x["vx"]), {}),  # scalars and arrays mixed
        (dict(x), dict(turn_slip=True)),
        (dict(x, omega=None), dict(limits=False)),
    ]
    for inputs, modes in cases:
        whole = _evaluate(model, 10**9, monkeypatch, **inputs, **modes)
        chunked = _evaluate(model, CHUNK, monkeypatch, **inputs, **modes)
        assert chunked.fx.shape == (n,)
        _assert_same(chunked, whole)
        if n > CHUNK:  # the outputs are distinct arrays, none a view of an input
            assert not np.shares_memory(chunked.fx, chunked.fy)
            assert not any(np.shares_memory(chunked[k], v) for k in ("vx", "kappa") for v in x.values())


def test_chunked_broadcast_shapes(monkeypatch):
    model = mftyre.load_tir(FILES[0])
    fz = np.linspace(1000.0, 6000.0, 9)[:, None]
    alpha = np.linspace(-0.2, 0.2, 13)  # 9 x 13 = 117 points: three chunks of 39
    whole = _evaluate(model, 10**9, monkeypatch, fz, 0.02, alpha, gamma=np.full((9, 1), 0.01))
    chunked = _evaluate(model, CHUNK, monkeypatch, fz, 0.02, alpha, gamma=np.full((9, 1), 0.01))
    assert chunked.fy.shape == (9, 13) and chunked.gamma.shape == (9, 13)
    _assert_same(chunked, whole)


def test_clipping_warning_counts_points_over_the_whole_call(monkeypatch):
    model = mftyre.load_tir(FILES[0])
    prm = model.params
    n = 3 * CHUNK + 7
    kappa = np.zeros(n)
    outside = [3, CHUNK + 4, 2 * CHUNK + 1, n - 1]  # one in every chunk
    kappa[outside] = prm.KPUMAX + 0.5
    monkeypatch.setattr(model_module, "_CHUNK", CHUNK)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = model.evaluate(4000.0, kappa, 0.0)
    clipped = [w for w in caught if issubclass(w.category, InputClippedWarning)]
    assert len(clipped) == 1
    assert f"kappa outside KPUMIN..KPUMAX = [{prm.KPUMIN:g}, {prm.KPUMAX:g}] - at {len(outside)} of {n} point(s)" \
        in str(clipped[0].message)
    at_bound = model.evaluate(4000.0, prm.KPUMAX, 0.0)
    assert np.all(out.fx[outside] == at_bound.fx)


def test_non_finite_output_error_names_the_original_index_and_counts_every_chunk(monkeypatch):
    """Q_V1 = -1433 leaves the spin of a rolling wheel without a finite solution (a standstill is fine): the error
    names the first such point by its index in the call, and counts the points of every chunk."""
    # values no tyre can have: with_params refuses them, the unchecked replace() does not
    bad = mftyre.MFModel(mftyre.load_tir(FILES[1]).params.replace(Q_V1=-1433.0, Q_V2=480.0))
    n = 3 * CHUNK + 7
    vx = np.zeros(n)
    vx[[2 * CHUNK + 3, 2 * CHUNK + 9, 3 * CHUNK + 2]] = 40.0
    monkeypatch.setattr(model_module, "_CHUNK", CHUNK)
    # evaluate refuses the speeds first (the free radius would change by more than 10 % at 0.14 m/s) ...
    with pytest.raises(ModelInputError, match=rf"vx = 40 .* at 3 of {n} points, first at point {2 * CHUNK + 3},"):
        bad.evaluate(4000.0, 0.0, 0.0, vx=vx)
    # ... and the chunked check of the outputs behind it names the same point
    arrays = as_float_arrays(dict(fz=4000.0, kappa=0.0, alpha=0.0, gamma=0.0, phit=0.0, vx=vx, p=2.2e5, omega=0.0))
    with pytest.raises(ModelInputError, match=rf"non-finite .* at 3 of {n} point\(s\), first at point "
                                              rf"{2 * CHUNK + 3}: .*vx=40"):
        bad._evaluate_arrays(arrays, False, Modes(), check_finite=True)


def test_threads_sharing_one_model_get_the_serial_results(monkeypatch):
    """8 threads evaluate different multi-chunk batches on one model at once: each result equals the serial one."""
    monkeypatch.setattr(model_module, "_CHUNK", CHUNK)
    models = [mftyre.load_tir(FILES[0]), mftyre.load_tir(FILES[1], side="left")]
    jobs = [(models[i % 2], _inputs(models[i % 2], 4 * CHUNK + i, seed=i)) for i in range(8)]
    serial = [m.evaluate(**x) for m, x in jobs]
    results = [None] * len(jobs)
    barrier = threading.Barrier(len(jobs))

    def run(i):
        barrier.wait()
        model, x = jobs[i]
        results[i] = [model.evaluate(**x) for _ in range(5)]

    threads = [threading.Thread(target=run, args=(i,)) for i in range(len(jobs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i, expected in enumerate(serial):
        for got in results[i]:
            _assert_same(got, expected)


@pytest.mark.parametrize("fill", ["none", "all", "some"])
def test_numpy_where_and_sign_nz_shortcuts_give_np_where_values(fill):
    """The NumPy backend skips the selection pass where one side holds everywhere: values, shape and dtype as
    np.where gives them, for array and number operands and operands that broadcast."""
    from mftyre.backend import NUMPY

    x = np.array([-2.0, -0.0, 0.0, 3.0, 5.0])
    cond = {"none": np.zeros(5, bool), "all": np.ones(5, bool), "some": x > 1}[fill]
    for a, b in [(x, 2 * x), (x, 7.0), (7.0, x), (x, np.array([1.0])), (x[:, None], x), (1, 2)]:
        got, expected = NUMPY.where(cond, a, b), np.where(cond, a, b)
        assert np.shape(got) == expected.shape and np.result_type(got) == expected.dtype
        np.testing.assert_array_equal(got, expected)
    for v in (x, np.abs(x) + 1.0, -np.abs(x) - 1.0):
        np.testing.assert_array_equal(np.broadcast_to(NUMPY.sign_nz(v), v.shape), np.where(v < 0, -1.0, 1.0))
