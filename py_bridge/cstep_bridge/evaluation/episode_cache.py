"""Evaluated episodes kept on disk, so that an evaluation re-run with one more model (a new seed, a
new agent) flies only that model, and an evaluation interrupted part-way resumes where it was.

An entry holds one model's episodes on one evaluation set, by configuration index. Its key is a
digest of everything an episode depends on: the model's weights, the observation statistics it
is normalised with, the environment, the evaluation set's contents, the acting rule, the source
of every module of this package that the evaluation loads (simulation, envs, controller, metrics
— not, say, the bag recorder), its data files, the drone's URDF and the versions of the
libraries that fly and act (PyBullet, whose pybullet_data ships the Husky's URDF, PyTorch,
stable-baselines3, NumPy, SciPy); any change to
one of them makes a new key, so a stale entry is never read. Entries are pickles: the cache is a
directory of the user's own files, not a format to exchange.
"""

from __future__ import annotations

import ast
import hashlib
import pickle
from importlib.metadata import version
from pathlib import Path

from ..resources import PACKAGE, drone_urdf
from ..training.normalization import stats_path
from .metrics import Episode

LIBRARIES = ("pybullet", "torch", "stable-baselines3", "numpy", "scipy")
FLYING_MODULES = (
    "evaluation.flights",
    "evaluation.acting",
    "envs",
    "envs.drone",
    "envs.maze",
    "envs.husky",
    "sim.drone",
    "sim.maze",
    "sim.husky",
    "sim.world",
    "training.normalization",
    "evaluation.metrics",
)
"""What an evaluation worker runs; the key covers these and every package module they import."""


def _module_file(name: str) -> Path | None:
    """The source of package module ``name`` (dotted, relative to the package), if it is one."""
    base = PACKAGE.joinpath(*name.split(".")) if name else PACKAGE
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _package_imports(name: str, source: Path) -> set[str]:
    """The package modules (dotted, relative to the package) that module ``name`` imports,
    at its top or inside a function, with the packages above each."""
    found = set()
    package = name if source.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(source.read_text(), str(source))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".") if package else []
                parts = parts[: len(parts) - node.level + 1] + (node.module or "").split(".")
                target = ".".join(p for p in parts if p)
            elif (node.module or "").split(".")[0] == PACKAGE.name:
                target = node.module.partition(".")[2]
            else:
                continue
            found.add(target)
            found |= {f"{target}.{a.name}".lstrip(".") for a in node.names}
        elif isinstance(node, ast.Import):
            found |= {
                a.name.partition(".")[2] for a in node.names if a.name.startswith(PACKAGE.name)
            }
    modules = set()
    for target in found:
        parts = target.split(".") if target else []
        modules |= {".".join(parts[:i]) for i in range(len(parts) + 1)}
    return {m for m in modules if _module_file(m)}


def _evaluation_sources() -> list[Path]:
    """The files of this package's modules an evaluation loads, and its data files, each named by
    its place in the package (a data file may be a link to the repository's ``config/``).

    The modules are found by reading their imports, not by importing them: which modules a
    process happens to hold depends on its caller (``python -m`` runs its module as
    ``__main__``), and the key must not. Written by hand: ``modulefinder`` would also walk every
    third-party import (PyTorch alone takes minutes), which the library versions cover."""
    todo, seen = {""} | set(FLYING_MODULES), set()
    while todo:
        name = todo.pop()
        seen.add(name)
        todo |= _package_imports(name, _module_file(name)) - seen
    files = {_module_file(name).resolve() for name in seen}
    files |= {p for p in (PACKAGE / "data").rglob("*") if p.is_file()}
    return sorted(files)


def entry_key(model: Path, env: str, eval_set: Path | None, acting: str) -> str:
    """The digest that names ``model``'s entry for ``env``, ``eval_set`` (None: the env's default
    set, itself part of the package's files when it is read from there) and the ``acting`` rule."""
    h = hashlib.sha256()
    for path in (model, stats_path(model), eval_set, drone_urdf()):
        if path is not None and path.exists():
            h.update(path.read_bytes())
        h.update(b"\0")
    h.update(env.encode() + b"\0")
    h.update(acting.encode() + b"\0")
    h.update(" ".join(version(lib) for lib in LIBRARIES).encode())
    for source in _evaluation_sources():
        h.update(str(source.relative_to(PACKAGE)).encode())
        h.update(source.read_bytes())
    return h.hexdigest()[:32]


class EpisodeCache:
    """A directory of entries, one file per (model, env, evaluation set) key."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory

    def _path(self, key: str) -> Path:
        return self.directory / f"{key}.pkl"

    def load(self, key: str) -> dict[int, Episode]:
        """The episodes stored under ``key`` by configuration index (empty if none)."""
        path = self._path(key)
        if not path.exists():
            return {}
        with path.open("rb") as f:
            return pickle.load(f)

    def store(self, key: str, episodes: dict[int, Episode]) -> None:
        """Replaces ``key``'s entry with ``episodes``, atomically (a rename), so that an
        interrupted write never leaves a truncated entry behind."""
        self.directory.mkdir(parents=True, exist_ok=True)
        path = self._path(key)
        partial = path.with_suffix(".partial")
        with partial.open("wb") as f:
            pickle.dump(episodes, f)
        partial.replace(path)
