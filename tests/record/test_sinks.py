"""The CSV row format: six decimals, byte-stable, no negative zero."""

from __future__ import annotations

import random

from mobot_cli.record.sinks import CSV_COLUMNS, csv_row


def reference(values) -> str:
    texts = [f"{v:.6f}" for v in values]
    return ",".join("0.000000" if t == "-0.000000" else t for t in texts) + "\n"


def test_negative_zero_and_tiny_negatives_print_as_zero():
    values = (-0.0, -4e-7, 4e-7, -10.0, -0.5, -100.0000004) + (0.0,) * (len(CSV_COLUMNS) - 6)
    assert csv_row(values).startswith("0.000000,0.000000,0.000000,-10.000000,-0.500000,-100.000000,")


def test_matches_the_per_value_rule_on_random_rows():
    rng = random.Random(1)
    pool = [0.0, -0.0, -4e-7, 4e-7, -1e-9, -10.0, -0.5, 123.456789, -100.0000004]
    for _ in range(5000):
        values = tuple(rng.choice(pool + [rng.uniform(-50, 50)]) for _ in CSV_COLUMNS)
        assert csv_row(values) == reference(values)
