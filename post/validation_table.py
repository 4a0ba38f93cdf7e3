#!/usr/bin/env python3
"""Assembles the README's validation table from the rows the tests write.

Each row of the table is written by the test that asserts it (``validation_row`` in
``tests/common/mod.rs``) to ``docs/validation/<key>.md`` when ``VALIDATION_WRITE_DOC`` is set;
sorting the file names gives the row order. This script puts the rows, sorted, under the
header ``| check | reference | result | test |`` and

* replaces the table in README.md between ``<!-- validation-table:start -->`` and
  ``<!-- validation-table:end -->``;
* writes docs/validation.md (the same table, its links made relative to docs/, and a line
  saying how it was generated).

Usage, from anywhere in the repository::

    VALIDATION_WRITE_DOC=1 cargo test --release
    python3 post/validation_table.py

``tests/validation_doc.rs`` fails when either table differs from what the committed rows
assemble to. Files are written to a temporary name and renamed.
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
    readme = ROOT / "README.md"
    write(readme, replace_table(readme.read_text(encoding="utf-8"), table, "README.md"))
    doc = (
        "# Validation\n\n"
        "What the tests check and what they measured. Every row is written by the test named in "
        "its last column, right after the assertions it reports, with the numbers of that run "
        "(`docs/validation/<key>.md`); this file and the table in the README were assembled from "
        "those rows by `python3 post/validation_table.py` after "
        "`VALIDATION_WRITE_DOC=1 cargo test --release`. Do not edit the table by hand: "
        "`tests/validation_doc.rs` fails when it differs from the rows.\n\n"
        f"{START}\n{table.replace('](docs/', '](')}\n{END}\n"
    )
    write(ROOT / "docs" / "validation.md", doc)
    print(f"{n} rows: README.md and docs/validation.md")


if __name__ == "__main__":
    main()
