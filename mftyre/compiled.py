"""Compiled evaluation: the Magic Formula as C, compiled with the system C compiler, called through ctypes,
cached on disk; and compiled CasADi functions with their derivatives for optimal control.

    from mftyre.compiled import compile_model, compile_external
    tyre = compile_model(model, outputs=("fx", "fy", "mz"))         # first call compiles (seconds), later: cached
    fx, fy, mz = tyre(4000.0, 0.02, 0.05, 0.0, 0.0, 20.0, 2.2e5)     # one point, floats in -> floats out
    FX, FY, MZ = tyre.batch(fz_array, kappa_array, ...)              # arrays (broadcast) in -> arrays out
    FX, FY, MZ = tyre.batch(..., threads=0)                          # the same on every core
    f = compile_external(model, ("fz", "kappa", "alpha"), ("fx", "fy"), hessian=True)   # casadi.Function

Evaluation (:func:`compile_model`, :class:`CompiledFunction`). The C is written here from the CasADi SX graph of
:meth:`mftyre.MFModel.casadi_function` (after common-subexpression elimination): one straight-line kernel over a
block of points, vectorised by the compiler (``#pragma omp simd``; on x86-64 Linux with glibc's vector maths
library libmvec, one clone per instruction set, chosen at load time), plus a batch loop in C over all points and a
single-point entry: scalar, it skips the branches of if_else not taken (e.g. the MF 6.2 loaded-radius Newton steps
once converged, ``early_stop``), and where CPython's headers are found it is called through a small CPython entry
compiled into the same library (floats in, a tuple out: ~0.1 us of overhead where ctypes takes ~0.6; without the
headers, ctypes). Every call works on its own arrays (the caller's inputs, fresh outputs, stack buffers in C): a
compiled object may be called from any number of threads at once, and ``batch`` releases the GIL while the C runs.
Inputs are checked in C like :meth:`mftyre.MFModel.evaluate` (:mod:`mftyre.inputs`): NaN or +-inf and p <= 0 raise
:class:`ModelInputError`; values outside the .tir ranges give one :class:`~mftyre.errors.InputClippedWarning` per
call (``limits=True``). Compiler flags: ``-O1 -ftree-loop-vectorize -fno-math-errno -fno-trapping-math
-freciprocal-math -ffp-contract=off``: of the fast-math family only multiplication by a reciprocal instead of
division (at most 1 ulp per division, 15 % faster for MF 6.2); no reassociation, no finite-math assumptions, no
flush-to-zero. The vector maths functions are within a few ulp: the C agrees with NumPy to about 3e-11 relative and
reproduces the MFeval tables at the tolerances of the NumPy path (tests/test_compiled.py).

Derivatives (:func:`compile_external`): CasADi's own C for the function, its Jacobian (``jac_<name>``) and on
request the Jacobian of that (``jac_jac_<name>``, second derivatives), compiled once and loaded with
``casadi.external``: an NLP (IPOPT) calls the compiled tyre and its derivatives while the rest of the problem stays
a small graph, instead of generating C for the whole problem. :func:`compile_tyre_kernels`: the fused kernels
(value; value and Jacobian; value, Jacobian and Hessian of mu^T y) from which :func:`mftyre.ocp.assembled_nlp`
assembles an NLP's exact derivatives (the lane change's fastest route).

Cache. The key is a SHA-256 of everything that defines the function (parameter values, side, options, input and
output names, the versions of mftyre and CasADi, the source of this module, the backend and the equations, the
compiler and platform, and the Python ABI where the library has the CPython entry). The folder is ``$MFTYRE_CACHE``
or ``~/.cache/mftyre``; it must belong to the current user (or root) and be writable by no one else, as must every
library loaded, else :class:`CacheSecurityError`. A library is compiled under a unique temporary name in that folder
and renamed atomically to ``<stem>_<sha-256 of the library>.so``, then its description ``<stem>_<sha>.json``
(inputs, outputs, checks, size and SHA-256 of the library) is written the same way, so concurrent threads and
processes never see half a pair. Before a library is loaded its size and SHA-256 are checked against the
description: a truncated or altered file is rebuilt (from the cache) or refused. Compiler: ``$CC`` or ``cc``.
:func:`cached_library` is this cache for every compiled library of the project (the SWIFT stepper of
:mod:`swift.simulate` too).
"""
from __future__ import annotations

import ctypes
import functools
import hashlib
import json
import math
import numbers
import operator
import os
import platform
import shutil
import stat
import struct
import subprocess
import sysconfig
import tempfile
import threading
from pathlib import Path

import numpy as np

from .errors import MFTyreError, ModelInputError
from .inputs import check_finite, check_finite_outputs, check_pressure, hard_limits, input_ranges, warn_outside

__all__ = ["CompiledFunction", "BatchOutputs", "CacheSecurityError", "CompileError", "compile_model", "compile_function",
           "compile_external", "tyre_kernels", "compile_tyre_kernels", "cached_library", "compile_c", "cache_dir",
           "install_libraries", "platform_tag", "generate_c", "CASADI_LOCK", "BLOCK_POINTS"]

_BLOCK = 256  # points per call of the vectorised kernel (inputs broadcast into stack buffers of this length)
#: The kernel's block of points: a batch's result at a point may differ in the last ulp with the point's place in
#: its block (the vector maths' remainder), so batches split at multiples of this give the same bits as one batch.
BLOCK_POINTS = _BLOCK
# -O1 with loop vectorisation runs the straight-line kernel as fast as -O3 and compiles in half the time.
# -fno-tree-dominator-opts: gcc 12's dominator pass folded the 0/1 masks of the unrolled MF 6.2 loaded-radius
# solver (Dekker's method, before the Newton solver) into boolean chains of mixed precision that its vectoriser
# rejects ("relevant stmt not supported: patt = patt ? _ : 0"), leaving the whole kernel scalar (MF 6.2 batch
# 920 -> 270 ns/point with the flag). The Newton solver vectorises either way at the same speed; the flag stays
# as a guard for other masks (tests/test_compiled.py checks the loop is vectorised)
_FLAGS = ("-O1", "-ftree-loop-vectorize", "-fno-tree-dominator-opts", "-fPIC", "-shared", "-fno-math-errno", "-fno-trapping-math",
          "-freciprocal-math", "-ffp-contract=off", "-fopenmp-simd")
_PACKED = 4096  # batches of at most this many points are passed as one packed copy of the inputs
_FLAG_BITS = 16  # flags of the single-point entry: bit k non-finite input k, 16+k non-positive, 32+k outside
_INPUT_FLAGS = (1 << (3 * _FLAG_BITS)) - 1  # (and bit 48: an output not finite)
_OUTPUT_FLAG = 1 << (3 * _FLAG_BITS)
#: the ABI of this interpreter (its extension modules' suffix): a library's one-point CPython entry is used only
#: by the interpreter it was built for
_PYTHON_ABI = sysconfig.get_config_var("EXT_SUFFIX") if platform.python_implementation() == "CPython" else None


#: the hash of this module, the backend, the graph's builder (model.py: casadi_function, the run-time parameters) and
#: the equations: part of every cache key, so that a changed generator or equation (e.g. fewer unrolled solver
#: steps) never meets an old library
_GENERATOR = hashlib.sha256(b"".join(path.read_bytes() for path in (
    Path(__file__), *(Path(__file__).with_name(n) for n in ("backend.py", "model.py")),
    *sorted(Path(__file__).with_name("formula").glob("*.py"))
))).hexdigest()


#: CasADi's expressions and sparsity patterns are shared, reference-counted and cached without atomic counts or
#: locks, and its Python calls release the GIL: two threads building graphs, generating C or creating CasADi
#: matrices at once can corrupt them (seen as crashes when two SWIFT tyres were built at once). Every CasADi call
#: of the compile cache and of :mod:`swift.simulate` holds this lock (the compiled C never needs it).
CASADI_LOCK = threading.RLock()


class CompileError(MFTyreError):
    """The C compiler refused a generated source (its message and the command are in the text)."""


class CacheSecurityError(MFTyreError):
    """A cache folder or library could be changed by another user: it is not used."""


# ------------------------------------------------------------------------------------------------ files
def _check_private(path: Path, what: str) -> None:
    """Refuse ``path`` unless it belongs to the current user (or root) and no one else may write to it."""
    info = path.stat()
    owners = (os.geteuid(), 0)
    problem = None
    if info.st_uid not in owners:
        problem = f"it belongs to user id {info.st_uid}, not to you ({os.geteuid()})"
    elif info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        problem = f"it is writable by group or others (mode {stat.filemode(info.st_mode)})"
    if problem:
        raise CacheSecurityError(f"refusing to load compiled code from {what} {path}: {problem}. Use a private "
                                 f"folder (chmod go-w, or set MFTYRE_CACHE to a folder only you can write).")


