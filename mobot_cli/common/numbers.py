"""Numbers as the run folder's files write them (CSV rows, results.csv)."""

from __future__ import annotations


def number(value: float) -> str:
    """Fixed six decimals, so that files compare byte for byte; never '-0.000000'."""
    text = f"{value:.6f}"
    return "0.000000" if text == "-0.000000" else text
