"""An MRCLAM-layout folder written as if recorded in another world frame, at another time and
with other barcodes.

An experiment on MRCLAM data must not depend on where run 6's Vicon frame lies, on the date it
was recorded or on which barcodes its robots wore: it has to work on an MRCLAM run nobody here
has. :func:`move_mrclam` writes such a run from one recording, ``relloc mrclam move SRC DST
--rotate 2 --shift=3.7,-1.2 --clock-shift 123456.789 --barcodes 5:11,14:12``, on which every
figure of an experiment must come out as on ``SRC`` (up to the rounding below). With
``R(φ)`` the rotation by ``φ = rotation_rad``, ``s = shift_m``, ``c = clock_s`` and ``m`` the
map ``barcodes``:

- every ground-truth position, the robots' ``(x, y)`` and the landmarks', ``p ↦ R(φ) p + s``;
- every heading ``θ ↦ wrap(θ + φ)``, in ``[−π, π]``;
- every time stamp ``t ↦ t + c``, added in decimal: the stamp keeps its digits and gains only
  those of ``c`` (the shortest decimal of the float), at most 12 decimals, the finest step the
  loader resolves (:data:`relloc.datasets.mrclam.MAX_CLOCK_DECIMALS`); moving back by ``−c``
  gives the stamp back, as written when ``c`` has no more decimals than it;
- every barcode ``b ↦ m(b)`` (``b`` itself when ``m`` does not name it), in ``Barcodes.dat``
  and in the second column of the measurements.

Positions and headings are written with 8 decimals (1e-8 m, 1e-8 rad; MRCLAM writes 8), or
with the source's when it writes more (the finer of x and y, which a turn mixes), at most 12.
Ranges, bearings and odometry are body-frame readings and are copied byte for byte, so every
relative figure of the run (where a robot sees another, in its own frame) is unchanged:
``R(−θᵢ − φ)(R(φ)pⱼ + s − R(φ)pᵢ − s) = R(−θᵢ)(pⱼ − pᵢ)``, and ``θⱼ − θᵢ`` stays as it is.
The subjects and the landmarks' standard deviations ``σx σy`` are copied too: the layout has no
room for the correlation a turn gives two axis-wise deviations, and they are sub-millimetre.

``Barcodes.dat``, ``Landmark_Groundtruth.dat`` and the three files of every robot the loader
finds are written; other files are not (nor are they by the cut). Their rows are read as
:func:`relloc.datasets.mrclam_cut.cut_mrclam` reads them: lines cut at ``\\n``,
blank lines dropped, comment lines kept as they are and in place. A data row keeps its own
separators and the columns the move does not touch. A row that cannot be moved (not the file's
number of columns, or a column the move rewrites that is not a finite ASCII numeral inside the
loader's bounds, a whole number for a barcode) is left out and counted (``unreadable``), as the
cut leaves out a row without a readable time; the loader skips such a row in the source too, so
a moved run loads the same rows as its source.

Refused with :class:`~relloc.errors.ConfigError`, nothing written, the message starting with the
parameter (``rotation_rad:``, ``shift_m:``, ``clock_s:``, ``barcodes:``, which the CLI turns into
its flag): a rotation, shift or clock shift that is not a finite number; a barcode that is not
an id in ``[1, 2³¹ − 1]``; a map of a barcode that ``Barcodes.dat`` does not list; a map that
gives two subjects one barcode (two barcodes mapped onto one, or onto the barcode another
subject keeps); a new barcode that the measurements read where it names no subject (those
sightings would become sightings of the subject given it; file and line named); a move that
takes a stamp or a position the loader accepts outside its bounds (file and line named). An
existing ``DST`` is refused as the cut refuses it (``mrclam move: DST exists``). A source that
does not load is the loader's :class:`~relloc.errors.DataError`. The run is written beside
``DST`` first and loaded; only a run that loads becomes ``DST``.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from decimal import Context, Decimal
from pathlib import Path

from relloc.core.limits import MAX_ABS_POSITION_M
from relloc.datasets.mrclam import (
    BARCODES_FILE,
    LANDMARKS_FILE,
    MAX_ABS_ANGLE_RAD,
    MAX_CLOCK_DECIMALS,
    MAX_ID,
    MAX_UNIX_TIME_S,
    ROBOT_KINDS,
    data_row,
    finite_numeral,
    load_mrclam,
)
from relloc.datasets.mrclam_cut import staged_write
from relloc.errors import ConfigError

#: Decimals of a moved position or heading, unless the source writes more (module docstring).
POSE_DECIMALS = 8

# The loader's column separator, captured so that a row keeps its own.
_SEPARATOR = re.compile(rb"([ \t]+)")
# Enough digits for a stamp below 2³² s with MAX_CLOCK_DECIMALS decimals.
_DECIMAL = Context(prec=40)


@dataclass(frozen=True)
class FileMove:
    """What became of one file's data rows: ``moved + unreadable`` is all of them."""

    moved: int
    unreadable: int


