"""The documentation's generated pages cover what they describe (every flag of every app, every scene-file key,
every benchmark table), and the README and the site stand on their own: within 200 lines, and pointing at
nothing outside the repository. (The site itself is built with -W by .ci/run.)"""

import importlib
import re
import sys
from pathlib import Path

import pytest

from taichi_pneuma.scene.scenefile import key_reference

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "docs"))
generate = importlib.import_module("_generate")


@pytest.mark.parametrize("app", generate.APPS)
def test_the_apps_page_lists_every_flag(app):
    page = generate.app_page(app)
    parser = importlib.import_module(f"taichi_pneuma.apps.{app}").parser()
    flags = [s for action in parser._actions for s in action.option_strings if s not in ("-h", "--help")]
    assert "--version" in flags
    assert all(f"`{flag}" in page or f", {flag}" in page for flag in flags), [f for f in flags if f not in page]


def test_the_scene_key_reference_lists_every_key():
    page = "".join(generate.scene_keys_page(dim) for dim in generate.SCENE_KEYS)
    keys = [info.key for info in key_reference()]
    rows = [line for line in page.splitlines() if line.startswith("| `")]
    assert len(rows) == len(keys) and all(f"| `{key}` |" in page for key in keys)


def test_every_benchmark_table_is_on_a_page():
    pages = "\n".join(generate.results_pages().values())
    tables = sorted((ROOT / "benchmarks" / "results").glob("*.md"))
    assert tables and all(path.read_text().strip() in pages for path in tables)
    assert all(re.match(r"Machine: .*\d{4}-\d\d-\d\d", path.read_text()) for path in tables)  # with its date
    assert set(generate.RESULTS_PAGES) == {path.stem for path in tables}  # each with a title and its command


def test_the_readme_is_short_and_self_contained():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 200
    sources = [
        ROOT / "README.md",
        *(ROOT / "docs").rglob("*.md"),
        *(ROOT / "taichi_pneuma").rglob("*.py"),
        *(ROOT / "examples").glob("*.py"),
    ]
    citing = [p for p in sources if re.search(r"SPEC\.md|\.\./shared", p.read_text())]
    assert not citing
    for link in re.findall(r"\]\(((?:docs/|CHANGELOG|LICENSE)[^)#]*)", readme):  # every local link resolves
        assert (ROOT / link).exists(), link


def test_plain_docstrings_become_valid_rest():
    """Inline markup escaped, an indented block made literal, a list set off by blank lines."""
    lines = [
        "The energy |F|^2 of x_ and *a:",
        "",
        "    E = 1/2 k (A - A*)^2",
        "text after it",
        "- one",
        "- two",
        "  continued",
        "after the list",
    ]
    generate.plain_docstring(None, "function", "f", None, {}, lines)
    assert lines[0] == r"The energy \|F\|^2 of x\_ and \*a:"
    assert lines[2:5] == ["::", "", "    E = 1/2 k (A - A*)^2"]  # literal: left as it is
    assert lines[lines.index("text after it") - 1] == ""
    assert lines[lines.index("- one") - 1] == "" and lines[lines.index("after the list") - 1] == ""
    assert "  continued" in lines
