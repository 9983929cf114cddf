//! The export's legibility check, shared by the layout tests and the screen audit: a
//! figure laid out at a size (a tile, or an export preset) by the export's own code, and
//! judged on the layout record it keeps.

use tactile_workbench::figures::{Figure, FigureLayout, RenderOptions, layout_of};

/// A workbench tile, and the export presets (column, page width, screen).
pub fn sizes() -> Vec<(&'static str, RenderOptions)> {
    vec![
        (
            "tile 300×200",
            RenderOptions {
                width: 300,
                height: 200,
                dpi: 96.0,
            },
        ),
        ("column preset", RenderOptions::column()),
        ("page preset", RenderOptions::page()),
        ("screen preset", RenderOptions::default()),
    ]
}

/// What is wrong with the layout of `fig` at this size (empty when nothing is).
pub fn legibility_problems(fig: &Figure, opts: &RenderOptions) -> Vec<String> {
    let layout: FigureLayout = match layout_of(fig, opts) {
        Ok(l) => l,
        Err(e) => return vec![format!("not drawn: {e}")],
    };
    let mut problems = Vec::new();
    for (a, b) in layout.overlapping_texts() {
        problems.push(format!("{:?} overprints {:?}", a.text, b.text));
    }
    for t in &layout.texts {
        let b = t.bounds;
        let slack = 1.0;
        if b.left < -slack
            || b.top < -slack
            || b.right > layout.width + slack
            || b.bottom > layout.height + slack
        {
            problems.push(format!("{:?} runs off the image", t.text));
        }
    }
    for axis in &layout.axes {
        let distinct: std::collections::BTreeSet<&String> = axis.labels.iter().collect();
        if distinct.len() < axis.labels.len() {
            problems.push(format!(
                "axis {:?} repeats a tick label: {:?}",
                axis.title, axis.labels
            ));
        }
        let needed = axis.categories.map_or(3, |n| n.min(3));
        if axis.labels.len() < needed {
            problems.push(format!(
                "axis {:?} shows {} tick labels {:?}",
                axis.title,
                axis.labels.len(),
                axis.labels
            ));
        }
    }
    let hidden = layout.data_under_legend().len();
    if hidden > 0 {
        problems.push(format!("the legend covers {hidden} data marks"));
    }
    problems
}