@dataclass(frozen=True)
class MoveReport:
    """The run written: the move applied and every file's rows (``t0_unix`` is the source's;
    the destination's is ``t0_unix + clock_s``)."""

    source: Path
    destination: Path
    t0_unix: float
    rotation_rad: float
    shift_m: tuple[float, float]
    clock_s: float
    barcodes: dict[int, int]
    files: dict[str, FileMove]


def move_mrclam(
    source: Path | str,
    destination: Path | str,
    *,
    rotation_rad: float = 0.0,
    shift_m: Sequence[float] = (0.0, 0.0),
    clock_s: float = 0.0,
    barcodes: Mapping[int, int] | None = None,
) -> MoveReport:
    """Write ``source`` as the MRCLAM folder ``destination`` with every position
    ``p ↦ R(rotation_rad) p + shift_m``, heading ``θ ↦ wrap(θ + rotation_rad)``, time stamp
    ``t ↦ t + clock_s`` and barcode ``b ↦ barcodes.get(b, b)`` (module docstring)."""
    src, dst = Path(source), Path(destination)
    rotation, shift, clock, mapping = _checked(rotation_rad, shift_m, clock_s, barcodes or {})
    if dst.exists():
        raise ConfigError(f"mrclam move: {dst} exists; name a new folder")
    whole = load_mrclam(src)
    _check_barcodes(mapping, whole.barcodes, src / BARCODES_FILE)
    move = _Move(rotation, shift, clock, mapping, whole.barcodes)
    rows = {
        BARCODES_FILE: move.barcode_row,
        LANDMARKS_FILE: move.landmark_row,
        **{
            f"Robot{n}_{kind}.dat": getattr(move, f"{kind.lower()}_row")
            for n in whole.robot_ids
            for kind in ROBOT_KINDS
        },
    }
    files: dict[str, FileMove] = {}

    def write(staging: Path) -> None:
        for name, move_row in rows.items():
            files[name] = _move_file(src / name, staging / name, move_row)

    staged_write(dst, write, f"mrclam move: {src} moved is not a usable run")
    return MoveReport(src, dst, whole.t0_unix, rotation, shift, clock, mapping, files)


# ----------------------------------------------------------------------------------------------
# Settings
# ----------------------------------------------------------------------------------------------


def _finite(value: object) -> bool:
    """A finite real number that is not a bool."""
    return (
        isinstance(value, numbers.Real)
        and not isinstance(value, bool)
        and math.isfinite(float(value))
    )


def _is_id(value: object) -> bool:
    """An integer id in ``[1, MAX_ID]`` (not a bool)."""
    return (
        isinstance(value, numbers.Integral)
        and not isinstance(value, bool)
        and 1 <= int(value) <= MAX_ID
    )


def _checked(
    rotation_rad: object, shift_m: object, clock_s: object, barcodes: Mapping[int, int]
) -> tuple[float, tuple[float, float], float, dict[int, int]]:
    """The settings as floats and a dict, or a ConfigError starting with the parameter."""
    if not _finite(rotation_rad):
        raise ConfigError(f"rotation_rad: the turn must be a finite angle, got {rotation_rad}")
    if not (isinstance(shift_m, Sequence) and len(shift_m) == 2 and all(map(_finite, shift_m))):
        raise ConfigError(f"shift_m: the shift must be two finite numbers x, y, got {shift_m}")
    if not _finite(clock_s):
        raise ConfigError(f"clock_s: the clock shift must be a finite time, got {clock_s}")
    for old, new in barcodes.items():
        if not (_is_id(old) and _is_id(new)):
            raise ConfigError(f"barcodes: {old!r}→{new!r}: barcodes are integers in [1, {MAX_ID}]")
    x, y = shift_m
    return (
        float(rotation_rad),  # type: ignore[arg-type]
        (float(x), float(y)),
        float(clock_s),  # type: ignore[arg-type]
        {int(old): int(new) for old, new in barcodes.items()},
    )


