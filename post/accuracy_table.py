#!/usr/bin/env python3
"""The README's "accuracy to expect" table, from the mesh-convergence study of docs/convergence.md.

The study (`LADDER_WRITE_DOC=1 cargo test --release --test ladder`) runs Hertz, Cattaneo–Mindlin,
the paper's Fig. 2 (ramp law, Lambda = 0.05) and a slip-controlled run through Q_max on every
level of the VM272 ladder, L0-L7, and writes its tables into docs/convergence.md. This script
reads three of them (per level; as history.csv reports; the finite-body references) and prints,
per level, the resolution (elements across the contact width 2a/h, the element size over the
slip-weakening transition length h/s0 of Fig. 2's law, s0 = 2 Lambda a / pi) and the error of
what a run reports (history.csv's a, c, b and the largest sampled Q) against the finite-body
limit, with the pressure's largest deviation from the finest level's. Errors are the mesh's
alone: the half-plane closed forms differ from that limit by the finite bodies' share, given
below the table.

    python3 post/accuracy_table.py                 # prints the table
    python3 post/accuracy_table.py --write README.md   # replaces it between the markers

`tests/validation_doc.rs` fails when the README's table differs from what this prints.
"""
import argparse
import math
import os
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
START = "<!-- accuracy-table:start -->"
END = "<!-- accuracy-table:end -->"
LAMBDA = 0.05   # Fig. 2's law


def tables(text):
    """The markdown tables of `text`, each as (header cells, rows of cells)."""
    out, cur = [], None
    for line in text.splitlines():
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
            if cur is None:
                cur = (cells, [])
            elif not set(line) <= set("|-: "):
                cur[1].append(cells)
        elif cur is not None:
            out.append(cur)
            cur = None
    if cur is not None:
        out.append(cur)
    return out


def find(ts, first_cells):
    for head, rows in ts:
        if head[:len(first_cells)] == first_cells:
            return head, rows
    sys.exit(f"accuracy_table.py: no table starting {first_cells} in docs/convergence.md")


def col(head, name):
    for i, h in enumerate(head):
        if h.startswith(name):
            return i
    sys.exit(f"accuracy_table.py: no column {name!r} in {head}")


def number(cell):
    try:
        return float(cell)
    except ValueError:
        return None


def pct(err):
    """Two significant digits; below 0.001 (%) as such."""
    if err is None:
        return "—"
    if abs(err) < 1e-3:
        return "< 0.001"
    digits = max(0, 1 - math.floor(math.log10(abs(err))))
    return f"{err:.{digits}f}"


def build():
    text = (ROOT / "docs" / "convergence.md").read_text(encoding="utf-8")
    ts = tables(text)
    per_head, per = find(ts, ["level", "h (mm)", "a_H/h"])
    his_head, his = find(ts, ["level", "node spacing h/2 (mm)"])
    ref_head, ref = find(ts, ["quantity", "observed order p", "limit"])
    limit = {r[0]: float(r[col(ref_head, "limit")]) for r in ref}
    names = [("a", "a (mm)", "a"), ("c CM", "c C–M (mm)", "c (C–M)"),
             ("c F2", "c Fig. 2 (mm)", "c (Fig. 2)"), ("b F2", "b Fig. 2 (mm)", "b (Fig. 2)"),
             ("Q", "Q_max sample", "Q_max")]
    lines = [
        "| level | elements across 2a | h/s0 (Λ = 0.05) | a | c, Cattaneo–Mindlin | c, Fig. 2 "
        "| b, Fig. 2 | Q_max | pressure (% of p0) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p, h in zip(per, his):
        level = p[0]
        a_h = float(p[col(per_head, "a_H/h")])
        h_s0 = math.pi / (2.0 * LAMBDA * a_h)
        errs = []
        for _, hcol, key in names:
            v = number(h[col(his_head, hcol)])
            errs.append(None if v is None else 100.0 * abs(v / limit[key] - 1.0))
        pl7 = number(p[col(per_head, "max\\|p − p_L7\\|/p0")])
        pressure = "(ref.)" if pl7 is None else pct(100.0 * pl7)
        lines.append(f"| {level} | {2 * a_h:g} | {h_s0:.2g} | "
                     + " | ".join(pct(e) for e in errs) + f" | {pressure} |")
    offsets = {r[0]: r[col(ref_head, "limit vs closed form")].split(" (")[0] for r in ref}
    note = (
        "Errors in % of the finite-body limit (c, b and Q_max of Fig. 2's law; a and c of "
        "Hertz and Cattaneo–Mindlin), as `history.csv` reports them; pressure: the largest "
        "|p − p_L7| over |x| ≤ 0.9a. The limits differ from the half-plane closed forms by "
        f"a {offsets['a']}, c (C–M) {offsets['c (C–M)']}, c (Fig. 2) {offsets['c (Fig. 2)']}, "
        f"b {offsets['b (Fig. 2)']}, Q_max {offsets['Q_max']} (two discs of 8 mm, a/R = 0.085)."
    )
    return "\n".join(lines) + "\n\n" + note


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", metavar="FILE", help="replace the table between the markers")
    o = ap.parse_args()
    table = build()
    if not o.write:
        print(table)
        return
    path = pathlib.Path(o.write)
    text = path.read_text(encoding="utf-8")
    if text.count(START) != 1 or text.count(END) != 1:
        sys.exit(f"accuracy_table.py: {path} needs `{START}` and `{END}` once each")
    a, b = text.index(START), text.index(END)
    new = text[:a + len(START)] + "\n" + table + "\n" + text[b:]
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    tmp.write_text(new, encoding="utf-8")
    os.replace(tmp, path)
    print(f"accuracy table: {path}")


if __name__ == "__main__":
    main()
