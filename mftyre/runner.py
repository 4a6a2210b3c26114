"""The one runner of parallel work (campaign fits, sweeps, Monte-Carlo, refits): tasks on dask.distributed.

    from mftyre.runner import Runner
    with Runner(workers=2) as runner:                         # a LocalCluster of 2 processes on this machine
        outcome = runner.run(function, {"a": {...}, "b": {...}}, results="out/tasks", resume=True)
    outcome.results["a"], outcome.failures                    # key -> result; Failure(key, inputs, error)

Where the work runs. ``Runner(workers=N)`` starts a ``distributed.LocalCluster`` of N worker processes (one thread
each; default: the cores this process may use); ``Runner(scheduler="tcp://host:8786")``, or the environment
variable ``MFTYRE_SCHEDULER``, connects to a running scheduler instead (its workers on any machines); either way the
tasks go through one ``distributed.Client`` and the same code below. ``Runner(workers=0)`` runs the same tasks one
after the other in this process, without dask: the serial baseline of the benchmarks and of the identity tests.

Tasks. ``function`` is a function defined at the top level of a module the workers can import (it travels by name);
each task is ``function(**inputs)`` with ``inputs`` plain data (str, bytes, numbers, None, lists, tuples, dicts with
string keys, NumPy arrays, pandas DataFrames: a .tir file's text, a slice of measurements, seeds), checked before
anything is sent, so that no CasADi, ctypes or other live object leaves this process: a worker builds its models
from the text, and its compiled libraries come from the compile cache (:func:`mftyre.compiled.cached_library`: built
under a unique temporary name and renamed atomically, so the processes of one machine share one cache and build a
library once; a worker on another machine builds into its own ``$MFTYRE_CACHE``). A result must be JSON data (dicts,
lists, strings, numbers; floats are written with all their digits and read back bit for bit); it is sent back as
JSON text, so that a result read from the results folder equals a fresh one. A long array in a result goes as
:func:`pack` text (its float64 bytes in base64: exact, and 20x cheaper to write and read than a JSON list of
numbers), read back with :func:`unpack`.

Failures. A task that raises is reported (:class:`Failure`: its key, its inputs' summary and the traceback) and the
others go on; so is a worker that dies. Warnings a task gives are collected per task (``outcome.warnings``).

Results folder (``results=``). Each finished task is written as ``<key>.json`` (its inputs' SHA-256 and the
result) through :func:`mftyre.files.write_atomically`; with ``resume=True`` a task whose file is there with the same
inputs is not run again (a changed task is). Progress: one line on stderr, rewritten in place on a terminal
(``tasks done/total, failed, resumed``).
"""
from __future__ import annotations

import base64
import dataclasses
import hashlib
import json
import os
import re
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from .errors import MFTyreError
from .lazy import LazyModule

pd = LazyModule("pandas")  # imported when first used: the command line starts without it

__all__ = ["Runner", "Outcome", "Failure", "RunnerError", "add_runner_options", "runner_from_args", "default_workers",
           "SCHEDULER_VARIABLE", "pack", "unpack"]

#: The environment variable naming a scheduler's address (``tcp://host:8786``) when none is given.
SCHEDULER_VARIABLE = "MFTYRE_SCHEDULER"
#: dask settings of the local cluster: no sampling profiler (every 10 ms in each worker) nor GIL monitor (every
#: 1 ms), which serve the dashboard this runner does not start, and the event loops' watchdog tick every 500 ms
#: instead of 20 ms (it only times how long a loop was blocked, for a log line): together they cost CPU that a shared
#: machine's users feel (the tick alone: an idle 2-worker cluster took 6 % of a core in this process and 3 % in each
#: worker, half that at 500 ms). A cluster's own workers keep their configuration
#: (DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False, DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL=500ms set it).
QUIET = {"distributed.worker.profile.enabled": False, "distributed.admin.system-monitor.gil.enabled": False,
         "distributed.admin.tick.interval": "500ms"}
_KEY = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,119}")


class RunnerError(MFTyreError):
    """Tasks that cannot be sent (not plain data, a bad key, a function workers cannot import) or a scheduler that
    cannot be reached."""


