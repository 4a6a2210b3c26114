"""The runner (mftyre.runner) on a 2-process LocalCluster (one for the file, left without a process or thread at
its end) and on a scheduler started in a separate process: plain tasks, failures reported while the others go on,
--resume, results identical to serial; the campaign fit (mftyre.campaign, on that scheduler) bitwise equal to
fitting each tyre alone; sweeps (mftyre.sweep) against the models' own entry points, their CSV and Parquet tables;
MFModel.evaluate_chunked against one compiled batch and evaluate()."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pandas as pd
import pytest

import mftyre
from mftyre.campaign import campaign_tyres, run_campaign
from mftyre.data import TyreData, read_data, trailer_programme, write_tydex
from mftyre.fit import fit_tir
from mftyre.runner import Runner, RunnerError
from mftyre.sweep import parse_distribution, run_batch, sweep, sweep_runs
from mftyre.tir import read_tir

from conftest import TIR_FILES

SAMPLE = TIR_FILES / "car_205_60R15_mf61.tir"
SWIFT = TIR_FILES / "car_205_60R15_mf62_swift.tir"
OPTIONS = {"axle": "height", "start": 0.0, "distance": 1.0, "dt": 1e-3}


@pytest.fixture(scope="module")
def cluster():
    """A LocalCluster of 2 worker processes, shared by the tests of this file; at the end no process or thread of
    it is left (a worker left behind would hold the pytest-xdist process that runs this file)."""
    import psutil

    before = set(threading.enumerate())
    with Runner(workers=2) as runner:
        workers = [psutil.Process(pid) for pid in runner.client().run(os.getpid).values()]
        assert len(workers) == 2 and os.getpid() not in [w.pid for w in workers]  # processes, not threads
        assert runner.slots() == 2 and Runner(workers=0).slots() == 1
        yield runner
    _, alive = psutil.wait_procs(workers, timeout=30)
    assert not alive, f"worker processes left running: {alive}"
    for _ in range(100):  # dask's threads end shortly after the client and cluster are closed
        left = [t for t in set(threading.enumerate()) - before if t.is_alive() and not t.daemon]
        if not left:
            break
        time.sleep(0.1)
    assert not left, f"threads left running: {left}"


def _steady_runs(n=6, seed=3):
    model = mftyre.load_tir(SAMPLE)
    variables = [parse_distribution("LMUY=normal(1, 0.05)"), parse_distribution("fz=grid(3000, 5000, 2)"),
                 parse_distribution("alpha=0.08")]
    return sweep_runs("steady", variables, [""], [15.0], n, seed, model.params)


def test_tasks_carry_plain_data_only():
    import casadi as ca

    runner = Runner(workers=0)
    with pytest.raises(RunnerError, match=r"task a\['x'\]: a casadi.*plain data"):
        runner.run(run_batch, {"a": {"x": ca.SX.sym("x")}})
    with pytest.raises(RunnerError, match="top level of an importable module"):
        runner.run(lambda x: x, {"a": {"x": 1}})
    with pytest.raises(RunnerError, match="task key 'a/b'"):
        runner.run(run_batch, {"a/b": {}})


def test_packed_arrays_come_back_bit_for_bit_through_a_json_result():
    """pack / unpack: a result's long arrays as text (float64 bytes in base64) that survive the JSON round trip
    exactly, signed zeros, subnormals, infinities and NaN payloads included; text that is not base64 is refused."""
    from mftyre.runner import pack, unpack

    values = np.array([0.1, -0.0, 5e-324, np.inf, -np.inf, np.nan, 1e308, -1.2345678901234567e-100])
    back = unpack(json.loads(json.dumps({"v": pack(values)}))["v"])
    assert back.dtype == np.float64 and back.flags.writeable
    assert np.array_equal(back.view(np.int64), values.view(np.int64))
    assert np.array_equal(unpack(pack(np.arange(3, dtype=np.float32))), [0.0, 1.0, 2.0])
    with pytest.raises(ValueError):
        unpack("not base64!")


def test_draws_are_the_seeded_generators_and_recorded():
    runs = _steady_runs(n=5, seed=11)
    expected = np.random.default_rng(11).normal(1.0, 0.05, (2, 5))  # two conditions (fz grid), five samples
    assert np.array_equal(runs["LMUY"].to_numpy().reshape(2, 5), expected)
    assert (runs["seed"] == 11).all() and list(runs["fz"].unique()) == [3000.0, 5000.0]
    with pytest.raises(mftyre.errors.ModelInputError, match="neither an input of the swift model"):
        sweep_runs("swift", [parse_distribution("alpha=0.1")], [""], [10.0], 1, 0, mftyre.load_tir(SWIFT).params)


def test_steady_sweep_on_the_cluster_equals_serial_and_the_model(cluster, tmp_path):
    runs = _steady_runs()
    parallel, failed = sweep(SAMPLE, "steady", runs, cluster, options=OPTIONS, batch=4, tasks=tmp_path / "t")
    serial, _ = sweep(SAMPLE, "steady", runs, Runner(workers=0), options=OPTIONS, batch=5)
    assert not failed and (parallel["error"] == "").all()
    pd.testing.assert_frame_equal(parallel, serial, check_exact=True)
    model = mftyre.load_tir(SAMPLE)
    for row in parallel.itertuples():  # each row: the model with that LMUY at that load, evaluated directly
        out = model.with_params(LMUY=row.LMUY).evaluate(fz=row.fz, kappa=0.0, alpha=0.08, vx=15.0)
        assert row.fy_peak == float(out.fy) and row.fz_max == row.fz
    assert len(list((tmp_path / "t").glob("runs-*.json"))) == 3


def test_a_failing_task_is_reported_with_its_inputs_and_resume_skips_what_is_done(cluster, tmp_path):
    good = {"model_kind": "steady", "tir_text": SAMPLE.read_text(), "source": str(SAMPLE), "options": OPTIONS}
    runs = _steady_runs(n=2)
    tasks = {"b1": {**good, "runs": runs.iloc[:3]}, "bad": {**good, "model_kind": "bogus", "runs": runs.iloc[3:]},
             "b2": {**good, "runs": runs.iloc[3:]}}
    folder = tmp_path / "tasks"
    first = cluster.run(run_batch, tasks, results=folder)
    assert list(first.results) == ["b1", "b2"] and [f.key for f in first.failures] == ["bad"]
    failure = first.failures[0]
    assert failure.inputs["model_kind"] == "bogus" and "KeyError: 'bogus'" in failure.error
    assert "task bad (model_kind='bogus'" in failure.summary()
    assert sorted(p.name for p in folder.iterdir()) == ["b1.json", "b2.json"]
    stamp = (folder / "b1.json").stat().st_mtime_ns
    tasks["b2"] = {**good, "runs": runs.iloc[4:]}  # a changed task runs again; an unchanged one is kept
    again = cluster.run(run_batch, tasks, results=folder, resume=True)
    assert again.resumed == ["b1"] and again.results["b1"] == first.results["b1"]
    assert (folder / "b1.json").stat().st_mtime_ns == stamp
    assert [r["run"] for r in again.results["b2"]] == list(runs["run"].iloc[4:])
    assert json.loads((folder / "b2.json").read_text())["result"] == again.results["b2"]


def _campaign(folder):
    truth = mftyre.load_tir(SAMPLE)
    for i, name in enumerate(("tyreA.tdx", "tyreB/run1.tdx", "tyreB/run2.tdx")):
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        data = trailer_programme(truth.with_params(LMUX=1.0 + 0.05 * i, PKX1=truth.params.PKX1 * (1 + 0.03 * i)),
                                 loads=(0.6, 1.0, 1.4), pressures=(1.0,), cambers_deg=(0.0,), points=11, noise=0.5,
                                 seed=i)
        write_tydex(data, folder / name)
    return folder


@pytest.fixture
def scheduler(monkeypatch):
    """The address of a dask scheduler with one worker (a thread of it) started in a separate process, and named by
    $MFTYRE_SCHEDULER; the process ends when its standard input closes (at the end of the test, or when this
    process dies: nothing is left behind)."""
    script = ("import sys\nfrom distributed import LocalCluster\n"
              "with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol='tcp://', "
              "host='127.0.0.1', scheduler_port=0, dashboard_address=None) as cluster:\n"
              "    print(cluster.scheduler_address, flush=True)\n    sys.stdin.read()\n")
    env = {**os.environ, "PYTHONWARNINGS": "ignore", "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "False",
           "DASK_DISTRIBUTED__ADMIN__SYSTEM_MONITOR__GIL__ENABLED": "False",
           "DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL": "500ms"}  # (mftyre.runner.QUIET, for a cluster's processes)
    process = subprocess.Popen([sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, env=env, text=True)
    try:
        address = process.stdout.readline().strip()  # ("" when the process ended without starting)
        assert address.startswith("tcp://127.0.0.1:"), f"the scheduler did not start (exit {process.poll()})"
        monkeypatch.setenv("MFTYRE_SCHEDULER", address)
        yield address
    finally:
        process.stdin.close()
        try:
            process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=30)
            raise


def test_campaign_on_a_scheduler_in_a_separate_process_is_bitwise_the_fit_of_each_tyre_alone(scheduler, tmp_path):
    """The folder campaign on the cluster of a scheduler in another process ($MFTYRE_SCHEDULER: the variable names
    the cluster when no address is given) against each tyre fitted alone in this process, as ``mftyre fit RUN``
    fits it (read_data, fit_tir; tyreB's two runs joined)."""
    source = _campaign(tmp_path / "campaign")
    defaults = {"start": None, "stages": ["pure_fx"], "weighting": "uniform", "bins": 40, "max_nfev": None,
                "no_pressure": False}
    assert {k: len(v["runs"]) for k, v in campaign_tyres(source, defaults).items()} == {"tyreA": 1, "tyreB": 2}
    out = tmp_path / "out"
    with Runner(workers=2) as runner:
        assert runner.describe() == f"the cluster of scheduler {scheduler}"
        runner.client().wait_for_workers(1, timeout=60)
        assert runner.slots() == 1  # the scheduler's worker threads, not the 2 asked of a local cluster
        summary, failures = run_campaign(source, out, runner, defaults=defaults, say=lambda text: None)
    assert not failures and list(summary["status"]) == ["fitted", "fitted"]
    assert pd.read_csv(out / "summary.csv")["tyre"].tolist() == ["tyreA", "tyreB"]
    for tyre in ("tyreA", "tyreB"):
        assert (out / f"{tyre}.md").is_file() and (out / f"{tyre}_pure_fx.png").is_file()

    for tyre, runs in (("tyreA", ["tyreA.tdx"]), ("tyreB", ["tyreB/run1.tdx", "tyreB/run2.tdx"])):
        parts = [read_data(source / run) for run in runs]
        alone = fit_tir(TyreData.pool(parts), stages=["pure_fx"])
        written = read_tir(out / f"{tyre}.tir")  # the campaign's file, read back
        assert all(repr(written[k]) == repr(alone.params[k]) for k in alone.params), tyre
        assert summary.loc[summary["tyre"] == tyre, "pure_fx FX [%]"].iloc[0] == alone.fit_errors["pure_fx"]
    assert written["PDX1"] != read_tir(out / "tyreA.tir")["PDX1"]  # two tyres, two results


def test_campaign_manifest_rows_and_a_tyre_that_cannot_be_read(tmp_path):
    source = _campaign(tmp_path / "campaign")
    (source / "manifest.csv").write_text("tyre,runs,stages,bins\nA,tyreA.tdx,pure_fx;mz,12\n"
                                         "lost,missing.tdx;tyreA.tdx,,\n")
    defaults = {"start": None, "stages": ["vertical"], "weighting": "load", "bins": 40, "max_nfev": None,
                "no_pressure": False}
    tyres = campaign_tyres(source / "manifest.csv", defaults)
    assert tyres["A"]["stages"] == ["pure_fx", "mz"] and tyres["A"]["bins"] == 12 and tyres["A"]["weighting"] == "load"
    assert tyres["lost"]["stages"] == ["vertical"] and tyres["lost"]["runs"][1] == source / "tyreA.tdx"
    (source / "manifest.csv").write_text("tyre,runs\nlost,missing.tdx;tyreA.tdx\n")
    summary, failures = run_campaign(source / "manifest.csv", tmp_path / "out", Runner(workers=0),
                                     defaults=defaults, say=lambda text: None)
    assert summary["status"].iloc[0].startswith("failed") and "missing.tdx: file not found" in failures[0]
    assert not (tmp_path / "out" / "lost.tir").exists() and (tmp_path / "out" / "summary.csv").is_file()
    (source / "bad.csv").write_text("tyre,runs,stages\nA,tyreA.tdx,pure_fz\n")
    with pytest.raises(mftyre.errors.DataError, match=r"bad.csv, row 2: unknown stage\(s\) pure_fz"):
        campaign_tyres(source / "bad.csv", defaults)


def test_swift_and_transient_runs_on_a_flat_road_carry_the_load():
    """Axle height held at the loaded radius of fz on a flat road: the peak load is fz (the static equilibrium);
    the relaxed wheel's side force after a slip-angle step reaches the steady model's."""
    model = mftyre.load_tir(SWIFT)
    text, short = SWIFT.read_text(), {**OPTIONS, "distance": 0.3}
    swift_rows = run_batch("swift", text, str(SWIFT), pd.DataFrame([{"run": 0, "road": "", "speed": 10.0,
                                                                     "fz": fz} for fz in (3000.0, 5000.0)]), short)
    # (the ring's static load at the MF's loaded radius is within a few per cent of it)
    assert [r["fz_max"] for r in swift_rows] == pytest.approx([3000.0, 5000.0], rel=3e-2)
    rows = run_batch("transient", text, str(SWIFT), pd.DataFrame([{"run": 0, "road": "", "speed": 10.0,
                                                                   "fz": 4000.0, "alpha": 0.03}]),
                     {**OPTIONS, "distance": 3.0})
    steady = model.evaluate(fz=4000.0, kappa=0.0, alpha=0.03, vx=10.0)
    assert rows[0]["fz_max"] == pytest.approx(4000.0, rel=2e-3)
    assert rows[0]["fy_peak"] == pytest.approx(float(steady.fy), rel=1e-2)
    bad = run_batch("steady", text, str(SWIFT), pd.DataFrame([{"run": 7, "road": "", "speed": 10.0,
                                                               "FNOMIN": -1.0}]), OPTIONS)
    assert math.isnan(bad[0]["fy_peak"]) and "FNOMIN: must be positive" in bad[0]["error"]


def test_evaluate_chunked_is_one_compiled_batch_and_the_model(cluster):
    import dask

    from mftyre.compiled import compile_model

    model = mftyre.load_tir(SAMPLE)
    rng = np.random.default_rng(5)
    fz, kappa, alpha = rng.uniform(1500, 7000, 6000), rng.uniform(-0.3, 0.3, 6000), rng.uniform(-0.2, 0.2, 6000)
    out = model.evaluate_chunked(fz, kappa, alpha, outputs=("fy",), chunks=1000)  # 6 chunks of 1024, the last short
    assert out["fy"].numblocks == (6,)
    with cluster.client().as_current():  # the chunks on the workers
        fy, = dask.compute(out["fy"])
    kernel = compile_model(model, outputs=("fy",))
    one = kernel.batch(fz, kappa, alpha, 0.0, 0.0, model.params.LONGVL, model.params.INFLPRES)
    assert np.array_equal(fy, one[0])
    ref = model.evaluate(fz, kappa, alpha)
    assert np.max(np.abs(fy - ref.fy)) <= 1e-9 * np.max(np.abs(ref.fy))
    loads, angles = np.linspace(2000, 6000, 7)[:, None], np.linspace(-0.2, 0.2, 5)
    grid = model.evaluate_chunked(loads, 0.0, angles, outputs=("fy",), chunks=8)["fy"]  # (this process's threads)
    assert grid.shape == (7, 5)
    assert np.allclose(grid.compute(), model.evaluate(loads, 0.0, angles).fy, rtol=1e-9, atol=1e-9)
    with pytest.raises(mftyre.errors.ModelInputError, match="fz"):
        model.evaluate_chunked(np.array([4000.0, np.nan]), 0.0, 0.0, outputs=("fy",))["fy"].compute()


def test_sweep_command_writes_the_table_and_plot_and_resumes(tmp_path, capsys):
    from mftyre.cli import main

    out, plot = tmp_path / "runs.csv", tmp_path / "runs.png"
    argv = ["sweep", str(SAMPLE), "--model", "steady", "--vary", "LMUY=normal(1, 0.05)", "--vary", "alpha=0.05",
            "--speed", "36km/h", "-n", "4", "--seed", "9", "--batch", "2", "-o", str(out), "--plot", str(plot),
            "--workers", "0", "--quiet"]
    assert main(argv) == 0
    table = pd.read_csv(out, keep_default_na=False)
    assert len(table) == 4 and (table["seed"] == 9).all() and (table["speed"] == 10.0).all()
    assert np.array_equal(table["LMUY"], np.random.default_rng(9).normal(1.0, 0.05, 4))
    assert plot.read_bytes()[:4] == b"\x89PNG"
    assert main(argv) == 2 and "pass --overwrite" in capsys.readouterr().err  # no --resume, no --overwrite
    first = out.read_bytes()
    assert main([*argv, "--resume"]) == 0 and out.read_bytes() == first
    assert main([*argv[:-7], "-o", str(tmp_path / "x.txt"), "--workers", "0"]) == 2


def test_fit_command_dispatches_a_folder_to_the_campaign(tmp_path, capsys):
    from mftyre.cli import main

    (tmp_path / "campaign" / "tyreX").mkdir(parents=True)
    (tmp_path / "campaign" / "tyreX" / "run.csv").write_text("FZ,SA\n1,x\n")
    out = tmp_path / "out"
    assert main(["fit", str(tmp_path / "campaign"), "-o", str(out), "--report", "r.md", "--quiet"]) == 2
    assert "--report: a campaign writes one report per tyre" in capsys.readouterr().err
    assert main(["fit", str(tmp_path / "campaign"), "-o", str(out), "--workers", "0", "--quiet"]) == 1
    captured = capsys.readouterr()
    assert "tyre tyreX (runs " in captured.err and "run.csv" in captured.err
    assert pd.read_csv(out / "summary.csv")["status"].iloc[0].startswith("failed")
    assert main(["fit", str(tmp_path / "campaign"), "-o", str(out), "--workers", "0", "--quiet"]) == 2  # not empty


def _steady_sweep_argv(out):
    return ["sweep", str(SAMPLE), "--model", "steady", "--vary", "LMUY=normal(1, 0.05)", "--vary", "fz=values(3000, "
            "5000)", "-n", "3", "--seed", "4", "-o", str(out), "--workers", "0", "--quiet"]


def test_sweep_parquet_table_reads_back_as_the_csv_table(tmp_path):
    pytest.importorskip("pyarrow", reason="pyarrow is not installed: the Parquet output (pip install "
                                          "\"mftyre[parquet]\") is not tested; its error without pyarrow is")
    from mftyre.cli import main

    assert main(_steady_sweep_argv(tmp_path / "runs.parquet")) == 0
    assert main(_steady_sweep_argv(tmp_path / "runs.csv")) == 0
    table = pd.read_parquet(tmp_path / "runs.parquet")
    assert len(table) == 6 and table["fz"].tolist() == [3000.0] * 3 + [5000.0] * 3
    assert np.array_equal(table["LMUY"], np.random.default_rng(4).normal(1.0, 0.05, 6))
    assert (table["error"] == "").all() and table["fy_peak"].notna().all()
    pd.testing.assert_frame_equal(table, pd.read_csv(tmp_path / "runs.csv", keep_default_na=False),
                                  check_exact=True)  # every column, type and bit


def test_sweep_parquet_without_pyarrow_says_how_to_get_it(tmp_path, monkeypatch, capsys):
    from mftyre.cli import main

    monkeypatch.setitem(sys.modules, "pyarrow", None)  # `import pyarrow` raises ImportError, as when absent
    assert main(_steady_sweep_argv(tmp_path / "runs.parquet")) == 2
    err = capsys.readouterr().err
    assert "writing Parquet needs pyarrow, which is not installed" in err and 'pip install "mftyre[parquet]"' in err
    assert list(tmp_path.iterdir()) == []  # nothing run, nothing written