def cache_dir() -> Path:
    """The compile cache: ``$MFTYRE_CACHE`` or ``~/.cache/mftyre``, created private (0700) and checked."""
    path = Path(os.environ.get("MFTYRE_CACHE") or Path.home() / ".cache" / "mftyre")
    return _private_dir(path)


def _private_dir(path) -> Path:
    path = Path(path)
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
    except (OSError, ValueError) as exc:  # a file in the way (MFTYRE_CACHE naming a file), no permission
        raise CacheSecurityError(f"cannot use {path} as the compile cache: {getattr(exc, 'strerror', None) or exc}; "
                                 "set MFTYRE_CACHE to a folder (new, or one only you can write)") from None
    _check_private(path, "the folder")
    return path


def _atomic_write(directory: Path, name: str, data: bytes) -> None:
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, directory / name)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def compile_c(source: Path, library: Path, flags=("-O2", "-fPIC", "-shared"), libraries=("-lm",)) -> None:
    """Compile the C file ``source`` into the shared library ``library``: written under a unique temporary
    name in the same folder and renamed (atomic; concurrent compilations of one library do not collide)."""
    compiler = os.environ.get("CC", "cc")
    if shutil.which(compiler) is None:
        raise MFTyreError(f"no C compiler found ({compiler!r}); install gcc or set CC to compile CasADi functions")
    library = Path(library)
    fd, tmp = tempfile.mkstemp(dir=library.parent, prefix=f".{library.name}.", suffix=".tmp")
    os.close(fd)
    try:
        cmd = [compiler, *flags, str(source), "-o", tmp, *libraries]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            raise CompileError(f"compiling {source} failed ({' '.join(cmd)}):\n{run.stderr[-2000:]}")
        os.chmod(tmp, 0o644)
        os.replace(tmp, library)
    finally:
        Path(tmp).unlink(missing_ok=True)


# ------------------------------------------------------------------------------------------ generator
def _c_number(value: float) -> str:
    if math.isnan(value):
        return "NAN"
    if math.isinf(value):
        return "INFINITY" if value > 0 else "(-INFINITY)"
    return f"({value!r})" if value < 0 else repr(value)


def _operations():
    """CasADi operation code -> C expression with ``{0}``, ``{1}`` for the operands (CasADi's semantics)."""
    import casadi as ca

    table = {
        "ASSIGN": "{0}", "NEG": "(-{0})", "ADD": "{0}+{1}", "SUB": "{0}-{1}", "MUL": "{0}*{1}", "DIV": "{0}/{1}",
        "SQ": "{0}*{0}", "TWICE": "2.0*{0}", "INV": "1.0/{0}", "FABS": "fabs({0})", "SQRT": "sqrt({0})",
        "EXP": "exp({0})", "LOG": "log({0})", "POW": "pow({0},{1})", "CONSTPOW": "pow({0},{1})",
        "SIN": "sin({0})", "COS": "cos({0})", "TAN": "tan({0})", "ASIN": "asin({0})", "ACOS": "acos({0})",
        "ATAN": "atan({0})", "ATAN2": "atan2({0},{1})", "SINH": "sinh({0})", "COSH": "cosh({0})",
        "TANH": "tanh({0})", "ASINH": "asinh({0})", "ACOSH": "acosh({0})", "ATANH": "atanh({0})",
        "ERF": "erf({0})", "LOG1P": "log1p({0})", "EXPM1": "expm1({0})", "HYPOT": "hypot({0},{1})",
        "FLOOR": "floor({0})", "CEIL": "ceil({0})", "FMOD": "fmod({0},{1})", "COPYSIGN": "copysign({0},{1})",
        # comparisons and logic give 0.0 / 1.0 (no short-circuit: no branches in the kernel);
        # if_else_zero(c, x) = c ? x : 0 (x may be NaN or inf: dropped)
        "LT": "({0}<{1}?1.0:0.0)", "LE": "({0}<={1}?1.0:0.0)", "EQ": "({0}=={1}?1.0:0.0)",
        "NE": "({0}!={1}?1.0:0.0)", "NOT": "({0}==0?1.0:0.0)", "AND": "(({0}!=0)&({1}!=0)?1.0:0.0)",
        "OR": "(({0}!=0)|({1}!=0)?1.0:0.0)", "IF_ELSE_ZERO": "({0}!=0?{1}:0.0)",
        # C99 fmin/fmax (a NaN operand yields the other) and CasADi's sign (sign(0) = 0), in vectorisable form
        "FMIN": "((({0}<{1})|({1}!={1}))?{0}:{1})", "FMAX": "((({0}>{1})|({1}!={1}))?{0}:{1})",
        "SIGN": "({0}<0?-1.0:({0}>0?1.0:{0}))",
    }
    return {getattr(ca, f"OP_{name}"): expr for name, expr in table.items() if hasattr(ca, f"OP_{name}")}


# functions of glibc's vector maths library (2.35+), declared with their SIMD variants when it is present
_LIBMVEC = ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "asinh", "acosh",
            "atanh", "exp", "log", "pow", "erf", "log1p", "expm1", "hypot")


_GATED_MIN = 16  # instructions: smaller branches of an if_else are computed whatever the condition


def _point_body(f, ops) -> list:
    """C lines of the one-point kernel of the SX function ``f`` (after CSE): one variable per instruction, and
    where an instruction's value is read only by ``if_else_zero(c, .)`` (CasADi's if_else is a sum of two), and so
    on up its arguments, those instructions (at least :data:`_GATED_MIN`) run inside ``if (c != 0)``, moved after
    ``c`` where needed: the branch of an if_else not taken is skipped, e.g. the MF 6.2 loaded-radius Newton steps
    after convergence (``early_stop``). Skipped values are never read (``c ? v : 0`` reads v only if c): the
    operations that decide the results are those of the straight-line code."""
    import casadi as ca

    n = f.n_instructions()
    kinds, operands, text, writer = [], [], [], {}
    for k in range(n):
        op, o, i = f.instruction_id(k), f.instruction_output(k), f.instruction_input(k)
        kinds.append(op)
        if op == ca.OP_INPUT:
            operands.append(())
            text.append(f"v{k} = x{i[0]}[i];")
        elif op == ca.OP_OUTPUT:
            operands.append((writer[i[0]],))
            text.append(f"y{o[0]}[i] = v{writer[i[0]]};")
        elif op == ca.OP_CONST:
            operands.append(())
            text.append(f"v{k} = {_c_number(f.instruction_constant(k))};")
        elif op in ops:
            operands.append(tuple(writer[j] for j in i))  # the instructions that wrote the work variables read
            text.append(f"v{k} = {ops[op].format(*(f'v{j}' for j in operands[k]))};")
        else:
            raise MFTyreError(f"CasADi operation {op} is not supported by mftyre's C generator")
        if op != ca.OP_OUTPUT:
            writer[o[0]] = k
    readers = [[] for _ in range(n)]
    for k, args in enumerate(operands):
        for position, j in enumerate(args):
            readers[j].append((k, position))
    gate = ca.OP_IF_ELSE_ZERO
    cones = {}  # condition -> the instructions needed only where it is not zero
    for c in sorted({operands[k][0] for k in range(n) if kinds[k] == gate}):
        cone = set()
        for i in range(n - 1, -1, -1):  # readers come after what they read
            if i != c and kinds[i] not in (ca.OP_INPUT, ca.OP_OUTPUT) and readers[i] and all(
                    j in cone or (kinds[j] == gate and position == 1 and operands[j][0] == c)
                    for j, position in readers[i]):
                cone.add(i)
        if len(cone) >= _GATED_MIN:
            cones[c] = cone
    conditions = [[] for _ in range(n)]  # of each instruction, outer (larger) cones first
    for c in sorted(cones, key=lambda c: (-len(cones[c]), c)):
        for i in cones[c]:
            conditions[i].append(c)
    place = {}

    def place_of(i):  # after every condition it runs under
        if i not in place:
            place[i] = max([float(i)] + [place_of(c) + 0.5 for c in conditions[i]])
        return place[i]

    order = sorted(range(n), key=lambda i: (place_of(i), i))
    rank = {i: r for r, i in enumerate(order)}
    if any(rank[j] >= rank[k] for k in range(n) for j in operands[k]):  # (cannot happen: then no branches)
        order, conditions, cones = list(range(n)), [[] for _ in range(n)], {}
    gated = set().union(*cones.values())
    plain = [k for k in range(n) if kinds[k] != ca.OP_OUTPUT and k not in gated]
    lines = [f"double {', '.join(f'v{k}' for k in plain)};"] if plain else []
    if gated:  # (initialised: a skipped value is never read, but no variable is read uninitialised either)
        lines.append(f"double {', '.join(f'v{k} = 0.0' for k in sorted(gated))};")
    stack = []
    for i in order:
        want = conditions[i]
        common = 0
        while common < min(len(stack), len(want)) and stack[common] == want[common]:
            common += 1
        while len(stack) > common:
            stack.pop()
            lines.append("  " * len(stack) + "}")
        for c in want[common:]:
            lines.append("  " * len(stack) + f"if (v{c} != 0) {{")
            stack.append(c)
        lines.append("  " * len(stack) + text[i])
    while stack:
        stack.pop()
        lines.append("  " * len(stack) + "}")
    return lines