@dataclasses.dataclass
class Failure:
    """A task that raised: its ``key``, its ``inputs`` (as given) and the ``error`` (the traceback's text)."""

    key: str
    inputs: dict
    error: str

    def summary(self) -> str:
        """One line: the key, the inputs (long values shortened) and the error's last line."""
        shown = ", ".join(f"{k}={_shown(v)}" for k, v in self.inputs.items())
        last = self.error.strip().splitlines()[-1] if self.error.strip() else "?"
        return f"task {self.key} ({shown}) failed: {last}"


@dataclasses.dataclass
class Outcome:
    """What :meth:`Runner.run` brings back: ``results`` (key -> result, in the order the tasks were given; failed
    tasks absent), ``failures`` (list of :class:`Failure`), ``resumed`` (keys read from the results folder),
    ``warnings`` (key -> the warning messages the task gave) and ``seconds``."""

    results: dict
    failures: list
    resumed: list
    warnings: dict
    seconds: float


def default_workers() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


class Runner:
    """Runs tasks on dask.distributed (see the module notes): ``workers`` processes of a LocalCluster (default
    :func:`default_workers`; 0: serially in this process, no dask), or the cluster of ``scheduler`` (an address;
    default ``$MFTYRE_SCHEDULER``). ``progress``: write the progress line on stderr. Use as a context manager (or
    call :meth:`close`): the cluster is started on the first :meth:`run` and stopped at the end."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None, *, progress: bool = False):
        self.scheduler = scheduler or os.environ.get(SCHEDULER_VARIABLE) or None
        if workers is not None and not (isinstance(workers, int) and workers >= 0):
            raise RunnerError(f"workers must be an integer >= 0, got {workers!r}")
        self.workers = default_workers() if workers is None else workers
        self.progress = progress
        self._client = self._cluster = None

    @property
    def serial(self) -> bool:
        return self.scheduler is None and self.workers == 0

    def describe(self) -> str:
        if self.scheduler:
            return f"the cluster of scheduler {self.scheduler}"
        return "this process (serial)" if self.serial else f"a local cluster of {self.workers} worker processes"

    def client(self):
        """The ``distributed.Client`` (started on first use), None when serial."""
        if self.serial or self._client is not None:
            return self._client
        import logging

        from distributed import Client, LocalCluster

        if self.scheduler:
            try:
                self._client = Client(self.scheduler, timeout="20s")
            except (OSError, TimeoutError) as exc:
                raise RunnerError(f"scheduler {self.scheduler}: cannot connect ({exc}); expected the address of a "
                                  "running dask scheduler, e.g. tcp://host:8786") from None
        else:  # processes with one thread each: the GIL and CasADi's lock are per process
            import dask

            with dask.config.set(QUIET):  # (the workers take the configuration in force when they start)
                self._cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1, processes=True,
                                             dashboard_address=None, silence_logs=logging.ERROR)
            self._client = Client(self._cluster)
        return self._client

    def slots(self) -> int:
        """How many tasks run at once: 1 when serial, else the worker threads of the cluster (starting it)."""
        if self.serial:
            return 1
        if self.scheduler is None:
            return self.workers
        workers = self.client().scheduler_info().get("workers", {})
        return max(1, sum(int(w.get("nthreads", 1)) for w in workers.values()))

    def close(self) -> None:
        for part in (self._client, self._cluster):
            if part is not None:
                part.close()
        self._client = self._cluster = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------------------------------ running
    def run(self, function: Callable, tasks: Mapping[str, dict], *, results=None, resume: bool = False) -> Outcome:
        """Run ``function(**inputs)`` for every ``key -> inputs`` of ``tasks``; see the module notes."""
        t0 = time.perf_counter()
        name = _function_name(function)
        tasks = dict(tasks)
        digests = {}
        for key, inputs in tasks.items():
            if not isinstance(key, str) or not _KEY.fullmatch(key):
                raise RunnerError(f"task key {key!r}: expected letters, digits, '.', '_' or '-' (a file name), "
                                  "at most 120 characters, starting with a letter or digit")
            if not isinstance(inputs, dict):
                raise RunnerError(f"task {key}: inputs must be a dict of keyword arguments, got {type(inputs).__name__}")
            _check_plain(inputs, f"task {key}")
            digests[key] = _digest([name, inputs])
        folder = Path(results) if results is not None else None
        done, resumed = {}, []
        if folder is not None:
            from .files import make_output_folder

            make_output_folder(folder, "results folder")
            if resume:
                for key in tasks:
                    found = _read_done(folder / f"{key}.json", digests[key])
                    if found is not None:
                        done[key] = found
                        resumed.append(key)
        todo = [k for k in tasks if k not in done]
        failures, notes = [], {}
        bar = _Progress(len(tasks), len(resumed), self.progress)

        def finish(key, answer):
            status, payload, caught = answer
            if caught:
                notes[key] = caught
            if status == "ok":
                done[key] = json.loads(payload)
                if folder is not None:
                    from .files import write_atomically

                    write_atomically(folder / f"{key}.json", json.dumps(
                        {"key": key, "inputs_sha256": digests[key], "result": done[key]}))
            else:
                failures.append(Failure(key, tasks[key], payload))
            bar.update(len(done) + len(failures), len(failures))

        client = self.client() if todo else None
        if client is None:
            for key in todo:
                finish(key, call_task(function, tasks[key]))
        else:
            from distributed import as_completed

            futures = {client.submit(call_task, function, tasks[key], key=f"mftyre-{key}-{digests[key][:16]}",
                                     pure=False): key for key in todo}
            for future in as_completed(futures):
                key = futures[future]
                try:
                    answer = future.result()
                except Exception as exc:  # the worker died (KilledWorker) or the task could not be sent
                    answer = ("error", f"{type(exc).__name__}: {exc}", [])
                finish(key, answer)
                future.release()
        bar.close()
        ordered = {k: done[k] for k in tasks if k in done}
        return Outcome(ordered, sorted(failures, key=lambda f: list(tasks).index(f.key)), resumed, notes,
                       time.perf_counter() - t0)


def pack(values) -> str:
    """An array of floats as text for a task's JSON result: its float64 bytes (little-endian) in base64."""
    return base64.b64encode(np.ascontiguousarray(values, dtype="<f8").tobytes()).decode("ascii")


