//! CSV of the numbers a figure draws, with a header row. Missing values are written `NaN`;
//! numbers use Rust's shortest round-trip formatting, so nothing is lost.
//!
//! - chart: one row per point: `series, x[, category], y[, lower, upper][, label]` (the
//!   category: the name of the x slot, on a category axis), then one row per
//!   reference line (`series` = `reference: <label>`, the value in `x` or `y`);
//! - bars: one row per category, one column per group (and its error, if any);
//! - heatmap: the matrix, row labels in the first column, column labels in the header;
//! - image grid: one row per cell that has a value: `image, caption, row, column, value`.

use std::fmt::Write;

use super::FigureError;
use super::model::{Figure, FigureKind, Orientation};

/// Quote a field when it holds a separator, a quote or a line break (RFC 4180).
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn num(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else {
        format!("{v}")
    }
}

/// Append one CSV row, quoting fields where needed.
pub fn row(out: &mut String, cells: impl IntoIterator<Item = String>) {
    let cells: Vec<String> = cells.into_iter().map(|c| field(&c)).collect();
    // Writing to a String cannot fail.
    let _ = writeln!(out, "{}", cells.join(","));
}

/// The figure's data as CSV text.
pub fn to_csv(fig: &Figure) -> Result<String, FigureError> {
    fig.validate()?;
    let mut out = String::new();
    match &fig.kind {
        FigureKind::Chart(c) => {
            let errors = c.series.iter().any(|s| s.error.is_some());
            let labels = c.series.iter().any(|s| !s.point_labels.is_empty());
            // A category axis names each point's slot beside its position.
            let categories = !c.x.categories.is_empty();
            let mut header = vec!["series".to_string()];
            if categories {
                header.extend([format!("{} position", c.x.text()), c.x.title.clone()]);
            } else {
                header.push(c.x.text());
            }
            header.push(c.y.text());
            if errors {
                header.extend(["lower".to_string(), "upper".to_string()]);
            }
            if labels {
                header.push("label".into());
            }
            row(&mut out, header);
            for s in &c.series {
                for i in 0..s.x.len() {
                    let mut cells = vec![s.name.clone(), num(s.x[i])];
                    if categories {
                        cells.push(c.x.category_at(s.x[i]).unwrap_or_default().to_string());
                    }
                    cells.push(num(s.y[i]));
                    if errors {
                        let (lo, hi) = s
                            .error
                            .as_ref()
                            .map_or((String::new(), String::new()), |e| {
                                (num(e.lower[i]), num(e.upper[i]))
                            });
                        cells.extend([lo, hi]);
                    }
                    if labels {
                        cells.push(s.point_labels.get(i).cloned().unwrap_or_default());
                    }
                    row(&mut out, cells);
                }
            }
            for r in &c.ref_lines {
                let (x, y) = match r.orientation {
                    Orientation::Vertical => (num(r.value), String::new()),
                    Orientation::Horizontal => (String::new(), num(r.value)),
                };
                let mut cells = vec![format!("reference: {}", r.label), x];
                if categories {
                    cells.push(String::new());
                }
                cells.push(y);
                cells.resize(
                    cells.len() + 2 * errors as usize + labels as usize,
                    String::new(),
                );
                row(&mut out, cells);
            }
        }
        FigureKind::Bars(b) => {
            let mut header = vec![b.x.text()];
            for g in &b.groups {
                header.push(format!("{} [{}]", g.name, b.y.text()));
                if g.error.is_some() {
                    header.push(format!("{} error", g.name));
                }
            }
            row(&mut out, header);
            for (k, cat) in b.categories.iter().enumerate() {
                let mut cells = vec![cat.clone()];
                for g in &b.groups {
                    cells.push(num(g.values[k]));
                    if let Some(e) = &g.error {
                        cells.push(num(e[k]));
                    }
                }
                row(&mut out, cells);
            }
        }
        FigureKind::Heatmap(h) => {
            let corner = format!("{} \\ {} [{}]", h.y.text(), h.x.text(), h.colors.text());
            row(
                &mut out,
                std::iter::once(corner).chain(h.columns.iter().cloned()),
            );
            for (label, values) in h.rows.iter().zip(&h.values) {
                row(
                    &mut out,
                    std::iter::once(label.clone()).chain(values.iter().map(|&v| num(v))),
                );
            }
        }
        FigureKind::ImageGrid(g) => {
            let value = format!("value [{}]", g.colors.text());
            row(
                &mut out,
                ["image", "caption", "row", "column", &value].map(String::from),
            );
            for (i, im) in g.images.iter().enumerate() {
                for (r, values) in im.values.iter().enumerate() {
                    for (k, &v) in values.iter().enumerate().filter(|(_, v)| v.is_finite()) {
                        row(
                            &mut out,
                            [
                                i.to_string(),
                                im.caption.clone(),
                                r.to_string(),
                                k.to_string(),
                                num(v),
                            ],
                        );
                    }
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::model::{Axis, Series};

    #[test]
    fn fields_are_quoted_when_needed() {
        assert_eq!(field("a,b"), "\"a,b\"");
        assert_eq!(field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(field("plain"), "plain");
    }

    #[test]
    fn chart_csv_has_header_points_and_references() {
        let fig = Figure::chart(
            "Accuracy",
            Axis::new("Trials", ""),
            Axis::new("Accuracy", "%"),
            vec![Series::new("DS", vec![1.0, 2.0], vec![50.5, f64::NAN])],
        )
        .ref_line(Orientation::Vertical, 1.5, "threshold");
        let csv = to_csv(&fig).unwrap();
        assert_eq!(
            csv,
            "series,Trials,Accuracy (%)\nDS,1,50.5\nDS,2,NaN\nreference: threshold,1.5,\n"
        );
    }

    #[test]
    fn a_category_axis_names_each_points_slot() {
        let fig = Figure::chart(
            "Electrode by outcome",
            Axis::new("outcome", "").categories(vec!["success".into(), "fail, slip".into()]),
            Axis::new("mf taxel 7", "a.u."),
            vec![Series::new(
                "points",
                vec![0.8, 2.2, 2.6],
                vec![1.0, 2.0, 3.0],
            )],
        );
        let csv = to_csv(&fig).unwrap();
        assert_eq!(
            csv,
            "series,outcome position,outcome,mf taxel 7 (a.u.)\npoints,0.8,success,1\n\
             points,2.2,\"fail, slip\",2\npoints,2.6,,3\n"
        );
    }
}
