"""The README's commands run as written: every command of its ```bash blocks, in order, in one fresh
directory, as a user types them after the set-up (the virtual environment activated).

The rule, also stated in the README's set-up section: lines that set up or install (venv, pip,
activate, pytest), that need a Ray cluster or a display (ray, --ray, --interactive), and the long
ones (pneuma-bench: minutes; --design: a root-finder over 10-16 ramps, tested in test_reach.py) are
not run (SKIP); every other command is an app of the package, run through its console script's
entry point (pyproject's [project.scripts]; `python -m taichi_pneuma.apps.X` is the same main) with
`--quality draft --steps 8` appended (a coarser mesh, a looser tolerance and 7 increments for the
reference beam; a scene file its draft mesh, coarser than its own, and its own schedule: this test
checks the commands, the figures are tested elsewhere), and a sweep with `--workers 1` (one worker process to start, not
one per core), and must exit 0.
"""

import importlib
import re
import shlex
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SKIP = re.compile(
    r"^(python3 -m venv|\.venv/bin/|pip |\. \.venv|source |ray |python -m pytest|pneuma-bench)"
    r"|--ray|--interactive|--design"
)
FAST = ["--quality", "draft", "--steps", "8"]
ONE_WORKER = ["--workers", "1"]


def readme_commands() -> list[str]:
    """Every command line of the README's bash blocks, in order (continuation lines joined)."""
    text = (ROOT / "README.md").read_text()
    lines = []
    for block in re.findall(r"```bash\n(.*?)```", text, re.S):
        lines += [line.strip() for line in block.replace("\\\n", " ").splitlines() if line.strip()]
    return [line for line in lines if not line.startswith("#")]


def entry_point(argv: list[str]):
    """The main() a README command runs, and its arguments: `pneuma-X ARGS` or `python -m MODULE ARGS`."""
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    if argv[0] in scripts:
        module, _, function = scripts[argv[0]].partition(":")
        return getattr(importlib.import_module(module), function), argv[1:]
    assert argv[:2] == ["python", "-m"] and argv[2].startswith("taichi_pneuma.apps."), (
        f"a README command this test cannot run: {' '.join(argv)}"
    )
    return importlib.import_module(argv[2]).main, argv[3:]


def test_the_rule_is_stated_in_the_readme():
    text = (ROOT / "README.md").read_text()
    assert "tests/test_readme.py" in text and " ".join(FAST) in text and " ".join(ONE_WORKER) in text


@pytest.mark.slow
def test_every_readme_command_runs_as_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    ran = []
    for line in readme_commands():
        if SKIP.search(line):
            continue
        argv = shlex.split(line, comments=True)
        main, args = entry_point(argv)
        code = main([*args, *FAST, *(ONE_WORKER if main.__module__.endswith(".sweep") else [])])
        captured = capsys.readouterr()
        assert code == 0, f"{line!r} exited {code}:\n{captured.err[-2000:]}"
        ran.append(line)
    assert len(ran) >= 10 and any(line.startswith("pneuma-inflate") for line in ran)
