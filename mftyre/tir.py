"""Reading, writing and checking TNO/ADAMS ``.tir`` tyre property files.

Syntax accepted (as found in the wild)::

    [SECTION]                      $ case-insensitive section headers
    NAME = value   $ comment       ! also a comment      { also a comment }
    NAME = 'quoted string'         "double quotes work too"; '$' inside quotes is text
    TYRESIDE = LEFT                unquoted words
    PKX1 = 1.0D+1                  Fortran exponents (D/d), 1.E5, .5 ...

Whole-line comments start with ``$``, ``!`` or ``{``. CRLF, CR and LF line endings are accepted. Names
are case-insensitive. Parameters not in the schema are kept with their section; unknown sections that
are not made of ``NAME = value`` lines (e.g. MF 5.2 ``[SHAPE]`` tables) are kept verbatim. A parameter
given twice is an error naming both lines.

Units: every dimensional parameter (see the unit-kind rule in :mod:`mftyre.params`) is converted to SI
with the factors of the file's ``[UNITS]`` section (a missing entry means SI). When ``[UNITS]`` has no
``PRESSURE`` entry, pressures are in FORCE/LENGTH^2 of the file (ADAMS convention), which is pascal for
an SI file. Parameters not in the schema are kept as read, unconverted.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

from .errors import ModelInputError, TirError, spelled
from .files import TIR_MAX_BYTES, read_user_file, same_file, write_atomically
from .inputs import load_factor_problems, pressure_factor_edges
from .geometry import geometry_problems
from .params import (
    CORE_PARAMETERS,
    PARAMETERS,
    SECTIONS,
    MissingParameterWarning,
    TyreParameters,
    VALID_FITTYP,
    implausible_values,
    invalid_values,
)

__all__ = ["read_tir", "read_tir_text", "parse_tir", "write_tir", "check_tir", "validate_params", "Finding", "UNIT_FACTORS",
           "unit_factor"]


#: Most parameters not in the schema a file may hold (each is kept to be written back; real files have a few).
MAX_UNKNOWN_PARAMETERS = 10_000
#: Most distinct section names a file may hold (real files have about 25; each is kept to be written back).
MAX_SECTIONS = 1_000


class _TirFileExists(TirError, FileExistsError):
    """The target file exists and overwrite=False."""


# ----------------------------------------------------------------------------------------------------
# Units
# ----------------------------------------------------------------------------------------------------
_DEG = Fraction(math.pi) / 180
_LBF = Fraction("4.4482216152605")  # N, exact by definition (0.45359237 kg * 9.80665 m/s^2)
_INCH = Fraction("0.0254")
_FOOT = Fraction("0.3048")

#: [UNITS] key -> accepted spelling (lower case) -> factor to SI.
UNIT_FACTORS: dict[str, dict[str, Fraction]] = {
    "LENGTH": {
        "meter": Fraction(1), "meters": Fraction(1), "metre": Fraction(1), "m": Fraction(1),
        "millimeter": Fraction(1, 1000), "millimeters": Fraction(1, 1000), "millimetre": Fraction(1, 1000),
        "mm": Fraction(1, 1000),
        "centimeter": Fraction(1, 100), "centimeters": Fraction(1, 100), "cm": Fraction(1, 100),
        "kilometer": Fraction(1000), "kilometers": Fraction(1000), "km": Fraction(1000),
        "inch": _INCH, "inches": _INCH, "in": _INCH,
        "foot": _FOOT, "feet": _FOOT, "ft": _FOOT,
    },
    "FORCE": {
        "newton": Fraction(1), "newtons": Fraction(1), "n": Fraction(1),
        "kilonewton": Fraction(1000), "kilonewtons": Fraction(1000), "kn": Fraction(1000),
        "pound_force": _LBF, "lbf": _LBF,
        "kilogram_force": Fraction("9.80665"), "kgf": Fraction("9.80665"),
    },
    "ANGLE": {
        "radian": Fraction(1), "radians": Fraction(1), "rad": Fraction(1),
        "degree": _DEG, "degrees": _DEG, "deg": _DEG,
    },
    "MASS": {
        "kg": Fraction(1), "kilogram": Fraction(1), "kilograms": Fraction(1),
        "gram": Fraction(1, 1000), "grams": Fraction(1, 1000), "g": Fraction(1, 1000),
        "tonne": Fraction(1000),
        "pound_mass": Fraction("0.45359237"), "lbm": Fraction("0.45359237"),
        "slug": _LBF / _FOOT,
    },
    "TIME": {
        "second": Fraction(1), "seconds": Fraction(1), "sec": Fraction(1), "s": Fraction(1),
        "millisecond": Fraction(1, 1000), "milliseconds": Fraction(1, 1000), "ms": Fraction(1, 1000),
        "minute": Fraction(60), "minutes": Fraction(60), "min": Fraction(60),
        "hour": Fraction(3600), "hours": Fraction(3600), "h": Fraction(3600),
    },
    "PRESSURE": {
        "pascal": Fraction(1), "pa": Fraction(1),
        "kilopascal": Fraction(1000), "kpa": Fraction(1000),
        "megapascal": Fraction(10**6), "mpa": Fraction(10**6),
        "bar": Fraction(100000), "mbar": Fraction(100),
        "psi": _LBF / _INCH**2,
        "atm": Fraction(101325),
    },
}

_SI_UNITS = {"LENGTH": "meter", "FORCE": "newton", "ANGLE": "radians", "MASS": "kg", "TIME": "second"}
_UNIT_KEY_OF_KIND = {"length": "LENGTH", "force": "FORCE", "angle": "ANGLE", "mass": "MASS", "time": "TIME",
                     "pressure": "PRESSURE"}


def _base_factors(units: dict[str, str]) -> dict[str, Fraction]:
    """Base kind -> factor to SI for a dict of (validated, lower-case) [UNITS] spellings."""
    out = {}
    for kind, key in _UNIT_KEY_OF_KIND.items():
        if key in units:
            out[kind] = UNIT_FACTORS[key][units[key]]
        elif key == "PRESSURE":
            out[kind] = None  # filled below
        else:
            out[kind] = Fraction(1)
    if out["pressure"] is None:
        out["pressure"] = out["force"] / out["length"] ** 2
    return out


def unit_factor(kind: str, base: dict[str, Fraction]) -> Fraction:
    """Factor to SI of a compound unit kind such as ``"force*time/length"`` or ``"1/length^2"``."""
    if kind in ("-", "string", "integer"):
        return Fraction(1)
    parts = kind.split("/")
    factor = Fraction(1)
    for i, part in enumerate(parts):
        for term in part.split("*"):
            term = term.strip()
            if term == "1":
                continue
            name, _, power = term.partition("^")
            if name not in base:
                raise ValueError(f"unknown unit kind {name!r} in {kind!r}")
            f = base[name] ** int(power or 1)
            factor = factor * f if i == 0 else factor / f
    return factor


def _convert(value: float, factor: Fraction) -> float:
    if factor == 1:
        return value
    return float(Fraction(value) * factor)


# ----------------------------------------------------------------------------------------------------
# Lexing
# ----------------------------------------------------------------------------------------------------
_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_HEADER_RE = re.compile(r"\[\s*([A-Za-z0-9_]+(?:[ \t]+[A-Za-z0-9_]+)*)\s*\](.*)\Z")
# Each digit can be taken by one sub-pattern only, so a match fails in time linear in the length (the form
# "\d+\.?\d*" made 40,000 digits followed by a letter take 37 s).
_NUMBER_RE = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eEdD][+-]?\d+)?\Z")


def _shown(text: str, limit: int = 60) -> str:
    """``repr(text)``, shortened to about ``limit`` characters for an error message."""
    return repr(text) if len(text) <= limit else repr(text[:limit]) + f"... ({len(text)} characters)"


def _err(source: str, line: int | None, parameter: str | None, message: str, cls=TirError) -> TirError:
    where = f"{source}:{line}" if line is not None else f"{source}"
    what = f" {parameter}:" if parameter else ""
    exc = cls(f"{where}:{what} {message}")
    exc.source, exc.line, exc.parameter = source, line, parameter
    return exc


def _is_comment_or_blank(stripped: str) -> bool:
    return not stripped or stripped[0] in "$!{"


def _strip_trailing_comment(text: str) -> str:
    """Remove a trailing comment (``$``, ``!`` or ``{...}``) from unquoted text."""
    out = []
    i = 0
    while i < len(text):
        c = text[i]
        if c in "$!":
            break
        if c == "{":
            j = text.find("}", i + 1)
            if j < 0:
                break
            i = j + 1
            out.append(" ")
            continue
        out.append(c)
        i += 1
    return "".join(out)


def _split_assignment(raw: str, source: str, lineno: int):
    """``NAME = value [comment]`` -> (NAME upper, value text, quoted)."""
    stripped = raw.strip()
    eq = stripped.find("=")
    head = _strip_trailing_comment(stripped if eq < 0 else stripped[:eq]).strip()
    if eq < 0:
        raise _err(source, lineno, (head.split() or [None])[0],
                   f"expected 'NAME = value' but found no '=' in {_shown(stripped)}")
    name = head
    if not _NAME_RE.match(name):
        raise _err(source, lineno, name or None,
                   f"invalid parameter name {_shown(name)}: expected letters, digits and '_' before '='")
    rest = stripped[eq + 1:].lstrip()
    if rest[:1] in ("'", '"'):
        q = rest[0]
        end = rest.find(q, 1)
        if end < 0:
            raise _err(source, lineno, name.upper(),
                       f"unterminated quoted string {_shown(rest)}: expected a closing {q}")
        value = rest[1:end]
        after = _strip_trailing_comment(rest[end + 1:]).strip()
        if after:
            raise _err(source, lineno, name.upper(),
                       f"unexpected text {_shown(after)} after the quoted value: expected a comment ($ or !) "
                       "or nothing")
        return name.upper(), value, True
    value = _strip_trailing_comment(rest).strip()
    if not value:
        raise _err(source, lineno, name.upper(), "missing value after '='")
    return name.upper(), value, False


def _parse_number(text: str) -> float | None:
    t = text.strip()
    if not _NUMBER_RE.match(t):
        return None
    return float(t.replace("d", "e").replace("D", "e"))


def _raw_value(text: str, quoted: bool) -> Any:
    """Value of a parameter not in the schema: number when it looks like one, else the text."""
    if not quoted:
        num = _parse_number(text)
        if num is not None:
            return num
    return text


# ----------------------------------------------------------------------------------------------------
# Parsing
# ----------------------------------------------------------------------------------------------------
def _lines(text: str) -> list[str]:
    """The lines of ``text`` (CR LF, CR or LF line ends; a byte-order mark dropped)."""
    if text.startswith("\ufeff"):
        text = text[1:]
    return re.split(r"\r\n|\r|\n", text)


def _section_header(stripped: str):
    """The canonical section name of a header line ``[NAME]`` (upper case, blanks as '_'), ``"\0bad"`` for a
    malformed header, None for a line that is not a header."""
    if not stripped.startswith("["):
        return None
    m = _HEADER_RE.match(stripped)
    if m is None or _strip_trailing_comment(m.group(2)).strip():
        return "\0bad"
    return re.sub(r"\s+", "_", m.group(1).strip()).upper()


def _is_assignment(raw: str) -> bool:
    return "=" in raw and bool(_NAME_RE.match(_strip_trailing_comment(raw.split("=", 1)[0]).strip() or "-"))


def parse_tir(text: str, source: str = "<string>", *, strict: bool = False) -> TyreParameters:
    """Parse the text of a .tir file into :class:`TyreParameters` (SI).

    Missing parameters (used by the file's model version and not optional) give one
    :class:`~mftyre.params.MissingParameterWarning` listing them with their defaults, or a
    :class:`~mftyre.errors.TirError` when ``strict``. Malformed input raises TirError naming
    ``source``, the line and the parameter.
    """
    return _parse(text, source, strict=strict, stacklevel=3)[0]


def _parse(text: str, source: str, *, strict: bool, stacklevel: int, validate: bool = True):
    """-> (TyreParameters, {schema name: section it was read in}). ``stacklevel`` is for the warning;
    ``validate``: raise TirError on the first value no tyre can have (:func:`mftyre.params.invalid_values`)."""
    source = str(source)
    lines_of_text = _lines(text)
    headers = (_section_header(raw.strip()) for raw in lines_of_text)
    if not any(h is not None and h != "\0bad" for h in headers):
        for i, raw in enumerate(lines_of_text, start=1):
            if _section_header(raw.strip()) == "\0bad":
                raise _err(source, i, None, "malformed section header: expected '[SECTION_NAME]'")
        raise _err(source, None, None, "not a .tir property file: no [SECTION] headers found "
                                       "(expected e.g. [MDI_HEADER], [MODEL], [VERTICAL])")

    known_sections = set(SECTIONS)
    raw_values: dict[str, tuple[str, str, bool, int]] = {}  # name -> (section, text, quoted, line)
    unknown: dict[str, tuple[str, object]] = {}
    extra_parts: dict[str, list[str]] = {}  # unknown non-assignment section -> its lines (joined once, at the end)
    units: dict[str, str] = {}  # key -> lower-case spelling
    units_as_read: dict[str, str] = {}
    unit_lines: dict[str, int] = {}
    lines: dict[str, int] = {}  # parameter -> line (also how a duplicate is found)

    def assign(section: str, lineno: int, raw: str) -> None:
        name, value, quoted = _split_assignment(raw, source, lineno)
        if section == "UNITS" and name in UNIT_FACTORS:
            if name in unit_lines:
                raise _err(source, lineno, name, f"duplicate parameter: defined on line {unit_lines[name]} and "
                                                  f"again on line {lineno}")
            unit_lines[name] = lineno
            spelling = value.strip().lower()
            if spelling not in UNIT_FACTORS[name]:
                accepted = ", ".join(UNIT_FACTORS[name])
                raise _err(source, lineno, name,
                           f"unknown unit {_shown(value)}: accepted spellings (any case, quoted or not) are "
                           f"{accepted}")
            units[name] = spelling
            units_as_read[name] = value
            return
        if name in lines:
            raise _err(source, lineno, name,
                       f"duplicate parameter: defined on line {lines[name]} and again on line {lineno}")
        lines[name] = lineno
        if name in PARAMETERS:
            raw_values[name] = (section, value, quoted, lineno)
        elif len(unknown) < MAX_UNKNOWN_PARAMETERS:
            unknown[name] = (section, _raw_value(value, quoted))
        else:
            raise too_many_unknown(lineno, raw)

    def end_unknown_section(section: str, first_line: int, body: list[str]) -> None:
        """An unknown section: parameters when every content line is ``NAME = value``, else kept verbatim."""
        content = [raw for raw in body if not _is_comment_or_blank(raw.strip())]
        if content and all(_is_assignment(raw) for raw in content):
            del content
            for k, raw in enumerate(body):
                if not _is_comment_or_blank(raw.strip()):
                    assign(section, first_line + k, raw)
            return
        while body and _is_comment_or_blank(body[-1].strip()) and not body[-1].strip().startswith("{"):
            body.pop()
        extra_parts.setdefault(section, []).append("\n".join(body))

    def too_many_unknown(lineno: int, raw: str) -> TirError:
        return _err(source, lineno, _split_assignment(raw, source, lineno)[0],
                    f"more than {MAX_UNKNOWN_PARAMETERS:,} parameters that are not in the schema: not a tyre property "
                    "file (real files have none or a few)")

    section, first_line, body = None, 1, []  # body: the lines of the unknown section being read
    sections_seen: set[str] = set()
    assignments = 0  # lines NAME = value in the unknown section being read (refused early beyond the limit)
    for lineno, raw in enumerate(lines_of_text, start=1):
        stripped = raw.strip()
        header = _section_header(stripped)
        if header == "\0bad":
            raise _err(source, lineno, None, f"malformed section header {_shown(stripped)}: expected '[SECTION_NAME]'")
        if header is not None:
            if section is not None and section not in known_sections:
                end_unknown_section(section, first_line, body)
            section, first_line, body, assignments = header, lineno + 1, [], 0
            sections_seen.add(header)
            if len(sections_seen) > MAX_SECTIONS:
                raise _err(source, lineno, None, f"more than {MAX_SECTIONS:,} different sections ({_shown(stripped)} "
                                                 "is one too many): not a tyre property file (real files have about "
                                                 "25)")
        elif section is None:
            if not _is_comment_or_blank(stripped):
                name = raw.split("=", 1)[0].strip() if "=" in raw else None
                raise _err(source, lineno, name.upper() if name else None,
                           "text before the first [SECTION] header: expected a section header such as [MDI_HEADER]")
        elif section in known_sections:
            if not _is_comment_or_blank(stripped):
                assign(section, lineno, raw)
        else:
            body.append(raw)
            if "=" in raw and _is_assignment(raw):
                assignments += 1
                if len(unknown) + assignments > MAX_UNKNOWN_PARAMETERS:
                    raise too_many_unknown(lineno, raw)
    if section is not None and section not in known_sections:
        end_unknown_section(section, first_line, body)
    del lines_of_text, body
    extra_sections = {name: "\n".join(parts) for name, parts in extra_parts.items()}

    # -- typed values, converted to SI ----------------------------------------------------------------
    base = _base_factors(units)
    values: dict[str, Any] = {}
    for name, (section, text_value, quoted, lineno) in raw_values.items():
        spec = PARAMETERS[name]
        if spec.is_string:
            values[name] = text_value
            continue
        num = _parse_number(text_value)
        if num is None:
            what = "a quoted string" if quoted else _shown(text_value)
            kind = "an integer" if spec.is_integer else "a number"
            raise _err(source, lineno, name,
                       f"expected {kind} ({spec.description}), got {what}")
        if not math.isfinite(num):
            raise _err(source, lineno, name, f"expected a finite number, got {_shown(text_value)}")
        if spec.is_integer:
            if num != int(num):
                raise _err(source, lineno, name, f"expected an integer, got {_shown(text_value)}")
            values[name] = int(num)
        else:
            try:
                values[name] = _convert(num, unit_factor(spec.unit, base))
            except OverflowError:
                raise _err(source, lineno, name, f"{_shown(text_value)} converted to SI with the file's [UNITS] is "
                                                 "beyond the range of a floating-point number") from None

    if "FITTYP" not in values:
        raise _err(source, None, "FITTYP",
                   "FITTYP is missing: expected FITTYP = 61, 62 or an MF 5.2 code (6, 21, 52) in [MODEL]")
    if values["FITTYP"] not in VALID_FITTYP:
        raise _err(source, raw_values["FITTYP"][3], "FITTYP",
                   f"unknown FITTYP {values['FITTYP']}: expected 61 (MF 6.1), 62 (MF 6.2) "
                   "or an MF 5.2 code (6, 21, 50-59)")

    try:
        prm = TyreParameters(
            values,
            source=source,
            unknown=unknown,
            extra_sections=extra_sections,
            units_as_read=units_as_read,
            lines=lines,
        )
    except ModelInputError as exc:  # pragma: no cover - values were checked above
        raise _err(source, None, None, str(exc)) from exc
    if validate:
        _validate(prm, source)

    if prm.missing_reported:
        listing = ", ".join(f"{n}={prm[n]!r}" for n in prm.missing_reported)
        version = prm.version
        msg = (f"{source}: {len(prm.missing_reported)} parameter(s) used by MF {version[0]}.{version[1]} "
               f"(FITTYP {prm.fittyp}) are missing; using defaults: {listing}")
        if strict:
            raise _err(source, None, None,
                       f"{len(prm.missing_reported)} parameter(s) used by MF {version[0]}.{version[1]} are "
                       f"missing (strict mode): {', '.join(prm.missing_reported)}")
        warnings.warn(msg, MissingParameterWarning, stacklevel=stacklevel)
    sections_read = {name: sec for name, (sec, _, _, _) in raw_values.items()}
    return prm, sections_read


def _validate(prm: TyreParameters, source: str) -> None:
    """TirError naming file, line and parameter for the first value no tyre can have."""
    for name, message in invalid_values(prm):
        where = "" if name in prm.lines else " (its default: the file does not set it)"
        raise _err(source, prm.lines.get(name), name, message + where)


def read_tir(path, *, strict: bool = False) -> TyreParameters:
    """Read a .tir file (see :func:`parse_tir`)."""
    p = Path(path)
    text = read_tir_text(p)
    return _parse(text, str(p), strict=strict, stacklevel=3)[0]


def read_tir_text(p) -> str:
    """The text of the .tir file ``p`` (UTF-8, else Latin-1), read by the rule of :mod:`mftyre.files`; TirError
    naming the file when it cannot be read or is binary."""
    p = Path(p)
    data = read_user_file(p, max_bytes=TIR_MAX_BYTES, what=".tir property file", error=TirError)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    if "\0" in text:
        raise _err(str(p), None, None, "binary data: expected a text .tir property file")
    return text


def validate_params(prm: TyreParameters, source: str = "parameters") -> TyreParameters:
    """``prm`` when every value is one a tyre can have (:func:`mftyre.params.invalid_values`), else TirError naming
    the parameter (and its line when read from a file): the check of :func:`read_tir`, :func:`write_tir`,
    :meth:`mftyre.MFModel.with_params` and the FMU builders."""
    for name, message in invalid_values(prm):
        raise _err(source, None, name, message)
    return prm


# ----------------------------------------------------------------------------------------------------
# Writing
# ----------------------------------------------------------------------------------------------------
def _format_value(value: Any, string: bool, name: str = "") -> str:
    """The text of a value as :func:`parse_tir` reads it back: a string in the quotes it does not contain, or
    without quotes when it holds both kinds (TirError when no spelling reads back the same text)."""
    if string or isinstance(value, str):
        text = str(value)
        if "\n" in text or "\r" in text:
            raise _err("write_tir", None, name or None, f"the text {_shown(text)} spans lines: a .tir value is one line")
        if "'" not in text:
            return "'" + text + "'"
        if '"' not in text:
            return '"' + text + '"'
        if text == text.strip() and text[:1] not in "'\"" and not any(c in text for c in "$!{"):
            return text  # both quote kinds: unquoted, read back as written
        raise _err("write_tir", None, name or None,
                   f"the text {_shown(text)} holds both quote kinds and a comment character or surrounding blanks: "
                   "no .tir spelling reads it back unchanged")
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, int):
        return str(value)
    return repr(float(value))


def _line(name: str, value: str, comment: str = "") -> str:
    text = f"{name:<25}= {value}"
    if comment:
        text = f"{text:<50} ${comment}"
    return text


def _one_line(text) -> str:
    """``text`` as one printable line: line breaks and other control characters spelled as escapes (``\\n``), so
    a name written into a comment can never start a line (a section, a parameter) of the written file."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in str(text))


def tir_text(params: TyreParameters, comments=(), *, notes: dict | None = None, closing=()) -> str:
    """The text :func:`write_tir` writes for ``params``; ``comments``: lines added to the header as ``!``
    comments (e.g. the provenance of fitted values); ``notes``: parameter -> a comment written after its
    description (``! fitted +- 0.02 (pure_fy)``); ``closing``: ``!`` comment lines at the end of the file."""
    notes = notes or {}
    version = params.version
    missing = set(params.missing)
    out: list[str] = []
    by_section: dict[str, list[str]] = {s: [] for s in SECTIONS}
    for name, spec in PARAMETERS.items():
        value = params[name]
        present = name not in missing
        relevant = version in spec.versions
        non_default = value != spec.default
        if not (present or relevant or non_default or name == "FITTYP"):
            continue
        if not present and spec.optional:  # absent = "effect as the file's equations say", not the default's
            continue                       # number (SWIFT_PSTIFF absent is PFZ1, not 0): it stays absent
        line = _line(name, _format_value(value, spec.is_string, name), spec.description)
        if name in notes:
            line = f"{line:<95} ! " + _one_line(" ".join(str(notes[name]).split()))
        by_section[spec.section].append(line)
    extra_param_sections: dict[str, list[str]] = {}
    for name, (section, value) in params.unknown.items():
        line = _line(name, _format_value(value, False, name))
        if section in by_section:
            by_section[section].append(line)
        else:
            extra_param_sections.setdefault(section, []).append(line)
    by_section["UNITS"] = [_line(k, f"'{v}'") for k, v in _SI_UNITS.items()] + by_section["UNITS"]

    for section in SECTIONS:
        entries = by_section[section]
        if not entries:
            continue
        if section != "MDI_HEADER":
            out.append("$" + "-" * (60 - len(section)) + section.lower())
        out.append(f"[{section}]")
        out.extend(entries)
        if section == "MDI_HEADER":
            out.append("!")
            out.append("! Written by mftyre (Magic Formula tyre model, Python); values in SI units.")
            out.append(f"! Source: {_one_line(params.source) if params.source else '(created in memory)'}")
            out.append(f"! Model: FITTYP {params.fittyp} (MF {version[0]}.{version[1]})")
            out.extend("! " + " ".join(str(c).split()) for c in comments)
            out.append("!")
    for section, entries in extra_param_sections.items():
        out.append("$" + "-" * max(1, 60 - len(section)) + section.lower())
        out.append(f"[{section}]")
        out.extend(entries)
    for section, body in params.extra_sections.items():
        out.append("$" + "-" * max(1, 60 - len(section)) + section.lower())
        out.append(f"[{section}]")
        if body:
            out.append(body)
    if closing:
        out.append("$" + "-" * 50 + "summary")
        out.extend("! " + _one_line(str(c).rstrip()) for c in closing)
    return "\n".join(out) + "\n"


def write_tir(params: TyreParameters, path, *, overwrite: bool = False, comments=(), notes: dict | None = None,
              closing=()) -> Path:
    """Write ``params`` to ``path`` as a .tir file in SI units; returns the path written. ``comments``: lines for
    the file's header (``!`` comments, read back as comments); ``notes`` and ``closing``: see :func:`tir_text`.

    Refuses to overwrite an existing file unless ``overwrite=True``, and never overwrites the file the
    parameters were read from (``params.source``).
    """
    if not isinstance(params, TyreParameters):
        raise ModelInputError(f"write_tir expects TyreParameters, got {type(params).__name__}")
    p = Path(path)
    if params.source and same_file(p, Path(params.source)):
        raise _err(str(p), None, None,
                   "refusing to overwrite the file these parameters were read from "
                   "(params.source); write to a different path")
    if p.exists() and not overwrite:
        raise _err(str(p), None, None, f"file exists: pass {spelled('overwrite=True', '--overwrite')} to replace it",
                   cls=_TirFileExists)
    if p.is_dir():
        raise _err(str(p), None, None, "is a directory: expected a file path")
    _validate(params, str(p))
    write_atomically(p, tir_text(params, comments, notes=notes, closing=closing))
    return p


# ----------------------------------------------------------------------------------------------------
# Checking
# ----------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Finding:
    """One result of :func:`check_tir`."""

    severity: str  # "error" | "warning" | "info"
    parameter: str | None
    line: int | None
    message: str

    def __str__(self) -> str:
        loc = f"line {self.line}: " if self.line is not None else ""
        return f"{loc}{self.severity}: {self.message}"


def check_tir(path) -> list[Finding]:
    """Findings about a .tir file: parse errors, missing/unknown parameters, suspicious values."""
    findings: list[Finding] = []
    try:
        p = Path(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", MissingParameterWarning)
            prm, sections_read = _parse(read_tir_text(p), str(p), strict=False, stacklevel=2, validate=False)
    except TirError as exc:
        return [Finding("error", getattr(exc, "parameter", None), getattr(exc, "line", None), str(exc))]

    def add(sev: str, name: str | None, msg: str):
        findings.append(Finding(sev, name, prm.lines.get(name) if name else None,
                                f"{name}: {msg}" if name else msg))

    core = CORE_PARAMETERS[prm.version]
    for name in prm.missing_reported:
        severity = "error" if name in core else "warning"
        add(severity, name, f"missing; the default {prm[name]!r} is used ({PARAMETERS[name].description})"
            + (": a core coefficient of the model, which the file must define" if name in core else ""))
    for name, message in invalid_values(prm):
        add("error", name, message)
    for name, message in implausible_values(prm):
        add("error", name, message)
    si = all(UNIT_FACTORS[k][v.strip().lower()] == 1 for k, v in prm.units_as_read.items())
    for name, (section, value) in prm.unknown.items():
        add("warning", name, f"unknown parameter in [{section}] (kept and written back unchanged"
                             + ("" if si else ", NOT converted to SI") + ")")
    for name, section in sections_read.items():
        if section != PARAMETERS[name].section:
            add("info", name, f"found in [{section}]; its canonical section is [{PARAMETERS[name].section}]")
    for section in prm.extra_sections:
        findings.append(Finding("info", None, None, f"[{section}]: unknown section kept verbatim"))
    if not si and "PRESSURE" not in prm.units_as_read:
        findings.append(Finding("info", None, None,
                                "[UNITS] has no PRESSURE entry: pressures were read in FORCE/LENGTH^2 of the file"))

    v = prm
    checks = []
    for name in ("PCX1", "PCY1", "PDX1", "PDY1"):
        checks.append((v[name] <= 0, "warning", name, f"should be positive, got {v[name]!r}"))
    if v.version in ("52", "61"):
        checks.append((v.Q_FZ2 == 0, "warning", "Q_FZ2",
                       "is 0: the reference evaluator's MF 6.1 deflection divides by 2*Q_FZ2 (its rho, Rl and Cz "
                       "are meaningless); mftyre uses a form that stays finite"))
    checks.append(((v.PRESMIN <= v.PRESMAX) and not (v.PRESMIN <= v.INFLPRES <= v.PRESMAX), "warning", "INFLPRES",
                   f"{v.INFLPRES!r} Pa is outside PRESMIN..PRESMAX = {v.PRESMIN!r}..{v.PRESMAX!r} Pa"))
    for edge, side, names, what in pressure_factor_edges(v):
        checks.append((v.PRESMIN <= edge <= v.PRESMAX, "warning", names.split(" ")[0],
                       f"{names} makes the {what} factor change sign at {edge:.6g} Pa, inside PRESMIN..PRESMAX = "
                       f"{v.PRESMIN!r}..{v.PRESMAX!r} Pa: {'above' if side > 0 else 'below'} it that property has "
                       "the wrong sign (the evaluator and SWIFT warn when used there)"))
    for name, message in load_factor_problems(v):
        checks.append((True, "warning", name, message))
    for name, message in geometry_problems(v):
        checks.append((True, "error" if name == "RIM_RADIUS" else "warning", name, message))
    for cond, sev, name, msg in checks:
        if cond:
            add(sev, name, msg)
    return findings
