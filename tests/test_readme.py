"""The README and the pages under docs/: every command of the project's own entry points that
they give parses with that entry point's real options, in document order; the README stays a
front door; no commit ids, issue references or "this VM"; every relative link points to a file.

Commands are taken from fenced code blocks and backticked spans: ``python -m MODULE ARGS`` for
the project's modules (``drake_sim.*``, ``planning.*``, ``benchmarks.*``) and ``python
benchmarks/X.py ARGS``. Each is checked in a temporary working directory that mirrors the
repository's sources: the files that the same document's earlier commands write (their output
options, and the map files and sweep tables they write by default) are created there first as
placeholders, in document order, so that a command reading a file nothing before it makes (a
``--map maps/room.yaml`` before any mapping run) fails here as it would for a reader. Nothing
is simulated: the modules are imported and their argument parsers run.
"""

import argparse
import contextlib
import dataclasses as dc
import importlib
import importlib.util
import inspect
import io
import os
import re
import shlex
import sys
from pathlib import Path

import pytest
import yaml

import drake_sim.runs.explore as explore_app
import drake_sim.runs.mapping as mapping_app
from drake_sim.runs import command as run_command

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
DOCS = (README, *sorted((ROOT / "docs").glob("*.md")))
GENERATED_PAGES = ("docs/benchmarks.md",)
"""Pages another command writes (``python -m benchmarks.report``): a link to one of them may
point nowhere in a checkout that has not generated it yet."""

README_MAX_LINES = 300
QUICKSTART = (
    "pip install -e . && python -m drake_sim.flip",
    "pip install -e '.[test]' && python -m pytest",
)
"""The Quickstart's two commands, verbatim (the CI runs the second as it is written)."""

SOURCES = (
    "README.md",
    "benchmarks",
    "config",
    "diagrams",
    "docs",
    "drake_sim",
    "models",
    "notebooks",
    "planning",
    "pyproject.toml",
    "tests",
)
"""The repository's entries that a documented command may read as it stands; outputs that a
developer's checkout may hold (``maps/``, ``sweeps/``, reports) are deliberately not here."""

PROJECT_PACKAGES = ("drake_sim", "planning", "benchmarks")
PYTHONS = ("python", "python3")
SEPARATORS = {"&&", "||", ";", "|", "&"}
REDIRECTIONS = {">", ">>", "<", ">|", "&>"}
PLACEHOLDER = "placeholder written by tests/test_readme.py\n"

FENCE = re.compile(r"^ {0,3}(```|~~~)[^\n]*\n(.*?)^ {0,3}\1[ \t]*$", re.S | re.M)
SPAN = re.compile(r"(`+)(.+?)\1", re.S)
LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HTML_SRC = re.compile(r"""<(?:img|a|source)\b[^>]*?\b(?:src|href)=["']([^"']+)["']""", re.I)
HEADING = re.compile(r"^ {0,3}#{1,6}[ \t]+(.+?)[ \t#]*$", re.M)

FORBIDDEN = {
    "a commit id": re.compile(r"(?<![0-9A-Za-z])[0-9a-f]{40}(?![0-9A-Za-z])"),
    "an abbreviated commit id": re.compile(
        r"(?<![0-9A-Za-z.\-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,12}(?![0-9A-Za-z])"
    ),
    "an issue reference": re.compile(r"(?<![\w&/])#\d+\b"),
    '"this VM"': re.compile(r"\bthis\s+VM\b", re.I),
}


@dc.dataclass
class Command:
    """One documented command: ``python -m module args`` or ``python script args``."""

    document: Path
    line: int
    text: str
    module: str | None
    script: str | None
    args: list[str]
    redirected_to: list[str] = dc.field(default_factory=list)  # ``> FILE``: files it writes

    def where(self) -> str:
        return f"{self.document.relative_to(ROOT)}:{self.line}: {self.text}"


# Reading the documents ---------------------------------------------------------------------


def _code_pieces(text: str) -> list[tuple[int, str]]:
    """The fenced blocks' contents and the backticked spans outside them, as ``(offset,
    text)`` in document order."""
    pieces = []
    covered = []
    for match in FENCE.finditer(text):
        pieces.append((match.start(2), match.group(2)))
        covered.append((match.start(), match.end()))
    outside = list(text)
    for start, end in covered:
        outside[start:end] = " " * (end - start)
    for match in SPAN.finditer("".join(outside)):
        pieces.append((match.start(2), " ".join(match.group(2).split())))
    return sorted(pieces)