def unpack(text: str) -> np.ndarray:
    """The 1-D float64 array :func:`pack` made ``text`` of (a new, writable array)."""
    return np.frombuffer(base64.b64decode(text, validate=True), dtype="<f8").astype(float)


def call_task(function, inputs: dict):
    """Run one task where it lands: ``("ok", result as JSON text, warnings)`` or ``("error", traceback,
    warnings)``; an exception never leaves (the other tasks go on)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = function(**inputs)
            answer = ("ok", json.dumps(result, allow_nan=True))
        except Exception:
            answer = ("error", traceback.format_exc())
    seen = list(dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught))
    return (*answer, seen)


def _function_name(function) -> str:
    module, qualname = getattr(function, "__module__", None), getattr(function, "__qualname__", "")
    if not module or "<" in qualname or module == "__main__":
        raise RunnerError(f"{function!r}: a task function must be defined at the top level of an importable module "
                          "(workers import it by name)")
    return f"{module}:{qualname}"


_PLAIN = (str, bytes, bool, int, float, type(None), np.floating, np.integer, np.bool_)


def _check_plain(value, where: str) -> None:
    """RunnerError unless ``value`` is plain data (see the module notes)."""
    if isinstance(value, _PLAIN):
        return
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "O":  # e.g. a DataFrame's text column: every item plain
            for item in value.ravel():
                if not isinstance(item, _PLAIN):
                    _check_plain(item, f"{where}, an item")
        elif value.dtype.kind not in "biufcUSM":
            raise RunnerError(f"{where}: an array of {value.dtype}: expected numbers or strings")
        return
    if isinstance(value, pd.DataFrame):
        for column in value.columns:
            _check_plain(np.asarray(value[column]), f"{where}, column {column!r}")
        return
    if isinstance(value, (list, tuple)):
        for i, item in enumerate(value):
            _check_plain(item, f"{where}[{i}]")
        return
    if isinstance(value, dict):
        for k, item in value.items():
            if not isinstance(k, str):
                raise RunnerError(f"{where}: key {k!r}: expected string keys")
            _check_plain(item, f"{where}[{k!r}]")
        return
    raise RunnerError(f"{where}: a {type(value).__module__}.{type(value).__name__}: tasks carry plain data (text, "
                      "numbers, lists, dicts, NumPy arrays, DataFrames), never live objects such as CasADi "
                      "functions or compiled libraries; pass the .tir text and let the worker build the model")


def _digest(value) -> str:
    """SHA-256 of plain data (types, shapes and bytes; dict order ignored)."""
    h = hashlib.sha256()

    def feed(v):
        if isinstance(v, pd.DataFrame):
            h.update(b"F")
            for c in v.columns:
                feed(str(c))
                feed(np.asarray(v[c]))
        elif isinstance(v, np.ndarray):
            h.update(f"A{v.dtype.str}{v.shape}".encode())
            h.update(np.ascontiguousarray(v).tobytes() if v.dtype.kind != "O" else repr(v.tolist()).encode())
        elif isinstance(v, dict):
            h.update(b"D")
            for k in sorted(v):
                feed(k)
                feed(v[k])
        elif isinstance(v, (list, tuple)):
            h.update(f"L{len(v)}".encode())
            for item in v:
                feed(item)
        else:
            h.update(f"{type(v).__name__}:{v!r};".encode())

    feed(value)
    return h.hexdigest()


def _read_done(path: Path, digest: str):
    """The result recorded in ``path`` when it was made from the same inputs, else None (run again)."""
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("inputs_sha256") != digest or "result" not in record:
        return None
    return record["result"]


def _shown(value, limit: int = 40) -> str:
    text = f"<{len(value)} rows>" if isinstance(value, pd.DataFrame) else repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


class _Progress:
    """``tasks done/total`` on stderr: rewritten in place on a terminal, else a line at every tenth."""

    def __init__(self, total: int, resumed: int, on: bool):
        self.total, self.resumed, self.on = total, resumed, on and total > 0
        self.terminal = sys.stderr.isatty()
        self.t0, self.shown = time.perf_counter(), -1
        self.update(resumed, 0)

    def update(self, done: int, failed: int) -> None:
        if not self.on:
            return
        tenth = done * 10 // max(self.total, 1)
        if not self.terminal and tenth == self.shown and done != self.total:
            return
        self.shown = tenth
        width = 30
        filled = width * done // max(self.total, 1)
        line = (f"  [{time.perf_counter() - self.t0:6.1f} s] |{'#' * filled}{'.' * (width - filled)}| {done}/"
                f"{self.total} tasks" + (f", {failed} failed" if failed else "")
                + (f", {self.resumed} resumed" if self.resumed else ""))
        print(("\r" if self.terminal else "") + line, end="" if self.terminal else "\n", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.on and self.terminal:
            print(file=sys.stderr)


# ------------------------------------------------------------------------------------------ command line
def add_runner_options(parser, *, resume: bool = True, what: str = "") -> None:
    """``--workers N``, ``--scheduler ADDRESS`` and (``resume``) ``--resume``, for the commands that run tasks;
    ``what``: what runs in parallel, said in the group's title."""
    from .arguments import number_type

    group = parser.add_argument_group("parallel work (dask.distributed)" + (f": {what}" if what else ""))
    group.add_argument("--workers", type=number_type(0, integer=True), default=None, metavar="N",
                       help=f"worker processes of a local cluster (default: the cores, {default_workers()}; 0: "
                            "serially in this process; ignored with a scheduler)")
    group.add_argument("--scheduler", metavar="ADDRESS", default=None,
                       help=f"use the running dask scheduler at ADDRESS (tcp://host:8786) and its workers instead "
                            f"(default: ${SCHEDULER_VARIABLE} when set)")
    if not resume:
        return
    group.add_argument("--resume", action="store_true",
                       help="keep the tasks already done (same inputs) in the tasks folder of the outputs, run the "
                            "rest and write the outputs again")


def runner_from_args(args) -> Runner:
    return Runner(workers=args.workers, scheduler=args.scheduler, progress=not getattr(args, "quiet", False))
