"""The sweep's results table: a CSV file with one row per rollout, saved as each rollout
finishes, so that a stopped sweep keeps every finished row and ``--resume`` knows which rollout
indices are done.

The table is rewritten whole and atomically (``drake_sim.base.files.write_atomic``) with each
new row: a stop or a crash at any moment leaves the table as it was before that row or after
it, never a truncated row, and never a header-only table where rows stood. A table is written
only once it has a row. (Rewriting costs the table's size per row: some hundred kilobytes for
a sweep of a few thousand rollouts, little next to a rollout.)

Cells are plain text: strings as they are, an absent value empty, everything else as JSON (so
``true``, ``0.25``, ``[0.5, 0.1, 0.04]`` read back as what they were).
"""

import csv
import io
import json
from pathlib import Path

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic

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
        with path.open(newline="", encoding="utf-8") as f:
            reader = csv.reader(f)
            header = next(reader, [])
            rows = [dict(zip(header, map(parse_cell, r), strict=False)) for r in reader if r]
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise ConfigError(f"{path}: cannot read the results table ({e})") from None
    return header, rows


class Table:
    """A results table being written, with the rollout indices it already holds.

    Args:
        path: the CSV file.
        header: its columns (``columns``).
        resume: keep the rows already there (their header must be ``header``), byte for byte;
            without it an existing table with rows is an error, never overwritten. A table
            with no rows (a header alone) is simply started again.

    Raises:
        ConfigError: the table exists without ``resume``, was written by another sweep, or
            cannot be read.
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
        self._data = b""  # The table's bytes as saved: the old rows kept as they were.
        if rows:
            try:
                self._data = path.read_bytes()
            except OSError as e:
                raise ConfigError(f"{path}: cannot read the results table ({e.strerror})") from None
            if not self._data.endswith(b"\n"):  # a last row cut short by an older writer
                self._data += b"\r\n"

    def append(self, row: dict) -> None:
        """Saves the table with one more row (missing columns empty), atomically.

        Raises:
            ConfigError: the table cannot be written; it is then as it was.
        """
        text = io.StringIO()
        writer = csv.writer(text)
        if not self._data:
            writer.writerow(self.header)
        writer.writerow([cell(row.get(key)) for key in self.header])
        data = self._data + text.getvalue().encode("utf-8")
        write_atomic(self.path, data, "results table")
        self._data = data
        self.done.add(row["index"])

    def close(self) -> None:
        """Nothing is left to write: every row was saved as it came."""
