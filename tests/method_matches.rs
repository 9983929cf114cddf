//! Issue #42's rule: no `match` on a method outside the registry ends in a catch-all (`_`
//! or a bare binding), so that a new method cannot slip silently into another method's
//! arm; the compiler then lists every place that must answer for it. The registry itself
//! (`src/catalogue/`) may, as it is where the methods are declared.
//!
//! The check reads the source: every `match` whose arms name a method type and whose arms
//! include a catch-all is reported with its file and line.

use std::path::{Path, PathBuf};

/// The method ids and the enums that mirror them (a model of each kind, each learner).
const METHOD_TYPES: &[&str] = &[
    "MethodId::",
    "ClassifierId::",
    "SupervisedLearner::",
    "UnsupervisedLearner::",
    "Model::",
    "Experts::",
    "Clusterer::",
    "TableOneLearner::",
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

/// The text with comments, string and char literals blanked (same length, newlines kept),
/// so that braces and arrows inside them do not count.
fn code_only(text: &str) -> Vec<u8> {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => {
                let end = text[i..].find('\n').map_or(b.len(), |e| i + e);
                blank(&mut out, i, end);
                i = end;
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let end = text[i + 2..].find("*/").map_or(b.len(), |e| i + 2 + e + 2);
                blank(&mut out, i, end);
                i = end;
            }
            b'r' if (b.get(i + 1) == Some(&b'"') || b.get(i + 1) == Some(&b'#'))
                && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')) =>
            {
                let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
                if b.get(i + 1 + hashes) != Some(&b'"') {
                    i += 1;
                    continue;
                }
                let close = format!("\"{}", "#".repeat(hashes));
                let start = i + 2 + hashes;
                let end = text[start..]
                    .find(&close)
                    .map_or(b.len(), |e| start + e + close.len());
                blank(&mut out, i, end);
                i = end;
            }
            b'"' => {
                let mut j = i + 1;
                while j < b.len() && b[j] != b'"' {
                    j += if b[j] == b'\\' { 2 } else { 1 };
                }
                blank(&mut out, i, (j + 1).min(b.len()));
                i = j + 1;
            }
            // A char literal ('x', '\n', '{'), not a lifetime ('a).
            b'\'' => {
                let len = if b.get(i + 1) == Some(&b'\\') {
                    b[i + 2..].iter().position(|&c| c == b'\'').map(|p| p + 3)
                } else {
                    let ch = text[i + 1..].chars().next().map_or(1, char::len_utf8);
                    (b.get(i + 1 + ch) == Some(&b'\'')).then_some(ch + 2)
                };
                match len {
                    Some(n) => {
                        blank(&mut out, i, i + n);
                        i += n;
                    }
                    None => i += 1,
                }
            }
            _ => i += 1,
        }
    }
    out
}

/// The top-level arm patterns of the `match` block that opens at `open` (a `{`).
fn arm_patterns(code: &[u8], open: usize) -> Vec<String> {
    let mut patterns = Vec::new();
    let (mut depth, mut start) = (0usize, open + 1);
    let mut i = open + 1;
    while i < code.len() {
        match code[i] {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' => depth = depth.saturating_sub(1),
            b'}' if depth == 0 => break,
            b'}' => {
                depth -= 1;
                // A block body ends its arm, unless it closed a struct pattern.
                let next = code[i + 1..]
                    .iter()
                    .position(|c| !c.is_ascii_whitespace())
                    .map(|p| i + 1 + p);
                let continues = next.is_some_and(|n| {
                    code[n..].starts_with(b"=>")
                        || code[n] == b'|'
                        || code[n..].starts_with(b"if ")
                        || code[n] == b','
                });
                if depth == 0 && !continues {
                    start = i + 1;
                }
            }
            b',' if depth == 0 => start = i + 1,
            b'=' if depth == 0 && code.get(i + 1) == Some(&b'>') => {
                let p = String::from_utf8_lossy(&code[start..i]).trim().to_string();
                patterns.push(p.trim_start_matches('|').trim().to_string());
                i += 1;
            }
            _ => {}
        }
        i += 1;
    }
    patterns
}

