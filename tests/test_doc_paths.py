"""The maps of the tree stay true to it: every file or folder docs/architecture.md and docs/extending.md name exists,
architecture.md's app list names every app, the line counts extending.md gives are the file's, and tests/README.md
lists every test file under a package that exists."""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "taichi_pneuma"
# a path in backticks (a file with an extension, or a folder ending in /), and a Markdown link to a page
PATH = re.compile(r"`([\w./-]+\.(?:py|md|toml|msh|npz|csv|json)|[\w./-]+/)`")
LINK = re.compile(r"\]\(([\w./-]+\.md)\)")


def named_paths(page: Path) -> set[str]:
    """The files and folders a page names: in backticks, or as the target of a link."""
    text = page.read_text()
    return set(PATH.findall(text)) | set(LINK.findall(text))


def exists(name: str) -> bool:
    """Whether the name is a path from the repository, the package or docs/, or one under some package folder (a
    page's table names a module by its name in its package's row: `output.py` in io/)."""
    name = name.rstrip("/")
    return any((base / name).exists() for base in (ROOT, PACKAGE, ROOT / "docs")) or any(PACKAGE.glob(f"**/{name}"))


@pytest.mark.parametrize("page", ["architecture.md", "extending.md"])
def test_every_path_a_page_names_exists(page):
    names = named_paths(ROOT / "docs" / page)
    assert len(names) > 20  # the pattern finds them
    assert [name for name in sorted(names) if not exists(name)] == []


def test_the_architecture_names_every_app():
    row = next(
        line for line in (ROOT / "docs" / "architecture.md").read_text().splitlines() if line.startswith("| `apps/`")
    )
    apps = sorted(p.name for p in (PACKAGE / "apps").glob("*.py") if p.name != "__init__.py")
    assert "serve.py" in apps and [app for app in apps if f"`{app}`" not in row] == []


def code_lines(path: Path) -> int:
    """A module's lines that are neither blank, nor comments, nor in a docstring."""
    source = path.read_text()
    docstrings = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef)) and ast.get_docstring(node) is not None:
            docstrings.update(range(node.body[0].lineno, node.body[0].end_lineno + 1))
    return sum(
        1
        for number, line in enumerate(source.splitlines(), 1)
        if line.strip() and not line.strip().startswith("#") and number not in docstrings
    )


def test_the_closed_gas_kind_has_the_lines_the_page_says():
    """extending.md: the closed gas kind is "N lines with its docstrings" and, in the parts table, "M lines" of code."""
    text = " ".join((ROOT / "docs" / "extending.md").read_text().split())
    path = PACKAGE / "terms" / "chambers" / "closed_gas.py"
    total = int(re.search(r"closed_gas\.py`, (\d+) lines with its docstrings", text).group(1))
    code = int(re.search(r"the closed gas kind below: (\d+) lines", text).group(1))
    assert (total, code) == (len(path.read_text().splitlines()), code_lines(path))


def test_the_tests_readme_lists_every_test_file_under_a_package():
    text = (ROOT / "tests" / "README.md").read_text()
    listed = re.findall(r"`(\w+\.py)`", text)
    files = sorted(p.name for p in (ROOT / "tests").glob("*.py"))
    assert [name for name in files if name not in listed] == []
    assert [name for name in set(listed) if not (ROOT / "tests" / name).exists() and not exists(name)] == []
    headings = re.findall(r"^## (.*)$", text, flags=re.M)
    packages = sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists())
    assert [p for p in packages if not any(f"`{p}/`" in h for h in headings)] == []
