//! What a spec refuses: its layouts and trial pattern ([`SpecError`]), and a recording's
//! objects and classes ([`LabelError`]).

use crate::error::Kept;
use crate::session::error::shorten;
use crate::session::trial_pattern::PatternError;

/// What is wrong with a spec's layout or trial pattern. The caller names the spec and the
/// field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpecError {
    #[error(
        "`{}` is not a layout: use icub-fingertip, biotac-sp, grid RxC (e.g. grid 4x4) or a \
         layout object",
        shorten(name)
    )]
    UnknownLayout { name: String },
    /// A layout object that does not parse (the JSON parser's error kept).
    #[error("{0}")]
    LayoutObject(#[source] Kept<serde_json::Error>),
    #[error("expected a layout name or a layout object")]
    NotALayout,
    #[error("{0}")]
    Pattern(#[from] PatternError),
    /// A capture that is neither the object, the trial nor a label set.
    #[error(
        "`{{{}}}` is neither `{{object}}`, `{{trial}}` nor a label set of the spec",
        shorten(name)
    )]
    UnknownCapture { name: String },
    /// A pattern that does not capture the object or a label set.
    #[error(
        "`{pattern}` does not capture `{{{name}}}`: a trial's object and classes come from \
         its path"
    )]
    Uncaptured { pattern: String, name: String },
    #[error("`{pattern}` does not end in `.csv`: trial files are CSVs")]
    NotCsv { pattern: String },
    /// No `trials.pattern`, and the one made of the label sets' names is not one.
    #[error("no `trials.pattern`, and the default `{pattern}` is not one: {source}")]
    DefaultPattern {
        pattern: String,
        #[source]
        source: Kept<SpecError>,
    },
}

/// Why the spec refuses a recording's object or classes (a CSV row's, a bag window's or
/// event's, a trial file path's, a live stream's). The caller names where they were.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LabelError {
    #[error("an empty object name")]
    EmptyObject,
    /// An object the spec's `object` label set does not list.
    #[error(
        "object `{}` is not a class of label set `object` ({})",
        shorten(object),
        classes.join(", ")
    )]
    UnknownObject {
        object: String,
        classes: Vec<String>,
    },
    #[error(
        "`{}` is not a class of label set `{set}` ({})",
        shorten(class),
        classes.join(", ")
    )]
    NotAClass {
        class: String,
        set: String,
        classes: Vec<String>,
    },
    /// An `end` event (quoted as `shown`) whose labels are not one per recorded label set.
    #[error(
        "`{}` gives {given} labels; the spec's label sets ({}) need one each",
        shorten(shown),
        sets.join(", ")
    )]
    LabelCount {
        shown: String,
        given: usize,
        sets: Vec<String>,
    },
}