/// A pattern that takes whatever the arms above left: `_` or a bare binding, unguarded.
fn catch_all(pattern: &str) -> bool {
    pattern == "_"
        || (!pattern.is_empty()
            && pattern
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            && pattern.starts_with(|c: char| c.is_ascii_lowercase() || c == '_'))
}

/// Lines (1-based) of the `match`es in `text` that name a method type and end in a
/// catch-all.
fn wildcard_method_matches(text: &str) -> Vec<usize> {
    let code = code_only(text);
    let mut found = Vec::new();
    let mut at = 0;
    while let Some(p) = find_word(&code, b"match", at) {
        at = p + 5;
        // The block opens at the first `{` outside the scrutinee's brackets.
        let mut depth = 0usize;
        let mut open = None;
        for (j, &c) in code.iter().enumerate().skip(at) {
            match c {
                b'(' | b'[' => depth += 1,
                b')' | b']' => depth = depth.saturating_sub(1),
                b'{' if depth == 0 => {
                    open = Some(j);
                    break;
                }
                b';' if depth == 0 => break,
                _ => {}
            }
        }
        let Some(open) = open else { continue };
        let patterns = arm_patterns(&code, open);
        let names_method = patterns
            .iter()
            .any(|p| METHOD_TYPES.iter().any(|t| p.contains(t)));
        if names_method && patterns.iter().any(|p| catch_all(p)) {
            found.push(1 + code[..p].iter().filter(|&&c| c == b'\n').count());
        }
    }
    found
}

fn find_word(code: &[u8], word: &[u8], from: usize) -> Option<usize> {
    let is_ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    (from..code.len().saturating_sub(word.len() - 1)).find(|&i| {
        code[i..].starts_with(word)
            && (i == 0 || !is_ident(code[i - 1]))
            && code.get(i + word.len()).is_none_or(|&c| !is_ident(c))
    })
}

#[test]
fn no_match_on_a_method_outside_the_registry_ends_in_a_catch_all() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    files.sort();
    let mut offenders = Vec::new();
    for f in &files {
        let rel = f
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if rel.starts_with("src/catalogue/") {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        for line in wildcard_method_matches(&text) {
            offenders.push(format!("{rel}:{line}"));
        }
    }
    assert!(
        offenders.is_empty(),
        "a match on a method ends in a catch-all (make it exhaustive, or move the fact \
         into the catalogue's MethodInfo):\n  {}",
        offenders.join("\n  ")
    );
}

#[test]
fn the_check_sees_a_catch_all_and_passes_an_exhaustive_match() {
    let wild = r#"
fn f(m: MethodId) -> u8 {
    // a comment with a brace {
    let s = "a string with => and {";
    match m {
        MethodId::Ds | MethodId::Gs => 1,
        MethodId::Classifier(c) => { let _ = c; 2 }
        _ => 0,
    }
}
fn g(m: SupervisedLearner) -> u8 {
    match (m) {
        SupervisedLearner::Ds => 1,
        other => { let _ = other; 0 }
    }
}"#;
    assert_eq!(wildcard_method_matches(wild), vec![5, 12]);
    let exhaustive = r#"
fn f(m: MethodId, x: Option<u8>) -> u8 {
    let c = '{';
    match m {
        MethodId::Ds | MethodId::Gs => match x { Some(v) => v, _ => 0 },
        MethodId::Classifier(Foo { a, .. }) => a,
        MethodId::SparseSvm | MethodId::RawSvm => 3,
    }
}"#;
    assert!(wildcard_method_matches(exhaustive).is_empty());
    // A guarded binding is not a catch-all; `_` is, after any pattern.
    assert!(!catch_all("m if m.uses_features()"));
    assert!(catch_all("_") && catch_all("other"));
    assert!(!catch_all("MethodId::Ds"));
    // The arms of a nested match on another type do not count for the outer one.
    let nested_wild =
        "fn f() { match m { MethodId::Ds => match y { A::B => 1, _ => 2 }, MethodId::Gs => 3 } }";
    assert!(wildcard_method_matches(nested_wild).is_empty());
}
