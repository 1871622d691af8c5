"""Every pipe table of the documentation renders as a table, not as raw ``| a | b |`` text.

MyST-parser (markdown-it's GFM tables) drops a table to a plain paragraph when its header and
separator rows have different cell counts, silently cuts a body row's extra cells, and splits a
cell at every unescaped ``|``, inside backticks and ``$...$`` too (``|q|`` must be written
``\\|q\\|``, which markdown-it turns back into ``|`` before parsing the cell).  ``sphinx -W`` warns
about none of these, so this test reads the markdown sources (a site build is too slow for the
default suite): in every table the header, the separator and every body row have the same number of
cells, split at unescaped pipes.  Where markdown-it is installed (the docs extra), each table is also
rendered and must come out as a table with that many columns.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)
SEPARATOR_CELL = re.compile(r"^\s*:?-+:?\s*$")
FENCE = re.compile(r"^\s{0,3}(`{3,}|~{3,})")


def cells(row: str) -> list[str]:
    """The cells of a table row, split at the pipes not escaped by a backslash."""
    parts = re.split(r"(?<!\\)\|", row.strip())
    if parts and not parts[0].strip():
        parts = parts[1:]
    if parts and not parts[-1].strip():
        parts = parts[:-1]
    return parts


def tables(text: str) -> list[tuple[int, list[str]]]:
    """(first line number, rows) of each run of two or more lines starting with ``|`` outside fenced blocks."""
    found, run, start, fence = [], [], 0, None
    for number, line in enumerate(text.splitlines() + [""], 1):
        m = FENCE.match(line)
        if fence is None and m:
            fence = m.group(1)[0] * len(m.group(1))
        elif fence is not None and line.strip().startswith(fence) and not line.strip().strip(fence[0]):
            fence = None
            continue
        if fence is None and line.lstrip().startswith("|"):
            if not run:
                start = number
            run.append(line)
            continue
        if len(run) > 1:  # a lone line starting with | (a list item's |q| = R) is text, not a table
            found.append((start, run))
        run = []
    return found


def table_problems(rows: list[str]) -> list[str]:
    """What would make markdown-it render these rows as anything but one table (empty: nothing)."""
    if len(rows) < 2 or not all(SEPARATOR_CELL.match(c) for c in cells(rows[1])):
        return ["the second row is not a separator row (| --- | --- |): the block renders as text"]
    width = len(cells(rows[0]))
    out = []
    if len(cells(rows[1])) != width:
        out.append(f"header has {width} cells, separator {len(cells(rows[1]))}: the block renders as text")
    out += [f"row {i + 1} has {len(cells(r))} cells, the header {width} (an unescaped | inside a cell?): {r.strip()}"
            for i, r in enumerate(rows[2:], 2) if len(cells(r)) != width]
    return out


def test_pages_are_found():
    names = {p.name for p in PAGES}
    assert {"index.md", "conventions.md", "units.md", "dzhanibekov.md"} <= names
    assert sum(len(tables(p.read_text())) for p in PAGES) > 20


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(DOCS)) for p in PAGES])
def test_every_table_has_one_cell_count(page):
    bad = [f"{page.name}:{line}: {problem}" for line, rows in tables(page.read_text()) for problem in table_problems(rows)]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(DOCS)) for p in PAGES])
def test_markdown_it_renders_every_table(page):
    """The renderer MyST uses agrees: each block is one table whose rows all have the header's width."""
    markdown_it = pytest.importorskip("markdown_it")
    md = markdown_it.MarkdownIt("commonmark").enable("table")
    for line, rows in tables(page.read_text()):
        tokens = md.parse("\n".join(rows) + "\n")
        assert [t.type for t in tokens].count("table_open") == 1, f"{page.name}:{line} renders as text"
        width = len(cells(rows[0]))
        row_widths, n = [], 0
        for t in tokens:
            if t.type == "tr_open":
                n = 0
            elif t.type in ("th_open", "td_open"):
                n += 1
            elif t.type == "tr_close":
                row_widths.append(n)
        assert row_widths == [width] * (len(rows) - 1), f"{page.name}:{line}"


@pytest.mark.parametrize("rows, ok", [
    (["| a | b |", "| --- | --- |", "| 1 | 2 |"], True),
    (["| a | b |", "|:--|--:|", r"| `x\|y` | \|q\| |"], True),
    (["| a | b |", "| --- | --- | --- |", "| 1 | 2 |"], False),
    (["| a | b |", "| --- | --- |", "| |q| | 2 |"], False),
    (["| a | b |", "| --- | --- |", "| `x|y` | 2 |"], False),
    (["| a | b |", "| 1 | 2 |"], False),
])
def test_the_check_tells_a_table_from_raw_text(rows, ok):
    """The checker on tables known to render (or not) as MyST does."""
    assert (table_problems(rows) == []) is ok


def test_fenced_blocks_are_not_tables():
    text = "```text\n| not | a table\n```\n\n| a | b |\n| - | - |\n| 1 | 2 |\n"
    assert tables(text) == [(5, ["| a | b |", "| - | - |", "| 1 | 2 |"])]
