"""``python -m benchmarks.report``: re-runs the benchmarks and writes ``docs/benchmarks.md``.

    python -m benchmarks.report [--only NAME [NAME ...] | --no-run] [--list] [--mbm-dataset PATH]

Runs each benchmark of ``report_sections.SECTIONS`` (sizes chosen so that the whole report
takes about 20 minutes on two cores) in its own process, as ``python
benchmarks/<name>_benchmark.py ... --json FILE`` (``python -m planning.benchmark ... --report
FILE`` for the MotionBenchMaker problems, whose rows are summarised here), and keeps each
section's figures, with the date (UTC), the wall and CPU time, the load average and the machine
(CPU, cores, memory, OS, Python and package versions), in ``docs/benchmarks.json``. Then it
writes ``docs/benchmarks.md`` (every figure, as tables with units) and replaces the block
between ``<!-- benchmarks:start -->`` and ``<!-- benchmarks:end -->`` in ``README.md`` with the
headline figures (a warning, and the README untouched, when the markers are missing). Every
file is written atomically.

``--only`` re-runs the named sections and keeps the others as stored; ``--no-run`` runs nothing
and writes the document and the README's block again from the stored figures. A section whose
benchmark fails keeps its previous figures and says when and why the last attempt failed;
the exit code is then 1. Ctrl-C (or SIGTERM) stops the run: the sections measured by then are
written, the others stay as they were. Bad input (an unknown section, a malformed
``docs/benchmarks.json``) is one line on stderr and exit code 2.
"""

from __future__ import annotations

import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

from benchmarks import report_markdown as md
from benchmarks.report_sections import HEADLINES, NAMES, SECTIONS, Section, mbm_figures
from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "benchmarks.md"
STORE = ROOT / "docs" / "benchmarks.json"
README = ROOT / "README.md"
PACKAGES = ("drake", "numpy", "numba", "scipy")
"""Packages whose versions are stated with the machine."""


class SectionError(RuntimeError):
    """A benchmark ended with an error or wrote no figures (the message says why)."""


def utc_now() -> str:
    """The time now, UTC, as ``2026-11-29T07:41:05Z``."""
    return datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def machine() -> dict:
    """The machine: CPU model, cores, memory (GiB), OS, kernel, Python, package versions."""
    cpu = platform.processor() or platform.machine()
    memory = None
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(
                (ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), cpu
            )
        with open("/proc/meminfo") as f:
            kib = next((int(ln.split()[1]) for ln in f if ln.startswith("MemTotal:")), None)
        memory = None if kib is None else kib / 2**20
    except OSError:
        pass
    try:
        system = platform.freedesktop_os_release()["PRETTY_NAME"]
    except (OSError, KeyError, AttributeError):
        system = platform.system()
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "memory_gib": memory,
        "os": system,
        "kernel": f"{platform.system()} {platform.release()} {platform.machine()}",
        "python": platform.python_version(),
        "packages": {name: _version(name) for name in PACKAGES},
    }


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def command_argv(section: Section, mbm_dataset: Path | None = None) -> list[str]:
    """What follows ``python`` in the section's command (``--dataset`` for the MBM section)."""
    argv = list(section.argv)
    if section.name == "mbm" and mbm_dataset is not None:
        argv += ["--dataset", str(mbm_dataset)]
    return argv


