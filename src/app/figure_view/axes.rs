//! Axes and legends of charts on screen: ticks at the figure model's scale, the legend in
//! the corner where it covers the fewest points.

use super::*;

/// How far from a frame's ends the first and last tick stay: half a label along the x axis
/// (clear of the value axis' labels), half a line along the y axis (clear of the header
/// above and the x axis' labels below).
pub(crate) const X_EDGE: f64 = 16.0;
pub(crate) const Y_EDGE: f64 = 9.0;

/// egui_plot puts the value axis' title this far left of the plot's rectangle.
pub(super) const TITLE_INSET: f32 = 5.0;

/// Show a plot `TITLE_INSET` in from the left, so that its value axis' title stays in.
pub(super) fn inset<R>(ui: &mut egui::Ui, plot: impl FnOnce(&mut egui::Ui) -> R) -> R {
    ui.horizontal_top(|ui| {
        ui.spacing_mut().item_spacing.x = 0.0;
        ui.add_space(TITLE_INSET);
        plot(ui)
    })
    .inner
}

/// egui_plot's default minimum grid spacing, in points: its `GridInput::base_step_size` is
/// this many points in plot units.
const GRID_SPACING_MIN: f64 = 8.0;

/// Grid marks at the export's ticks (1, 2, 5 × 10^k; round values on a log axis), about
/// one per `px_per_label` points and never fewer than three, thinned by the export's rule so
/// that no two labels touch (`room`: a label's extent along the axis, in points), so that the
/// screen shows the same ticks as the paper at any tile size. No mark lies within `edge`
/// points of either end: its label, centred on it, would run past the frame into a
/// neighbour's.
pub(crate) fn tick_spacer(
    scale: Scale,
    px_per_label: f64,
    edge: f64,
    room: impl Fn(&str) -> f64 + 'static,
) -> impl Fn(GridInput) -> Vec<GridMark> {
    move |input: GridInput| {
        let (lo, hi) = input.bounds;
        let per_px = input.base_step_size.max(f64::MIN_POSITIVE) / GRID_SPACING_MIN;
        let px = (hi - lo) / per_px;
        let max = figures::legibility::tick_count(px - 2.0 * edge, px_per_label);
        let (lo, hi) = if px > 4.0 * edge {
            (lo + edge * per_px, hi - edge * per_px)
        } else {
            (lo, hi)
        };
        let length = (hi - lo) / per_px;
        let ticks = figures::fitted_axis_ticks(
            value(scale, lo),
            value(scale, hi),
            scale,
            length,
            max,
            &room,
        );
        let coords: Vec<f64> = (ticks.into_iter())
            .filter_map(|(v, _)| coord(scale, v))
            .collect();
        // egui_plot draws a mark's label when its step leaves room for it: each mark's step
        // is the gap to its nearest neighbour (log ticks are unevenly spaced).
        (0..coords.len())
            .map(|i| {
                let before = i.checked_sub(1).map(|j| coords[i] - coords[j]);
                let after = coords.get(i + 1).map(|c| c - coords[i]);
                let step = before
                    .into_iter()
                    .chain(after)
                    .fold(f64::INFINITY, f64::min);
                GridMark {
                    value: coords[i],
                    step_size: if step.is_finite() { step } else { hi - lo },
                }
            })
            .collect()
    }
}

