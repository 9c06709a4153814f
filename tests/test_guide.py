"""The user guide against the program: every command and option of ``navfmu --help`` in the
guide's command table and nothing there that the command line lacks; every relative link of
the README and of docs/ resolving to a file (and a heading, where it names one)."""
from __future__ import annotations

import re
from pathlib import Path

import click
import pytest

from orchestrator.cli.commands import cli

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide"
COMMANDS_PAGE = GUIDE / "commands.md"
GLOBAL_OPTIONS = {"--help", "--debug"}


def _commands():
    """(path words, click command) of every leaf command, e.g. (("convert", "kf-gins"), cmd)."""
    ctx = click.Context(cli)
    found = []

    def walk(group, words):
        for name in group.list_commands(ctx):
            cmd = group.get_command(ctx, name)
            if isinstance(cmd, click.Group):
                walk(cmd, words + (name,))
            else:
                found.append((words + (name,), cmd))

    walk(cli, ())
    return found


def _table_rows(text: str):
    """First cells of the Markdown table rows whose cell starts with `navfmu`."""
    return [m.group(1) for m in re.finditer(r"^\| `(navfmu [^`]*)`", text, re.M)]


def _rows_of(words, rows):
    prefix = "navfmu " + " ".join(words)
    return [r for r in rows if r == prefix or r.startswith(prefix + " ")]


def _options(cmd):
    return {o for p in cmd.params if isinstance(p, click.Option) for o in p.opts}


COMMANDS = _commands()


@pytest.mark.parametrize("words,cmd", COMMANDS, ids=[" ".join(w) for w, _ in COMMANDS])
def test_every_command_and_option_is_in_the_guide(words, cmd):
    rows = _rows_of(words, _table_rows(COMMANDS_PAGE.read_text()))
    assert rows, f"docs/guide/commands.md has no row for navfmu {' '.join(words)}"
    written = set(re.findall(r"--[a-z][a-z-]*", " ".join(rows)))
    assert _options(cmd) - written == set(), "options missing from the guide"
    assert written - _options(cmd) - GLOBAL_OPTIONS == set(), "options the command lacks"


def test_the_guide_names_no_command_the_program_lacks():
    known = {" ".join(w) for w, _ in COMMANDS}
    for row in _table_rows(COMMANDS_PAGE.read_text()):
        words = row.split()[1:]
        assert any(" ".join(words[:n]) in known for n in (1, 2)), row


def test_the_readme_lists_every_command_once():
    readme = (ROOT / "README.md").read_text()
    names = sorted({w[0] for w, _ in COMMANDS})
    listed = re.findall(r"^\| `navfmu ([a-z-]+)", readme, re.M)
    assert sorted(listed) == names


def _slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    text = re.sub(r"[`*]", "", heading.strip().lower())   # GitHub keeps underscores
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def _anchors(path: Path):
    return {_slug(m.group(1)) for m in re.finditer(r"^#+ (.+)$", path.read_text(), re.M)}


MARKDOWN = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


@pytest.mark.parametrize("page", MARKDOWN, ids=[str(p.relative_to(ROOT)) for p in MARKDOWN])
def test_every_relative_link_resolves(page):
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    broken = []
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        file_part, _, anchor = target.partition("#")
        path = (page.parent / file_part).resolve() if file_part else page
        if not path.exists():
            broken.append(target)
        elif anchor and path.suffix == ".md" and anchor not in _anchors(path):
            broken.append(target)
    assert broken == []


def test_the_guide_index_links_every_page():
    index = (GUIDE / "index.md").read_text()
    pages = {p.name for p in GUIDE.glob("*.md")} - {"index.md"}
    linked = set(re.findall(r"\]\(([\w-]+\.md)\)", index))
    assert pages - linked == set()
