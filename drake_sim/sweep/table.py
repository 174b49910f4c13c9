"""The sweep's results table: a CSV file with one row per rollout, appended and flushed as each
rollout finishes, so that a stopped sweep keeps every finished row and ``--resume`` knows which
rollout indices are done.

Cells are plain text: strings as they are, an absent value empty, everything else as JSON (so
``true``, ``0.25``, ``[0.5, 0.1, 0.04]`` read back as what they were).
"""

import csv
import json
from pathlib import Path

from drake_sim.base.errors import ConfigError

TABLE_FILE = "results.csv"
FIRST_COLUMNS = ("index", "status", "success", "seed")
LAST_COLUMNS = ("wall_time_s", "worker", "reason")


def columns(parameters, metrics) -> list[str]:
    """The table's header: the rollout, its parameters, its metrics, then how it ran."""
    return [*FIRST_COLUMNS, *parameters, *metrics, *LAST_COLUMNS]


def cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, str):
        return value
    return json.dumps(value)


def parse_cell(text: str):
    if text == "":
        return None
    try:
        return json.loads(text)
    except ValueError:
        return text


def read_rows(path: Path) -> tuple[list[str], list[dict]]:
    """The header and rows (cells parsed) of a table; ([], []) when it does not exist."""
    if not path.exists():
        return [], []
    try:
        with path.open(newline="") as f:
            reader = csv.reader(f)
            header = next(reader, [])
            rows = [dict(zip(header, map(parse_cell, r), strict=False)) for r in reader if r]
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise ConfigError(f"{path}: cannot read the results table ({e})") from None
    return header, rows


class Table:
    """An open results table, with the rollout indices it already holds.

    Args:
        path: the CSV file.
        header: its columns (``columns``).
        resume: keep the rows already there (their header must be ``header``); without it an
            existing table with rows is an error, never overwritten. A table with no rows (a
            sweep that stopped before its first rollout finished) is simply started again.

    Raises:
        ConfigError: the table exists without ``resume``, was written by another sweep, or
            cannot be written.
    """

    def __init__(self, path: Path, header: list[str], *, resume: bool):
        self.path = path
        self.header = header
        old_header, rows = read_rows(path)
        if rows and not resume:
            raise ConfigError(f"{path} exists: pass --resume to continue it, or another --out")
        if rows and old_header != header:
            raise ConfigError(
                f"{path}: its columns are not this sweep's (another sweep file?): use another --out"
            )
        self.done = {row["index"] for row in rows}
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._file = path.open("a" if rows else "w", newline="")
        except OSError as e:
            raise ConfigError(f"{path}: cannot write the results table ({e.strerror})") from None
        self._writer = csv.writer(self._file)
        if not rows:
            self._writer.writerow(header)
            self._file.flush()

    def append(self, row: dict) -> None:
        """Writes one row (missing columns empty) and flushes it to disk."""
        self._writer.writerow([cell(row.get(key)) for key in self.header])
        self._file.flush()
        self.done.add(row["index"])

    def close(self) -> None:
        self._file.close()
