"""Compare a value printed in a paper with a recomputed one, at the printed precision.

A printed "24.15" stands for any value in [24.145, 24.155]: the recomputed value agrees when
|x - printed| <= 0.5 * 10^-d (+ a tiny relative epsilon for binary floating point), d the
number of printed decimals. "<0.0001" (Design-Expert's p-value floor) agrees when x < 0.0001;
">" likewise. A printed percent sign and Unicode minus signs are accepted.
"""

from __future__ import annotations

import re

from soilcal.errors import InputError

_NUM = re.compile(r"^\s*([<>]=?)?\s*([+-]?)(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?\s*%?\s*$")


def parse_printed(printed: str) -> tuple[str | None, float, int]:
    """(comparison sign or None, value, decimals) of a printed number."""
    s = str(printed).replace("\u2212", "-").replace("\u2013", "-").replace(",", "").replace(" ", "")
    m = _NUM.match(s)
    if not m or (not m.group(3) and not m.group(4)):
        raise InputError(None, "printed", "a printed number like '24.15', '<0.0001', '2.10%'", printed)
    op, sign, ip, fp, ex = m.groups()
    value = float(f"{sign}{ip or '0'}.{fp or '0'}" + (f"e{ex}" if ex else ""))
    decimals = len(fp or "") - (int(ex) if ex else 0)
    return op, value, decimals


def compare_printed(printed: str, recomputed: float, rel_eps: float = 1e-9) -> tuple[bool, int]:
    """(agrees, decimals): does ``recomputed`` round to the printed string?"""
    op, value, decimals = parse_printed(printed)
    x = float(recomputed)
    if op == "<":
        return x < value, decimals
    if op == "<=":
        return x <= value, decimals
    if op == ">":
        return x > value, decimals
    if op == ">=":
        return x >= value, decimals
    tol = 0.5 * 10.0 ** (-decimals) + rel_eps * max(1.0, abs(x))
    return abs(x - value) <= tol, decimals


__all__ = ["compare_printed", "parse_printed"]