def generate_c(function, checks=None, point_function=None) -> str:
    """C source of the scalar-in, scalar-out SX ``function``: ``mft_point`` (one point) and ``mft_batch``
    (n points, inputs with stride 0 or 1 or any, outputs contiguous), both checking the inputs first.

    ``checks``: per input ``{"positive": bool, "range": [lo, hi]}`` (both optional); default: finite only.
    ``point_function``: the same function, for ``mft_point``, written for one point (e.g. with ``early_stop``:
    branches the one-point C skips); default ``function``.
    """
    import casadi as ca

    n_in, n_out = function.n_in(), function.n_out()
    for kind, n, size in (("input", n_in, function.size_in), ("output", n_out, function.size_out)):
        bad = [function.name_in(k) if kind == "input" else function.name_out(k) for k in range(n) if size(k) != (1, 1)]
        if bad:
            raise MFTyreError(f"compiled functions take and return scalars; {kind}(s) {bad} are not 1x1")
    if n_in > _FLAG_BITS:
        raise MFTyreError(f"compiled functions take at most {_FLAG_BITS} inputs, got {n_in}")
    point_function = function if point_function is None else point_function
    if (point_function.name_in(), point_function.name_out()) != (function.name_in(), function.name_out()):
        raise MFTyreError(f"the one-point function takes {point_function.name_in()} and returns "
                          f"{point_function.name_out()}; the function {function.name_in()}, {function.name_out()}")

    def kernel(function):  # CSE'd SX
        function = function if function.is_a("SXFunction") else function.expand()
        sx = function.sx_in()
        return ca.Function("kernel", sx, function.call(sx), {"cse": True})

    f = kernel(function)
    f_point = f if point_function is function else kernel(point_function)
    ops = _operations()
    body, used = [], set()
    for k in range(f.n_instructions()):
        op, o, i = f.instruction_id(k), f.instruction_output(k), f.instruction_input(k)
        if op == ca.OP_INPUT:
            body.append(f"w{o[0]} = x{i[0]}[i];")
        elif op == ca.OP_OUTPUT:
            body.append(f"y{o[0]}[i] = w{i[0]};")
        elif op == ca.OP_CONST:
            body.append(f"w{o[0]} = {_c_number(f.instruction_constant(k))};")
        elif op in ops:
            expr = ops[op].format(*(f"w{j}" for j in i))
            call = ops[op].split("(")[0]
            if call in _LIBMVEC:
                used.add(call)
            body.append(f"w{o[0]} = {expr};")
        else:
            raise MFTyreError(f"CasADi operation {op} is not supported by mftyre's C generator")
    zero = [f"y{j}[i] = 0.0;" for j in range(n_out) if f.nnz_out(j) == 0]
    checks = checks or [{} for _ in range(n_in)]
    lo, hi = zip(*(c.get("range") or (-math.inf, math.inf) for c in checks))
    pos = [int(bool(c.get("positive"))) for c in checks]
    # the rim speed |(1 + kappa) vx| of an estimated spin: flagged as input kappa outside (``"rim"`` with ``"vx"``)
    rim_k = next((k for k, c in enumerate(checks) if "rim" in c and "rim_vx" in c), -1)
    rim_vx, rim = (checks[rim_k]["rim_vx"], checks[rim_k]["rim"]) if rim_k >= 0 else (0, math.inf)
    n_w = f.sz_w()
    decl = "\n".join(f"extern double {name}({', '.join(['double'] * (2 if name in ('atan2', 'pow', 'hypot') else 1))})"
                     f" __attribute__((__simd__(\"notinbranch\")));" for name in sorted(used))
    clones = '__attribute__((target_clones("default", "avx2", "arch=x86-64-v4")))'
    pointers = "\n".join([f"  const double *restrict x{k} = in[{k}];" for k in range(n_in)]
                         + [f"  double *restrict y{j} = out[{j}];" for j in range(n_out)])
    loop_body = (f"    double {', '.join(f'w{j}' for j in range(max(n_w, 1)))};\n    "
                 + "\n    ".join(body + zero))
    point_body = "    " + "\n    ".join(_point_body(f_point, ops)
                                          + [f"y{j}[i] = 0.0;" for j in range(n_out) if f_point.nnz_out(j) == 0])
    return f"""/* {function.name()}: {n_in} inputs, {n_out} outputs; generated by mftyre.compiled */
#ifdef MFT_PYTHON
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#endif
#include <math.h>
#include <stdint.h>

#ifdef MFT_LIBMVEC
{decl}
#define MFT_CLONES {clones}
#else
#define MFT_CLONES
#endif

#define N_IN {n_in}
#define N_OUT {n_out}
#define BLOCK {_BLOCK}

static const double LO[N_IN] = {{{', '.join(map(_c_number, lo))}}};
static const double HI[N_IN] = {{{', '.join(map(_c_number, hi))}}};
static const int POSITIVE[N_IN] = {{{', '.join(map(str, pos))}}};
#define RIM_KAPPA {rim_k}
#define RIM_VX {rim_vx}
static const double RIM_LIMIT = {_c_number(rim)};

MFT_CLONES
static void kernel(int64_t m, const double *const *in, double *const *out)
{{
{pointers}
  int64_t i;
#pragma omp simd
  for (i = 0; i < m; ++i) {{
{loop_body}
  }}
}}

/* the same for one point, scalar, skipping the branches of if_else not taken (see _point_body): with the
   dominator optimisations that the vectorised loop must do without */
__attribute__((optimize("tree-dominator-opts")))
static void kernel_point(const double *const *in, double *const *out)
{{
{pointers}
  const int64_t i = 0;
  {{
{point_body}
  }}
}}

/* one point, inputs then outputs in xy: returns flags (bit k: input k not finite; 16+k: not positive;
   32+k: outside its range; 48: an output not finite); evaluates unless an input is not finite or not positive */
int64_t mft_point(double *xy)
{{
  const double *x = xy;
  double *y = xy + N_IN;
  int64_t flags = 0;
  const double *in[N_IN];
  double *out[N_OUT];
  int k;
  for (k = 0; k < N_IN; ++k) {{
    double v = x[k];
    if (!(v - v == 0.0)) flags |= (int64_t)1 << k;
    else if (POSITIVE[k] && !(v > 0.0)) flags |= (int64_t)1 << ({_FLAG_BITS} + k);
    if (v < LO[k] || v > HI[k]) flags |= (int64_t)1 << ({2 * _FLAG_BITS} + k);
    in[k] = x + k;
  }}
  if (flags & (((int64_t)1 << {2 * _FLAG_BITS}) - 1)) return flags;
  if (RIM_KAPPA >= 0 && fabs((1.0 + x[RIM_KAPPA]) * x[RIM_VX]) > RIM_LIMIT)
    flags |= (int64_t)1 << ({2 * _FLAG_BITS} + RIM_KAPPA);
  for (k = 0; k < N_OUT; ++k) out[k] = y + k;
  kernel_point(in, out);
  for (k = 0; k < N_OUT; ++k)
    if (!(y[k] - y[k] == 0.0)) return flags | ((int64_t)1 << {3 * _FLAG_BITS});
  return flags;
}}

#ifdef MFT_PYTHON
/* mft_point for CPython (built where Python.h is found): floats or ints in, a tuple of floats out, the GIL held
   (no shared state: thread-safe). context = (fallback, flagged): nonzero flags go to flagged(flags, inputs,
   outputs), which raises or warns and returns the outputs; any other call (arity, keywords, other types) to
   fallback(*args), the ctypes route, so that every error is raised by the same Python code. */
static PyObject *mft_python_point(PyObject *context, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames)
{{
  double xy[N_IN + N_OUT];
  PyObject *inputs, *outputs, *flagged, *call[3];
  int64_t flags;
  Py_ssize_t k;
  if (nargs != N_IN || kwnames) goto fallback;
  for (k = 0; k < N_IN; ++k) {{
    PyObject *v = args[k];
    if (PyFloat_Check(v)) xy[k] = PyFloat_AS_DOUBLE(v);
    else if (PyLong_CheckExact(v)) {{  /* (subclasses may define __float__: the fallback converts them) */
      xy[k] = PyLong_AsDouble(v);
      if (xy[k] == -1.0 && PyErr_Occurred()) {{ PyErr_Clear(); goto fallback; }}
    }} else goto fallback;
  }}
  flags = mft_point(xy);
  if (!(outputs = PyTuple_New(N_OUT))) return NULL;
  for (k = 0; k < N_OUT; ++k) {{
    PyObject *y = PyFloat_FromDouble(xy[N_IN + k]);
    if (!y) {{ Py_DECREF(outputs); return NULL; }}
    PyTuple_SET_ITEM(outputs, k, y);
  }}
  if (!flags) return outputs;
  if (!(inputs = PyTuple_New(N_IN))) {{ Py_DECREF(outputs); return NULL; }}
  for (k = 0; k < N_IN; ++k) {{
    PyObject *x = PyFloat_FromDouble(xy[k]);
    if (!x) {{ Py_DECREF(inputs); Py_DECREF(outputs); return NULL; }}
    PyTuple_SET_ITEM(inputs, k, x);
  }}
  call[0] = PyLong_FromLongLong(flags); call[1] = inputs; call[2] = outputs;
  flagged = call[0] ? PyObject_Vectorcall(PyTuple_GET_ITEM(context, 1), call, 3, NULL) : NULL;
  Py_XDECREF(call[0]); Py_DECREF(inputs); Py_DECREF(outputs);
  return flagged;
fallback:
  return PyObject_Vectorcall(PyTuple_GET_ITEM(context, 0), args, nargs, kwnames);
}}

static PyMethodDef MFT_PYTHON_POINT = {{"point", (PyCFunction)(void (*)(void))mft_python_point,
                                        METH_FASTCALL | METH_KEYWORDS, "one point: floats in, a tuple of floats out"}};

/* the one-point function bound to context (a tuple (fallback, flagged)): a new reference */
PyObject *mft_python_function(PyObject *context)
{{
  if (!PyTuple_Check(context) || PyTuple_GET_SIZE(context) != 2) {{
    PyErr_SetString(PyExc_TypeError, "mft_python_function: context must be a tuple (fallback, flagged)");
    return NULL;
  }}
  return PyCFunction_NewEx(&MFT_PYTHON_POINT, context, NULL);
}}
#endif

/* n points: input k at in[k][i * stride[k]]; output j at out[j][i]. counts[3k..3k+2]: points where input k is
   not finite, not positive, outside its range. Returns 1 (nothing evaluated) if any is not finite or not
   positive, else 0. */
int mft_batch(int64_t n, const double *const *in, const int64_t *stride, double *const *out, int64_t *counts)
{{
  int64_t start, i;
  int k, fatal = 0;
  for (k = 0; k < N_IN; ++k) {{
    const double *x = in[k];
    const int64_t s = stride[k];
    const int64_t m = s ? n : (n > 0);
    int64_t nonfinite = 0, nonpositive = 0, outside = 0;
    for (i = 0; i < m; ++i) {{
      double v = x[i * s];
      nonfinite += !(v - v == 0.0);
      nonpositive += POSITIVE[k] && !(v > 0.0);
      outside += (v < LO[k]) | (v > HI[k]);
    }}
    if (!s) {{ nonfinite *= n; nonpositive *= n; outside *= n; }}
    counts[3 * k] = nonfinite; counts[3 * k + 1] = nonpositive; counts[3 * k + 2] = outside;
    fatal |= nonfinite || nonpositive;
  }}
  if (fatal) return 1;
  if (RIM_KAPPA >= 0) {{ /* with the points outside kappa's range, those beyond the rim-speed limit */
    const double *kap = in[RIM_KAPPA], *vx = in[RIM_VX];
    const int64_t sk = stride[RIM_KAPPA], sv = stride[RIM_VX];
    int64_t rim = 0;
    for (i = 0; i < n; ++i) rim += fabs((1.0 + kap[i * sk]) * vx[i * sv]) > RIM_LIMIT;
    counts[3 * RIM_KAPPA + 2] += rim;
  }}
  for (start = 0; start < n; start += BLOCK) {{
    const int64_t m = n - start < BLOCK ? n - start : BLOCK;
    double buffer[N_IN][BLOCK];
    const double *block_in[N_IN];
    double *block_out[N_OUT];
    for (k = 0; k < N_IN; ++k) {{
      if (stride[k] == 1) {{
        block_in[k] = in[k] + start;
      }} else {{
        for (i = 0; i < m; ++i) buffer[k][i] = in[k][(start + i) * stride[k]];
        block_in[k] = buffer[k];
      }}
    }}
    for (k = 0; k < N_OUT; ++k) block_out[k] = out[k] + start;
    kernel(m, block_in, block_out);
  }}
  return 0;
}}

/* n points packed: input k at X[k * n + i], output j at Y[j * n + i]; as mft_batch */
int mft_packed(int64_t n, const double *X, double *Y, int64_t *counts)
{{
  const double *in[N_IN];
  double *out[N_OUT];
  int64_t stride[N_IN];
  int k;
  for (k = 0; k < N_IN; ++k) {{ in[k] = X + k * n; stride[k] = 1; }}
  for (k = 0; k < N_OUT; ++k) out[k] = Y + k * n;
  return mft_batch(n, in, stride, out, counts);
}}
"""