def _check_barcodes(mapping: Mapping[int, int], known: Mapping[int, int], path: Path) -> None:
    """ConfigError unless every mapped barcode is listed in ``path`` (``known``: barcode →
    subject) and every subject still carries a barcode of its own after the map."""
    unlisted = sorted(b for b in mapping if b not in known)
    if unlisted:
        raise ConfigError(
            f"barcodes: {unlisted[0]} is not a barcode of {path} (its barcodes: "
            f"{', '.join(str(b) for b in sorted(known))})"
        )
    carrier: dict[int, int] = {}  # new barcode -> its old one
    for old in sorted(known):
        new = mapping.get(old, old)
        if new in carrier:
            first = carrier[new]
            how = [f"{b}→{new}" if b in mapping else f"keeps {new}" for b in (first, old)]
            raise ConfigError(
                f"barcodes: subjects {known[first]} ({how[0]}) and {known[old]} ({how[1]}) "
                f"would both carry barcode {new}; a barcode names one subject"
            )
        carrier[new] = old


class _Move:
    """How each file's data row (its columns) is moved, by checked settings."""

    def __init__(
        self,
        rotation_rad: float,
        shift_m: tuple[float, float],
        clock_s: float,
        barcodes: dict[int, int],
        known: Mapping[int, int],
    ) -> None:
        self.rotation_rad, self.shift_m, self.clock_s = rotation_rad, shift_m, clock_s
        self.barcodes = barcodes
        self.known = known  # barcode -> subject, as the loader read Barcodes.dat
        self.taken_by = {new: old for old, new in barcodes.items()}
        self.turn = math.remainder(rotation_rad, math.tau)  # exact; keeps θ's digits
        self.cos, self.sin = math.cos(self.turn), math.sin(self.turn)
        self.clock = Decimal(repr(clock_s)).normalize()
        self.clock_decimals = min(_decimals(self.clock), MAX_CLOCK_DECIMALS)

    # -- columns ---------------------------------------------------------------------------

    def stamp(self, token: bytes, where: str) -> bytes | None:
        """``t + clock_s`` in decimal (module docstring), or None if ``token`` is not a time."""
        t = finite_numeral(token)
        if t is None or not 0.0 <= t <= MAX_UNIX_TIME_S:
            return None
        exact = _exact(token)
        places = min(max(_decimals(exact), self.clock_decimals), MAX_CLOCK_DECIMALS)
        moved = _DECIMAL.add(exact, self.clock)
        if 0 <= moved <= 2 * MAX_UNIX_TIME_S:  # else too many digits to quantize
            moved = moved.quantize(Decimal(1).scaleb(-places), context=_DECIMAL)
        if not 0.0 <= float(moved) <= MAX_UNIX_TIME_S:
            raise ConfigError(
                f"clock_s: shifted by {self.clock_s} s, the stamp {token.decode()} at {where} "
                f"becomes {float(moved):.15g}, outside the loader's [0, {MAX_UNIX_TIME_S:.0f}] s"
            )
        return format(moved, "f").encode("ascii")

    def position(self, xs: bytes, ys: bytes, where: str) -> tuple[bytes, bytes] | None:
        """``R(rotation_rad) (x, y) + shift_m``, or None if the tokens are not a position."""
        x, y = finite_numeral(xs), finite_numeral(ys)
        if x is None or y is None or max(abs(x), abs(y)) > MAX_ABS_POSITION_M:
            return None
        places = _pose_decimals(xs, ys)
        mx = _rounded(self.cos * x - self.sin * y + self.shift_m[0], places)
        my = _rounded(self.sin * x + self.cos * y + self.shift_m[1], places)
        if max(abs(mx), abs(my)) > MAX_ABS_POSITION_M:
            raise ConfigError(
                f"shift_m: turned by {self.rotation_rad} rad and shifted by "
                f"({self.shift_m[0]}, {self.shift_m[1]}) m, the position "
                f"{xs.decode()} {ys.decode()} at {where} becomes {mx:.{places}f} "
                f"{my:.{places}f}, outside the loader's ±{MAX_ABS_POSITION_M:.0f} m"
            )
        return f"{mx:.{places}f}".encode(), f"{my:.{places}f}".encode()

    def heading(self, token: bytes) -> bytes | None:
        """``wrap(θ + rotation_rad)``, or None if ``token`` is not a heading."""
        theta = finite_numeral(token)
        if theta is None or abs(theta) > MAX_ABS_ANGLE_RAD:
            return None
        places = _pose_decimals(token)
        moved = _rounded(math.remainder(theta + self.turn, math.tau), places)
        return f"{moved:.{places}f}".encode()

    def barcode(self, token: bytes, where: str, *, measured: bool) -> bytes | None:
        """``barcodes.get(b, b)``, or None if ``token`` is not a barcode. A ``measured`` barcode
        that names no subject must not become one that does."""
        b = finite_numeral(token)
        if b is None or not (b.is_integer() and 1 <= b <= MAX_ID):
            return None
        code = int(b)
        if code in self.barcodes:
            return str(self.barcodes[code]).encode()
        if measured and code in self.taken_by and code not in self.known:
            old = self.taken_by[code]
            raise ConfigError(
                f"barcodes: {old}→{code}, but {where} reads barcode {code}, which names no "
                f"subject; its sightings would become sightings of subject {self.known[old]}"
            )
        return token

    # -- rows: the tokens of one data row, moved, or None when it cannot be moved ----------

    def barcode_row(self, c: list[bytes], where: str) -> list[bytes] | None:
        """``subject barcode``."""
        if len(c) != 2 or (code := self.barcode(c[1], where, measured=False)) is None:
            return None
        return [c[0], code]

    def landmark_row(self, c: list[bytes], where: str) -> list[bytes] | None:
        """``subject x y σx σy``."""
        if len(c) != 5 or (xy := self.position(c[1], c[2], where)) is None:
            return None
        return [c[0], *xy, c[3], c[4]]

    def groundtruth_row(self, c: list[bytes], where: str) -> list[bytes] | None:
        """``t x y θ``."""
        if len(c) != 4:
            return None
        t, xy, th = self.stamp(c[0], where), self.position(c[1], c[2], where), self.heading(c[3])
        return None if t is None or xy is None or th is None else [t, *xy, th]

    def odometry_row(self, c: list[bytes], where: str) -> list[bytes] | None:
        """``t v ω``."""
        if len(c) != 3 or (t := self.stamp(c[0], where)) is None:
            return None
        return [t, c[1], c[2]]

    def measurement_row(self, c: list[bytes], where: str) -> list[bytes] | None:
        """``t barcode range bearing``."""
        if len(c) != 4 or (t := self.stamp(c[0], where)) is None:
            return None
        code = self.barcode(c[1], where, measured=True)
        return None if code is None else [t, code, c[2], c[3]]


