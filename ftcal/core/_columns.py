"""The one header and number reader behind every CSV entry point (datasets, run logs, ``ftcal predict``).

Every text table ftcal reads has a header naming its columns. The rules are
the same everywhere, so that a file accepted by one reader means the same to
the others:

* a UTF-8 byte-order mark before the first name is dropped (spreadsheet
  exports write one); surrounding spaces are dropped;
* names are ASCII: a letter or ``_`` then letters, digits, ``_`` or ``-``
  (a look-alike such as a full-width ``ｓ0`` would otherwise silently drop a
  channel);
* no name appears twice (otherwise one of the two columns would be lost);
* numbered columns (``s0, s1, ...``; ``q1, q2, ...``) have no leading zeros
  and no gaps;
* numbers are plain decimal or scientific notation (``1e-3``, ``-2.5``);
  Python's ``float`` would also take ``1_000`` or ``٣``, which no sensor
  logger writes, so those are rejected with the file and line.

Errors are raised as the caller's domain error class (``DatasetFileError``,
``LogFormatError``, the CLI's error) with the file, the line and what to fix.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from itertools import chain

__all__ = ["Header", "read_header", "parse_number", "is_number", "check_plain_fields", "DTYPE_KIND_NAMES", "csv_rows",
           "repeated_names"]

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_\-]*")
_NUMBER = re.compile(r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf|infinity)", re.IGNORECASE | re.ASCII)
_BOM = "\ufeff"
#: A character no plain number or separator has: lines holding one are parsed field by field.
_NOT_PLAIN = re.compile(r"[^0-9eE+\-.,\s]")


def is_number(text: str) -> bool:
    """Whether ``text`` is a plain decimal / scientific number (``nan`` and ``inf`` included).

    Examples
    --------
    >>> [is_number(t) for t in ("1e-3", "-2.", ".5", "1_000", "0x10", "nan")]
    [True, True, True, False, False, True]
    """
    return _NUMBER.fullmatch(text.strip()) is not None


def csv_rows(*blocks) -> Iterator[str]:
    """CSV lines (with ``\\n``) of the row-aligned 2-D ``blocks`` side by side, every number exactly as stored.

    Floats are written as ``repr`` (the shortest text that reads back to the same float64, up to 17 significant
    digits), integers as integers: a written file reads back bit for bit (:func:`parse_number`).

    Examples
    --------
    >>> import numpy as np
    >>> list(csv_rows(np.array([[0.1, 1e6 + 1e-9]]), np.array([[2**53 + 1]], dtype=object)))
    ['0.1,1000000.000000001,9007199254740993\\n']
    """
    for parts in zip(*(block.tolist() for block in blocks)):
        yield ",".join(map(repr, chain.from_iterable(parts))) + "\n"


def parse_number(text: str, where: str, error: type[Exception]) -> float:
    """``float(text)`` for a plain number, else ``error`` naming ``where`` (file and line, column).

    Examples
    --------
    >>> parse_number(" 2.5e1 ", "x.csv: line 3", ValueError)
    25.0
    >>> parse_number("1_000", "x.csv: line 3", ValueError)
    Traceback (most recent call last):
    ...
    ValueError: x.csv: line 3: '1_000' is not a number (plain decimal or scientific notation, e.g. 1000 or 1e3).
    """
    if not is_number(text):
        raise error(f"{where}: {text.strip()!r} is not a number (plain decimal or scientific notation, e.g. 1000 or 1e3).")
    return float(text)


#: What an array of each dtype kind that holds no real numbers is (the calibrators' and the dataset readers'
#: messages; scikit-learn and numpy would convert most of them to numbers silently).
DTYPE_KIND_NAMES = {"c": "complex numbers", "b": "booleans", "M": "dates", "m": "time spans", "U": "text",
                    "S": "text", "O": "objects (a MATLAB cell array)", "V": "records (a MATLAB struct)"}


def check_plain_fields(line: str, where: str, names: Sequence[str], error: type[Exception], *,
                       quick: bool = False) -> None:
    """Raise ``error`` at the first field of the CSV ``line`` that is empty or no plain number, naming ``where``
    (file and line) and the field's column in ``names``.

    With ``quick``, a line holding only characters of plain numbers and separators is passed without looking at
    its fields: the guard in front of ``numpy.loadtxt``, which (like ``float``) reads ``1_000`` as 1000.

    Examples
    --------
    >>> check_plain_fields("1.5,1_000", "d.csv: line 4", ["s0", "s1"], ValueError)
    Traceback (most recent call last):
    ...
    ValueError: d.csv: line 4, column s1: '1_000' is not a number (plain decimal or scientific notation, e.g. 1000 or 1e3).
    """
    if quick and not _NOT_PLAIN.search(line):
        return
    for k, field in enumerate(line.split(",")):
        text = field.strip()
        column = names[k] if k < len(names) else f"{k + 1}"
        if not text:
            raise error(f"{where}, column {column}: empty value; every cell needs a number.")
        parse_number(text, f"{where}, column {column}", error)


@dataclass(frozen=True)
class Header:
    """The columns of a validated header line.

    Attributes
    ----------
    names : tuple of str
        Column names in file order.
    index : dict
        Column position of each name.
    """

    names: tuple[str, ...]
    index: dict[str, int]

    def numbered(self, prefix: str) -> list[int]:
        """Positions of the columns ``prefix0/1, prefix1/2, ...`` in number order."""
        found = sorted((int(n[len(prefix):]), i) for n, i in self.index.items()
                       if n.startswith(prefix) and n[len(prefix):].isdigit())
        return [i for _, i in found]

    def __contains__(self, name: str) -> bool:
        return name in self.index


def read_header(fields: Sequence[str], *, where: str, error: type[Exception], required: Sequence[str] = (),
                numbered: Sequence[tuple[str, int, str]] = (("s", 0, "raw channel"),), optional: Sequence[str] = (),
                allow_other: bool = False, expected: str = "") -> Header:
    """Validate a header's column names and return their positions.

    Parameters
    ----------
    fields : sequence of str
        The header split into names.
    where : str
        ``"file: line N"`` for the messages.
    error : exception class
        Raised for every problem (a ``ValueError`` subclass of the caller's domain).
    required : sequence of str
        Names that must be present.
    numbered : sequence of (prefix, first, what)
        Numbered families: ``("s", 0, "raw channel")`` means ``s0, s1, ...``
        from 0 without gaps; at least one column of each family is required.
    optional : sequence of str
        Further names that may be present.
    allow_other : bool
        Whether other (valid, unique) names are allowed and ignored.
    expected : str
        The layout shown in messages, e.g. ``"s0,...,s{N-1},Fx,...,Tz[,group]"``.

    Examples
    --------
    >>> h = read_header(["\\ufeffs0", "s1", "s2", "Fx"], where="d.csv: line 1", error=ValueError, required=["Fx"])
    >>> h.numbered("s"), h.index["Fx"]
    ([0, 1, 2], 3)
    >>> read_header(["s0", "s0", "s1"], where="d.csv: line 1", error=ValueError)
    Traceback (most recent call last):
    ...
    ValueError: d.csv: line 1: column 's0' appears 2 times; each column must be named once.
    """
    layout = f" Expected header: {expected}." if expected else ""
    names = [f.strip() for f in fields]
    if names and names[0].startswith(_BOM):
        names[0] = names[0][len(_BOM):].strip()
    if not names or names == [""]:
        raise error(f"{where}: empty header line.{layout}")
    for pos, name in enumerate(names):
        if not _NAME.fullmatch(name):
            shown = name.encode("ascii", "backslashreplace").decode()
            raise error(
                f"{where}: column {pos + 1} is named {shown!r}; column names must be ASCII letters, digits, '_' or "
                f"'-' (a look-alike character or an empty name would silently drop a column).{layout}"
            )
    twice = repeated_names(names)  # one pass: a header of 200 000 columns is read in linear time
    if twice:
        raise error(f"{where}: column {twice[0][0]!r} appears {twice[0][1]} times; each column must be named once.")
    index = {n: i for i, n in enumerate(names)}
    family_names: set[str] = set()
    for prefix, first, what in numbered:
        members = [n for n in names if n.startswith(prefix) and n[len(prefix):].isdigit()]
        family_names.update(members)
        zero_padded = [n for n in members if len(n) > len(prefix) + 1 and n[len(prefix)] == "0"]
        if zero_padded:
            raise error(f"{where}: column {zero_padded[0]!r}: write {what} numbers without leading zeros "
                        f"({prefix}{int(zero_padded[0][len(prefix):])}).")
        numbers = sorted(int(n[len(prefix):]) for n in members)
        if not numbers:
            raise error(f"{where}: the header names no {what} columns {prefix}{first}, {prefix}{first + 1}, ...{layout}")
        missing = sorted(set(range(first, numbers[-1] + 1)) - set(numbers))
        if missing:
            raise error(f"{where}: {what} column {prefix}{missing[0]} is missing (the header has "
                        f"{prefix}{numbers[0]}..{prefix}{numbers[-1]}); {what} columns must run from "
                        f"{prefix}{first} without gaps.")
        if numbers[0] != first:
            raise error(f"{where}: {what} columns must start at {prefix}{first}; the first is {prefix}{numbers[0]}.")
    absent = [n for n in required if n not in index]
    if absent:
        raise error(f"{where}: the header lacks columns {absent}.{layout}")
    if not allow_other:
        known = set(required) | set(optional) | family_names
        other = [n for n in names if n not in known]
        if other:
            raise error(f"{where}: unknown column {other[0]!r}.{layout}")
    return Header(names=tuple(names), index=index)


def repeated_names(names) -> list[tuple[str, int]]:
    """The names that appear more than once in ``names``, sorted, each with its count (one pass: linear time).

    Examples
    --------
    >>> repeated_names(["s1", "s0", "s1", "Fx", "s0", "s1"])
    [('s0', 2), ('s1', 3)]
    """
    from collections import Counter

    return sorted((n, k) for n, k in Counter(names).items() if k > 1)
