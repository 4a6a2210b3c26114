"""Road profiles for SWIFT: height w_r(x) [m] along the travelled distance x [m] (ISO-W: x forward, z up).

Every road has a vectorised ``height(x, y=0.0)``; 2D profiles ignore ``y`` (the obstacle covers the whole tyre
width), :class:`TwoTrack` varies across ``y`` for road camber (banking) input. Piecewise roads also list their
``breakpoints`` (abscissae of kinks and jumps): the cam search in :mod:`swift.enveloping` evaluates them
exactly, so a cleat edge is not smeared by the sampling grid. At a jump ``height`` returns the higher side
(the value a cam resting on the edge touches). They also list their ``level_spans``, the open intervals on which
the height is one number (the floor before and after an obstacle, a cleat's top): a cam whose window lies inside
one rests at that height, so the search there is skipped.

    >>> from swift.road import Cleat, Sine, Flat
    >>> road = Flat() + Cleat(x0=1.0, length=0.05, height=0.01)      # roads add up
    >>> road.height([0.9, 1.02, 1.2])
    array([0.  , 0.01, 0.  ])

Profiles: :class:`Flat`, :class:`Step` (up or down), :class:`Cleat` (rectangular), :class:`Trapezoid`,
:class:`CircularBump`, :class:`Sine`, :class:`Sampled` (samples, or a CSV file via :meth:`Sampled.from_csv`),
:class:`TwoTrack` (left/right profiles for banking), and sums of these.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from mftyre.errors import DataError, ModelInputError

__all__ = ["Road", "Flat", "Step", "Cleat", "Trapezoid", "CircularBump", "Sine", "Sampled", "TwoTrack", "parse_road",
           "check_road", "MAX_DISTANCE", "MAX_HEIGHT"]

#: Largest |x| [m] of an obstacle edge and largest |height| [m] of a road profile (1000 km, 100 m).
MAX_DISTANCE = 1e6
MAX_HEIGHT = 100.0


class Road:
    """A road profile. Subclasses implement :meth:`_height` (2D) and may list ``breakpoints``."""

    breakpoints: tuple = ()
    #: True for roads whose height changes across y (road camber for the multi-track cams); 2D profiles: False.
    varies_with_y: bool = False

    def height(self, x, y=0.0):
        """Road height [m] at the travelled distance ``x`` [m] (and lateral position ``y`` [m]), vectorised."""
        x = np.asarray(x, dtype=float)
        return self._height(x, np.asarray(y, dtype=float) + 0.0 * x)

    def _height(self, x, y):
        raise NotImplementedError

    def height_range(self) -> tuple[float, float]:
        """(lowest, highest) height of the profile; bounds the cam search window in :mod:`swift.enveloping`."""
        raise NotImplementedError

    def level_spans(self) -> tuple[tuple[float, float], ...]:
        """Open intervals (a, b), increasing and disjoint, on which ``height`` returns the same number at every x
        (for each y). No spans by default: the cam search then runs everywhere."""
        return ()

    def __add__(self, other: "Road") -> "Road":
        return _Sum(self, other)


def _positive(name, value):
    if not value > 0:
        raise ModelInputError(f"{name} must be positive, got {value!r}")
    return float(value)


class Flat(Road):
    """Constant height ``z`` (default 0)."""

    def __init__(self, z: float = 0.0):
        self.z = float(z)

    def _height(self, x, y):
        return self.z + 0.0 * x

    def height_range(self):
        return self.z, self.z

    def level_spans(self):
        return ((-np.inf, np.inf),)


class Step(Road):
    """Step of ``height`` (negative: step down) at ``x0``; 0 before."""

    def __init__(self, x0: float, height: float):
        self.x0, self.h = float(x0), float(height)
        self.breakpoints = (self.x0,)

    def _height(self, x, y):
        after = x >= self.x0 if self.h > 0 else x > self.x0  # at x0 the higher side (module notes)
        return np.where(after, self.h, 0.0)

    def height_range(self):
        return min(0.0, self.h), max(0.0, self.h)

    def level_spans(self):
        return (-np.inf, self.x0), (self.x0, np.inf)


class Cleat(Road):
    """Rectangular cleat (bar across the road) from ``x0`` to ``x0 + length`` of ``height``."""

    def __init__(self, x0: float, length: float, height: float):
        self.x0, self.length, self.h = float(x0), _positive("cleat length", length), float(height)
        self.breakpoints = (self.x0, self.x0 + self.length)

    def _height(self, x, y):
        return np.where((x >= self.x0) & (x <= self.x0 + self.length), self.h, 0.0)

    def height_range(self):
        return min(0.0, self.h), max(0.0, self.h)

    def level_spans(self):
        return (-np.inf, self.x0), (self.x0, self.x0 + self.length), (self.x0 + self.length, np.inf)


class Trapezoid(Road):
    """Trapezoidal bump: ramps of length ``ramp`` up to ``height``, a plateau of ``top_length``; starts at ``x0``."""

    def __init__(self, x0: float, top_length: float, height: float, ramp: float):
        self.x0, self.top, self.h = float(x0), float(top_length), float(height)
        self.ramp = _positive("ramp length", ramp)
        if self.top < 0:
            raise ModelInputError(f"top_length must be >= 0, got {top_length!r}")
        r, t = self.ramp, self.top
        self.breakpoints = (self.x0, self.x0 + r, self.x0 + r + t, self.x0 + 2 * r + t)

    def _height(self, x, y):
        s = x - self.x0
        r, t = self.ramp, self.top
        return self.h * np.clip(np.minimum(s / r, (2 * r + t - s) / r), 0.0, 1.0)

    def height_range(self):
        return min(0.0, self.h), max(0.0, self.h)

    def level_spans(self):
        x0, x1, x2, x3 = self.breakpoints
        return ((-np.inf, x0),) + (((x1, x2),) if x2 > x1 else ()) + ((x3, np.inf),)


class CircularBump(Road):
    """Circular-segment bump of chord ``length`` and ``height`` (its radius follows), starting at ``x0``."""

    def __init__(self, x0: float, length: float, height: float):
        self.x0, self.length, self.h = float(x0), _positive("bump length", length), _positive("bump height", height)
        half = self.length / 2
        if self.h > half:
            raise ModelInputError(f"a circular bump is at most a half disc: height {height} > length/2 {half}")
        self.radius = (half**2 + self.h**2) / (2 * self.h)  # chord-height relation of a circle
        self.breakpoints = (self.x0, self.x0 + self.length)

    def _height(self, x, y):
        s = x - self.x0 - self.length / 2
        inside = np.abs(s) <= self.length / 2
        return np.where(inside, np.sqrt(np.maximum(self.radius**2 - s**2, 0.0)) - (self.radius - self.h), 0.0)

    def height_range(self):
        return 0.0, self.h

    def level_spans(self):
        return (-np.inf, self.x0), (self.x0 + self.length, np.inf)


class Sine(Road):
    """A * sin(2 pi (x - x0) / wavelength), optionally only on ``x0 <= x <= x_end``."""

    def __init__(self, amplitude: float, wavelength: float, x0: float = 0.0, x_end: float | None = None):
        self.A, self.wavelength, self.x0 = float(amplitude), _positive("wavelength", wavelength), float(x0)
        self.x_end = None if x_end is None else float(x_end)
        self.breakpoints = (self.x0,) + (() if x_end is None else (self.x_end,))

    def _height(self, x, y):
        z = self.A * np.sin(2 * np.pi * (x - self.x0) / self.wavelength)
        on = x >= self.x0 if self.x_end is None else (x >= self.x0) & (x <= self.x_end)
        return np.where(on, z, 0.0)

    def height_range(self):
        return -abs(self.A), abs(self.A)

    def level_spans(self):
        return ((-np.inf, self.x0),) + (() if self.x_end is None else ((self.x_end, np.inf),))


class Sampled(Road):
    """Measured or designed profile: heights ``z`` at increasing ``x``, linear in between, constant outside."""

    def __init__(self, x, z):
        x, z = np.asarray(x, dtype=float), np.asarray(z, dtype=float)
        if x.ndim != 1 or x.shape != z.shape or x.size < 2:
            raise DataError(f"sampled road needs 1-D x and z of equal length >= 2, got shapes {x.shape}, {z.shape}")
        if np.any(np.diff(x) <= 0):
            raise DataError("sampled road: x must be strictly increasing")
        if not (np.isfinite(x).all() and np.isfinite(z).all()):
            raise DataError("sampled road: x and z must be finite")
        self.x, self.z = x, z
        self.breakpoints = tuple(x)

    @classmethod
    def from_csv(cls, path, x_column: str = "x", z_column: str = "z", delimiter: str = ","):
        """Read a profile from a CSV file with a header row naming ``x_column`` and ``z_column`` (metres)."""
        from mftyre.files import DATA_MAX_BYTES, read_user_file

        path = Path(path)
        raw = read_user_file(path, max_bytes=DATA_MAX_BYTES, what="road profile CSV file", error=DataError)
        try:
            data = np.genfromtxt(io.BytesIO(raw), delimiter=delimiter, names=True)
        except ValueError as exc:
            raise DataError(f"{path}: cannot read road profile ({exc})") from exc
        names = data.dtype.names or ()
        missing = [c for c in (x_column, z_column) if c not in names]
        if missing:
            raise DataError(f"{path}: column(s) {missing} not found; columns are {list(names)}")
        return cls(data[x_column], data[z_column])

    def _height(self, x, y):
        return np.interp(x, self.x, self.z)

    def height_range(self):
        return float(self.z.min()), float(self.z.max())

    def level_spans(self):
        """Before the first and after the last sample, and along runs of equal samples."""
        equal = np.concatenate(([False], self.z[1:] == self.z[:-1], [False]))
        starts, ends = np.flatnonzero(~equal[:-1] & equal[1:]), np.flatnonzero(equal[:-1] & ~equal[1:])
        runs = tuple((float(self.x[i]), float(self.x[j])) for i, j in zip(starts, ends))
        return ((-np.inf, float(self.x[0])),) + runs + ((float(self.x[-1]), np.inf),)


class TwoTrack(Road):
    """Left and right profiles at ``y = +spacing/2`` and ``-spacing/2`` (ISO-W: y left), linear in between and
    constant beyond: a road with banking (road camber) for :func:`swift.enveloping.effective_road_3d`."""

    varies_with_y = True

    def __init__(self, left: Road, right: Road, spacing: float):
        self.left, self.right, self.spacing = left, right, _positive("track spacing", spacing)
        self.breakpoints = tuple(sorted(set(left.breakpoints) | set(right.breakpoints)))

    def _height(self, x, y):
        t = np.clip(y / self.spacing + 0.5, 0.0, 1.0)  # 0 right, 1 left
        return t * self.left.height(x) + (1 - t) * self.right.height(x)

    def height_range(self):
        lo = [self.left.height_range(), self.right.height_range()]
        return min(r[0] for r in lo), max(r[1] for r in lo)

    def level_spans(self):
        return _common_spans(self.left.level_spans(), self.right.level_spans())


class _Sum(Road):
    def __init__(self, a: Road, b: Road):
        self.a, self.b = a, b
        self.varies_with_y = a.varies_with_y or b.varies_with_y
        self.breakpoints = tuple(sorted(set(a.breakpoints) | set(b.breakpoints)))

    def _height(self, x, y):
        return self.a._height(x, y) + self.b._height(x, y)

    def height_range(self):
        (a0, a1), (b0, b1) = self.a.height_range(), self.b.height_range()
        return a0 + b0, a1 + b1

    def level_spans(self):
        return _common_spans(self.a.level_spans(), self.b.level_spans())


def _common_spans(first, second):
    """The intersections of two increasing lists of disjoint open intervals (where both profiles are level)."""
    common, i, j = [], 0, 0
    while i < len(first) and j < len(second):
        a, b = max(first[i][0], second[j][0]), min(first[i][1], second[j][1])
        if b > a:
            common.append((a, b))
        if first[i][1] < second[j][1]:
            i += 1
        else:
            j += 1
    return tuple(common)


_EXPRESSION_ARGS = {  # name in a road expression -> (class, argument names)
    "flat": (Flat, ("z",)),
    "step": (Step, ("x0", "height")),
    "cleat": (Cleat, ("x0", "length", "height")),
    "trapezoid": (Trapezoid, ("x0", "top_length", "height", "ramp")),
    "bump": (CircularBump, ("x0", "length", "height")),
    "sine": (Sine, ("amplitude", "wavelength", "x0", "x_end")),
}


def parse_road(spec, base_dir=None) -> Road:
    """A road from text: a CSV file (columns x, z in metres; relative to ``base_dir``) or a sum of obstacles
    written like calls with literal numbers, e.g. ``cleat(x0=3.0, length=0.05, height=0.01) + step(10, 0.02)``
    (``flat``, ``step``, ``cleat``, ``trapezoid``, ``bump``, ``sine``; sine needs ``x_end``; ``csv("file.csv")``,
    ``points([[x, z], ...])``). Empty: flat.
    Nothing is evaluated as Python; errors (:class:`ModelInputError`) name the term and what was expected."""
    if isinstance(spec, Road):
        return check_road(spec)
    return check_road(_parse_road(spec, base_dir))


def check_road(road: Road, what: str = "road") -> Road:
    """``road`` when every obstacle lies within +-MAX_DISTANCE and its heights within +-MAX_HEIGHT, else
    ModelInputError naming the value (positions such as 1e308 overflow the tables built around them)."""
    for x in road.breakpoints:
        if not abs(x) <= MAX_DISTANCE:
            raise ModelInputError(f"{what}: an obstacle edge at x = {x!r} m: expected positions within "
                                  f"+-{MAX_DISTANCE:g} m")
    for z in road.height_range():
        if not abs(z) <= MAX_HEIGHT:
            raise ModelInputError(f"{what}: a height of {z!r} m: expected heights within +-{MAX_HEIGHT:g} m")
    return road


def _parse_road(spec, base_dir=None) -> Road:
    import ast

    text = "" if spec is None else str(spec).strip()
    if text == "":
        return Flat()
    path = Path(text) if base_dir is None or Path(text).is_absolute() else Path(base_dir) / text
    if text.lower().endswith(".csv"):
        if not path.is_file():
            raise DataError(f"road file {str(path)!r} not found")
        return Sampled.from_csv(path)
    try:
        tree = ast.parse(text, mode="eval").body
    except SyntaxError as exc:
        raise ModelInputError(f"road {text!r}: not a CSV file nor a sum of obstacles like "
                              f"cleat(x0=3, length=0.05, height=0.01) ({exc.msg})") from None

    def literal(node, what):
        try:
            value = ast.literal_eval(node)
        except ValueError:
            value = None
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            raise ModelInputError(f"road {text!r}: {what} must be a number")
        return float(value)

    def term(node):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
            return term(node.left) + term(node.right)
        names_all = (*_EXPRESSION_ARGS, "csv", "points")
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in names_all):
            raise ModelInputError(f"road {text!r}: each term must be one of "
                                  f"{', '.join(n + '(...)' for n in names_all)}")
        name = node.func.id
        if name in ("csv", "points"):
            if len(node.args) != 1 or node.keywords:
                raise ModelInputError(f"road {text!r}: {name} takes one argument")
            try:
                value = ast.literal_eval(node.args[0])
            except ValueError:
                raise ModelInputError(f"road {text!r}: the argument of {name} must be a literal") from None
            if name == "csv":
                path = Path(str(value))
                return Sampled.from_csv(path if base_dir is None or path.is_absolute() else Path(base_dir) / path)
            try:
                pairs = [(float(a), float(b)) for a, b in value]
            except (TypeError, ValueError):
                raise ModelInputError(f"road {text!r}: points needs a list of [x, z] pairs") from None
            return Sampled([a for a, _ in pairs], [b for _, b in pairs])
        cls, names = _EXPRESSION_ARGS[name]
        if len(node.args) > len(names):
            raise ModelInputError(f"road {text!r}: {name} takes at most {len(names)} arguments ({', '.join(names)})")
        kwargs = {n: literal(a, f"{name} argument {n}") for n, a in zip(names, node.args)}
        for kw in node.keywords:
            if kw.arg not in names:
                raise ModelInputError(f"road {text!r}: {name} has no argument {kw.arg!r} ({', '.join(names)})")
            kwargs[kw.arg] = literal(kw.value, f"{name} argument {kw.arg}")
        if name == "sine" and "x_end" not in kwargs:
            raise ModelInputError(f"road {text!r}: sine needs x_end (the road must be constant beyond its obstacles)")
        missing = [n for n in names if n not in kwargs and not (name in ("sine", "flat") and n in ("x0", "z"))]
        if missing:
            raise ModelInputError(f"road {text!r}: {name} needs {', '.join(missing)}")
        return cls(**kwargs)

    return term(tree)
