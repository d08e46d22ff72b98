"""Argument types for the command line: numbers checked as they are parsed, with one-line errors."""

from __future__ import annotations

import argparse


def _number(text: str, kind: type, what: str) -> float:
    try:
        return kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, not {text!r}") from None


def integer(text: str) -> int:
    """Any whole number."""
    return int(_number(text, int, "a whole number"))


def positive_int(text: str) -> int:
    """A whole number ≥ 1."""
    v = int(_number(text, int, "a whole number"))
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ 1, not {v}")
    return v


def positive_float(text: str) -> float:
    """A finite number > 0."""
    v = _number(text, float, "a number")
    if not 0 < v < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, not {text}")
    return v


def nonneg_float(text: str) -> float:
    """A finite number ≥ 0."""
    v = _number(text, float, "a number")
    if not 0 <= v < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number ≥ 0, not {text}")
    return v
