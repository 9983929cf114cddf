//! The replay view: the focused grasp frame by frame, in one tile of its own (the same pane
//! every analysis view can show beside its figures).

use super::Room;
use super::pane::Pane;
use crate::app::View;

#[derive(Default)]
pub struct ReplayRoom;

impl Room for ReplayRoom {
    fn view(&self) -> View {
        View::Replay
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        vec![vec![Pane::Replay]]
    }
}
