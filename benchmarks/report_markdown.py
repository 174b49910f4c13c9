"""The Markdown of ``python -m benchmarks.report``: ``docs/benchmarks.md`` and the README's block.

Pure functions of the stored figures (``docs/benchmarks.json``), so that the tests render fake
figures. A section's record holds its ``title``, ``command``, ``measured_utc``, ``wall_time_s``,
``cpu_time_s``, ``load_average``, ``machine``, ``settings``, ``figures`` (named scalars) and
``tables``; a table is ``{"title", "columns": [[key, header, unit, format], ...], "rows":
[{key: value}], "note"}`` (``format`` a Python format spec such as ``".3f"``, empty for
``str(value)``).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

START_MARKER = "<!-- benchmarks:start -->"
END_MARKER = "<!-- benchmarks:end -->"


@dataclass(frozen=True)
class Headline:
    """One line of the README's block: ``text`` formatted with the section's settings and
    figures (``"{real_time_factor:.1f}x real time"``); left out when a figure is missing."""

    section: str
    text: str


def slug(title: str) -> str:
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces as hyphens."""
    return re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")


def format_cell(value, spec: str = "") -> str:
    """One table cell: ``-`` for nothing, yes/no, numbers with ``spec``, lists joined by commas."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, str):
        return value.replace("|", "\\|")
    if isinstance(value, list | tuple):
        return ", ".join(format_cell(item, spec) for item in value)
    if isinstance(value, float) and math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return format(value, spec) if spec else str(value)


def render_table(table: Mapping) -> str:
    """A Markdown table, headers with their units, numeric columns right-aligned."""
    columns = table["columns"]
    rows = table["rows"]
    headers = [f"{header} ({unit})" if unit else header for _, header, unit, _ in columns]
    aligns = []
    for key, *_ in columns:
        values = [row.get(key) for row in rows if row.get(key) is not None]
        numeric = values and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in values
        )
        aligns.append("---:" if numeric else "---")
    lines = []
    if table.get("title"):
        lines += [f"**{table['title']}**", ""]
    lines.append("| " + " | ".join(headers) + " |")
    lines.append("|" + "|".join(aligns) + "|")
    for row in rows:
        cells = (format_cell(row.get(key), spec) for key, _, _, spec in columns)
        lines.append("| " + " | ".join(cells) + " |")
    if table.get("note"):
        lines += ["", table["note"]]
    return "\n".join(lines)


def duration_text(seconds: float) -> str:
    """``"42 s"``, ``"3 min 5 s"``."""
    seconds = round(seconds)
    return f"{seconds} s" if seconds < 60 else f"{seconds // 60} min {seconds % 60} s"


def utc_text(iso: str) -> str:
    """``2026-11-29T07:41:05Z`` as ``2026-11-29 07:41 UTC``."""
    return f"{iso[:10]} {iso[11:16]} UTC"


def machine_line(machine: Mapping) -> str:
    """The machine in one line: CPU, cores, memory, OS."""
    return (
        f"{machine.get('cpu', '?')}, {machine.get('cores', '?')} cores, "
        f"{format_cell(machine.get('memory_gib'), '.1f')} GiB, {machine.get('os', '?')}"
    )


def machine_table(machine: Mapping) -> str:
    """The machine as a two-column table: CPU, memory, OS, Python and package versions."""
    packages = machine.get("packages", {})
    rows = [
        {"item": "CPU", "value": f"{machine.get('cpu', '?')}, {machine.get('cores', '?')} cores"},
        {"item": "memory", "value": f"{format_cell(machine.get('memory_gib'), '.1f')} GiB"},
        {"item": "OS", "value": machine.get("os", "?")},
        {"item": "kernel", "value": machine.get("kernel", "?")},
        {"item": "Python", "value": machine.get("python", "?")},
        *(
            {"item": name, "value": version or "not installed"}
            for name, version in packages.items()
        ),
    ]
    columns = [["item", "item", "", ""], ["value", "value", "", ""]]
    return render_table({"columns": columns, "rows": rows})


def render_section(name: str, title: str, about: str, record: Mapping | None, *, machine) -> str:
    """One section: heading, command, when it was measured (wall and CPU time, load average),
    what it measures, its tables."""
    lines = [f"## {title}", ""]
    if record is None or "tables" not in record:
        lines.append(f"Not measured yet: `python -m benchmarks.report --only {name}`.")
    else:
        load = record.get("load_average")
        load_text = "" if load is None else f", load average {load:.1f} at the start"
        cpu = record.get("cpu_time_s")
        cpu_text = "" if cpu is None else f" ({duration_text(cpu)} of CPU time)"
        lines.append(
            f"`{record['command']}`: measured {utc_text(record['measured_utc'])}, "
            f"{duration_text(record['wall_time_s'])} of wall time{cpu_text}{load_text}."
        )
        if record.get("machine") and record["machine"] != machine:
            lines.append(f"Machine: {machine_line(record['machine'])}.")
    failure = (record or {}).get("last_failure")
    if failure:
        lines += [
            "",
            f"The last attempt, {utc_text(failure['date_utc'])}, failed: {failure['reason']}",
        ]
    lines += ["", about]
    for table in (record or {}).get("tables", []):
        lines += ["", render_table(table)]
    return "\n".join(lines)


def render_document(sections: Sequence, records: Mapping[str, Mapping]) -> str:
    """``docs/benchmarks.md``: ``sections`` (objects with ``name``, ``title``, ``about``) in
    order, with the records stored for them."""
    measured = [records[s.name] for s in sections if "tables" in records.get(s.name, {})]
    latest = max(measured, key=lambda r: r["measured_utc"], default=None)
    machine = latest["machine"] if latest else {}
    lines = [
        "# Benchmarks",
        "",
        "Written by `python -m benchmarks.report`, which re-runs the benchmarks and keeps their",
        "figures in [benchmarks.json](benchmarks.json); do not edit by hand. `--only NAME ...`",
        "re-runs some sections and keeps the others as they were measured. Each section names",
        "the command that printed its figures (the report adds `--json FILE` to collect them),",
        "when it ran, its wall time and CPU time, and the 1-minute load average when it started:",
        "times and real-time factors depend on the machine and on what else runs on it (a wall",
        "time well above the CPU time of a one-process benchmark means it waited for a core).",
    ]
    if measured:
        first, last = min(r["measured_utc"] for r in measured), latest["measured_utc"]
        when = utc_text(first) if first == last else f"from {utc_text(first)} to {utc_text(last)}"
        lines += [
            "",
            f"Measured {when} on:",
            "",
            machine_table(machine),
        ]
    lines += ["", "## Contents", ""]
    for s in sections:
        record = records.get(s.name, {})
        when = utc_text(record["measured_utc"]) if "tables" in record else "not measured"
        lines.append(f"- [{s.title}](#{slug(s.title)}) (`--only {s.name}`, {when})")
    for s in sections:
        body = render_section(s.name, s.title, s.about, records.get(s.name), machine=machine)
        lines += ["", body]
    return "\n".join(lines) + "\n"


def headline_values(headline: Headline, record: Mapping) -> str | None:
    """The headline's text with the record's settings and figures, or None if one is missing."""
    values = {**record.get("settings", {}), **record.get("figures", {})}
    try:
        return headline.text.format(**values)
    except (KeyError, IndexError, TypeError, ValueError):
        return None


def render_readme_block(
    sections: Sequence, records: Mapping[str, Mapping], headlines: Sequence[Headline], link: str
) -> str:
    """The README's block: a table of headline figures, each linking to its section at
    ``link`` (the path of docs/benchmarks.md from the README)."""
    titles = {s.name: s.title for s in sections}
    rows, dates, machine = [], [], None
    for headline in headlines:
        record = records.get(headline.section, {})
        text = headline_values(headline, record) if "tables" in record else None
        if text is None:
            continue
        title = titles[headline.section]
        rows.append(f"| [{title}]({link}#{slug(title)}) | {text} |")
        dates.append(record["measured_utc"][:10])
        machine = record.get("machine") or machine
    if not rows:
        return f"No benchmark figures yet: run `python -m benchmarks.report` ([figures]({link}))."
    when = min(dates) if min(dates) == max(dates) else f"{min(dates)} to {max(dates)}"
    lines = [
        f"Measured {when} (UTC) by `python -m benchmarks.report` on {machine_line(machine or {})}.",
        f"Every figure, the commands and the machine: [docs/benchmarks.md]({link}).",
        "",
        "| benchmark | figures |",
        "|---|---|",
        *rows,
    ]
    return "\n".join(lines)


def replace_block(text: str, block: str) -> str | None:
    """``text`` with what lies between the markers replaced by ``block``; None when the
    markers are missing, repeated or out of order."""
    if text.count(START_MARKER) != 1 or text.count(END_MARKER) != 1:
        return None
    start = text.index(START_MARKER) + len(START_MARKER)
    end = text.index(END_MARKER)
    if end < start:
        return None
    return f"{text[:start]}\n{block}\n{text[end:]}"


def relative_link(target: Path, start: Path) -> str:
    """The path of ``target`` from the folder of ``start``, with forward slashes."""
    return Path(os.path.relpath(target.resolve(), start.resolve().parent)).as_posix()
