"""What scripts/plot_study.py and scripts/plot_federation.py share: reading their CSV input with
errors that name the file, line and column.

Runs with /usr/bin/python3; nothing beyond the standard library.
"""
import csv
import os


class InputError(Exception):
    """A missing file, a missing column or a value that is not what it should be."""


def read_table(path, columns):
    """Rows of a CSV file as (line number, dict), after checking that every column is present."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: file not found")
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames is None:
            raise InputError(f"{path}: empty file (expected a header with {', '.join(columns)})")
        missing = [c for c in columns if c not in reader.fieldnames]
        if missing:
            raise InputError(f"{path}: missing column(s) {', '.join(missing)} "
                             f"(header: {', '.join(reader.fieldnames)})")
        return [(i + 2, row) for i, row in enumerate(reader)]


def number(path, line, row, column):
    """A float from a cell ("inf", "nan" and "-inf" included), or InputError naming the cell."""
    text = (row.get(column) or "").strip()
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{path}:{line}: column {column}: not a number: {text!r}") from None


def flag(path, line, row, column):
    text = (row.get(column) or "").strip().lower()
    if text in ("1", "true"):
        return True
    if text in ("0", "false"):
        return False
    raise InputError(f"{path}:{line}: column {column}: expected 1 or 0, got {text!r}")