@functools.lru_cache(maxsize=None)
def _toolchain() -> tuple:
    """(flags, libraries, tag): with libmvec where a probe library using it compiles, links and loads."""
    base = (_FLAGS, ("-lm",), "scalar")
    if platform.system() != "Linux" or platform.machine() not in ("x86_64", "AMD64"):
        return base
    probe = ('#include <math.h>\nextern double atan(double) __attribute__((__simd__("notinbranch")));\n'
             '__attribute__((target_clones("default", "avx2", "arch=x86-64-v4")))\n'
             'void f(int n, double *x) {\n#pragma omp simd\nfor (int i = 0; i < n; ++i) x[i] = atan(x[i]);\n}\n')
    try:
        with tempfile.TemporaryDirectory() as tmp:
            src = Path(tmp) / "probe.c"
            src.write_text(probe)
            flags = (*_FLAGS, "-DMFT_LIBMVEC", "-Wl,--no-undefined")
            compile_c(src, Path(tmp) / "probe.so", flags, ("-lmvec", "-lm"))
            ctypes.CDLL(str(Path(tmp) / "probe.so"))
        return flags, ("-lmvec", "-lm"), "libmvec"
    except (MFTyreError, OSError):
        return base


# ------------------------------------------------------------------------------------------ loading
def _read_meta(library: Path) -> dict:
    meta_path = library.with_suffix(".json")
    try:
        meta = json.loads(meta_path.read_text())
        fields = ("inputs", "outputs", "checks", "size", "sha256")
        if not isinstance(meta, dict) or any(k not in meta for k in fields):
            raise ValueError(f"fields {fields} expected")
    except (OSError, ValueError) as exc:
        raise MFTyreError(f"{meta_path}: not a description of a compiled mftyre library ({exc})") from None
    return meta


def _verify(library: Path) -> dict:
    """Check a library against its description (owner, permissions, size, SHA-256) without loading it;
    returns the description."""
    _check_private(library.parent, "the folder")
    meta = _read_meta(library)
    _check_private(library, "the library")
    data = library.read_bytes()
    if len(data) != meta["size"] or hashlib.sha256(data).hexdigest() != meta["sha256"]:
        raise MFTyreError(f"{library} is damaged: {len(data)} bytes, SHA-256 "
                          f"{hashlib.sha256(data).hexdigest()[:16]}..., its description says {meta['size']} bytes, "
                          f"{meta['sha256'][:16]}...; delete it to rebuild")
    return meta