# ----------------------------------------------------------------------------------------------
# Numbers and files
# ----------------------------------------------------------------------------------------------


def _exact(token: bytes) -> Decimal:
    """The finite numeral ``token`` as the decimal it writes; the float the loader reads where
    its exponent is beyond :mod:`decimal`'s range (``0e-99999999999999999999``)."""
    try:
        return Decimal(token.decode("ascii"))
    except ArithmeticError:  # decimal.InvalidOperation
        return Decimal(repr(float(token)))


def _decimals(d: Decimal) -> int:
    """Digits after the decimal point of the finite decimal ``d`` as written."""
    exponent = d.as_tuple().exponent
    assert isinstance(exponent, int)  # finite
    return max(0, -exponent)


def _pose_decimals(*tokens: bytes) -> int:
    """:data:`POSE_DECIMALS`, or the tokens' own decimals when finer (at most 12)."""
    written = max(_decimals(_exact(tok)) for tok in tokens)
    return min(max(POSE_DECIMALS, written), MAX_CLOCK_DECIMALS)


def _rounded(x: float, places: int) -> float:
    """``x`` rounded to ``places`` decimals, a rounded −0 written as 0."""
    return round(x, places) + 0.0


def _move_file(
    src: Path, dst: Path, move_row: Callable[[list[bytes], str], list[bytes] | None]
) -> FileMove:
    """Write ``src``'s comment lines and its data rows moved by ``move_row`` to ``dst``."""
    lines: list[bytes] = []
    moved = unreadable = 0
    for number, line in enumerate(src.read_bytes().split(b"\n"), start=1):
        row = data_row(line)
        if row is None:
            if line.strip():  # a comment, not a blank line
                lines.append(line)
            continue
        parts = _SEPARATOR.split(row)  # columns at even places, their separators between
        new = move_row(parts[::2], f"{src}:{number}")
        if new is None:
            unreadable += 1
            continue
        parts[::2] = new
        lines.append(b"".join(parts))
        moved += 1
    dst.write_bytes(b"\n".join(lines) + b"\n")
    return FileMove(moved=moved, unreadable=unreadable)
