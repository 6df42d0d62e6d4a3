"""The commands the README and docs/ show still exist as shown: every ``cstep`` subcommand and
``python -m cstep_bridge.X`` module they run accepts each option they pass it (asked through its
own ``--help``), every ``-p``/``ros2 param set`` name is a parameter of the table, and every
``name:=value`` given to ``ros2 launch cstep cstep.launch.py`` is an argument the launch file
declares. The commands are not run (they train, fly or wait for Ctrl-C); what rots in docs is
names, and names are what this checks."""

from __future__ import annotations

import ast
import os
import re
import shlex
import subprocess
import sys
from functools import cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
SHELL = {"", "sh", "bash", "console", "shell"}
LONG_OPTION = re.compile(r"^--[a-z][a-z0-9-]*")


def shell_blocks(text: str) -> list[list[str]]:
    """The lines of each fenced block of `text` whose language is a shell's (or unnamed)."""
    blocks, current, language = [], None, None
    for line in text.splitlines():
        fence = line.strip()
        if fence.startswith("```"):
            if current is None:
                language, current = fence[3:].strip(), []
            else:
                if language in SHELL:
                    blocks.append(current)
                current = None
        elif current is not None:
            current.append(line)
    return blocks


def shell_lines() -> list[tuple[str, str]]:
    """(document, command) for every line of the docs' shell blocks, comments dropped and
    ``$P`` (the README's short form of ``.venv/bin/python -m cstep_bridge``) expanded."""
    lines = []
    for doc in DOCS:
        prefix = None
        for block in shell_blocks(doc.read_text()):
            for raw in block:
                line = raw.split("  #")[0].split(" # ")[0].strip().rstrip("\\").strip()
                if line.startswith("P="):
                    prefix = shlex.split(line[2:])[0]
                    continue
                if prefix:
                    line = line.replace("$P", prefix)
                if line and not line.startswith("#"):
                    lines.append((doc.name, line))
    return lines


def words(line: str) -> list[str]:
    """The line's words, as far as shlex reads it (a line may hold half a quoted string)."""
    try:
        return shlex.split(line.rstrip("&").strip())
    except ValueError:
        return line.split()


def options(args: list[str]) -> set[str]:
    """The long options among ``args`` (``--x=1`` as ``--x``), up to ``--ros-args``."""
    found = set()
    for arg in args:
        if arg == "--ros-args":
            break
        if match := LONG_OPTION.match(arg):
            found.add(match.group(0))
    return found


def cstep_calls() -> list[tuple[str, str, list[str]]]:
    """(document, subcommand, its arguments) for every command line in the docs that runs
    ``cstep`` (``cargo run --release -- X``, or the binary by a path ending in ``cstep``),
    after any ``NAME=value`` assignments before it."""
    calls = []
    for doc, line in shell_lines():
        args = words(line)
        while args and re.fullmatch(r"[A-Z_]+=\S*", args[0]):
            args = args[1:]
        if args[:1] == ["cargo"] and "--" in args:
            rest = args[args.index("--") + 1 :]
        elif args and Path(args[0]).name == "cstep":
            rest = args[1:]
        else:
            continue
        if rest and re.fullmatch(r"[a-z]+", rest[0]):
            calls.append((doc, rest[0], rest[1:]))
    return calls


def module_calls() -> list[tuple[str, str, list[str]]]:
    """(document, module, its arguments) for every ``python -m cstep_bridge.X`` in the docs."""
    calls = []
    for doc, line in shell_lines():
        args = words(line)
        for i, word in enumerate(args[:-1]):
            if word == "-m" and args[i + 1].startswith("cstep_bridge."):
                calls.append((doc, args[i + 1], args[i + 2 :]))
    return calls


@cache
def cstep_help(subcommand: str) -> str:
    binary = os.environ.get("CSTEP_BIN") or str(REPO / "target" / "release" / "cstep")
    if not Path(binary).exists():
        pytest.skip(f"no cstep binary at {binary} (make test builds it)")
    done = subprocess.run(
        [binary, subcommand, "--help"], check=False, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, f"cstep {subcommand} --help: {done.stderr}"
    return done.stdout


@cache
def module_help(module: str, subcommand: str | None = None) -> str:
    """``python -m module [subcommand] --help``."""
    env = dict(os.environ, PYTHONPATH=str(REPO / "py_bridge"))
    done = subprocess.run(
        [sys.executable, "-m", module, *([subcommand] if subcommand else []), "--help"],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=REPO,
    )
    assert done.returncode == 0, f"python -m {module} --help: {done.stderr[-2000:]}"
    return done.stdout


@cache
def parameter_names() -> set[str]:
    """The parameter table's names, as docs/parameters.md (generated from it) lists them."""
    table = (REPO / "docs" / "parameters.md").read_text()
    return set(re.findall(r"^\| `([a-z_]+)` \|", table, re.MULTILINE))


def launch_arguments() -> set[str]:
    """The arguments cstep.launch.py declares."""
    tree = ast.parse((REPO / "launch" / "cstep.launch.py").read_text())
    return {
        node.args[0].value
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and getattr(node.func, "id", None) == "DeclareLaunchArgument"
        and node.args
        and isinstance(node.args[0], ast.Constant)
    }


def test_the_docs_show_commands_of_every_kind_this_checks():
    # A parse that finds nothing would pass everything below.
    assert len(cstep_calls()) >= 5
    assert {m for _, m, _ in module_calls()} >= {
        "cstep_bridge.train",
        "cstep_bridge.evaluate",
        "cstep_bridge.campaign",
    }


@pytest.mark.parametrize(
    "doc, subcommand, args", cstep_calls(), ids=lambda v: v if isinstance(v, str) else None
)
def test_every_cstep_command_in_the_docs_takes_its_options(doc, subcommand, args):
    help_text = cstep_help(subcommand)
    unknown = sorted(o for o in options(args) if o not in help_text)
    assert not unknown, f"{doc}: cstep {subcommand} has no {unknown}"
    for i, arg in enumerate(args[:-1]):
        if arg in ("-p", "--param") and ":=" in args[i + 1]:
            name = args[i + 1].split(":=")[0]
            assert name in parameter_names(), f"{doc}: no parameter {name!r}"


@pytest.mark.parametrize(
    "doc, module, args", module_calls(), ids=lambda v: v if isinstance(v, str) else None
)
def test_every_python_command_in_the_docs_takes_its_options(doc, module, args):
    help_text = module_help(module)
    # A command with subcommands ({record,replay,…}) is asked about the one the line runs.
    choices = re.findall(r"\{([a-z,]+)\}", help_text)
    if args and any(args[0] in group.split(",") for group in choices):
        help_text = module_help(module, args[0])
    unknown = sorted(o for o in options(args) if o not in help_text)
    assert not unknown, f"{doc}: python -m {module} has no {unknown}"


def test_parameters_set_and_launch_arguments_in_the_docs_exist():
    declared = launch_arguments()
    checked = 0
    for doc, line in shell_lines():
        args = words(line)
        if args[:3] == ["ros2", "param", "set"] and len(args) >= 5:
            assert args[4] in parameter_names(), f"{doc}: no parameter {args[4]!r}"
            checked += 1
        if args[:2] == ["ros2", "launch"] and "cstep.launch.py" in args:
            for arg in args[args.index("cstep.launch.py") + 1 :]:
                if ":=" in arg:
                    assert arg.split(":=")[0] in declared, f"{doc}: {arg}"
                    checked += 1
    assert checked >= 3
