//! Bar charts on screen, with category names and hover values.

use super::axes::{axis_hints, tick_spacer};
use super::*;

pub(super) fn show_bars(
    ui: &mut egui::Ui,
    id: &str,
    bars: &figures::BarChart,
    height: f32,
    legend_shown: bool,
) {
    let categories = bars.categories.clone();
    let n = categories.len().max(1);
    let n_groups = bars.groups.len().max(1) as f64;
    let width = 0.8 / n_groups;
    // Every category labelled when there is room, else every k-th, abbreviated to fit.
    let slot = (ui.available_width() - 60.0).max(40.0) / n as f32;
    let chars = ((slot / 6.5).floor() as usize).clamp(3, 14);
    let longest = categories
        .iter()
        .map(|c| c.chars().count())
        .max()
        .unwrap_or(1);
    let every = if longest <= chars {
        1
    } else {
        ((longest.min(8) as f32 * 6.5) / slot).ceil().max(1.0) as usize
    };
    let y_title = bars.y.text();
    let y_unit = bars.y.unit.clone();
    let x_title = bars.x.title.clone();
    let mut plot = Plot::new(id)
        .allow_scroll(false)
        .height(height)
        .custom_x_axes(vec![
            AxisHints::new_x()
                .label(figures_axis_text(&bars.x.title, &bars.x.unit))
                .label_spacing(8.0..=10.0)
                .formatter(move |m, _| {
                    let i = m.value.round();
                    if (m.value - i).abs() < 1e-6 && i >= 0.0 {
                        categories
                            .get(i as usize)
                            .map(|c| abbreviated(c, chars.max(longest.min(8))))
                            .unwrap_or_default()
                    } else {
                        String::new()
                    }
                }),
        ])
        .custom_y_axes(vec![axis_hints(false, y_title, bars.y.scale)])
        .x_grid_spacer(move |input: GridInput| {
            let (lo, hi) = input.bounds;
            (0..n)
                .step_by(every)
                .map(|k| k as f64)
                .filter(|&k| k >= lo && k <= hi)
                .map(|value| GridMark {
                    value,
                    step_size: every as f64,
                })
                .collect()
        })
        .y_grid_spacer(tick_spacer(bars.y.scale, 36.0));
    if legend_shown {
        plot = plot.legend(
            Legend::default()
                .position(Corner::RightTop)
                .color_conflict_handling(ColorConflictHandling::PickLast),
        );
    }
    plot.show(ui, |p| {
        for (g, group) in bars.groups.iter().enumerate() {
            let color = series_rgb(p.ctx(), group.color, g);
            let offset = (g as f64 - (n_groups - 1.0) / 2.0) * width;
            let items: Vec<Bar> = group
                .values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(c, &v)| {
                    let fill = if bars.sign_colors {
                        rgb(ColorMap::Diverging.at(if v >= 0.0 { 0.85 } else { 0.15 }))
                    } else {
                        color
                    };
                    Bar::new(c as f64 + offset, v)
                        .width(width * 0.95)
                        .fill(fill)
                        .name(bars.categories.get(c).cloned().unwrap_or_default())
                })
                .collect();
            let (group_name, x_title, y_unit) =
                (group.name.clone(), x_title.clone(), y_unit.clone());
            p.bar_chart(
                BarChart::new(group.name.clone(), items)
                    .color(color)
                    .element_formatter(Box::new(move |bar, _| {
                        format!(
                            "{group_name}\n{x_title}: {}\n{} {y_unit}",
                            bar.name,
                            exact(bar.value)
                        )
                    })),
            );
        }
    });
}