def measure(section: Section, mbm_dataset: Path | None = None) -> dict:
    """Runs the section's benchmark in its own process; returns its record (figures, date,
    wall and CPU time, load average at the start, machine).

    Raises:
        SectionError: the benchmark failed or wrote no figures.
    """
    argv = command_argv(section, mbm_dataset)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    date = utc_now()
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "figures.json"
        start, before = time.perf_counter(), _children_cpu_s()
        done = subprocess.run(
            [sys.executable, *argv, section.output, str(out)],
            cwd=ROOT,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
        )
        wall, cpu = time.perf_counter() - start, _children_cpu_s() - before
        if done.returncode != 0 or not out.is_file():
            lines = (done.stderr.strip() or done.stdout.strip()).splitlines()
            reason = lines[-1] if lines else "no output"
            raise SectionError(f"exit code {done.returncode}: {reason}")
        try:
            data = json.loads(out.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise SectionError(f"its figures are not JSON ({e})") from None
    if section.output == "--report":  # planning.benchmark's rows, summarised here
        limit = argv[argv.index("--limit") + 1] if "--limit" in argv else "all"
        try:
            data = mbm_figures(data, limit=limit)
        except (KeyError, TypeError, AttributeError, ValueError) as e:
            raise SectionError(f"its report rows cannot be read ({e})") from None
    if not isinstance(data, dict) or not isinstance(data.get("tables"), list):
        raise SectionError("its figures have no tables")
    return {
        "title": section.title,
        "command": " ".join(["python", *argv]),
        "measured_utc": date,
        "wall_time_s": wall,
        "cpu_time_s": cpu,
        "load_average": load,
        "machine": machine(),
        **data,
    }


def _children_cpu_s() -> float:
    """CPU time (user + system, s) of this process's finished children and their own."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def load_store(path: Path) -> dict[str, dict]:
    """The stored records by section name ({} when the file does not exist).

    Raises:
        ConfigError: the file is not a figures file written by this report.
    """
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ConfigError(f"{path}: cannot be read as benchmark figures ({e})") from None
    sections = data.get("sections") if isinstance(data, dict) else None
    if not isinstance(sections, dict) or not all(isinstance(r, dict) for r in sections.values()):
        raise ConfigError(f"{path}: not a benchmark figures file (no 'sections' object)")
    return {name: record for name, record in sections.items() if name in NAMES}


def store_text(records: Mapping[str, Mapping]) -> str:
    """The records as strict JSON (NaN and infinities as null), sections in report order."""

    def finite(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {k: finite(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [finite(v) for v in value]
        return value

    ordered = {name: finite(records[name]) for name in NAMES if name in records}
    return json.dumps({"sections": ordered}, indent=1, allow_nan=False) + "\n"


def update(
    records: dict[str, dict], names: Sequence[str], measure_section: Callable[[Section], dict]
) -> tuple[list[str], list[str], bool]:
    """Re-measures the named sections into ``records``; returns (measured, failed, stopped).

    A failed section keeps its record, with ``last_failure``; a stop (Ctrl-C, SIGTERM) ends the
    loop and keeps what was measured.
    """
    measured, failed = [], []
    chosen = [s for s in SECTIONS if s.name in names]
    for index, section in enumerate(chosen, 1):
        print(
            f"[{index}/{len(chosen)}] {section.name}: python {' '.join(section.argv)}", flush=True
        )
        start = time.perf_counter()
        try:
            records[section.name] = measure_section(section)
            measured.append(section.name)
            print(f"    done in {md.duration_text(time.perf_counter() - start)}", flush=True)
        except SectionError as e:
            failed.append(section.name)
            failure = {"date_utc": utc_now(), "reason": str(e)}
            records[section.name] = {**records.get(section.name, {}), "last_failure": failure}
            print(f"    failed: {e}", file=sys.stderr, flush=True)
        except BaseException as e:
            if not cli.is_stop(e):
                raise
            print(f"stopped during {section.name}", file=sys.stderr, flush=True)
            return measured, failed, True
    return measured, failed, False


def write_outputs(records: Mapping[str, Mapping], *, doc: Path, store: Path, readme: Path) -> None:
    """Writes the figures file, the document, and the README's block (if it has the markers)."""
    write_atomic(store, store_text(records), "benchmark figures")
    write_atomic(doc, md.render_document(SECTIONS, records), "benchmarks document")
    if not readme.is_file():
        print(f"warning: {readme} not found: no headline figures written", file=sys.stderr)
        return
    block = md.render_readme_block(SECTIONS, records, HEADLINES, md.relative_link(doc, readme))
    text = md.replace_block(readme.read_text(), block)
    if text is None:
        print(
            f"warning: {readme} has no single {md.START_MARKER} ... {md.END_MARKER} block: "
            "left as it was",
            file=sys.stderr,
        )
    else:
        write_atomic(readme, text, "README")


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m benchmarks.report", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--only", nargs="+", choices=NAMES, metavar="NAME", help=f"of {', '.join(NAMES)}"
    )
    parser.add_argument(
        "--no-run",
        action="store_true",
        help="run nothing: write the document and the README's block from the stored figures",
    )
    parser.add_argument("--list", action="store_true", help="list the sections and their commands")
    parser.add_argument(
        "--mbm-dataset",
        type=cli.input_path("MBM dataset"),
        metavar="PATH",
        help="passed to planning.benchmark as --dataset (default: its own lookup)",
    )
    parser.add_argument(
        "--doc", type=cli.output_file("document"), default=DOC, help="default: docs/benchmarks.md"
    )
    parser.add_argument(
        "--store",
        type=cli.output_file("figures file"),
        default=STORE,
        help="default: docs/benchmarks.json",
    )
    parser.add_argument("--readme", type=Path, default=README, help="default: README.md")
    args = parser.parse_args(argv)
    if args.no_run and args.only:
        raise ConfigError("--no-run runs nothing: drop --only")
    return args


def main(argv=None) -> int:
    args = _parse_args(argv)
    if args.list:
        for section in SECTIONS:
            print(f"{section.name:14s} python {' '.join(command_argv(section, args.mbm_dataset))}")
        return cli.EXIT_OK
    records = load_store(args.store)  # a bad file fails before minutes of benchmarks
    if args.no_run:
        if not records:
            raise ConfigError(f"{args.store}: no stored figures to write (run without --no-run)")
        write_outputs(records, doc=args.doc, store=args.store, readme=args.readme)
        print(f"wrote {args.doc} from {args.store}")
        return cli.EXIT_OK
    started = time.perf_counter()
    measured, failed, stopped = update(
        records, args.only or NAMES, lambda s: measure(s, args.mbm_dataset)
    )
    if measured or failed:
        write_outputs(records, doc=args.doc, store=args.store, readme=args.readme)
        print(
            f"wrote {args.doc} and {args.store} ({md.duration_text(time.perf_counter() - started)})"
        )
    if stopped:
        return cli.EXIT_OK
    if failed:
        print(f"error: failed: {', '.join(failed)} (previous figures kept)", file=sys.stderr)
        return cli.EXIT_FAILED
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