class BatchOutputs(tuple):
    """The arrays of :meth:`CompiledFunction.batch`: a tuple, one array per output in the order of ``names`` (the
    function's ``outputs``), also by name: ``out.fy``, ``out.to_dict()["fy"]``."""

    def __new__(cls, names, arrays):
        self = super().__new__(cls, arrays)
        self.names = tuple(names)
        return self

    def __getnewargs__(self):  # pickled with its names (results of a batch may travel between processes)
        return self.names, tuple(self)

    def __getattr__(self, name):
        names = self.__dict__.get("names", ())
        if name not in names:
            raise AttributeError(f"no output {name!r}; outputs: {', '.join(names)}")
        return self[names.index(name)]

    def to_dict(self) -> dict:
        return dict(zip(self.names, self))


class CompiledFunction:
    """A compiled function of scalars, called without CasADi at run time; thread-safe.

    ``inputs``, ``outputs``: the names, in call order. ``__call__(*floats)`` evaluates one point and returns a
    tuple of floats in the order of ``outputs``; ``batch(*arrays, threads=1)`` evaluates arrays broadcast together
    (``threads=0``: all cores) and returns one array per output (:class:`BatchOutputs`: by position or by name,
    ``out.fy``). Bad inputs raise :class:`ModelInputError`. ``batch`` calls the
    library through ctypes; one point goes through the library's CPython entry where it has one for this
    interpreter (``fast_point`` True: about 0.1 us of overhead instead of 0.6), else through ctypes, with the same
    results, errors and warnings.
    """

    def __init__(self, library, *, finite_outputs: bool = False):
        library = Path(library)
        self._finite_outputs = finite_outputs  # raise like MFModel.evaluate where finite inputs give non-finite outputs
        meta = _verify(library)
        self.library = library
        self.inputs, self.outputs = tuple(meta["inputs"]), tuple(meta["outputs"])
        self._checks = meta["checks"]
        self._lib = ctypes.CDLL(str(library))
        self._point = self._lib.mft_point
        self._point.restype = ctypes.c_int64
        self._batch = self._lib.mft_batch
        self._batch.restype = ctypes.c_int
        self._batch.argtypes = [ctypes.c_int64] + [ctypes.c_void_p] * 4
        self._packed = self._lib.mft_packed
        self._packed.restype = ctypes.c_int
        self._packed.argtypes = [ctypes.c_int64] + [ctypes.c_void_p] * 3
        self._local = threading.local()
        self._n_in = len(self.inputs)
        self._unpack = struct.Struct(f"{len(self.outputs)}d").unpack_from
        self._ranges = {name: (c["range"][0], c["range"][1], c.get("describe", "")) for name, c in
                        zip(self.inputs, self._checks) if c.get("range") and not c.get("hard")}
        #: input -> (index, lower, upper limit beyond which it is refused, their description)
        self._limits = {name: (k, *((-math.inf, c["limit"]) if "limit" in c else c["range"]), c["limit_describe"])
                        for k, (name, c) in enumerate(zip(self.inputs, self._checks)) if "limit_describe" in c}
        #: True where one point is evaluated by the library's CPython entry (built with it, for this interpreter)
        self.fast_point = bool(_PYTHON_ABI) and meta.get("python") == _PYTHON_ABI and hasattr(self._lib,
                                                                                             "mft_python_function")
        if self.fast_point:  # C: floats in, tuple out; flags, other argument types and arity back to Python
            entry = ctypes.PYFUNCTYPE(ctypes.py_object, ctypes.py_object)(("mft_python_function", self._lib))
            self._call = entry((self._call_ctypes, self._flagged))
        else:
            self._call = self._call_ctypes

    __call__ = property(operator.attrgetter("_call"), doc="""One point: the inputs as floats, in the order of
    :attr:`inputs`; returns a tuple of floats. (The instance's one-point function, C or ctypes: calling the
    object costs no Python frame.)""")

    def _call_ctypes(self, *values):
        """One point through ctypes (where the library has no CPython entry, and for any call that entry does not
        take: arguments that are not floats or ints, a wrong number of them)."""
        try:  # this thread's buffer: the inputs, then the outputs
            xy = self._local.xy
        except AttributeError:
            xy = self._local.xy = (ctypes.c_double * (len(self.inputs) + len(self.outputs)))()
        n_in = self._n_in
        try:
            xy[:n_in] = values
        except ValueError:
            raise ModelInputError(self._arity_message(len(values))) from None
        except (TypeError, OverflowError):  # other types (e.g. 0-d arrays) are converted; anything else is refused
            xy[:n_in] = [_real(name, v) for name, v in zip(self.inputs, values)]
        flags = self._point(xy)
        outputs = self._unpack(xy, 8 * n_in)
        return self._flagged(flags, tuple(xy[:n_in]), outputs, stacklevel=5) if flags else outputs

    def _flagged(self, flags, inputs, outputs, stacklevel=4):
        """The checks of one point from its flags (``mft_point``: input not finite, not positive, outside its
        range; an output not finite, checked in C at a tenth of the cost in Python): raise, or warn and return
        ``outputs``. ``stacklevel``: of the warning, 4 when the C entry calls this."""
        if flags & _INPUT_FLAGS:
            self._report(lambda k, kind: (flags >> (kind * _FLAG_BITS + k)) & 1, 1, inputs, stacklevel)
        if flags & _OUTPUT_FLAG and self._finite_outputs:
            self._check_outputs(outputs, inputs, ())
        return outputs

    def batch(self, *arrays, threads: int = 1):
        """Many points: one array (or number) per input, broadcast together; one array per output
        (:class:`BatchOutputs`: ``fx, fy, *rest = ...`` or ``out.fy``).
        ``threads``: how many threads share the points (0: one per available core)."""
        if isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or threads < 0:
            raise ModelInputError(f"threads must be 0 (one per available core) or a positive integer, got {threads!r}")
        if len(arrays) != len(self.inputs):
            raise ModelInputError(self._arity_message(len(arrays)))
        values = [self._as_array(name, a) for name, a in zip(self.inputs, arrays)]
        shapes = {v.shape for v in values if v.ndim}
        try:
            shape = shapes.pop() if len(shapes) == 1 else np.broadcast_shapes(*(v.shape for v in values))
        except ValueError:
            shapes = ", ".join(f"{name} {v.shape}" for name, v in zip(self.inputs, values))
            raise ModelInputError(f"inputs cannot be broadcast to one shape: {shapes}") from None
        n = math.prod(shape)
        n_in, n_out = len(self.inputs), len(self.outputs)
        if n <= _PACKED:  # few points: one packed copy of the inputs, fewer pointers to pass
            packed, result = np.empty((n_in, n)), np.empty((n_out, n))
            for row, v in zip(packed, values):
                row.reshape(shape)[...] = v
            counts = np.zeros((n_in, 3), dtype=np.int64)
            self._packed(n, _address(packed), _address(result), _address(counts))
            if counts.any():
                self._report(lambda k, kind: counts[k, kind], n, packed)
            if self._finite_outputs:
                self._check_outputs(result, packed, shape)
            return BatchOutputs(self.outputs, result.reshape((n_out, *shape)))
        flat, strides = [], []
        for v in values:
            if v.size == 1:  # one value for every point: stride 0, no copy
                flat.append(v.reshape(1))
                strides.append(0)
            else:
                flat.append(np.ascontiguousarray(np.broadcast_to(v, shape)).reshape(-1))
                strides.append(1)
        result = np.empty((n_out, n))
        if threads == 0:
            threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
        parts = max(1, min(int(threads), n // 4096))  # a thread for fewer points costs more than it saves
        counts = np.zeros((parts, n_in, 3), dtype=np.int64)
        in_addr = np.array([_address(a) for a in flat], dtype=np.uint64)
        stride_arr = np.array(strides, dtype=np.int64)
        out_addr = _address(result) + 8 * n * np.arange(n_out, dtype=np.uint64)

        def run(part):  # points [lo, hi): its own pointer arrays and counts
            lo, hi = n * part // parts, n * (part + 1) // parts
            pin = in_addr + (8 * lo) * stride_arr.astype(np.uint64)
            pout = out_addr + np.uint64(8 * lo)
            self._batch(hi - lo, _address(pin), _address(stride_arr), _address(pout), _address(counts[part]))

        if parts == 1:
            run(0)
        else:
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(parts) as pool:
                list(pool.map(run, range(parts)))
        total = counts.sum(axis=0)
        if total.any():
            self._report(lambda k, kind: total[k, kind], n, flat)
        if self._finite_outputs:
            self._check_outputs(result, [np.broadcast_to(v, shape) for v in values], shape)
        return BatchOutputs(self.outputs, result.reshape((n_out, *shape)))

    def _check_outputs(self, result, inputs, shape) -> None:
        """ModelInputError naming the outputs and the first point where finite inputs gave non-finite outputs
        (:func:`mftyre.inputs.check_finite_outputs`, the check of MFModel.evaluate)."""
        result = np.asarray(result, dtype=float).reshape((len(self.outputs), *shape))
        if np.isfinite(result).all():
            return
        check_finite_outputs(dict(zip(self.outputs, result)),
                             {name: np.asarray(v, dtype=float).reshape(shape) for name, v in zip(self.inputs, inputs)})

    def _as_array(self, name, value):
        arr = np.asarray(value)
        if arr.dtype.kind not in "iuf":
            try:
                arr = np.asarray(value, dtype=np.float64) if arr.dtype.kind == "O" else None
            except OverflowError:
                raise ModelInputError(f"input {name!r} must be finite; got a number beyond the largest float "
                                      "(~1.8e308)") from None
            except (TypeError, ValueError):
                arr = None
            if arr is None:
                raise ModelInputError(f"input {name!r} must be real numbers, got dtype {np.asarray(value).dtype}")
        return arr.astype(np.float64, copy=False)

    def _arity_message(self, got):
        return (f"expected {len(self.inputs)} inputs ({', '.join(self.inputs)}), got {got}"
                + (f"; missing {', '.join(self.inputs[got:])}" if got < len(self.inputs) else ""))

    def _report(self, count, n, values, stacklevel=4):
        """Raise for non-finite or non-positive inputs, warn for inputs outside their ranges (the warning
        ``stacklevel`` frames up from :func:`~mftyre.inputs.warn_outside`: the caller's line)."""
        for k, name in enumerate(self.inputs):
            if count(k, 0):
                raise ModelInputError(f"input {name!r} must be finite; {count(k, 0)} of {n} point(s) are NaN or "
                                      f"inf (e.g. {_first_bad(values[k], lambda v: ~np.isfinite(v))})")
            if count(k, 1):
                raise ModelInputError(f"input {name!r} must be positive (inflation pressure in Pa); {count(k, 1)} "
                                      f"of {n} point(s) are not (e.g. {_first_bad(values[k], lambda v: ~(v > 0))})")
        for name, (k, lo, hi, describe) in self._limits.items():  # refused beyond what a tyre can be
            if count(k, 2):
                v = np.atleast_1d(np.asarray(values[k], dtype=float))
                beyond = (v < lo) | (v > hi)
                if beyond.any():
                    raise ModelInputError(f"input {name} = {v[beyond][0]:.6g} at {int(np.sum(beyond))} of {n} "
                                          f"point(s) is beyond the limit of {describe}")
        if "kappa" in self.inputs and "rim" in self._checks[self.inputs.index("kappa")]:
            k, check = self.inputs.index("kappa"), self._checks[self.inputs.index("kappa")]
            if count(k, 2):  # the rim speed of the estimated spin, omega Re = (1 + kappa) vx (2.5)
                kappa = np.atleast_1d(np.asarray(values[k], dtype=float))
                with np.errstate(all="ignore"):
                    rim = np.abs((1.0 + kappa) * np.asarray(values[self.inputs.index("vx")], dtype=float))
                beyond = np.broadcast_to(rim > check["rim"], np.broadcast_shapes(rim.shape, kappa.shape))
                if beyond.any():
                    raise ModelInputError(f"input kappa = {np.broadcast_to(kappa, beyond.shape)[beyond][0]:.6g} (rim "
                                          f"speed {np.broadcast_to(rim, beyond.shape)[beyond][0]:.6g} m/s) at "
                                          f"{int(np.sum(beyond))} of {n} point(s) is beyond the limit of "
                                          f"{check['rim_describe']}")
        outside = {name: int(count(k, 2)) for k, name in enumerate(self.inputs) if name in self._ranges}
        if "kappa" in outside and "rim" in self._checks[self.inputs.index("kappa")] and outside["kappa"]:
            k = self.inputs.index("kappa")  # the C count includes the points beyond the rim speed (none left here)
            lo, hi = self._ranges["kappa"][:2]
            kappa = np.asarray(values[k], dtype=float)
            outside["kappa"] = int(np.count_nonzero((kappa < lo) | (kappa > hi))) * (n // max(kappa.size, 1))
        warn_outside(outside, n, self._ranges, stacklevel=stacklevel)


def _real(name, value) -> float:
    try:
        if isinstance(value, (str, bytes, complex)):
            raise TypeError
        return float(value)
    except OverflowError:
        raise ModelInputError(f"input {name!r} must be finite; got a number beyond the largest float (~1.8e308)") \
            from None
    except (TypeError, ValueError):
        raise ModelInputError(f"input {name!r} must be a real number, got {value!r}") from None


def _address(array) -> int:
    return array.__array_interface__["data"][0]


def _first_bad(values, test):
    values = np.atleast_1d(np.asarray(values, dtype=float))
    return values[test(values)][:1].tolist()[0]


# ------------------------------------------------------------------------------------------ building
def _stem(prefix: str, key: str) -> str:
    """File name stem of a library: the key with this generator, the compiler and the platform."""
    build = f"{key}|{_GENERATOR}|{os.environ.get('CC', 'cc')}|{platform.system()}|{platform.machine()}"
    return f"{prefix}_{hashlib.sha256(build.encode()).hexdigest()[:24]}"


def _build(directory: Path, stem: str, generate) -> Path:
    """Compile the C file that ``generate(folder)`` writes (it returns ``(source, flags, libraries, meta)``) into
    ``directory`` as ``<stem>_<sha>.so`` and its description ``<stem>_<sha>.json`` (``meta`` plus the library's
    size and SHA-256), each renamed atomically."""
    with tempfile.TemporaryDirectory(dir=directory) as tmp:
        built = Path(tmp) / f"{stem}.so"
        with CASADI_LOCK:  # the graph and the C source; the compilers may run at once
            source, flags, libraries, meta = generate(Path(tmp))
        compile_c(source, built, flags, libraries)
        data = built.read_bytes()
        sha = hashlib.sha256(data).hexdigest()
        library = directory / f"{stem}_{sha[:16]}.so"
        os.replace(built, library)
    meta = {**meta, "size": len(data), "sha256": sha}
    _atomic_write(directory, library.with_suffix(".json").name, json.dumps(meta, indent=1).encode())
    return library


def _find_cached(directory: Path, stem: str):
    """A valid cached library named ``<stem>_*.so``, or None (damaged ones are skipped: rebuilt)."""
    for meta in sorted(directory.glob(f"{stem}_*.json")):
        library = meta.with_suffix(".so")
        try:
            _verify(library)
            return library
        except CacheSecurityError:
            raise
        except (MFTyreError, OSError):
            continue
    return None


def cached_library(prefix: str, key: str, generate, directory: Path | None = None) -> Path:
    """The one way compiled code enters mftyre: the library for ``key``, verified before it is returned.

    Looks in the cache (``directory`` or :func:`cache_dir`) for ``<prefix>_<stem>_<sha>.so`` whose size and
    SHA-256 match its description and that, like its folder, belongs to you and is writable by no one else
    (:class:`CacheSecurityError` otherwise); a truncated or altered library is skipped and rebuilt. When none is
    found, ``generate(folder)`` writes the C source into a temporary ``folder`` and returns ``(source, flags,
    libraries, meta)`` (compiler flags, libraries to link, and the description's fields ``inputs``, ``outputs``,
    ``checks`` and any others); it is compiled under a unique temporary name and renamed atomically with its
    description, so threads and processes building the same key at once all succeed. ``key`` must name
    everything else that defines the code: this module's, the backend's and the equations' sources, the
    compiler and the platform are added here. Load the returned path at once (``ctypes.CDLL``,
    ``casadi.external``)."""
    directory = _private_dir(directory) if directory is not None else cache_dir()
    stem = _stem(prefix, key)
    found = _find_cached(directory, stem)
    if found is not None:
        return found
    library = _build(directory, stem, generate)
    _verify(library)
    return library


def compile_function(function, key: str, directory: Path | None = None, output_names=None, checks=None,
                     point_function=None) -> Path:
    """Generate C for the SX ``function`` (scalar inputs and outputs), compile and cache it under ``key``;
    returns the library. ``output_names`` (default: the function's) become :attr:`CompiledFunction.outputs`;
    ``checks``, ``point_function``: see :func:`generate_c`. ``function`` and ``point_function`` may also be
    callables returning them (called only when the library is not cached). Where CPython's headers are found
    (Linux), the same compiler run also builds the one-point entry for this interpreter (``mft_python_function``;
    the key then names its ABI, ``EXT_SUFFIX``)."""
    python_flags = _python_extension_flags()
    python = _PYTHON_ABI if python_flags else None

    def generate(folder):
        fn = function if hasattr(function, "n_in") else function()
        flags, libraries, tag = _toolchain()
        if python:  # the extension's Python symbols are resolved when the interpreter loads the library
            flags = (*(f for f in flags if f != "-Wl,--no-undefined"), *python_flags)
        fn_checks = checks or [{} for _ in range(fn.n_in())]
        point = point_function if point_function is None or hasattr(point_function, "n_in") else point_function()
        source = folder / "mftyre.c"
        source.write_text(generate_c(fn, fn_checks, point))
        return source, flags, libraries, {"inputs": list(fn.name_in()),
                                          "outputs": list(output_names or fn.name_out()), "checks": fn_checks,
                                          "toolchain": tag, "python": python}

    try:
        return cached_library("mftyre", f"{key}|python {python}" if python else key, generate, directory)
    except CompileError:
        if not python:
            raise
        # headers that do not compile (another interpreter's, a broken install): this process builds without the
        # entry from now on; a failure that is not the entry's fails again below and is raised
        _PYTHON_ENTRY_BUILDS.clear()
        return compile_function(function, key, directory, output_names, checks, point_function)


#: Non-empty while the one-point CPython entry builds in this process (emptied by the first build that fails).
_PYTHON_ENTRY_BUILDS = {True}


def _python_extension_flags() -> tuple:
    """:func:`_python_headers` unless building with them failed in this process."""
    return _python_headers() if _PYTHON_ENTRY_BUILDS else ()


@functools.lru_cache(maxsize=None)
def _python_headers() -> tuple:
    """Compiler flags that add the one-point CPython entry to a library (``-DMFT_PYTHON`` and the include folder),
    or ``()`` where it cannot be built (not CPython on Linux, or no Python.h): it is an optimisation of
    :meth:`CompiledFunction.__call__` (~0.5 us of ~1.9 per point), not a requirement; without it the call goes
    through ctypes."""
    include = sysconfig.get_paths().get("include")
    if not _PYTHON_ABI or platform.system() != "Linux" or not include or not Path(include, "Python.h").is_file():
        return ()
    return "-DMFT_PYTHON", f"-I{include}"


def _key(model, options: dict) -> str:
    import casadi as ca

    from . import __version__

    prm = model.params
    payload = {"parameters": {k: repr(prm[k]) for k in prm}, "side": model.side, "options": options,
               "mftyre": __version__, "casadi": ca.__version__}
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=repr).encode()).hexdigest()


def _model_checks(model, inputs, limits: bool) -> list:
    """Per input: finite always; p positive; the .tir range where ``limits`` saturates it (warned); the limits of
    :func:`mftyre.inputs.hard_limits` (refused): vx and omega as hard ranges (``"hard": True``), fz's margin above
    FZMAX checked where the C flags fz outside its range (``"limit"``), the rim speed |(1 + kappa) vx| of an estimated
    spin (no input omega) where the C flags kappa (``"rim"``, ``"rim_vx"`` the index of vx): outside KPUMIN..KPUMAX
    or beyond the rim-speed limit, at any kappa, as evaluate."""
    ranges = input_ranges(model.params, model.mirrored) if limits else {}
    lim = hard_limits(model.params)
    source = getattr(model.params, "source", None) or "the parameter set"
    hard = {"vx": (min(lim["vx"][0], lim["rim"][0]), lim["vx"] if lim["vx"][0] <= lim["rim"][0] else lim["rim"])}
    if np.isfinite(lim["rim"][0]):
        r0 = float(model.params.UNLOADED_RADIUS)
        hard["omega"] = (lim["rim"][0] / r0, (lim["rim"][0], f"{lim['rim'][0] / r0:.6g} rad/s (rim speed |omega R0| "
                                                            f"{lim['rim'][1]})"))
    checks = []
    for name in inputs:
        check = {"positive": name == "p"}
        if name in ranges:
            check.update(range=list(ranges[name][:2]), describe=ranges[name][2])
            if name == "fz":
                check.update(limit=lim["fz"][0], limit_describe=f"{source}: fz <= {lim['fz'][1]}")
        elif name in hard and np.isfinite(hard[name][0]):
            check.update(range=[-hard[name][0], hard[name][0]], hard=True,
                         limit_describe=f"{source}: |{name}| <= {hard[name][1][1]}")
        if name == "kappa" and "vx" in inputs and "omega" not in inputs and np.isfinite(lim["rim"][0]):
            check.update(rim=lim["rim"][0], rim_vx=list(inputs).index("vx"),
                         rim_describe=f"{source}: |(1 + kappa) vx| <= {lim['rim'][1]}")
        checks.append(check)
    return checks


def compile_model(model, inputs=("fz", "kappa", "alpha", "gamma", "phit", "vx", "p"), outputs=None,
                  directory: Path | None = None, **options) -> CompiledFunction:
    """Compile ``model.casadi_function(inputs, outputs, **options)`` (cached) and load it; one point is written
    from the same with ``early_stop=True`` (its C skips the MF 6.2 loaded-radius steps once converged)."""
    from .formula import OUTPUT_NAMES

    outputs = tuple(outputs or OUTPUT_NAMES)
    for name, value in (options.get("fixed") or {}).items():
        _check_fixed(name, value)
    checks = _model_checks(model, inputs, options.get("limits", True))
    key = _key(model, {"inputs": list(inputs), "outputs": list(outputs), "point": "early_stop", "checks": checks,
                       **options})
    # one point: the loaded-radius Newton steps stop once converged (the one-point C skips the rest; the vectorised
    # batch kernel would compute them anyway, and its graph stays the smaller one)
    point = {**options, "early_stop": True}
    library = compile_function(lambda: model.casadi_function(inputs, outputs, **options), key, directory, outputs,
                               checks, lambda: model.casadi_function(inputs, outputs, **point))
    return CompiledFunction(library, finite_outputs=True)


def _check_fixed(name, value):
    check_finite(name, value)
    if name == "p":
        check_pressure(value)


def _jacobian_of_adjoint(f):
    """CasADi's ``f.reverse(1).jacobian()`` (same name, inputs and outputs) for a function of scalars, written as
    the symmetric Hessian of lambda^T f (``casadi.hessian``: star colouring, each mixed second derivative once)
    and the transposed Jacobian of f (the block of the multipliers), with common subexpressions shared: 21 % fewer
    operations than the plain Jacobian of the adjoint for the lane change's MF tyre (6360 against 8102)."""
    import casadi as ca

    reference = f.reverse(1).jacobian()
    n_x, n_y = f.n_in(), f.n_out()
    if any(f.size_in(i) != (1, 1) for i in range(n_x)) or any(f.size_out(k) != (1, 1) for k in range(n_y)):
        return reference
    symbols = reference.sx_in()
    x, seeds = ca.vertcat(*symbols[:n_x]), ca.vertcat(*symbols[n_x + n_y:n_x + 2 * n_y])
    y = ca.vertcat(*f.call(symbols[:n_x]))
    hessian, _ = ca.hessian(ca.dot(seeds, y), x)
    jacobian = ca.jacobian(y, x)
    blocks = []  # d adj_x_i / d (x_j, nominal outputs (no dependence), seeds_k), in CasADi's order
    for i in range(n_x):
        blocks += [hessian[i, j] for j in range(n_x)] + [ca.SX(1, 1)] * n_y + [jacobian[k, i] for k in range(n_y)]
    blocks = [ca.densify(b) if reference.nnz_out(k) else ca.SX(1, 1) for k, b in enumerate(blocks)]  # its pattern
    return ca.Function(reference.name(), symbols, blocks, reference.name_in(), reference.name_out(), {"cse": True})


def compile_external(model, inputs=("fz", "kappa", "alpha"), outputs=("fx", "fy"), *, hessian: bool = False,
                     name: str = "tyre", directory: Path | None = None, **options):
    """A ``casadi.Function`` of the model, compiled to C with its derivatives, for optimal control.

    ``model.casadi_function(inputs, outputs, **options)`` (e.g. ``fixed=``, ``smooth=``, ``limits=``) is written
    by CasADi's code generator together with its Jacobian (``jac_<name>``) and, with ``hessian=True``, its
    adjoint (``adj1_<name>``, lambda^T J) and the Jacobian of that (``jac_adj1_<name>``: the Hessian of the
    Lagrangian an exact-Hessian IPOPT needs; 17 % less time per lane-change iteration than the Jacobian of the
    Jacobian, benchmarks/bench_ocp.py), compiled once (cached like :func:`compile_model`) and loaded with
    ``casadi.external``. ``hessian=False``: second derivatives, where a solver asks for them (IPOPT's exact
    mode), by finite differences of the compiled (exact) Jacobian (2.5x the time per lane-change iteration of
    ``hessian=True``); with IPOPT's ``hessian_approximation="limited-memory"`` none are asked for (2.3 ms per
    iteration against 3.5, 27x as many iterations). Call it in an MX or SX graph as
    any CasADi function: the optimiser then evaluates compiled C for the tyre and its derivatives, and the
    problem's own graph stays small (no need to generate and compile C for the whole problem).
    ``limits=True`` (the default) saturates slip, camber and pressure to the .tir ranges: beyond them, and at
    Fz <= 0, the derivatives with respect to those inputs are exactly zero (see
    :meth:`mftyre.MFModel.casadi_function`); keep an optimisation inside the ranges or use ``limits=False``.
    """
    import casadi as ca

    from .formula import OUTPUT_NAMES

    outputs = tuple(outputs or OUTPUT_NAMES)
    key = _key(model, {"external": name, "inputs": list(inputs), "outputs": list(outputs), "hessian": hessian,
                       **options})

    def functions():
        f = model.casadi_function(inputs, outputs, name=name, **options)
        sx = f.sx_in()
        f = ca.Function(name, sx, f.call(sx), f.name_in(), f.name_out(), {"cse": True})
        # second derivatives as the Jacobian of the adjoint (reverse) function, i.e. of lambda^T J: the Hessian of
        # the Lagrangian weighted by the outputs' multipliers, n_in^2 + n_in n_out entries where the Jacobian of
        # the Jacobian has n_out n_in^2 (and costs 4x as much per point)
        derivatives = (f.jacobian(), f.reverse(1), _jacobian_of_adjoint(f)) if hessian else (f.jacobian(),)
        meta = {"inputs": list(f.name_in()), "outputs": list(f.name_out()), "checks": [], "toolchain": "casadi",
                "function": name, "hessian": hessian}
        return (f, *derivatives), meta

    library = _casadi_library("mftyre_ext", key, functions, directory)
    # without the Hessian: second derivatives (where asked for) by differences of the compiled Jacobian; the
    # first derivatives stay the compiled ones ("enable_fd" on the function itself would difference those too:
    # 4x the time of a constraint Jacobian and, inexact, 2x the iterations of IPOPT's limited-memory mode)
    with CASADI_LOCK:
        return ca.external(name, str(library), {} if hessian else {"jacobian_options": {"enable_fd": True},
                                                                   "der_options": {"enable_fd": True}})


def _casadi_library(prefix: str, key: str, functions, directory: Path | None) -> Path:
    """The library (cached under ``prefix`` and ``key``) of the CasADi functions that ``functions()`` returns with
    the library's description, written by CasADi's code generator (:func:`compile_external`,
    :func:`compile_tyre_kernels`)."""
    import casadi as ca

    def generate(folder):
        members, meta = functions()
        gen = ca.CodeGenerator(f"{prefix}.c", {"with_header": False})
        for f in members:
            gen.add(f)
        flags = ("-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-math-errno")  # (errno unread: sqrt inlined)
        return Path(gen.generate(str(folder) + os.sep)), flags, ("-lm",), meta

    return cached_library(prefix, key, generate, directory)


def tyre_kernels(f, name: str | None = None):
    """(value, value_jacobian, value_hessian) of the tyre ``f`` (an SX ``casadi.Function`` of n_in scalar inputs
    and n_out scalar outputs), each an SX function with shared subexpressions:

    * ``value(u_1..u_n_in) -> (y_1..y_n_out)``;
    * ``value_jacobian(u) -> (y, dy_o/du_i for o, i)`` (output-major);
    * ``value_hessian(u, mu_1..mu_n_out) -> (y, dy_o/du_i, d2(mu^T y)/du_i du_j for i <= j)`` (row-major upper
      triangle)."""
    import casadi as ca

    name = name or f.name()
    if any(f.size_in(i) != (1, 1) for i in range(f.n_in())) or any(f.size_out(k) != (1, 1)
                                                                    for k in range(f.n_out())):
        raise ValueError(f"tyre function {f.name()} must have scalar inputs and outputs")
    u = f.sx_in()
    y = f.call(u)
    x, y_all = ca.vertcat(*u), ca.vertcat(*y)
    mu = [ca.SX.sym(f"mu_{n}") for n in f.name_out()]
    jacobian = ca.jacobian(y_all, x)
    n_in, n_out = f.n_in(), f.n_out()
    blocks = [jacobian[o, i] for o in range(n_out) for i in range(n_in)]
    hessian = ca.hessian(ca.dot(ca.vertcat(*mu), y_all), x)[0]
    upper = [hessian[i, j] for i in range(n_in) for j in range(i, n_in)]
    names_in = list(f.name_in())
    names_jac = [f"d{o}_d{i}" for o in f.name_out() for i in names_in]
    names_hess = [f"h_{names_in[i]}_{names_in[j]}" for i in range(n_in) for j in range(i, n_in)]
    cse = {"cse": True}
    return (ca.Function(name, u, y, names_in, list(f.name_out()), cse),
            ca.Function(f"{name}_value_jacobian", u, [*y, *blocks], names_in, [*f.name_out(), *names_jac], cse),
            ca.Function(f"{name}_value_hessian", [*u, *mu], [*y, *blocks, *upper],
                        [*names_in, *(f"mu_{n}" for n in f.name_out())], [*f.name_out(), *names_jac, *names_hess],
                        cse))


def compile_tyre_kernels(model, inputs=("fz", "kappa", "alpha"), outputs=("fx", "fy"), *, name: str = "tyre",
                         directory: Path | None = None, **options):
    """:func:`tyre_kernels` of ``model.casadi_function(inputs, outputs, **options)`` compiled to C in one library
    (cached in :func:`cache_dir`, built once: ~10-20 s of gcc for the MF tyre) and loaded with
    ``casadi.external``: the tuple (value, value_jacobian, value_hessian)."""
    import casadi as ca

    key = _key(model, {"kernels": name, "inputs": list(inputs), "outputs": list(outputs), **options})

    def functions():
        kernels = tyre_kernels(model.casadi_function(inputs, outputs, name=name, **options))
        meta = {"inputs": list(inputs), "outputs": list(outputs), "checks": [], "toolchain": "casadi",
                "functions": [k.name() for k in kernels]}
        # (CasADi's jac_<name>: the value's own first derivatives, which nlpsol's gradient of the Lagrangian asks for)
        return (*kernels, kernels[0].jacobian()), meta

    library = _casadi_library("mftyre_kernels", key, functions, directory)
    with CASADI_LOCK:
        return tuple(ca.external(n, str(library)) for n in (name, f"{name}_value_jacobian", f"{name}_value_hessian"))


# ------------------------------------------------------------------------------------------ shipped libraries
def platform_tag() -> str:
    """The platform a shipped library was built for (system, machine, Python version)."""
    import sys

    return f"{sys.platform}-{platform.machine()}-py{sys.version_info[0]}.{sys.version_info[1]}"


def install_libraries(directory, entry) -> int:
    """Copy shipped libraries (an FMU's: ``entry`` = {"platform": :func:`platform_tag`, "files": [names]} in
    ``directory``, each library before its description) into the cache (:func:`cache_dir`), where
    :func:`cached_library` finds and verifies them, when built for this platform and not there yet; returns how
    many files were copied. The copies are private to you, whatever the shipped files' modes."""
    if not entry or entry.get("platform") != platform_tag():
        return 0
    cache = cache_dir()
    cache.mkdir(parents=True, exist_ok=True)
    n = 0
    for name in entry.get("files", ()):
        target = cache / name
        if not target.exists() and (Path(directory) / name).is_file():
            tmp = cache / f".{name}.{os.getpid()}.tmp"
            shutil.copyfile(Path(directory) / name, tmp)
            os.chmod(tmp, 0o644)
            os.replace(tmp, target)
            n += 1
    return n