def _shell_commands(code: str) -> list[tuple[int, list[str], list[str]]]:
    """The simple commands of a shell snippet, as ``(line offset in code, tokens, files its
    output is redirected to)``: lines joined at a trailing backslash, comments, prompts and
    ``&&``, ``|``, ``;`` split off, ``> FILE`` taken out of the tokens."""
    commands = []
    lines = code.split("\n")
    index = 0
    while index < len(lines):
        first = index
        line = lines[index]
        while line.rstrip().endswith("\\") and index + 1 < len(lines):
            index += 1
            line = line.rstrip()[:-1] + " " + lines[index]
        index += 1
        line = re.sub(r"^\s*\$\s+", "", line)
        lexer = shlex.shlex(line, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        try:
            tokens = list(lexer)
        except ValueError:  # unbalanced quotes: not shell (a Python or YAML line)
            continue
        current: list[str] = []
        written: list[str] = []
        tokens = [*tokens, ";"]
        while tokens:
            token = tokens.pop(0)
            if token in SEPARATORS:
                if current:
                    commands.append((first, current, written))
                current, written = [], []
            elif token in REDIRECTIONS:
                target = tokens.pop(0) if tokens and tokens[0] not in SEPARATORS else ""
                if token.startswith(">") and target:
                    written.append(target)
            else:
                current.append(token)
    return commands


def _as_command(document: Path, line: int, tokens: list[str], written: list[str]) -> Command | None:
    """A ``Command`` when ``tokens`` run one of the project's entry points, else None."""
    while tokens and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*=\S*", tokens[0]):
        tokens = tokens[1:]  # environment assignments
    if len(tokens) < 2 or tokens[0] not in PYTHONS:
        return None
    text = shlex.join(tokens)
    if tokens[1] == "-m" and len(tokens) > 2:
        if tokens[2].split(".")[0] not in PROJECT_PACKAGES:
            return None  # pip, pytest, venv, ...
        return Command(document, line, text, tokens[2], None, tokens[3:], written)
    if tokens[1].startswith("benchmarks/") and tokens[1].endswith(".py"):
        return Command(document, line, text, None, tokens[1], tokens[2:], written)
    return None


def documented_commands(document: Path, text: str | None = None) -> list[Command]:
    """Every command of the project's entry points in ``document``, in document order."""
    text = document.read_text() if text is None else text
    commands = []
    for offset, code in _code_pieces(text):
        first_line = text.count("\n", 0, offset) + 1
        for line, tokens, written in _shell_commands(code):
            command = _as_command(document, first_line + line, tokens, written)
            if command is not None:
                commands.append(command)
    return commands


# Checking a command against its entry point ------------------------------------------------


class _Parsed(BaseException):
    """Raised by the patched ``parse_args`` to stop a ``main`` as soon as it has parsed."""


class _RefusedError(Exception):
    """A documented command that its entry point would refuse: the message says why."""


def _entry_module(command: Command):
    """The module that ``python -m`` or ``python script`` would run, imported."""
    if command.script is not None:
        path = ROOT / command.script
        if not path.is_file():
            raise _RefusedError(f"no such script: {command.script}")
        name = "_documented_" + re.sub(r"\W", "_", command.script)
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.path.insert(0, str(path.parent))  # as ``python benchmarks/X.py`` has it
        try:
            spec.loader.exec_module(module)
        except Exception as e:
            raise _RefusedError(f"{command.script} fails to import: {_one_line(e)}") from None
        finally:
            sys.path.remove(str(path.parent))
        return module
    try:
        spec = importlib.util.find_spec(command.module)
    except ModuleNotFoundError:
        spec = None
    if spec is None:
        raise _RefusedError(f"no module named {command.module}")
    name = command.module
    if spec.submodule_search_locations is not None:  # a package runs its __main__
        name += ".__main__"
        if importlib.util.find_spec(name) is None:
            raise _RefusedError(f"{command.module} is a package without __main__")
    try:
        module = importlib.import_module(name)
    except Exception as e:
        raise _RefusedError(f"{name} fails to import: {_one_line(e)}") from None
    source = inspect.getsource(module)
    if '__name__ == "__main__"' not in source:
        raise _RefusedError(f"{name} runs nothing as a script (no __main__ block)")
    forwarded = re.search(r'runpy\.run_module\(\s*"([\w.]+)"', source)  # a name for another app
    return importlib.import_module(forwarded.group(1)) if forwarded else module


def _one_line(error: Exception) -> str:
    return f"{type(error).__name__}: {' '.join(str(error).split())}"


def _load_scenario(module, args: argparse.Namespace):
    """The inputs of an app's command line, as the app loads them (its recipe's one loader:
    files, ``--set``, flags and seed; nothing built)."""
    return run_command.load_from_args(module.RECIPE, args)


def _placeholders(args: argparse.Namespace) -> list[Path]:
    """The options' files that are placeholders for what an earlier command writes."""
    paths = [v for v in vars(args).values() if isinstance(v, Path) and v.is_file()]
    return [
        p for p in paths if p.stat().st_size == len(PLACEHOLDER) and p.read_text() == PLACEHOLDER
    ]


def _parse(module, args: list[str]) -> tuple[argparse.Namespace, argparse.ArgumentParser]:
    """Runs the entry point's own argument parsing on ``args`` (its ``_parse_args`` where it
    has one, with the checks that follow the parser; else its ``main`` stopped right after
    ``parse_args``). With ``--set``, also applies the overrides to the app's scenario as the
    app does (its ``load_scenario``: files and keys, nothing built); a failure there counts
    unless it is about a placeholder's contents. Returns the options and the parser."""
    seen = []
    original = argparse.ArgumentParser.parse_args

    def parse_args(self, *a, **k):
        seen.append(self)
        return original(self, *a, **k)

    main = getattr(module, "main", None)
    home = sys.modules.get(getattr(main, "__module__", None), module)
    parse = getattr(home, "_parse_args", None) or getattr(module, "_parse_args", None)
    stderr = io.StringIO()
    patch = pytest.MonkeyPatch()
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            if parse is not None:
                patch.setattr(argparse.ArgumentParser, "parse_args", parse_args)
                namespace = parse(list(args))
            elif main is not None:

                def parse_and_stop(self, *a, **k):
                    raise _Parsed(parse_args(self, *a, **k))

                patch.setattr(argparse.ArgumentParser, "parse_args", parse_and_stop)
                patch.setattr(sys, "argv", [module.__name__, *args])
                try:
                    main(list(args)) if inspect.signature(main).parameters else main()
                except _Parsed as e:
                    namespace = e.args[0]
                else:  # main caught the parser's error itself (cli.run) and said why
                    lines = [line for line in stderr.getvalue().splitlines() if line.strip()]
                    raise _RefusedError(lines[-1] if lines else "main() returned before parsing")
            else:
                raise _RefusedError(f"{module.__name__} has neither _parse_args nor main")
            check = _load_scenario if hasattr(home, "RECIPE") else None
            if check is not None and getattr(namespace, "set", None):
                try:
                    check(home, namespace)
                except Exception as e:  # unless it is about a placeholder's contents
                    if not any(str(p) in str(e) for p in _placeholders(namespace)):
                        raise
    except SystemExit as e:
        if e.code not in (0, None):
            lines = [line for line in stderr.getvalue().splitlines() if line.strip()]
            raise _RefusedError(lines[-1] if lines else f"exit code {e.code}") from None
        raise _RefusedError("the command only prints its help") from None
    except Exception as e:  # ConfigError from cli.ArgumentParser and the post-parse checks
        if isinstance(e, _RefusedError):
            raise
        raise _RefusedError(_one_line(e)) from None
    finally:
        patch.undo()
    if not seen:
        raise _RefusedError("no argparse parser ran")
    return namespace, seen[-1]


def _outputs(command: Command, args: argparse.Namespace, parser) -> list[tuple[Path, bool]]:
    """What the command writes, as ``(path, is_folder)``: its ``output_file`` and
    ``output_dir`` options, and the files an entry point writes by default."""
    written = []
    for action in parser._actions:
        value = getattr(args, action.dest, None)
        kind = getattr(action.type, "__qualname__", "")
        if value is None or action.dest in _DEFAULT_OUTPUTS.get(command.module, {}):
            continue
        if kind.startswith("output_file."):
            written.append((Path(value), False))
        elif kind.startswith("output_dir."):
            written.append((Path(value), True))
    for rule in _DEFAULT_OUTPUTS.get(command.module, {}).values():
        written.extend(rule(args))
    written.extend((Path(target), False) for target in command.redirected_to)
    return written


def _mapping_outputs(args) -> list[tuple[Path, bool]]:
    """``python -m drake_sim.mapping`` writes ``--out``'s (default ``maps/<arena>``) ``.yaml``
    and ``.pgm``."""
    out = args.out
    if out is None:
        arena = args.arena
        if arena is None:  # the scenario's
            path = args.scenario or mapping_app.RECIPE.scenario.default_file()
            scenario = yaml.safe_load(Path(path).read_text())
            arena = scenario.get("arena") if isinstance(scenario, dict) else None
        if arena is None:
            return []
        out = Path("maps") / Path(arena).stem
    return [(Path(f"{out}.yaml"), False), (Path(f"{out}.pgm"), False)]


def _explore_outputs(args) -> list[tuple[Path, bool]]:
    """``python -m drake_sim.explore`` writes ``--out``'s (default ``maps/<place>_explored``,
    the place the arena or the ``--world`` map) ``.yaml`` and ``.pgm``."""
    out = args.out
    if out is None:
        place = args.world or args.arena
        if place is None:  # the scenario's
            path = args.scenario or explore_app.RECIPE.scenario.default_file()
            scenario = yaml.safe_load(Path(path).read_text())
            place = scenario.get("arena") if isinstance(scenario, dict) else None
        if place is None:
            return []
        out = Path("maps") / f"{Path(place).stem}_explored"
    return [(Path(f"{out}.yaml"), False), (Path(f"{out}.pgm"), False)]


def _sweep_outputs(args) -> list[tuple[Path, bool]]:
    """``python -m drake_sim.sweep SWEEP.yaml`` writes ``--out`` (default
    ``sweeps/<name>/``) with its ``results.csv``."""
    if args.sweep is None:
        return []
    out = args.out
    if out is None:
        name = (yaml.safe_load(Path(args.sweep).read_text()) or {}).get("name")
        out = Path("sweeps") / (name or Path(args.sweep).stem)
    return [(Path(out), True), (Path(out) / "results.csv", False)]


_DEFAULT_OUTPUTS = {
    "drake_sim.mapping": {"out": _mapping_outputs},
    "drake_sim.explore": {"out": _explore_outputs},
    "drake_sim.sweep": {"out": _sweep_outputs},
}
"""Per module, the options whose outputs an entry point names itself (replacing the generic
rule for that option): functions of the parsed options."""


class Workspace:
    """A temporary working directory that mirrors the repository's ``SOURCES`` by symbolic
    links; ``add`` writes a placeholder output there without touching the repository (a linked
    folder on the way is replaced by a real folder of links first)."""

    def __init__(self, folder: Path):
        folder.mkdir(parents=True, exist_ok=True)
        self.folder = folder.resolve()
        for name in SOURCES:
            if (ROOT / name).exists():
                (folder / name).symlink_to(ROOT / name)

    def add(self, path: Path, is_folder: bool) -> None:
        target = Path(os.path.normpath(self.folder / path))  # not resolved: links stay links
        if self.folder not in target.parents:
            return  # outside the workspace: nothing a later command of the page can rely on
        node = self.folder
        for part in target.relative_to(node).parts[:-1]:
            node = node / part
            self._unlink_folder(node)
            node.mkdir(exist_ok=True)
        if target.is_symlink():
            target.unlink()
        if is_folder:
            self._unlink_folder(target)
            target.mkdir(parents=True, exist_ok=True)
        else:
            target.write_text(PLACEHOLDER)

    @staticmethod
    def _unlink_folder(node: Path) -> None:
        """Turns a symbolic link to a folder into a real folder of links to its entries."""
        if node.is_symlink() and node.is_dir():
            source = node.resolve()
            node.unlink()
            node.mkdir()
            for entry in source.iterdir():
                (node / entry.name).symlink_to(entry)


def _stand_in_problems(folder: Path) -> Path:
    """A placeholder MotionBenchMaker set (one scene file per family), which
    ``python -m planning.benchmark``'s option checks find through ``DRAKE_SIM_MBM`` instead of
    downloading the real one."""
    from planning.io import mbm

    for family in mbm.FAMILIES:
        (folder / family).mkdir(parents=True, exist_ok=True)
        (folder / family / "scene0001.yaml").write_text(PLACEHOLDER)
    return folder


def check_commands(commands: list[Command], folder: Path, monkeypatch) -> list[str]:
    """Checks ``commands`` in order in a ``Workspace`` at ``folder/workspace``; returns one
    line per command that its entry point would refuse. Nothing is downloaded: the
    MotionBenchMaker problems are a stand-in set."""
    monkeypatch.setenv("DRAKE_SIM_MBM", str(_stand_in_problems(folder / "mbm")))
    folder = folder / "workspace"
    workspace = Workspace(folder)
    # Imports resolve from the repository, never from the workspace's links to it.
    monkeypatch.setattr(sys, "path", [str(ROOT) if p in ("", ".") else p for p in sys.path])
    monkeypatch.chdir(folder)
    problems = []
    for command in commands:
        try:
            module = _entry_module(command)
            args, parser = _parse(module, command.args)
        except _RefusedError as e:
            problems.append(f"{command.where()}\n    {e}")
            continue
        for path, is_folder in _outputs(command, args, parser):
            workspace.add(path, is_folder)
    return problems


# The tests ---------------------------------------------------------------------------------


@pytest.mark.parametrize("document", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_documented_command_parses_in_document_order(document, tmp_path, monkeypatch):
    commands = documented_commands(document)
    problems = check_commands(commands, tmp_path, monkeypatch)
    assert problems == [], "commands their entry points refuse:\n" + "\n".join(problems)


def test_the_readme_gives_the_quickstart_verbatim_and_the_apps_commands():
    text = README.read_text()
    for command in QUICKSTART:
        assert f"\n{command}\n" in text, f"the Quickstart's command is missing: {command}"
    modules = {c.module for c in documented_commands(README)}
    for app in ("flip", "pickplace", "walle", "mapping", "navigate", "sweep"):
        assert f"drake_sim.{app}" in modules, f"the README gives no drake_sim.{app} command"


def test_the_readme_is_a_front_door():
    lines = README.read_text().splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines"
    text = "\n".join(lines)
    assert "<!-- benchmarks:start -->" in text and "<!-- benchmarks:end -->" in text
    assert text.index("<!-- benchmarks:start -->") < text.index("<!-- benchmarks:end -->")
    assert "pip install -e '.[notebooks]'" in text


@pytest.mark.parametrize("document", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_development_log_in_the_docs(document):
    text = document.read_text()
    found = []
    for what, pattern in FORBIDDEN.items():
        for match in pattern.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            found.append(f"{document.relative_to(ROOT)}:{line}: {what}: {match.group(0)!r}")
    assert found == [], "\n".join(found)


def _anchors(page: Path) -> set[str]:
    """GitHub's anchors of a Markdown page's headings."""
    anchors = set()
    counts: dict[str, int] = {}
    for match in HEADING.finditer(re.sub(FENCE, "", page.read_text())):
        title = re.sub(r"`|\*\*|\[([^\]]*)\]\([^)]*\)", r"\1", match.group(1))
        slug = re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")
        n = counts.get(slug, 0)
        counts[slug] = n + 1
        anchors.add(slug if n == 0 else f"{slug}-{n}")
    return anchors


def relative_links(document: Path) -> list[tuple[int, str]]:
    """The relative link and image targets of a Markdown page (outside code), with lines."""
    text = document.read_text()
    for match in FENCE.finditer(text):  # code is not links; keep the line numbers
        text = text[: match.start()] + re.sub(r"[^\n]", " ", match.group(0)) + text[match.end() :]
    text = re.sub(SPAN, lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)
    links = []
    for pattern in (LINK, HTML_SRC):
        for match in pattern.finditer(text):
            target = match.group(1)
            if re.match(r"[a-z][a-z0-9+.\-]*:", target, re.I):
                continue  # https:, mailto:, ...
            links.append((text.count("\n", 0, match.start()) + 1, target))
    return sorted(links)


@pytest.mark.parametrize("document", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_points_to_a_file(document):
    broken = []
    for line, target in relative_links(document):
        path_text, _, anchor = target.partition("#")
        path = (document.parent / path_text).resolve() if path_text else document
        where = f"{document.relative_to(ROOT)}:{line}: {target}"
        relative = path.relative_to(ROOT).as_posix() if ROOT in path.parents else None
        if not path.exists():
            if relative not in GENERATED_PAGES:
                broken.append(f"{where}: no such file")
            continue
        if anchor and path.suffix == ".md" and anchor not in _anchors(path):
            broken.append(f"{where}: no heading with that anchor")
    assert broken == [], "\n".join(broken)


def test_the_docs_link_every_page_from_the_readme():
    linked = {(README.parent / t.partition("#")[0]).resolve() for _, t in relative_links(README)}
    for page in DOCS[1:]:
        assert page.resolve() in linked, f"README.md does not link {page.relative_to(ROOT)}"


# The checker itself ------------------------------------------------------------------------


def test_commands_are_taken_from_blocks_and_spans_in_order():
    text = (
        "Run `python -m drake_sim.flip --headless` first.\n\n"
        "```bash\n"
        "pip install -e . && python -m drake_sim.mapping --headless \\\n"
        "    --out maps/x   # a comment\n"
        "python -m pytest -q\n"
        "python benchmarks/flip_benchmark.py --runs 1 | tee out.txt\n"
        "python -m drake_sim.pickplace --print-scenario > mine.yaml\n"
        "```\n"
    )
    commands = documented_commands(README, text)
    assert [(c.line, c.module, c.script, c.args, c.redirected_to) for c in commands] == [
        (1, "drake_sim.flip", None, ["--headless"], []),
        (4, "drake_sim.mapping", None, ["--headless", "--out", "maps/x"], []),
        (7, None, "benchmarks/flip_benchmark.py", ["--runs", "1"], []),
        (8, "drake_sim.pickplace", None, ["--print-scenario"], ["mine.yaml"]),
    ]


def test_a_command_needs_the_files_earlier_commands_make(tmp_path, monkeypatch):
    navigate = "python -m drake_sim.navigate --map maps/room.yaml --headless"
    alone = documented_commands(README, f"`{navigate}`")
    problems = check_commands(alone, tmp_path / "alone", monkeypatch)
    assert len(problems) == 1 and "map file not found: maps/room.yaml" in problems[0]

    mapped = documented_commands(README, f"`python -m drake_sim.mapping --headless`\n`{navigate}`")
    assert check_commands(mapped, tmp_path / "mapped", monkeypatch) == []
    assert (tmp_path / "mapped" / "workspace" / "maps" / "room.pgm").read_text() == PLACEHOLDER


def test_unknown_modules_options_and_values_are_refused(tmp_path, monkeypatch):
    text = (
        "`python -m drake_sim.no_such_app`\n"
        "`python -m drake_sim.flip --no-such-option`\n"
        "`python -m drake_sim.flip --duration -1`\n"
        "`python -m drake_sim.sweep --address auto config/sweeps/flip_imu_noise.yaml`\n"
        "`python benchmarks/no_such_benchmark.py`\n"
        "`python benchmarks/flip_benchmark.py --no-such-option`\n"
        "`python -m drake_sim.tools.regions --scene config/pickplace.yaml`\n"
        "`python -m drake_sim.flip --set flip.no_such_key=1`\n"
        "`python -m drake_sim.pickplace --set 'scene.object.position[7]=0.5'`\n"
        "`python -m drake_sim.pickplace --set 'scene.object.position[0]=0.55'`\n"
    )
    problems = check_commands(documented_commands(README, text), tmp_path, monkeypatch)
    assert len(problems) == 8, "\n".join(problems)
    assert "no module named drake_sim.no_such_app" in problems[0]
    assert "unrecognized arguments: --no-such-option" in problems[1]
    assert "--duration" in problems[2]
    assert "--address is for --backend ray" in problems[3]
    assert "no such script" in problems[4]
    assert "unrecognized arguments: --no-such-option" in problems[5]
    assert "no_such_key" in problems[6]
    assert "position[7]" in problems[7]


def test_the_workspace_never_writes_into_the_repository(tmp_path):
    workspace = Workspace(tmp_path)
    workspace.add(Path("config/arenas/new.yaml"), False)
    workspace.add(Path("config/flip.yaml"), False)
    assert (tmp_path / "config" / "arenas" / "new.yaml").read_text() == PLACEHOLDER
    assert not (ROOT / "config" / "arenas" / "new.yaml").exists()
    assert (ROOT / "config" / "flip.yaml").read_text() != PLACEHOLDER
    assert (tmp_path / "config" / "arenas" / "room.yaml").resolve() == (
        ROOT / "config" / "arenas" / "room.yaml"
    )


def test_forbidden_patterns_catch_what_they_are_for():
    samples = {
        "a commit id": "at 0123456789abcdef0123456789abcdef01234567 then",
        "an abbreviated commit id": "(2bd7585, the start)",
        "an issue reference": "see #19 for",
        '"this VM"': "measured on this VM",
    }
    for what, sample in samples.items():
        assert FORBIDDEN[what].search(sample), what
    harmless = "## Heading, 1.5e-3 m, --set scene.object.position[0]=0.55, deadbeef, &#123;"
    assert not any(p.search(harmless) for p in FORBIDDEN.values())
