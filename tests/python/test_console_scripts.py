"""The commands pyproject.toml declares (``cstep-train``, ``cstep-evaluate``, ``cstep-campaign``)
name functions that exist and answer ``--help``, as the scripts ``pip install`` writes would call
them, and each is the ``main`` its ``python -m cstep_bridge.<tool>`` module runs."""

import importlib
import tomllib

import pytest
from conftest import REPO

SCRIPTS = tomllib.loads((REPO / "py_bridge" / "pyproject.toml").read_text())["project"]["scripts"]
MODULES = {"cstep-train": "train", "cstep-evaluate": "evaluate", "cstep-campaign": "campaign"}
"""Each command and the ``python -m cstep_bridge.<module>`` it stands beside."""


def _entry(name: str):
    module, _, function = SCRIPTS[name].partition(":")
    return getattr(importlib.import_module(module), function)


def test_the_three_commands_are_declared():
    assert set(SCRIPTS) == set(MODULES)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_each_command_answers_help(name, capsys):
    with pytest.raises(SystemExit) as done:
        _entry(name)(["--help"])
    assert done.value.code == 0
    assert capsys.readouterr().out.startswith("usage:")


@pytest.mark.parametrize("name", sorted(MODULES))
def test_each_command_is_its_python_m_modules_main(name):
    assert _entry(name) is importlib.import_module(f"cstep_bridge.{MODULES[name]}").main
