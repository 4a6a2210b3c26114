"""Compiled evaluation: a CasADi function of the Magic Formula generated as C, compiled with the system C
compiler and called through ctypes, cached on disk.

    from mftyre.compiled import compile_model
    tyre = compile_model(model, outputs=("fx", "fy", "mz"))         # first call compiles (seconds), later: cached
    fx, fy, mz = tyre(4000.0, 0.02, 0.05, 0.0, 0.0, 20.0, 2.2e5)     # one point, floats in -> floats out
    FX, FY, MZ = tyre.batch(fz_array, kappa_array, ...)              # arrays (broadcast) in -> arrays out

The cache key is a SHA-256 of everything that defines the function: the parameter values, the tyre side, the
options of :meth:`mftyre.MFModel.casadi_function`, and the versions of mftyre and CasADi. The cache folder is
``$MFTYRE_CACHE`` or ``~/.cache/mftyre``; a library is written to a temporary name and renamed, so concurrent
processes never load a half-written file. Compiler: ``$CC`` or ``cc``, with ``-O2 -fPIC -shared``.
"""
from __future__ import annotations

import ctypes
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from .errors import MFTyreError

__all__ = ["CompiledFunction", "compile_model", "compile_function", "compile_c", "cache_dir"]

_BATCH = 256  # points per call of the mapped (batch) function


def cache_dir() -> Path:
    return Path(os.environ.get("MFTYRE_CACHE", Path.home() / ".cache" / "mftyre"))


def compile_c(source: Path, library: Path) -> None:
    """Compile the C file ``source`` into the shared library ``library`` (written atomically)."""
    compiler = os.environ.get("CC", "cc")
    if shutil.which(compiler) is None:
        raise MFTyreError(f"no C compiler found ({compiler!r}); install gcc or set CC to compile CasADi functions")
    tmp = library.with_name(f".{library.name}.{os.getpid()}.tmp")
    cmd = [compiler, "-O2", "-fPIC", "-shared", str(source), "-o", str(tmp), "-lm"]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        raise MFTyreError(f"compiling {source} failed ({' '.join(cmd)}):\n{run.stderr[-2000:]}")
    os.replace(tmp, library)


def compile_function(function, key: str, directory: Path | None = None, output_names=None) -> Path:
    """Generate C for ``function`` and its ``_BATCH``-point map, compile, cache under ``key``; the library.
    ``output_names`` (default: the function's) are recorded as :attr:`CompiledFunction.outputs`."""
    import casadi as ca

    directory = Path(directory or cache_dir())
    directory.mkdir(parents=True, exist_ok=True)
    library = directory / f"mftyre_{key[:24]}.so"
    meta = library.with_suffix(".json")
    if library.exists() and meta.exists():
        return library
    sx = function.sx_in()
    point = ca.Function("point", sx, function.call(sx), function.name_in(), function.name_out())
    batch = point.map("batch", "serial", _BATCH, [], [])
    with tempfile.TemporaryDirectory(dir=directory) as tmp:
        gen = ca.CodeGenerator(f"mftyre_{key[:24]}.c", {"with_header": False})
        gen.add(point)
        gen.add(batch)
        source = Path(gen.generate(str(Path(tmp)) + os.sep))
        compile_c(source, library)
    meta.write_text(json.dumps({"inputs": function.name_in(), "outputs": list(output_names or function.name_out()),
                                "batch": _BATCH}))
    return library


class CompiledFunction:
    """A compiled point function and its batch map, called through ctypes without CasADi at run time."""

    def __init__(self, library: Path):
        library = Path(library)
        meta = json.loads(library.with_suffix(".json").read_text())
        self.inputs, self.outputs, self.batch_size = tuple(meta["inputs"]), tuple(meta["outputs"]), meta["batch"]
        self.library = library
        self._lib = ctypes.CDLL(str(library))
        self._point = self._bind("point", 1)
        self._batch = self._bind("batch", self.batch_size)

    def _bind(self, name, n):
        lib = self._lib
        fn = getattr(lib, name)
        work = getattr(lib, f"{name}_work")
        ll = ctypes.c_longlong
        sz = [ll() for _ in range(4)]
        work.argtypes = [ctypes.POINTER(ll)] * 4
        work(*(ctypes.byref(x) for x in sz))
        sz_arg, sz_res, sz_iw, sz_w = (x.value for x in sz)
        n_in, n_out = len(self.inputs), len(self.outputs)
        inbuf = np.zeros((n_in, n), dtype=np.float64)
        outbuf = np.zeros((n_out, n), dtype=np.float64)
        arg = (ctypes.c_void_p * max(sz_arg, n_in))(*[inbuf[i].ctypes.data for i in range(n_in)])
        res = (ctypes.c_void_p * max(sz_res, n_out))(*[outbuf[i].ctypes.data for i in range(n_out)])
        iw = (ll * max(sz_iw, 1))()
        w = (ctypes.c_double * max(sz_w, 1))()
        fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int]
        fn.restype = ctypes.c_int
        args = (ctypes.addressof(arg), ctypes.addressof(res), ctypes.addressof(iw), ctypes.addressof(w), 0)
        return fn, args, inbuf, outbuf, (arg, res, iw, w)

    def __call__(self, *values):
        """One point: the inputs as floats, in the order of :attr:`inputs`; returns a tuple of floats."""
        fn, args, inbuf, outbuf, _ = self._point
        if len(values) != len(self.inputs):
            raise MFTyreError(f"expected {len(self.inputs)} inputs {self.inputs}, got {len(values)}")
        inbuf[:, 0] = values
        if fn(*args):
            raise MFTyreError("compiled function reported an evaluation error")
        return tuple(outbuf[:, 0].tolist())

    def batch(self, *arrays):
        """Many points: arrays (broadcast together); returns one array per output."""
        fn, args, inbuf, outbuf, _ = self._batch
        flat = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in arrays))
        shape = flat[0].shape
        flat = [f.ravel() for f in flat]
        n = flat[0].size
        result = np.empty((len(self.outputs), n))
        b = self.batch_size
        for start in range(0, n, b):
            m = min(b, n - start)
            for i, a in enumerate(flat):
                inbuf[i, :m] = a[start:start + m]
            if m < b:
                inbuf[:, m:] = inbuf[:, :1]
            if fn(*args):
                raise MFTyreError("compiled function reported an evaluation error")
            result[:, start:start + m] = outbuf[:, :m]
        return tuple(r.reshape(shape) for r in result)


def _key(model, options: dict) -> str:
    import casadi as ca

    from . import __version__

    prm = model.params
    payload = {"parameters": {k: repr(prm[k]) for k in prm}, "side": model.side, "options": options,
               "mftyre": __version__, "casadi": ca.__version__}
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=repr).encode()).hexdigest()


def compile_model(model, inputs=("fz", "kappa", "alpha", "gamma", "phit", "vx", "p"), outputs=None,
                  directory: Path | None = None, **options) -> CompiledFunction:
    """Compile ``model.casadi_function(inputs, outputs, **options)`` (cached) and load it."""
    from .formula import OUTPUT_NAMES

    outputs = tuple(outputs or OUTPUT_NAMES)
    key = _key(model, {"inputs": list(inputs), "outputs": list(outputs), **options})
    library = Path(directory or cache_dir()) / f"mftyre_{key[:24]}.so"
    if not (library.exists() and library.with_suffix(".json").exists()):
        compile_function(model.casadi_function(inputs, outputs, **options), key, directory, outputs)
    return CompiledFunction(library)