/// Grid marks of a category axis (`names` at 1, 2, …): one at each category in view,
/// every k-th when their names would touch (the export's rule, [`thin_categories`]), so
/// that each name shown fits; the points' tooltips name the rest.
///
/// [`thin_categories`]: figures::legibility::thin_categories
pub(crate) fn category_spacer(
    ui: &egui::Ui,
    names: &[String],
) -> impl Fn(GridInput) -> Vec<GridMark> + 'static {
    // The widest name and a gap, and never less than egui_plot's full-strength spacing.
    let font = egui::TextStyle::Body.resolve(ui.style());
    let needed = (names.iter())
        .map(|n| {
            let w = (ui.painter())
                .layout_no_wrap(n.clone(), font.clone(), Color32::WHITE)
                .size()
                .x;
            f64::from(w) + 10.0
        })
        .fold(32.0, f64::max);
    let count = names.len();
    move |input: GridInput| {
        let (lo, hi) = input.bounds;
        let per_px = input.base_step_size.max(f64::MIN_POSITIVE) / GRID_SPACING_MIN;
        let thin = figures::legibility::thin_categories(count, 1.0 / per_px, needed);
        (0..count)
            .filter(|&i| thin.shows(i) && (lo..=hi).contains(&((i + 1) as f64)))
            .map(|i| GridMark {
                value: (i + 1) as f64,
                step_size: thin.step as f64,
            })
            .collect()
    }
}

/// The room an x tick label needs along its axis: its width (digits at most, a little
/// conservative for the narrower '.' and '-') and a gap, and never less than the spacing at
/// which egui_plot draws a label at full strength ([`axis_hints`]' 32 points).
pub(crate) fn x_label_room(ui: &egui::Ui) -> impl Fn(&str) -> f64 + 'static {
    let font = egui::TextStyle::Body.resolve(ui.style());
    let digit = (ui.painter())
        .layout_no_wrap("0".into(), font, Color32::WHITE)
        .size()
        .x as f64;
    move |label: &str| (label.chars().count() as f64 * digit + 10.0).max(32.0)
}

/// The room a y tick label needs along its axis: a line and a little, and never less than
/// egui_plot's full-strength spacing there (16 points).
pub(crate) fn y_label_room(ui: &egui::Ui) -> impl Fn(&str) -> f64 + 'static {
    let line = f64::from(ui.text_style_height(&egui::TextStyle::Body));
    move |_: &str| (line * 1.15).max(16.0)
}

pub(super) fn tick_text(scale: Scale, mark: GridMark) -> String {
    figures::tick_label(value(scale, mark.value), mark.step_size, scale)
}

/// An axis whose tick labels show even when a tile is small (egui_plot hides labels
/// closer than 60 points by default), its title at most `room` long.
pub(super) fn axis_hints(
    ui: &egui::Ui,
    x: bool,
    title: &str,
    room: f32,
    scale: Scale,
) -> AxisHints<'static> {
    // The title cut to the frame's length (the export shrinks, then cuts, the same way).
    let font = egui::TextStyle::Body.resolve(ui.style());
    let title = fit_text(ui, title, &font, room);
    let hints = if x {
        AxisHints::new_x().label_spacing(24.0..=32.0)
    } else {
        AxisHints::new_y().label_spacing(12.0..=16.0)
    };
    hints
        .label(title)
        .formatter(move |mark, _| tick_text(scale, mark))
}

/// A category x axis: each mark named after its category (see [`category_spacer`]).
pub(super) fn category_axis_hints(
    ui: &egui::Ui,
    title: &str,
    room: f32,
    names: Vec<String>,
) -> AxisHints<'static> {
    let font = egui::TextStyle::Body.resolve(ui.style());
    let title = fit_text(ui, title, &font, room);
    AxisHints::new_x()
        .label_spacing(24.0..=32.0)
        .label(title)
        .formatter(move |mark, _| {
            let i = mark.value.round();
            match (mark.value - i).abs() < 1e-6 && i >= 1.0 {
                true => names.get(i as usize - 1).cloned().unwrap_or_default(),
                false => String::new(),
            }
        })
}

/// The legend in `corner`, one entry per series in the series' colour (a series' band and
/// error bars share its entry; the solid line or markers, drawn last, give the swatch its
/// colour).
pub(super) fn legend(corner: Corner) -> Legend {
    Legend::default()
        .position(corner)
        .color_conflict_handling(ColorConflictHandling::PickLast)
        .follow_insertion_order(true)
}
