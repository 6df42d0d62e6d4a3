"""Where cstep_bridge finds its files: the `cstep` binary, ``config/cstep.yaml``, the URDFs, and
the data it carries itself (evaluation sets, hyperparameters).

The node's files are not part of this package, so they are looked for in order, first hit wins:

- **the binary**: an explicit argument; ``$CSTEP_BIN``; the ament index (``lib/cstep/cstep``
  under the first prefix of ``$AMENT_PREFIX_PATH`` that holds the ``cstep`` package, as a
  sourced colcon install does); ``cstep`` on ``$PATH``; the checkout's release build
  (``$CARGO_TARGET_DIR`` or ``<checkout>/target``, then ``release/cstep``).
- **the share files** (``config/``, ``urdf/``): ``$CSTEP_ROOT`` (a directory holding them: a
  checkout, or an install's ``share/cstep``); the ament index (``share/cstep``); the checkout.

"The checkout" is the repository this package sits in (``py_bridge/cstep_bridge`` two levels
below its ``Cargo.toml``), as with ``pip install -e`` or ``PYTHONPATH=py_bridge``; an installed
copy has none. A place named explicitly (an argument or a variable) must hold the file (for the
binary: an executable file): it is an error, not a reason to look further. When nothing is found,
:class:`ResourceNotFound` names every place tried and what was wrong there (missing, not
executable, not a file).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from .errors import ResourceNotFound

PACKAGE = Path(__file__).resolve().parent
"""This package's directory: its own data (``data/``, ``hyperparams/``) lies here."""

CHECKOUT = PACKAGE.parents[1] if (PACKAGE.parents[1] / "Cargo.toml").is_file() else None
"""The repository this package sits in when it runs from a checkout (the last place looked),
else None."""

CONFIG = "config/cstep.yaml"
"""The node's default configuration, relative to a share directory."""

DRONE_URDF = "urdf/cf2x.urdf"
"""The Crazyflie's URDF, relative to a share directory."""

BINARY_VAR = "CSTEP_BIN"
"""The environment variable naming the `cstep` binary."""

ROOT_VAR = "CSTEP_ROOT"
"""The environment variable naming a directory that holds ``config/`` and ``urdf/``."""

AMENT_PACKAGE = "cstep"
"""The node's package name in the ament index (``share/ament_index/resource_index/packages``)."""


def _ament_place(*parts: str) -> tuple[str, Path | None]:
    """The ament index as a place to look: ``parts`` under the first ``$AMENT_PREFIX_PATH``
    prefix whose index lists the ``cstep`` package, or no path when none does."""
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        marker = Path(prefix) / "share/ament_index/resource_index/packages" / AMENT_PACKAGE
        if prefix and marker.is_file():
            return "the ament index", Path(prefix).joinpath(*parts)
    return f"the ament index: no {AMENT_PACKAGE} package in $AMENT_PREFIX_PATH", None


def _missing(path: Path) -> str | None:
    """Why ``path`` cannot be used as a file to read: None when it exists."""
    return None if path.exists() else "missing"


def _not_runnable(path: Path) -> str | None:
    """Why ``path`` cannot be run as the binary: None when it is an executable file. A file
    without execute permission would otherwise be found and fail in ``subprocess`` with a raw
    :class:`PermissionError`."""
    if not path.exists():
        return "missing"
    if not path.is_file():
        return "not a file"
    return None if os.access(path, os.X_OK) else "not executable"


def _first(what: str, places: list[tuple[str, Path | None]], hint: str, problem=_missing) -> Path:
    """The first path of ``places`` (each a description and a path, or None where the place
    offers none) that ``problem`` finds nothing wrong with (default: that exists); else
    :class:`ResourceNotFound` for ``what``, listing every place tried with what was wrong there,
    then ``hint``. A place named explicitly (argument, variable) comes alone: a wrong setting is
    an error, never a reason to look further."""
    tried = []
    for place, path in places:
        why = None if path is None else problem(path)
        if path is not None and why is None:
            return path
        tried.append(place if path is None else f"{place}: {path} ({why})")
    lines = "".join(f"\n  - {place}" for place in tried)
    raise ResourceNotFound(f"{what} not found; looked in:{lines}\n{hint}")


def cstep_binary(explicit: Path | str | None = None) -> Path:
    """The `cstep` executable: ``explicit``, else the first found in the order the module
    docstring gives. Raises :class:`ResourceNotFound` naming every place tried and, where a file
    was there but cannot be run (not executable, a directory), saying so."""
    what = "the cstep binary"
    hint = f"Build it (cargo build --release) or set {BINARY_VAR} to the binary."
    if explicit:
        return _first(what, [("the binary argument", Path(explicit))], hint, _not_runnable)
    if os.environ.get(BINARY_VAR):
        return _first(what, [(f"${BINARY_VAR}", Path(os.environ[BINARY_VAR]))], hint, _not_runnable)
    on_path = shutil.which("cstep")
    target = os.environ.get("CARGO_TARGET_DIR") or (CHECKOUT and CHECKOUT / "target")
    places = [
        (f"${BINARY_VAR} (unset)", None),
        _ament_place("lib", AMENT_PACKAGE, "cstep"),
        ("cstep on $PATH (none)", Path(on_path) if on_path else None),
        ("the checkout's release build", Path(target) / "release" / "cstep")
        if target
        else ("the checkout's release build: cstep_bridge is not in a checkout", None),
    ]
    return _first(what, places, hint, _not_runnable)


def share_file(relative: str) -> Path:
    """The node's share file ``relative`` (e.g. :data:`CONFIG`): the first found in the order
    the module docstring gives. Raises :class:`ResourceNotFound` naming every place tried."""
    hint = f"Set {ROOT_VAR} to a directory holding {relative} (a checkout or share/cstep)."
    if os.environ.get(ROOT_VAR):
        return _first(relative, [(f"${ROOT_VAR}", Path(os.environ[ROOT_VAR]) / relative)], hint)
    places = [
        (f"${ROOT_VAR} (unset)", None),
        _ament_place("share", AMENT_PACKAGE, relative),
        ("the checkout", CHECKOUT / relative)
        if CHECKOUT
        else ("the checkout: cstep_bridge is not in one", None),
    ]
    return _first(relative, places, hint)


def config_file() -> Path:
    """The node's default configuration, ``config/cstep.yaml`` (see :func:`share_file`)."""
    return share_file(CONFIG)


def drone_urdf() -> Path:
    """The Crazyflie's URDF, ``urdf/cf2x.urdf`` (see :func:`share_file`)."""
    return share_file(DRONE_URDF)
