"""The robot descriptions of the ``vamp-planner`` release, taken into the cache once.

VAMP's source distribution (the one ``planning.io.mbm`` takes the MotionBenchMaker sets from)
ships each robot's description as ``resources/<robot>/``: ``<robot>.urdf``, ``<robot>.srdf``,
``meshes/`` (and a spherized URDF). ``vamp_resources`` puts them where
``robot_files`` finds its built-in package ``vamp_resources`` (fetched on demand)
(``package://vamp_resources/<robot>/<robot>.urdf``), checked against ``RESOURCES_SHA256``:
from a folder or sdist the caller gives, else from the sdist pip downloads from the package
index (``drake_sim.robots.files.vamp_sdist.download_sdist``). Nothing is committed; nothing is
downloaded twice.

Each robot's folder is copied beside its place, checked, stamped with its digest (``.sha256``)
and renamed into place, so processes running at the same time, or a run stopped half-way, never
see half a folder; a folder of another release (another stamp) is replaced.
"""

from __future__ import annotations

import hashlib
import shutil
import sys
import tarfile
import tempfile
from pathlib import Path

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import cache_dir
from drake_sim.robots.files.vamp_sdist import VAMP_PACKAGE, VAMP_VERSION, download_sdist

RESOURCES_SHA256 = {
    "panda": "fe28f0784d1e175c44f07b24641e9e9e85fdb20afd9b59adf40773607b5cb354",
    "ur5": "62d13e471f337135dc75edc46588e8a4b79ff99e8bb68d3f7b54523a13ee8bd8",
    "fetch": "bbfbda5df4e88c14eb09bf36b8ee633c262eccf68b89328c92058120a8cd0bcb",
    "baxter": "2c626c840260c3b771880feedcc809b2b0601fe51ac67d78f2cd89550caaceff",
}
"""``tree_digest`` of each robot's ``resources/<robot>/`` in the release (``problems.tar.bz2``
left out: ``planning.io.mbm.ARCHIVE_SHA256`` pins it)."""

_STAMP = ".sha256"
_PROBLEMS = "/problems.tar.bz2"


def fetched_packages_dir() -> Path:
    """Where packages fetched from the package index are kept: ``cache_dir()/packages``."""
    return cache_dir() / "packages"


def resources_root() -> Path:
    """The folder of the built-in package ``vamp_resources`` (it may not exist yet)."""
    return fetched_packages_dir() / "vamp_resources"


def ensure_resources() -> Path:
    """The folder of the built-in package ``vamp_resources`` with every robot in it, fetched
    first when one is missing (``vamp_resources``)."""
    missing = [
        name for name, pin in RESOURCES_SHA256.items() if _stamp(resources_root() / name) != pin
    ]
    if missing:
        vamp_resources(missing[0])
    return resources_root()


def vamp_resources(robot: str = "panda", source: Path | str | None = None) -> Path:
    """Makes the release's robot descriptions available in the cache; returns ``robot``'s folder.

    Every robot of ``RESOURCES_SHA256`` missing from the cache is taken at once (one download
    serves all four).

    Args:
        robot: one of ``RESOURCES_SHA256``.
        source: the release's ``resources/`` folder, a folder holding it (an unpacked sdist),
            or the sdist file; None downloads the sdist with pip (one line on stderr says so).

    Raises:
        ConfigError: an unknown robot, pip failing (no network), a source that is not the
            release's (a digest differs), or a folder that cannot be written.
    """
    if robot not in RESOURCES_SHA256:
        raise ConfigError(f"unknown VAMP robot {robot!r} (known: {', '.join(RESOURCES_SHA256)})")
    root = resources_root()
    if _stamp(root / robot) == RESOURCES_SHA256[robot]:
        return root / robot
    with tempfile.TemporaryDirectory(prefix="drake_sim-vamp-") as download:
        if source is None:
            print(
                f"note: downloading {VAMP_PACKAGE} {VAMP_VERSION} (sdist, ~65 MB) for its robot "
                f"descriptions, into {root}",
                file=sys.stderr,
                flush=True,
            )
            hint = "give the release's sdist or unpacked resources/ folder as source"
            source = download_sdist(Path(download) / "sdist", "the VAMP robot descriptions", hint)
        source = Path(source)
        if source.is_dir() and (source / "resources").is_dir():
            source = source / "resources"
        if not source.exists():
            raise ConfigError(f"VAMP resources not found: {source} does not exist")
        missing = [name for name, pin in RESOURCES_SHA256.items() if _stamp(root / name) != pin]
        root.mkdir(parents=True, exist_ok=True)
        scratch = Path(tempfile.mkdtemp(prefix=".unpacking-", dir=root))
        try:
            for name, folder in _stage(source, missing, scratch).items():
                _place(folder, root / name, f"{source}: resources/{name}/")
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
    return root / robot


def tree_digest(folder: Path | str) -> str:
    """SHA-256 over the relative path and SHA-256 of every file under ``folder``, in sorted
    order (``problems.tar.bz2`` and the ``.sha256`` stamp left out)."""
    folder = Path(folder)
    digest = hashlib.sha256()
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        relative = path.relative_to(folder).as_posix()
        if relative not in ("problems.tar.bz2", _STAMP):
            file_digest = hashlib.sha256(path.read_bytes()).hexdigest()
            digest.update(f"{relative}\0{file_digest}\n".encode())
    return digest.hexdigest()


def _stage(source: Path, robots: list[str], scratch: Path) -> dict[str, Path]:
    """Copies ``resources/<robot>/`` of each robot (its problems left out) from a folder or the
    sdist (read once) into ``scratch``; returns robot -> its copy."""
    prefix = f"vamp_planner-{VAMP_VERSION}/resources/"
    try:
        if source.is_dir():
            ignore = shutil.ignore_patterns("problems.tar.bz2")
            for robot in robots:
                shutil.copytree(source / robot, scratch / prefix / robot, ignore=ignore)
        else:
            wanted = tuple(f"{prefix}{robot}/" for robot in robots)
            with tarfile.open(source, "r:gz") as tar:
                members = [
                    member
                    for member in tar.getmembers()
                    if member.name.startswith(wanted) and not member.name.endswith(_PROBLEMS)
                ]
                tar.extractall(scratch, members=members, filter="data")
    except (tarfile.TarError, OSError, EOFError) as e:
        raise ConfigError(f"{source}: not a readable copy of VAMP's resources/ ({e})") from None
    for robot in robots:
        if not (scratch / prefix / robot).is_dir():
            raise ConfigError(f"{source}: holds no resources/{robot}/")
    return {robot: scratch / prefix / robot for robot in robots}


def _place(folder: Path, target: Path, what: str) -> None:
    """Checks a staged robot folder against its pin, stamps it and renames it into place
    (replacing a folder of another release)."""
    digest, expected = tree_digest(folder), RESOURCES_SHA256[target.name]
    if digest != expected:
        raise ConfigError(
            f"{what} has SHA-256 {digest}, expected {expected} ({VAMP_PACKAGE} {VAMP_VERSION})"
        )
    (folder / _STAMP).write_text(digest)
    if target.exists() and _stamp(target) != digest:  # another release's
        target.rename(folder.with_name(f".replaced-{target.name}"))
    try:
        folder.rename(target)
    except OSError as e:  # another process may have put it there first
        if _stamp(target) != digest:
            raise ConfigError(f"cannot write {target} ({e.strerror})") from None


def _stamp(folder: Path) -> str | None:
    """The digest a placed robot folder was checked against; None when there is none."""
    try:
        return (folder / _STAMP).read_text().strip()
    except OSError:
        return None
