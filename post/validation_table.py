#!/usr/bin/env python3
"""Assembles the validation table of docs/validation.md from the rows the tests write.

Each row of the table is written by the test that asserts it (``validation_row`` in
``tests/common/mod.rs``) to ``docs/validation/<key>.md`` when ``VALIDATION_WRITE_DOC`` is set;
sorting the file names gives the row order. This script puts the rows, sorted, under the
header ``| check | reference | result | test |`` and replaces the table in docs/validation.md
between ``<!-- validation-table:start -->`` and ``<!-- validation-table:end -->`` (the rows'
links, written relative to the repository's root, made relative to docs/). The prose around
the markers is the page's own.

Usage, from anywhere in the repository::

    VALIDATION_WRITE_DOC=1 cargo test --release
    python3 post/validation_table.py

``tests/validation_doc.rs`` fails when the table differs from what the committed rows assemble
to. The file is written to a temporary name and renamed.
"""

import os
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
ROWS = ROOT / "docs" / "validation"
HEADER = "| check | reference | result | test |\n|---|---|---|---|"
START = "<!-- validation-table:start -->"
END = "<!-- validation-table:end -->"


def fail(msg):
    sys.exit(f"validation_table.py: {msg}")


def assemble():
    """The header and the rows of docs/validation/*.md, sorted by file name."""
    files = sorted(p for p in ROWS.glob("*.md") if not p.name.startswith("."))
    if not files:
        fail(f"no rows in {ROWS}: run `VALIDATION_WRITE_DOC=1 cargo test --release` first")
    rows = []
    for p in files:
        text = p.read_text(encoding="utf-8")
        lines = text.splitlines()
        if len(lines) != 1 or not text.endswith("\n"):
            fail(f"{p.relative_to(ROOT)}: not exactly one line")
        line = lines[0]
        if not (line.startswith("| ") and line.endswith(" |")):
            fail(f"{p.relative_to(ROOT)}: not a table line: {line}")
        rows.append(line)
    return HEADER + "\n" + "\n".join(rows), len(rows)


def replace_table(text, table, name):
    """`text` with the part between the markers replaced by `table`."""
    if text.count(START) != 1 or text.count(END) != 1:
        fail(f"{name}: needs `{START}` and `{END}` once each")
    a, b = text.index(START), text.index(END)
    if b < a:
        fail(f"{name}: markers out of order")
    return text[: a + len(START)] + "\n" + table + "\n" + text[b:]


def write(path, text):
    """Writes `text` to a temporary file beside `path`, then renames it."""
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def main():
    table, n = assemble()
    doc = ROOT / "docs" / "validation.md"
    text = replace_table(doc.read_text(encoding="utf-8"), table.replace("](docs/", "]("),
                         "docs/validation.md")
    write(doc, text)
    print(f"{n} rows: docs/validation.md")


if __name__ == "__main__":
    main()
