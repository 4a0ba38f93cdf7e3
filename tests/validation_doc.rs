//! The validation table of docs/validation.md is generated: each row is written by the test
//! that asserts it (`common::validation_row`, into `docs/validation/<key>.md` when
//! `VALIDATION_WRITE_DOC` is set), and `post/validation_table.py` assembles the rows, sorted by
//! file name, between the markers of docs/validation.md. This test fails when the table differs
//! from what the committed rows assemble to (so the page cannot drift from the generated rows),
//! when a row file is not one well-formed table line, when a row's `test` column names no test
//! binary, or one that does not write that row, and when README.md holds a copy of the table
//! (it links to the page instead) or no link to it.
//!
//! The README's "accuracy to expect" table is generated too, by `post/accuracy_table.py` from
//! the tables `tests/ladder.rs` writes into docs/convergence.md; it must be what the script
//! prints.

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

/// The text between the validation-table markers of `file` (each once, in order).
fn between_markers(file: &str) -> String {
    between(file, START, END)
}

/// The text of `file` between `start` and `end` (each once, in order).
fn between(file: &str, start: &str, end: &str) -> String {
    let text = std::fs::read_to_string(repo().join(file)).unwrap();
    assert_eq!(text.matches(start).count(), 1, "{file}: `{start}` once");
    assert_eq!(text.matches(end).count(), 1, "{file}: `{end}` once");
    let (a, b) = (text.find(start).unwrap(), text.find(end).unwrap());
    assert!(a < b, "{file}: markers out of order");
    text[a + start.len()..b].trim().to_string()
}

#[test]
fn the_readme_accuracy_table_is_what_the_ladder_study_gives() {
    let out = std::process::Command::new("python3")
        .arg(repo().join("post/accuracy_table.py"))
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "post/accuracy_table.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let want = String::from_utf8(out.stdout).unwrap().trim().to_string();
    let got = between(
        "README.md",
        "<!-- accuracy-table:start -->",
        "<!-- accuracy-table:end -->",
    );
    assert!(
        got == want,
        "README.md: the accuracy table differs from what `python3 post/accuracy_table.py` \
         prints from docs/convergence.md; run `python3 post/accuracy_table.py --write README.md`\n\
         README:\n{got}\nscript:\n{want}"
    );
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
fn the_validation_page_holds_the_assembled_rows() {
    let rows = rows();
    let want = table(&rows);
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    assert!(
        !readme.contains(START) && !readme.contains(END),
        "README.md holds a copy of the validation table: it links to docs/validation.md instead"
    );
    assert!(
        readme.contains("](docs/validation.md)"),
        "README.md does not link to docs/validation.md"
    );
    let doc = between_markers("docs/validation.md");
    if validation_write_doc() {
        // The rows are being rewritten by this very run; `python3 post/validation_table.py`
        // assembles them afterwards. The markers it needs are checked above.
        println!("VALIDATION_WRITE_DOC is set: the table is compared on the next plain run");
        return;
    }
    let hint =
        "run `VALIDATION_WRITE_DOC=1 cargo test --release` then `python3 post/validation_table.py`";
    // docs/validation.md sits in docs/: its links are relative to it.
    let want = want.replace("](docs/", "](");
    if doc != want {
        let first = doc
            .lines()
            .zip(want.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(doc.lines().count().min(want.lines().count()));
        panic!(
            "docs/validation.md: the validation table differs from docs/validation/*.md at table line {} ({} lines against {}):\n  {}\nagainst the rows'\n  {}\n{hint}",
            first + 1,
            doc.lines().count(),
            want.lines().count(),
            doc.lines().nth(first).unwrap_or("(none)"),
            want.lines().nth(first).unwrap_or("(none)")
        );
    }
}
