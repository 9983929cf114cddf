//! A room's tiles: an `egui_tiles` tree of panes that persists per view, built from the
//! room's default groups (a grid of tab groups), kept in step with the shown result's figures
//! until the user edits it, with one tile maximised on request.

use egui_tiles::{
    Behavior, Container, EditAction, GridLayout, SimplificationOptions, Tile, TileId,
};
use serde::{Deserialize, Serialize};

use super::pane::TileRequest;
// The rooms name their default panes through here.
pub use super::pane::Pane;
use super::{Cx, Room, panes};
use crate::experiments::figure_id::FigureId;
use crate::experiments::result::AnalysisResult;

/// The smallest side of a tile (points).
const MIN_TILE: f32 = 160.0;

/// One view's tiles, as they persist between runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Layout {
    pub tree: egui_tiles::Tree<Pane>,
    /// The user changed the layout: it is no longer rebuilt for each new result.
    #[serde(default)]
    pub edited: bool,
    /// The tile shown alone, if one is maximised.
    #[serde(default)]
    pub maximised: Option<TileId>,
    /// The result the default layout was built for (not persisted: results are not).
    #[serde(skip)]
    pub built_for: Option<usize>,
}

impl Layout {
    /// A grid of tab groups; figures of `result` named nowhere in `groups` join the last group,
    /// and figures `result` lacks are left out.
    pub fn build(
        id: &str,
        groups: Vec<Vec<Pane>>,
        result: Option<&AnalysisResult>,
        result_index: Option<usize>,
    ) -> Layout {
        let mut groups: Vec<Vec<Pane>> = groups
            .into_iter()
            .map(|g| {
                g.into_iter()
                    .filter(|p| shows(p, result))
                    .collect::<Vec<_>>()
            })
            .filter(|g| !g.is_empty())
            .collect();
        if let Some(r) = result {
            let named = |id: FigureId| groups.iter().flatten().any(|p| *p == Pane::Figure(id));
            let extra: Vec<Pane> = r
                .figures
                .iter()
                .filter(|(n, _)| !named(*n))
                .map(|(n, _)| Pane::Figure(*n))
                .collect();
            if groups.len() < 4 {
                // Fill the grid first: each extra figure its own cell while there is room.
                let mut extra = extra.into_iter();
                while groups.len() < 4 {
                    match extra.next() {
                        Some(p) => groups.insert(groups.len().saturating_sub(1), vec![p]),
                        None => break,
                    }
                }
                if let Some(last) = groups.last_mut() {
                    last.extend(extra);
                }
            } else if let Some(last) = groups.last_mut() {
                last.extend(extra);
            }
        }
        let mut tiles = egui_tiles::Tiles::default();
        let cells: Vec<TileId> = groups
            .into_iter()
            .map(|g| {
                let panes = g.into_iter().map(|p| tiles.insert_pane(p)).collect();
                tiles.insert_tab_tile(panes)
            })
            .collect();
        let root = if cells.len() == 1 {
            cells[0]
        } else if cells.len() <= 4 {
            // Rows of two: a cell whose neighbour is hidden (a figure the result lacks, a
            // plot the session has no use for) takes its row instead of leaving a hole.
            let rows = (cells.chunks(2))
                .map(|row| match row {
                    [one] => *one,
                    _ => tiles.insert_horizontal_tile(row.to_vec()),
                })
                .collect();
            tiles.insert_vertical_tile(rows)
        } else {
            let mut grid = egui_tiles::Grid::new(cells);
            grid.layout = GridLayout::Columns(3);
            tiles.insert_new(Tile::Container(Container::Grid(grid)))
        };
        Layout {
            tree: egui_tiles::Tree::new(egui::Id::unique(("tiles", id)), root, tiles),
            edited: false,
            maximised: None,
            built_for: result_index,
        }
    }

    /// Add a pane as a new tab of the group that holds `beside` (else of the first group),
    /// and make it the active tab.
    pub fn add_beside(&mut self, pane: Pane, beside: Option<TileId>) {
        let new = self.tree.tiles.insert_pane(pane);
        let parent = beside.and_then(|b| self.tree.tiles.parent_of(b));
        let tabs = parent
            .filter(|p| {
                matches!(
                    self.tree.tiles.get(*p),
                    Some(Tile::Container(Container::Tabs(_)))
                )
            })
            .or_else(|| {
                self.tree.tiles.iter().find_map(|(id, t)| {
                    matches!(t, Tile::Container(Container::Tabs(_))).then_some(*id)
                })
            });
        match tabs {
            Some(id) => {
                if let Some(Tile::Container(Container::Tabs(t))) = self.tree.tiles.get_mut(id) {
                    t.add_child(new);
                    t.set_active(new);
                }
            }
            None => {
                let root = self.tree.root();
                let children: Vec<TileId> = root.into_iter().chain([new]).collect();
                let id = self.tree.tiles.insert_horizontal_tile(children);
                self.tree.root = Some(id);
            }
        }
        self.edited = true;
    }

