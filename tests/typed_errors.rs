//! Issue #42's rule for errors: one typed error per engine layer, with the lower layer's
//! error kept as its source; `Result<_, String>` only at the window and command-line edges
//! (`src/app/`, `src/cli/`, `src/main.rs`).
//!
//! The check reads the source (comments, and `#[cfg(test)]` modules, left out) and counts,
//! per file outside the edges:
//! - `Result<…, String>` (and `type Err = String` / `type Error = String`);
//! - `map_err(…)` whose closure turns the error it is given into text (`e.to_string()`,
//!   `format!("…{e}…")`, `format!("{}", e)`), so that the source is dropped.
//!
//! A file may hold at most what `ALLOWED` grants it, with the reason; a file holding fewer
//! than granted fails too, so that the allowance only ever shrinks.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where text is still the error, and why.
const ALLOWED: &[(&str, usize, &str)] = &[
    (
        "src/gp/sogp/state.rs",
        1,
        "a serde `Deserialize` impl: serde's errors carry text only (`serde::de::Error::custom`)",
    ),
    (
        "src/learners/mod.rs",
        1,
        "a serde `Deserialize` impl: serde's errors carry text only (`serde::de::Error::custom`)",
    ),
    (
        "src/session/bag/file.rs",
        1,
        "not an error: the name of the record's field that does not fit (`fields_fit`), placed in the message",
    ),
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The text without comments and without its `#[cfg(test)] mod …` tail.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod ") {
        Some(i) => &text[..i],
        None => text,
    };
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'"' {
            // A string literal stays (messages are looked at), skipped whole.
            let start = i;
            i += 1;
            while i < b.len() && b[i] != b'"' {
                if b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            i = (i + 1).min(b.len());
            out.push_str(&text[start..i]);
        } else if b[i] == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
            let end = text[i + 2..].find("*/").map_or(b.len(), |e| i + 2 + e + 2);
            out.extend(text[i..end].chars().filter(|&c| c == '\n'));
            i = end;
        } else {
            let c = text[i..].chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// The index of the `)` closing the `(` at `open`, strings skipped.
fn closing(s: &[u8], open: usize) -> usize {
    let mut depth = 0;
    let mut i = open;
    while i < s.len() {
        match s[i] {
            b'"' => {
                i += 1;
                while i < s.len() && s[i] != b'"' {
                    if s[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
            }
            b'(' => depth += 1,
            b')' => {
                depth -= 1;
                if depth == 0 {
                    return i;
                }
            }
            _ => {}
        }
        i += 1;
    }
    s.len()
}

/// `Result<…, String>` and `= String` error types.
fn string_results(code: &str) -> usize {
    let mut n = 0;
    for line in code.lines() {
        let mut rest = line;
        while let Some(i) = rest.find("Result<") {
            let tail = &rest[i..];
            let end = tail.find(';').unwrap_or(tail.len());
            if tail[..end].contains(", String>") {
                n += 1;
            }
            rest = &tail[7..];
        }
        if line.contains("type Err = String") || line.contains("type Error = String") {
            n += 1;
        }
    }
    n
}

/// `map_err` calls whose closure turns its error into text.
fn text_wrappings(code: &str) -> usize {
    let b = code.as_bytes();
    let mut n = 0;
    let mut from = 0;
    while let Some(i) = code[from..].find("map_err(") {
        let open = from + i + "map_err".len();
        let close = closing(b, open);
        let arg = &code[open + 1..close.min(code.len())];
        from = open + 1;
        // `|e| …` or `|err| …`: the closure's parameter.
        let Some(param) = arg
            .trim_start()
            .strip_prefix('|')
            .and_then(|a| a.split('|').next())
            .map(str::trim)
        else {
            continue;
        };
        if param.is_empty()
            || param == "_"
            || !param.chars().all(|c| c.is_alphanumeric() || c == '_')
        {
            continue;
        }
        let as_text = arg.contains(&format!("{param}.to_string()"))
            || arg.contains(&format!("{{{param}}}"))
            || arg.contains(&format!("{{{param}:"))
            || (arg.contains("format!(") && arg.contains(&format!(", {param})")));
        if as_text {
            n += 1;
        }
    }
    n
}

fn counts() -> BTreeMap<String, usize> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    let mut out = BTreeMap::new();
    for f in files {
        let rel = f
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if rel.starts_with("src/app/") || rel.starts_with("src/cli/") || rel == "src/main.rs" {
            continue;
        }
        let code = code(&std::fs::read_to_string(&f).unwrap());
        let n = string_results(&code) + text_wrappings(&code);
        if n > 0 {
            out.insert(rel, n);
        }
    }
    out
}

#[test]
fn engine_errors_are_typed_and_keep_their_sources() {
    let found = counts();
    let mut problems = Vec::new();
    for (file, &n) in &found {
        let allowed = ALLOWED
            .iter()
            .find(|(f, _, _)| f == file)
            .map_or(0, |&(_, a, _)| a);
        if n > allowed {
            problems.push(format!(
                "{file}: {n} text errors (`Result<_, String>`, or a `map_err` that turns its \
                 error into text) where {allowed} are allowed: give the layer's error type a \
                 variant that keeps the error as its source"
            ));
        }
    }
    for &(file, allowed, _) in ALLOWED {
        let n = found.get(file).copied().unwrap_or(0);
        if n < allowed {
            problems.push(format!(
                "{file}: {n} text errors, {allowed} allowed: lower its allowance to {n}"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The scanner sees what it is meant to see.
#[test]
fn the_scanner_counts_text_errors() {
    let src = r#"
        // fn f() -> Result<(), String> in a comment does not count
        fn a() -> Result<Vec<usize>, String> { Ok(vec![]) }
        fn b() -> Result<(), Error> { x.map_err(|e| Error::Data(e.to_string()))?; Ok(()) }
        fn c() { y.map_err(|err| format!("item {i}: {err}")); }
        fn d() { y.map_err(|_| format!("no {i}")); z.map_err(Error::Io); }
        fn e() { w.map_err(|e| Error::Io { path, source: e }); }
        impl TryFrom<String> for X { type Error = String; }
    "#;
    let code = code(src);
    assert_eq!(string_results(&code), 2);
    assert_eq!(text_wrappings(&code), 2);
}
