//! Bar charts on screen, with category names and hover values.

use super::axes::{TITLE_INSET, axis_hints, inset, tick_spacer, y_label_room};
use super::*;

pub(super) fn show_bars(ui: &mut egui::Ui, id: &str, bars: &figures::BarChart, size: Vec2) {
    let categories = bars.categories.clone();
    let n = categories.len().max(1);
    let n_groups = bars.groups.len().max(1) as f64;
    let width = 0.8 / n_groups;
    // The export's rule: every category labelled when the names fit their slots, else
    // every k-th, at least three; every bar names its category on hover.
    let font = egui::TextStyle::Body.resolve(ui.style());
    let widest = (categories.iter())
        .map(|c| {
            (ui.painter())
                .layout_no_wrap(c.clone(), font.clone(), Color32::WHITE)
                .size()
                .x
        })
        .fold(0.0f32, f32::max);
    // The plot's width less its value axis (about 60 points).
    let slot = ((size.x - 60.0).max(40.0) / n as f32) as f64;
    let thinning = figures::legibility::thin_categories(n, slot, f64::from(widest) + 8.0);
    let every = thinning.step;
    let label_font = FontId::new(font.size * thinning.scale as f32, font.family.clone());
    let y_title = bars.y.text();
    let y_unit = bars.y.unit.clone();
    let x_title = bars.x.title.clone();
    let mut plot = Plot::new(id)
        .allow_scroll(false)
        // Room right of the frame for half the last category's name, centred on its bar.
        .width((size.x - TITLE_INSET - widest / 2.0).max(0.0))
        .height(size.y)
        .custom_x_axes(vec![
            AxisHints::new_x()
                .label(fit_text(ui, &bars.x.text(), &font, size.x - 80.0))
                .label_spacing(1.0..=2.0)
                .tick_label_font(label_font)
                .formatter(move |m, _| {
                    let i = m.value.round();
                    if (m.value - i).abs() < 1e-6 && i >= 0.0 {
                        categories.get(i as usize).cloned().unwrap_or_default()
                    } else {
                        String::new()
                    }
                }),
        ])
        .custom_y_axes(vec![axis_hints(
            ui,
            false,
            &y_title,
            size.y - 50.0,
            bars.y.scale,
        )])
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
        .y_grid_spacer(tick_spacer(bars.y.scale, 36.0, Y_EDGE, y_label_room(ui)))
        .set_margin_fraction(Vec2::ZERO)
        .include_x(-0.5)
        .include_x(n as f64 - 0.5);
    // Anywhere in a category's column, the pointer names it (a bar of 0 is hard to find).
    let names = bars.categories.clone();
    let x_name = bars.x.title.clone();
    plot = plot.label_formatter(move |pos| match pos {
        HoverPosition::Elsewhere { position } => {
            let i = position.x.round();
            let name = (i >= 0.0).then(|| names.get(i as usize)).flatten()?;
            Some(format!("{x_name}: {name}"))
        }
        HoverPosition::NearDataPoint { .. } => None,
    });
    // The export's value range: from 0 to every bar and error, a share stopping at 1.
    if let Ok((lo, hi)) = figures::bar_limits(bars) {
        plot = plot.include_y(lo).include_y(hi);
    }
    inset(ui, |ui| {
        // A bar names itself only under the pointer: in a crowded chart, a neighbour's
        // within reach would answer for the column the pointer is in.
        ui.style_mut().interaction.interact_radius = 0.0;
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
        })
    });
}
