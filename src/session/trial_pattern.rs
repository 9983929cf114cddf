//! The path pattern of a folder of trial files (docs/import.md): where a trial file's object,
//! classes and trial number are in its path below the folder, e.g. `{object}/*.csv` (the
//! default: one folder per object) or `{object}_{outcome}_{trial}.csv`.
//!
//! `{name}` captures a non-empty run of characters other than `/` (`{trial}`: digits only),
//! `*` any run of characters other than `/` (not captured), and every other character stands
//! for itself; `/` separates folders. Where several splits match (`{object}_{trial}.csv` on
//! `big_cup_3.csv`), earlier captures take the longest text that lets the rest match, as a
//! regular expression's greedy groups do: `big_cup` and `3`.

use std::collections::HashSet;

/// The capture holding a grasp's trial number: digits only.
pub const TRIAL: &str = "trial";

/// What is wrong with a trial pattern's text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PatternError {
    #[error("an empty pattern")]
    Empty,
    #[error("the pattern is a path below the folder: it cannot start with `/`")]
    Absolute,
    /// A `{` or `/` between a capture's braces.
    #[error("`{0}` inside a capture's braces")]
    InsideBraces(char),
    #[error("a `{{` is not closed")]
    Unclosed,
    #[error("a capture without a name (`{{}}`)")]
    Unnamed,
    #[error("`{{{0}}}` is captured twice")]
    Twice(String),
    #[error("a `}}` without its `{{`")]
    Unopened,
}

#[derive(Clone, Debug, PartialEq)]
enum Part {
    Literal(String),
    Capture(String),
    Any,
}

#[derive(Clone, Debug, PartialEq)]
pub struct TrialPattern {
    text: String,
    parts: Vec<Part>,
}

