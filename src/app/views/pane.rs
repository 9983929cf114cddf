//! What a tile shows ([`Pane`]) and what a pane may ask of its layout ([`TileRequest`]): the
//! words the tile machinery (`tiles`) and the shared panes (`panes`) both speak, so neither
//! needs the other's module.

use egui_tiles::TileId;
use serde::{Deserialize, Serialize};

use crate::experiments::figure_id::FigureId;
use crate::experiments::result::AnalysisResult;

/// What a tile shows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Pane {
    /// A figure of the result the view shows.
    Figure(FigureId),
    /// A figure of one chosen result, kept beside the shown one for comparison.
    Pinned {
        figure: FigureId,
        /// The result's creation time and label (together they name it).
        created: u64,
        label: String,
    },
    /// The detail figure selected through figure `0` (a basis, a threshold).
    Detail(FigureId),
    /// Every number of the shown result.
    Scores,
    /// The replay of the focused grasp.
    Replay,
    /// The focused grasp as the shown stability model sees it: its key-frame patches, their
    /// reconstructions and the SVM's decision.
    Grasp,
    /// Recognition: accuracy as trials progress across every model of the session.
    Comparison,
    /// Speed against accuracy over every result.
    SpeedChart,
    /// The models on the speed chart, to open.
    Models,
    /// The active session's speed–accuracy frontiers by model size.
    Frontier,
    /// A tile of the live view.
    Live(LivePane),
    /// A plot of the Compare view.
    Compare(crate::compare::ComparePlot),
}

/// The live view's tiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LivePane {
    Touch,
    Traces,
    Model,
    Status,
}

impl LivePane {
    pub fn title(self) -> &'static str {
        match self {
            LivePane::Touch => "Latest frame",
            LivePane::Traces => "Traces",
            LivePane::Model => "Model at work",
            LivePane::Status => "Connection",
        }
    }
}

impl Pane {
    /// The tab title: short words from the figure's name (the figure's own title is drawn
    /// inside the tile).
    pub fn title(&self, result: Option<&AnalysisResult>) -> String {
        match self {
            Pane::Figure(id) => words(id.key()),
            Pane::Pinned { figure, label, .. } => format!("{} · {label}", words(figure.key())),
            Pane::Detail(id) => result
                .and_then(|r| r.details_of(*id))
                .map(|d| format!("Selected {}", d.selector))
                .unwrap_or_else(|| format!("{} detail", words(id.key()))),
            Pane::Scores => "All numbers".into(),
            Pane::Replay => "Replay".into(),
            Pane::Grasp => "Focused grasp".into(),
            Pane::Comparison => "Accuracy compared".into(),
            Pane::SpeedChart => "All trained models".into(),
            Pane::Models => "Models".into(),
            Pane::Frontier => "Frontier by model size".into(),
            Pane::Live(p) => p.title().into(),
            Pane::Compare(plot) => plot.title().into(),
        }
    }
}

/// "score-vs-bases" → "Score vs bases", "nmi-vs-effective" → "NMI vs effective".
fn words(name: &str) -> String {
    let s = name
        .split('-')
        .map(|w| match w {
            "nmi" | "svm" | "ari" => w.to_uppercase(),
            "kfold" => "10-fold".into(),
            _ => w.to_string(),
        })
        .collect::<Vec<_>>()
        .join(" ");
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().chain(c).collect(),
        None => s,
    }
}

/// What a pane asked of the layout this frame (applied after the tree is drawn).
pub enum TileRequest {
    Maximise(TileId),
    /// Put this pane beside the tile.
    AddBeside(Pane, TileId),
    /// Bring this pane's tab to the front, if the layout has it.
    Activate(Pane),
}
