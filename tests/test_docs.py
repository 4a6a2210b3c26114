"""The code in README.md and docs/*.md runs as written, so the pages stay true.

Per page, in a fresh temporary working folder (with ``tir_files/`` linked to the sample files, as in the
repository root), the blocks in page order: a ```python block is executed as written; in a ```console block every
line ``$ mftyre ...`` runs through the command line (``mftyre.cli.main``) and must exit 0 (a line may use files
made by earlier lines or blocks of the same page; other ``$`` lines, e.g. the install, are not run); ```text
blocks are not run. No other block language is used: a block is either checked or plainly text.
"""
from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

from mftyre import cli
from mftyre.files import sample_tir

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```([\w+-]*)[ \t]*\n(.*?)^```[ \t]*$", re.M | re.S)
LANGUAGES = ("python", "console", "text")
#: the README's test command, which .ci/run runs
TEST_COMMAND = ('python3 -m venv .venv && . .venv/bin/activate && pip install -q -e ".[test]" && '
                'python -m pytest -q -n 2 --dist loadfile')


def blocks(page: Path) -> list[tuple[str, str, int]]:
    """(language, code, line) of every fenced block of ``page``."""
    text = page.read_text(encoding="utf-8")
    return [(m.group(1), m.group(2), text.count("\n", 0, m.start()) + 1) for m in FENCE.finditer(text)]


def mftyre_lines(code: str) -> list[str]:
    return [line[len("$ "):] for line in code.splitlines() if line.startswith("$ mftyre ")]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_code_blocks_run(page, tmp_path, monkeypatch):
    (tmp_path / "tir_files").symlink_to(sample_tir("car_205_60R15_mf61.tir").parent, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    where = page.relative_to(ROOT)
    for language, code, line in blocks(page):
        assert language in LANGUAGES, f"{where}:{line}: a ```{language or ''} block; use one of {LANGUAGES}"
        if language == "python":
            exec(compile(code, f"{where}:{line}", "exec"), {"__name__": "__main__"})
        elif language == "console":
            for command in mftyre_lines(code):
                argv = shlex.split(command)[1:]
                assert not {"|", ">", "<", "&&", ";"} & set(argv), f"{where}:{line}: shell syntax in {command!r}"
                out, err = io.StringIO(), io.StringIO()
                with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                    status = cli.main(argv)
                assert status == 0, f"{where}:{line}: `{command}` exited {status}:\n{err.getvalue()[-2000:]}"


def test_pages_have_code_that_is_checked():
    """The pages that show commands show some that run (a page of text blocks alone would test nothing)."""
    checked = {page.name for page in PAGES
               if any(lang == "python" or (lang == "console" and mftyre_lines(code)) for lang, code, _ in blocks(page))}
    for name in ("README.md", "validation.md", "fitting.md", "swift.md", "fmu.md", "soil.md", "cli.md"):
        assert name in checked, f"{name} runs no code"


def test_readme_is_a_front_door():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    lines = text.splitlines()
    assert len(text) < 15_000, f"README.md has {len(text)} characters"
    head = "\n".join(lines[:60])
    assert "pip install" in head and TEST_COMMAND in head, "install and the two commands within the first 60 lines"
    assert TEST_COMMAND in (ROOT / ".ci" / "run").read_text(encoding="utf-8"), ".ci/run runs the README's command"
    assert "mftyre demo" in head
    assert re.search(r"!\[[^]]*\]\((docs/[\w.-]+\.png)\)", head), "a picture near the top"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_relative_links_resolve(page):
    """Links to files of the repository point at files that exist."""
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        assert (page.parent / target).exists(), f"{page.relative_to(ROOT)}: link to missing {target}"


def test_no_paths_of_the_development_machine():
    """Pages name paths a user has (the repository's own, ``../shared/reference/`` beside it), not ours."""
    for page in [*PAGES, ROOT / "tir_files" / "README.md"]:
        assert "/work/" not in page.read_text(encoding="utf-8"), f"{page.relative_to(ROOT)} names /work/"


def test_notebooks_extra_opens_the_notebooks():
    import tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["optional-dependencies"]
    assert any(req.startswith(("jupyterlab", "notebook")) for req in extras["notebooks"])
    assert 'pip install -e ".[notebooks]"' in (ROOT / "README.md").read_text(encoding="utf-8")