impl TrialPattern {
    /// Parse a pattern, or say what is wrong with it.
    pub fn parse(text: &str) -> Result<TrialPattern, PatternError> {
        if text.trim().is_empty() {
            return Err(PatternError::Empty);
        }
        if text.starts_with('/') {
            return Err(PatternError::Absolute);
        }
        let mut parts = Vec::new();
        let mut literal = String::new();
        let mut chars = text.chars();
        while let Some(c) = chars.next() {
            match c {
                '{' => {
                    let mut name = String::new();
                    loop {
                        match chars.next() {
                            Some('}') => break,
                            Some(c @ ('{' | '/')) => {
                                return Err(PatternError::InsideBraces(c));
                            }
                            Some(c) => name.push(c),
                            None => return Err(PatternError::Unclosed),
                        }
                    }
                    if name.trim().is_empty() {
                        return Err(PatternError::Unnamed);
                    }
                    if parts.iter().any(|p| *p == Part::Capture(name.clone())) {
                        return Err(PatternError::Twice(name));
                    }
                    if !literal.is_empty() {
                        parts.push(Part::Literal(std::mem::take(&mut literal)));
                    }
                    parts.push(Part::Capture(name));
                }
                '}' => return Err(PatternError::Unopened),
                '*' => {
                    if !literal.is_empty() {
                        parts.push(Part::Literal(std::mem::take(&mut literal)));
                    }
                    parts.push(Part::Any);
                }
                c => literal.push(c),
            }
        }
        if !literal.is_empty() {
            parts.push(Part::Literal(literal));
        }
        Ok(TrialPattern {
            text: text.to_string(),
            parts,
        })
    }

    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// The names it captures, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.parts.iter().filter_map(|p| match p {
            Part::Capture(n) => Some(n.as_str()),
            _ => None,
        })
    }

    /// Match a path below the folder (`/`-separated): each capture's name and text, in the
    /// pattern's order, or `None` when the path does not match.
    pub fn captures<'a>(&'a self, path: &'a str) -> Option<Vec<(&'a str, &'a str)>> {
        let mut spans = vec![(0, 0); self.parts.len()];
        let mut failed = HashSet::new();
        if !self.match_from(0, path, 0, &mut spans, &mut failed) {
            return None;
        }
        Some(
            self.parts
                .iter()
                .zip(&spans)
                .filter_map(|(p, &(a, b))| match p {
                    Part::Capture(n) => Some((n.as_str(), &path[a..b])),
                    _ => None,
                })
                .collect(),
        )
    }

    /// Whether parts `part..` match `path[pos..]`, recording capture spans. Failures are
    /// remembered by (part, position), so matching takes at most parts × length² steps
    /// whatever the path.
    fn match_from(
        &self,
        part: usize,
        path: &str,
        pos: usize,
        spans: &mut [(usize, usize)],
        failed: &mut HashSet<(usize, usize)>,
    ) -> bool {
        let Some(p) = self.parts.get(part) else {
            return pos == path.len();
        };
        if failed.contains(&(part, pos)) {
            return false;
        }
        let rest = &path[pos..];
        let matched = match p {
            Part::Literal(l) => {
                rest.starts_with(l.as_str())
                    && self.match_from(part + 1, path, pos + l.len(), spans, failed)
            }
            Part::Capture(_) | Part::Any => {
                let digits_only = matches!(p, Part::Capture(n) if n == TRIAL);
                let allowed = |c: char| c != '/' && (!digits_only || c.is_ascii_digit());
                let run = rest.find(|c: char| !allowed(c)).unwrap_or(rest.len());
                let shortest = usize::from(matches!(p, Part::Capture(_)));
                // Every end at a character boundary, longest first.
                let mut end = Some(run);
                let mut found = false;
                while let Some(e) = end.filter(|&e| e >= shortest) {
                    if self.match_from(part + 1, path, pos + e, spans, failed) {
                        spans[part] = (pos, pos + e);
                        found = true;
                        break;
                    }
                    end = rest[..e].char_indices().next_back().map(|(i, _)| i);
                }
                found
            }
        };
        if !matched {
            failed.insert((part, pos));
        }
        matched
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps(pattern: &str, path: &str) -> Option<Vec<(String, String)>> {
        let p = TrialPattern::parse(pattern).unwrap_or_else(|e| panic!("{pattern}: {e}"));
        p.captures(path).map(|c| {
            c.into_iter()
                .map(|(n, v)| (n.to_string(), v.to_string()))
                .collect()
        })
    }

    fn pairs(list: &[(&str, &str)]) -> Option<Vec<(String, String)>> {
        Some(
            list.iter()
                .map(|(n, v)| (n.to_string(), v.to_string()))
                .collect(),
        )
    }

    #[test]
    fn folders_and_file_names_capture_their_parts() {
        assert_eq!(
            caps("{object}/*.csv", "mug/trial-3.csv"),
            pairs(&[("object", "mug")])
        );
        assert_eq!(caps("{object}/*.csv", "mug/x/trial-3.csv"), None);
        assert_eq!(caps("{object}/*.csv", "trial-3.csv"), None);
        assert_eq!(
            caps("{object}_{outcome}_{trial}.csv", "cup_slip_12.csv"),
            pairs(&[("object", "cup"), ("outcome", "slip"), ("trial", "12")])
        );
        // The earlier capture takes the longest text that lets the rest match.
        assert_eq!(
            caps("{object}_{trial}.csv", "big_cup_3.csv"),
            pairs(&[("object", "big_cup"), ("trial", "3")])
        );
        // `{trial}` holds digits only; a capture is never empty.
        assert_eq!(caps("{object}_{trial}.csv", "cup_x.csv"), None);
        assert_eq!(caps("{object}_{trial}.csv", "_3.csv"), None);
        assert_eq!(caps("{object}.csv", "ü€.csv"), pairs(&[("object", "ü€")]));
    }

    #[test]
    fn a_long_path_against_many_captures_matches_quickly() {
        // Without remembering failures this tries about 200^5 splits.
        let pattern = "{a}a{b}a{c}a{d}a{e}b.csv";
        let p = TrialPattern::parse(pattern).unwrap_or_else(|e| panic!("{pattern}: {e}"));
        let path = format!("{}.csv", "a".repeat(200));
        assert_eq!(p.captures(&path), None);
    }

    #[test]
    fn malformed_patterns_are_refused() {
        for (bad, why, says) in [
            ("", PatternError::Empty, "an empty pattern"),
            (
                "/{object}.csv",
                PatternError::Absolute,
                "cannot start with `/`",
            ),
            ("{object", PatternError::Unclosed, "a `{` is not closed"),
            (
                "{}.csv",
                PatternError::Unnamed,
                "a capture without a name (`{}`)",
            ),
            ("a}.csv", PatternError::Unopened, "a `}` without its `{`"),
            ("{a/b}.csv", PatternError::InsideBraces('/'), "`/` inside"),
            (
                "{a}_{a}.csv",
                PatternError::Twice("a".into()),
                "`{a}` is captured twice",
            ),
        ] {
            let err = TrialPattern::parse(bad).unwrap_err();
            assert_eq!(err, why, "{bad}");
            assert!(err.to_string().contains(says), "{bad}: {err}");
        }
    }
}
