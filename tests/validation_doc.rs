//! The README's validation table is generated: each row is written by the test that asserts it
//! (`common::validation_row`, into `docs/validation/<key>.md` when `VALIDATION_WRITE_DOC` is
//! set), and `post/validation_table.py` assembles the rows, sorted by file name, into README.md
//! and docs/validation.md. This test fails when either table differs from what the committed
//! rows assemble to (so the README cannot drift from the generated rows), when a row file is not
//! one well-formed table line, or when a row's `test` column names no test binary, or one that
//! does not write that row.

mod common;
use common::{repo, validation_write_doc};

const HEADER: &str = "| check | reference | result | test |\n|---|---|---|---|";
const START: &str = "<!-- validation-table:start -->";
const END: &str = "<!-- validation-table:end -->";

/// The row files, sorted by name: (key, the row's one line).
fn rows() -> Vec<(String, String)> {
    let dir = repo().join("docs/validation");
    let mut out: Vec<(String, String)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".md") && !n.starts_with('.'))
        .map(|n| {
            let text = std::fs::read_to_string(dir.join(&n)).unwrap();
            (n.trim_end_matches(".md").to_string(), text)
        })
        .collect();
    out.sort();
    for (key, text) in &mut out {
        assert!(
            text.ends_with('\n') && text.lines().count() == 1,
            "docs/validation/{key}.md: not exactly one line"
        );
        *text = text.trim_end().to_string();
    }
    out
}

/// The table the rows assemble to, as `post/validation_table.py` writes it.
fn table(rows: &[(String, String)]) -> String {
    let lines: Vec<&str> = rows.iter().map(|(_, l)| l.as_str()).collect();
    format!("{HEADER}\n{}", lines.join("\n"))
}

/// The cells of a table line, split at the `|` not escaped by a backslash.
fn cells(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut escaped) = (Vec::new(), String::new(), false);
    for ch in line.chars() {
        if ch == '|' && !escaped {
            out.push(cur.trim().to_string());
            cur.clear();
        } else {
            cur.push(ch);
        }
        escaped = ch == '\\';
    }
    out.push(cur.trim().to_string());
    // A line `| a | b |` splits into "", a, b, "".
    assert!(
        out.len() >= 2 && out[0].is_empty() && out[out.len() - 1].is_empty(),
        "not a table line: {line}"
    );
    out[1..out.len() - 1].to_vec()
}

/// The text between the markers of `file` (which must hold each marker once, in order).
fn between_markers(file: &str) -> String {
    let text = std::fs::read_to_string(repo().join(file)).unwrap();
    assert_eq!(text.matches(START).count(), 1, "{file}: `{START}` once");
    assert_eq!(text.matches(END).count(), 1, "{file}: `{END}` once");
    let (a, b) = (text.find(START).unwrap(), text.find(END).unwrap());
    assert!(a < b, "{file}: markers out of order");
    text[a + START.len()..b].trim().to_string()
}

#[test]
fn every_row_is_one_table_line_written_by_the_test_it_names() {
    let rows = rows();
    assert!(rows.len() >= 35, "only {} rows", rows.len());
    for (key, line) in &rows {
        let prefix = key.split('-').next().unwrap();
        assert!(
            prefix.len() == 3 && prefix.bytes().all(|b| b.is_ascii_digit()),
            "{key}: the key must start with a three-digit order prefix"
        );
        let c = cells(line);
        assert_eq!(c.len(), 4, "{key}: {} cells in {line}", c.len());
        assert!(
            c[..3].iter().all(|s| !s.is_empty()),
            "{key}: empty cell in {line}"
        );
        let test = c[3]
            .strip_prefix('`')
            .and_then(|s| s.strip_suffix('`'))
            .unwrap_or_else(|| panic!("{key}: test column {} is not `name`", c[3]));
        let src = repo().join("tests").join(format!("{test}.rs"));
        let code = std::fs::read_to_string(&src)
            .unwrap_or_else(|e| panic!("{key}: test binary {}: {e}", src.display()));
        assert!(
            code.contains(&format!("\"{key}\"")),
            "{key}: tests/{test}.rs does not write this row (stale file?)"
        );
    }
}

#[test]
fn readme_and_docs_tables_are_the_assembled_rows() {
    let rows = rows();
    let want = table(&rows);
    let readme = between_markers("README.md");
    if validation_write_doc() {
        // The rows are being rewritten by this very run; `python3 post/validation_table.py`
        // assembles them afterwards (and writes docs/validation.md whole). The README markers
        // it needs are checked above.
        println!("VALIDATION_WRITE_DOC is set: the tables are compared on the next plain run");
        return;
    }
    let doc = between_markers("docs/validation.md");
    let hint =
        "run `VALIDATION_WRITE_DOC=1 cargo test --release` then `python3 post/validation_table.py`";
    for (file, got, want) in [
        ("README.md", readme, want.clone()),
        // docs/validation.md sits in docs/: its links are relative to it.
        ("docs/validation.md", doc, want.replace("](docs/", "](")),
    ] {
        if got != want {
            let first = got
                .lines()
                .zip(want.lines())
                .position(|(a, b)| a != b)
                .unwrap_or(got.lines().count().min(want.lines().count()));
            panic!(
                "{file}: the validation table differs from docs/validation/*.md at table line {} ({} lines against {}):\n  {}\nagainst the rows'\n  {}\n{hint}",
                first + 1,
                got.lines().count(),
                want.lines().count(),
                got.lines().nth(first).unwrap_or("(none)"),
                want.lines().nth(first).unwrap_or("(none)")
            );
        }
    }
}
