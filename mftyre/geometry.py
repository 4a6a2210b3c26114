"""Tyre geometry from a size designation, and the geometry no tyre has.

:func:`tyre_size` reads the designations of the tyres that are measured: the inch sizes of Formula Student and
kart tyres (``16x7.5-10``, ``20.5x7.0R13``: overall diameter x section width - rim diameter, inches) and the
ETRTO / ISO metric sizes (``205/60R15``, ``420/85 R24``: section width [mm] / aspect ratio [%] R rim diameter
[in]). It gives the .tir's UNLOADED_RADIUS, RIM_RADIUS, WIDTH and ASPECT_RATIO:

* inch size D x W - d: R0 = D/2, rim radius d/2, WIDTH = W, ASPECT_RATIO = (D - d) / (2 W);
* metric size W/A R d: WIDTH = W, ASPECT_RATIO = A/100, rim radius d/2, R0 = d/2 + A/100 W.

:func:`find_size` finds such a designation in free text (a file's header, a TTC ``tireid``, a file name).
:func:`geometry_problems` names geometry no tyre has: a rim (plus the bottoming offset) reaching the tread
(RIM_RADIUS + BOTTOM_OFFST above :data:`RIM_LIMIT` x UNLOADED_RADIUS), a section height that does not match the
radii, a width or aspect ratio outside what tyres have.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["TyreSize", "tyre_size", "find_size", "geometry_problems", "RIM_LIMIT"]

INCH = 0.0254
#: RIM_RADIUS + BOTTOM_OFFST at most this fraction of UNLOADED_RADIUS: above it the rim meets the road before the
#: tyre has deflected by 5 % of its radius (car tyres: about 0.65, Formula Student 10-inch tyres about 0.68).
RIM_LIMIT = 0.95

_NUM = r"(\d+(?:\.\d+)?)"
_INCH_SIZE = re.compile(rf"(?<![\d.]){_NUM}\s*[xX]\s*{_NUM}\s*(?:-|R|ZR|r)\s*{_NUM}(?![\d.])")
_METRIC_SIZE = re.compile(rf"(?<![\d.])(\d{{3}})\s*/\s*(\d{{2,3}})\s*(?:Z?R|-|B|D)\s*{_NUM}(?![\d.])")


@dataclass(frozen=True)
class TyreSize:
    """A tyre size designation in SI: free radius, rim radius, section width [m], aspect ratio [-]."""

    text: str
    unloaded_radius: float
    rim_radius: float
    width: float
    aspect_ratio: float

    def parameters(self) -> dict:
        """The .tir parameters of the size."""
        return dict(UNLOADED_RADIUS=self.unloaded_radius, RIM_RADIUS=self.rim_radius, WIDTH=self.width,
                    ASPECT_RATIO=self.aspect_ratio)


def _inch(m, text):
    d, w, rim = (float(g) for g in m.groups())
    if not (d > rim > 0 and w > 0):
        raise ValueError(f"tyre size {text!r}: overall diameter {d:g} in must exceed the rim diameter {rim:g} in")
    return TyreSize(m.group(0), d / 2 * INCH, rim / 2 * INCH, w * INCH, (d - rim) / (2 * w))


def _metric(m, text):
    w, a, rim = float(m.group(1)) / 1000, float(m.group(2)) / 100, float(m.group(3))
    return TyreSize(m.group(0), rim / 2 * INCH + a * w, rim / 2 * INCH, w, a)


def tyre_size(text: str) -> TyreSize:
    """The :class:`TyreSize` of a designation (``16x7.5-10``, ``205/60R15``); ValueError naming the forms
    expected when ``text`` is none."""
    s = str(text).strip()
    for pattern, make in ((_INCH_SIZE, _inch), (_METRIC_SIZE, _metric)):
        m = pattern.fullmatch(s)
        if m:
            return make(m, s)
    raise ValueError(f"cannot read {s!r} as a tyre size: expected DIAMETERxWIDTH-RIM in inches (e.g. 16x7.5-10) or "
                     "WIDTH/ASPECT R RIM (e.g. 205/60R15)")


def find_size(*texts) -> TyreSize | None:
    """The first tyre size designation found in ``texts`` (headers, ids, file names), or None."""
    for text in texts:
        if not text:
            continue
        for pattern, make in ((_INCH_SIZE, _inch), (_METRIC_SIZE, _metric)):
            m = pattern.search(str(text))
            if m:
                try:
                    return make(m, str(text))
                except ValueError:
                    continue
    return None


def geometry_problems(prm) -> list[tuple[str, str]]:
    """(parameter, message) for geometry no tyre has (see the module text)."""
    out = []
    r0, rim, off = float(prm["UNLOADED_RADIUS"]), float(prm["RIM_RADIUS"]), float(prm["BOTTOM_OFFST"])
    width, aspect = float(prm["WIDTH"]), float(prm["ASPECT_RATIO"])
    if r0 > 0 and rim + off > RIM_LIMIT * r0:
        out.append(("RIM_RADIUS", f"RIM_RADIUS + BOTTOM_OFFST = {rim:g} + {off:g} = {rim + off:.4g} m is above "
                                  f"{RIM_LIMIT:g} x UNLOADED_RADIUS = {RIM_LIMIT * r0:.4g} m: the rim would bottom "
                                  f"before the tyre deflects by {100 * (1 - RIM_LIMIT):.0f} % of its radius (a rim "
                                  f"of another tyre? a 10-inch rim is 0.127 m, a 15-inch rim 0.1905 m)"))
    if r0 > rim > 0 and width > 0 and aspect > 0:
        height = r0 - rim
        expected = aspect * width
        if not 0.6 < height / expected < 1.6:
            out.append(("ASPECT_RATIO", f"the section height UNLOADED_RADIUS - RIM_RADIUS = {height:.4g} m does not "
                                        f"match ASPECT_RATIO x WIDTH = {aspect:g} x {width:g} = {expected:.4g} m "
                                        "(expected within a factor 1.6; do WIDTH, ASPECT_RATIO and RIM_RADIUS belong "
                                        "to this tyre?)"))
    if r0 > 0 and width > 2.0 * r0:
        out.append(("WIDTH", f"{width:g} m is wider than the tyre's diameter {2 * r0:.4g} m"))
    if not 0.15 <= aspect <= 1.3:
        out.append(("ASPECT_RATIO", f"{aspect:g} is outside 0.15 .. 1.3, where tyres lie"))
    return out