    /// Fit the layout to the result it shows: a pane with nothing to show for it is hidden
    /// (it comes back for a result that has its figure), and a figure of the result that no
    /// tile shows gets a tab of the first group. The user's arrangement is otherwise kept.
    pub fn fit_to(&mut self, result: Option<&AnalysisResult>) {
        let panes: Vec<(TileId, bool)> = self
            .tree
            .tiles
            .iter()
            .filter_map(|(id, t)| match t {
                Tile::Pane(p) => Some((*id, shows(p, result))),
                Tile::Container(_) => None,
            })
            .collect();
        for (id, visible) in panes {
            self.tree.tiles.set_visible(id, visible);
        }
        let Some(r) = result else { return };
        let first_tabs =
            self.tree.tiles.iter().find_map(|(id, t)| {
                matches!(t, Tile::Container(Container::Tabs(_))).then_some(*id)
            });
        for (id, _) in &r.figures {
            let pane = Pane::Figure(*id);
            if self.tree.tiles.find_pane(&pane).is_some() {
                continue;
            }
            let new = self.tree.tiles.insert_pane(pane);
            match first_tabs.and_then(|t| self.tree.tiles.get_mut(t)) {
                Some(Tile::Container(Container::Tabs(t))) => t.add_child(new),
                _ => {
                    let children: Vec<TileId> = self.tree.root().into_iter().chain([new]).collect();
                    let tabs = self.tree.tiles.insert_tab_tile(children);
                    self.tree.root = Some(tabs);
                }
            }
        }
    }

    /// A group of tabs, or a row of groups, shows only while something in it does: one
    /// whose every pane is hidden gives its room to the others rather than showing empty.
    pub fn fold_empty_containers(&mut self) {
        // Children before parents: a row's visibility reads its groups' just set.
        let Some(root) = self.tree.root else { return };
        let mut order = Vec::new();
        let mut stack = vec![root];
        while let Some(id) = stack.pop() {
            order.push(id);
            if let Some(Tile::Container(c)) = self.tree.tiles.get(id) {
                stack.extend(c.children());
            }
        }
        for &id in order.iter().rev() {
            let visible = match self.tree.tiles.get(id) {
                Some(Tile::Container(c)) => {
                    c.children().any(|child| self.tree.tiles.is_visible(*child))
                }
                _ => continue,
            };
            self.tree.tiles.set_visible(id, visible);
        }
    }

    /// Make the tab holding `pane` the active one of its group.
    pub fn activate(&mut self, pane: &Pane) {
        if let Some(id) = self.tree.tiles.find_pane(pane) {
            self.tree.make_active(|t, _| t == id);
        }
    }
}

struct RoomTiles<'r, 'c, 'a> {
    room: &'r mut dyn Room,
    cx: &'c mut Cx<'a>,
    requests: Vec<TileRequest>,
    edited: bool,
}

impl Behavior<Pane> for RoomTiles<'_, '_, '_> {
    fn tab_title_for_pane(&mut self, pane: &Pane) -> egui::WidgetText {
        let shown = self.room.kind().and_then(|k| self.cx.shown(k));
        pane.title(shown.map(|i| &self.cx.analyses.results[i]))
            .into()
    }

    fn pane_ui(
        &mut self,
        ui: &mut egui::Ui,
        tile_id: TileId,
        pane: &mut Pane,
    ) -> egui_tiles::UiResponse {
        let frame = egui::Frame::new().inner_margin(6.0);
        frame.show(ui, |ui| {
            ui.set_min_size(ui.available_size());
            if !self.room.pane_ui(ui, pane, self.cx) {
                panes::pane_ui(ui, pane, tile_id, self.room, self.cx, &mut self.requests);
            }
        });
        egui_tiles::UiResponse::None
    }

    fn top_bar_right_ui(
        &mut self,
        _tiles: &egui_tiles::Tiles<Pane>,
        ui: &mut egui::Ui,
        _tile_id: TileId,
        tabs: &egui_tiles::Tabs,
        _scroll_offset: &mut f32,
    ) {
        if let Some(active) = tabs.active
            && ui
                .small_button("Maximise")
                .on_hover_text("Show this tile alone (Restore brings the layout back)")
                .clicked()
        {
            self.requests.push(TileRequest::Maximise(active));
        }
    }

    fn is_tab_closable(&self, _tiles: &egui_tiles::Tiles<Pane>, _tile_id: TileId) -> bool {
        true
    }

    fn simplification_options(&self) -> SimplificationOptions {
        SimplificationOptions {
            all_panes_must_have_tabs: true,
            ..Default::default()
        }
    }

    fn gap_width(&self, _style: &egui::Style) -> f32 {
        4.0
    }

    /// No tile is squeezed below a readable size (a chart with its ticks, a 4 × 7 heatmap).
    fn min_size(&self) -> f32 {
        MIN_TILE
    }

    fn on_edit(&mut self, _action: EditAction) {
        // Any edit, a tab chosen included, is the user's layout from now on.
        self.edited = true;
    }
}

/// Whether `pane` has something to show for `result`, the shown result of its room (None:
/// the room shows none, or has none yet).
fn shows(pane: &Pane, result: Option<&AnalysisResult>) -> bool {
    match (pane, result) {
        (Pane::Figure(id), Some(r)) => r.figure(*id).is_some(),
        (Pane::Detail(id), Some(r)) => r.figure(*id).is_some() && r.details_of(*id).is_some(),
        (Pane::Figure(_) | Pane::Detail(_), None) => false,
        (Pane::Grasp, _) => result.is_some_and(|r| !r.grasp_codes.is_empty()),
        _ => true,
    }
}

/// Draw `layout` for `room` in the rest of `ui`.
pub fn show(ui: &mut egui::Ui, layout: &mut Layout, room: &mut dyn Room, cx: &mut Cx) {
    let shown = room.kind().and_then(|k| cx.shown(k));
    layout.fit_to(shown.map(|i| &cx.analyses.results[i]));
    let hidden: Vec<TileId> = (layout.tree.tiles.iter())
        .filter_map(|(id, t)| matches!(t, Tile::Pane(p) if room.hides(p)).then_some(*id))
        .collect();
    for id in hidden {
        layout.tree.tiles.set_visible(id, false);
    }
    layout.fold_empty_containers();
    let mut behavior = RoomTiles {
        room,
        cx,
        requests: Vec::new(),
        edited: false,
    };
    // The tiles keep to the panel they are in: a wide row above them (a long headline)
    // widens the panel's layout rect past its clip, and egui_tiles clips each tile to the
    // tile's own rect, which would then paint over the form beside the panel.
    let rect = ui.available_rect_before_wrap().intersect(ui.clip_rect());
    let mut ui = ui.new_child(egui::UiBuilder::new().max_rect(rect));
    let ui = &mut ui;
    match layout.maximised {
        Some(id)
            if layout.tree.tiles.get_pane(&id).is_some() && layout.tree.tiles.is_visible(id) =>
        {
            ui.horizontal(|ui| {
                if ui.button("Restore layout").clicked() {
                    layout.maximised = None;
                }
                if let Some(p) = layout.tree.tiles.get_pane(&id) {
                    let title = behavior.tab_title_for_pane(p);
                    ui.strong(title.text());
                }
            });
            if let Some(Tile::Pane(pane)) = layout.tree.tiles.get_mut(id) {
                let _ = behavior.pane_ui(ui, id, pane);
            }
        }
        _ => {
            layout.maximised = None;
            layout.tree.ui(&mut behavior, ui);
        }
    }
    if behavior.edited {
        layout.edited = true;
    }
    for r in behavior.requests {
        match r {
            TileRequest::Maximise(id) => layout.maximised = Some(id),
            TileRequest::AddBeside(pane, id) => layout.add_beside(pane, Some(id)),
            TileRequest::Activate(pane) => layout.activate(&pane),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::result::tests::result;

    fn pane_visible(layout: &Layout, pane: &Pane) -> Option<bool> {
        let id = layout.tree.tiles.find_pane(pane)?;
        Some(layout.tree.tiles.is_visible(id))
    }

    /// A layout the user arranged for one result hides the tiles whose figures the next
    /// result lacks, gives that result's own figures tabs, and shows the hidden ones again
    /// for a result that has them.
    #[test]
    fn a_layout_fits_each_result_it_shows() {
        let first = result();
        let (first_id, _) = first.figures[0];
        let mut other = result();
        other.figures[0].0 = FigureId::Confusion;
        let mut layout = Layout::build(
            "test",
            vec![vec![Pane::Figure(first_id), Pane::Scores]],
            Some(&first),
            Some(0),
        );
        layout.edited = true;
        layout.fit_to(Some(&other));
        assert_eq!(pane_visible(&layout, &Pane::Figure(first_id)), Some(false));
        assert_eq!(
            pane_visible(&layout, &Pane::Figure(FigureId::Confusion)),
            Some(true)
        );
        assert_eq!(pane_visible(&layout, &Pane::Scores), Some(true));
        layout.fit_to(Some(&first));
        assert_eq!(pane_visible(&layout, &Pane::Figure(first_id)), Some(true));
        assert_eq!(
            pane_visible(&layout, &Pane::Figure(FigureId::Confusion)),
            Some(false)
        );
    }
}
