//! The comparison's figures, in the figure model every other figure uses (so they export
//! to SVG, PDF, PNG and CSV and pass the same readability audit): the grasps overlaid, one
//! band (or distribution) per group, and a grasps × time heatmap sorted by group.

use serde::{Deserialize, Serialize};

use super::groups::Groups;
use super::stats::{Band, Distribution, Spread, Trace};
use crate::figures::{
    Axis, AxisTitle, ColorScale, Figure, FigureKind, Series, SeriesStyle, series_color,
};
use crate::rng::Rng;
use crate::session::Session;

/// The comparison's plots, named once: the tile that shows each and its export's file stem.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ComparePlot {
    /// The selection's grasps overlaid (a strip of points for single frames).
    Overlay,
    /// One band per group (one distribution per group for single frames).
    Groups,
    /// Grasps × time of one signal, sorted by group.
    Heatmap,
}

impl ComparePlot {
    pub const ALL: [ComparePlot; 3] = [
        ComparePlot::Overlay,
        ComparePlot::Groups,
        ComparePlot::Heatmap,
    ];

    /// The export's file stem.
    pub fn key(self) -> &'static str {
        match self {
            ComparePlot::Overlay => "compare-overlay",
            ComparePlot::Groups => "compare-groups",
            ComparePlot::Heatmap => "compare-heatmap",
        }
    }

    pub fn title(self) -> &'static str {
        match self {
            ComparePlot::Overlay => "Grasps overlaid",
            ComparePlot::Groups => "Groups",
            ComparePlot::Heatmap => "Grasps × time",
        }
    }
}

/// A grasp as a plot names it: "object #trial", else "object · grasp n".
pub fn grasp_name(session: &Session, g: usize) -> String {
    match session.grasps.get(g) {
        Some(x) => match x.trial {
            Some(t) => format!("{} #{t}", x.object),
            None => format!("{} · grasp {}", x.object, g + 1),
        },
        None => format!("grasp {}", g + 1),
    }
}

/// What a figure's axis says about the signal and the time.
pub struct Labels {
    pub signal: String,
    pub unit: String,
    /// "time from contact onset".
    pub time: String,
}

/// The traces drawn over each other, one line per grasp coloured by its group; the series
/// are named after their grasps so that hover names them.
pub fn overlay(session: &Session, traces: &[Trace], groups: &Groups, l: &Labels) -> Figure {
    let series = (traces.iter())
        .map(|tr| {
            let mut s = Series::new(grasp_name(session, tr.grasp), tr.t.clone(), tr.v.clone());
            if let Some(Some(g)) = groups.of.get(tr.grasp) {
                s = s.color(series_color(*g));
            }
            s
        })
        .collect();
    Figure::chart(
        format!("{}, {} grasps", l.signal, traces.len()),
        Axis::new(&l.time, "s"),
        Axis::new(&l.signal, &l.unit),
        series,
    )
    .subtitle(format!("coloured by {}", groups.title))
}

/// One band per group: its centre as a line and its spread as a shaded band.
pub fn bands(groups: &Groups, bands: &[Band], spread: Spread, l: &Labels) -> Figure {
    let series = (bands.iter())
        .map(|b| {
            Series::new(
                format!("{} (n={})", groups.names[b.group], b.grasps),
                b.t.clone(),
                b.centre.clone(),
            )
            .band(b.lower.clone(), b.upper.clone())
            .color(series_color(b.group))
        })
        .collect();
    Figure::chart(
        format!("{} by {}", l.signal, groups.title),
        Axis::new(&l.time, "s"),
        Axis::new(&l.signal, &l.unit),
        series,
    )
    .subtitle(spread.text())
}

/// How far a strip's points spread sideways of their group's position.
const JITTER: f64 = 0.25;

/// Where each point of a strip chart stands for a grasp: `[series][point]`.
pub type PointGrasps = Vec<Vec<usize>>;

/// The most points a group's strip draws: past it, a seeded sample of its grasps stands for
/// the rest (the median and quartiles are still of them all), so that a session of a
/// hundred thousand grasps draws as fast as one of a thousand.
pub const STRIP_POINTS: usize = 2000;

/// One strip of points per group at positions 1, 2, … (seeded sideways jitter so that
/// equal values stay apart), and each group's median with its quartiles as error bars.
pub fn distributions(
    groups: &Groups,
    dists: &[Distribution],
    l: &Labels,
    seed: u64,
) -> (Figure, PointGrasps) {
    let mut rng = Rng::new(seed);
    let mut series = Vec::new();
    let mut grasps = Vec::new();
    let mut sampled = false;
    for (i, d) in dists.iter().enumerate() {
        let at = (i + 1) as f64;
        let mut shown: Vec<usize> = (0..d.values.len()).collect();
        if shown.len() > STRIP_POINTS {
            // A partial Fisher–Yates shuffle: the first STRIP_POINTS are a uniform sample.
            for k in 0..STRIP_POINTS {
                let j = k + rng.below(shown.len() - k);
                shown.swap(k, j);
            }
            shown.truncate(STRIP_POINTS);
            shown.sort_unstable();
            sampled = true;
        }
        let x = (shown.iter())
            .map(|_| at + rng.range(-JITTER, JITTER))
            .collect();
        let y = shown.iter().map(|&k| d.values[k].1).collect();
        series.push(
            Series::new(
                format!("{} (n={})", groups.names[d.group], d.values.len()),
                x,
                y,
            )
            .style(SeriesStyle::Markers)
            .color(series_color(d.group)),
        );
        grasps.push(shown.iter().map(|&k| d.values[k].0).collect());
    }
    if !dists.is_empty() {
        let at: Vec<f64> = (1..=dists.len()).map(|i| i as f64).collect();
        series.push(
            Series::new(
                "median, quartiles",
                at,
                dists.iter().map(|d| d.median).collect(),
            )
            .style(SeriesStyle::Markers)
            .error_bars(
                dists.iter().map(|d| d.q1).collect(),
                dists.iter().map(|d| d.q3).collect(),
            )
            .color(crate::figures::Rgb(0, 0, 0)),
        );
        grasps.push(Vec::new());
    }
    // Each strip's group named on the axis, on screen and on paper.
    let names = (dists.iter())
        .map(|d| groups.names[d.group].clone())
        .collect();
    let figure = Figure::chart(
        format!("{} by {}", l.signal, groups.title),
        Axis::new(&groups.title, "").categories(names),
        Axis::new(&l.signal, &l.unit),
        series,
    )
    .subtitle(if sampled {
        format!("at most {STRIP_POINTS} grasps per group drawn, a seeded sample; median and quartiles of all")
    } else {
        "one point per grasp; median and quartiles".to_string()
    });
    (figure, grasps)
}

/// A heatmap of grasps against time: the figure, each row's grasp and each column's time.
pub struct GraspsByTime {
    pub figure: Figure,
    pub rows: Vec<usize>,
    pub times: Vec<f64>,
}

/// Grasps × time of one signal, rows sorted by group (then by grasp), on the bands' grid
/// of `step` seconds; a cell without a value is missing.
pub fn heatmap(
    session: &Session,
    traces: &[Trace],
    groups: &Groups,
    step: f64,
    l: &Labels,
) -> GraspsByTime {
    let step = if step.is_finite() && step > 0.0 {
        step
    } else {
        1.0
    };
    let bin = |t: f64| (t / step).round() as i64;
    let bins =
        || (traces.iter()).flat_map(|tr| tr.t.iter().filter(|t| t.is_finite()).map(|&t| bin(t)));
    let lo = bins().min().unwrap_or(0);
    let hi = bins().max().unwrap_or(0);
    let mut order: Vec<&Trace> = traces.iter().collect();
    let group = |tr: &Trace| {
        groups
            .of
            .get(tr.grasp)
            .copied()
            .flatten()
            .unwrap_or(usize::MAX)
    };
    order.sort_by_key(|tr| (group(tr), tr.grasp));
    let width = (hi - lo + 1) as usize;
    let values: Vec<Vec<f64>> = (order.iter())
        .map(|tr| {
            let mut row = vec![f64::NAN; width];
            for (&t, &v) in tr.t.iter().zip(&tr.v) {
                if t.is_finite() {
                    row[(bin(t) - lo) as usize] = v;
                }
            }
            row
        })
        .collect();
    let rows = (order.iter())
        .map(|tr| {
            let g = groups.of.get(tr.grasp).copied().flatten();
            let name = g.map_or("no group", |g| groups.names[g].as_str());
            format!("{name} · {}", grasp_name(session, tr.grasp))
        })
        .collect();
    let times: Vec<f64> = (lo..=hi).map(|b| b as f64 * step).collect();
    let columns = (times.iter())
        .map(|&t| crate::figures::tick_label(t, step, crate::figures::Scale::Linear))
        .collect();
    let figure = Figure::heatmap(
        format!("{}, grasps by {}", l.signal, groups.title),
        AxisTitle::new(&l.time, "s"),
        AxisTitle::new(format!("grasp, by {}", groups.title), ""),
        columns,
        rows,
        values,
        ColorScale::viridis(&l.signal, &l.unit),
    );
    GraspsByTime {
        figure,
        rows: order.iter().map(|tr| tr.grasp).collect(),
        times,
    }
}

/// The columns of a grasps × time heatmap (each at its time of `times`) that lie in
/// `lo..=hi` (the time plots' zoom), as a heatmap of its own; None when no column does. The colour scale is the
/// whole heatmap's, so that a zoomed cell keeps its colour.
pub fn time_window(heatmap: &Figure, times: &[f64], lo: f64, hi: f64) -> Option<Figure> {
    let FigureKind::Heatmap(m) = &heatmap.kind else {
        return None;
    };
    let keep: Vec<usize> = (0..times.len())
        .filter(|&c| (lo..=hi).contains(&times[c]) && c < m.columns.len())
        .collect();
    if keep.is_empty() {
        return None;
    }
    let mut window = heatmap.clone();
    if let FigureKind::Heatmap(w) = &mut window.kind {
        if w.colors.limits.is_none() {
            let (lo, hi) = m.colors.resolve(m.values.iter().flatten().copied());
            w.colors.limits = Some([lo, hi]);
        }
        w.columns = keep.iter().map(|&c| m.columns[c].clone()).collect();
        w.values = (m.values.iter())
            .map(|row| keep.iter().map(|&c| row[c]).collect())
            .collect();
    }
    Some(window)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::stats::Distribution;

    #[test]
    fn a_large_group_draws_a_sample_of_its_grasps_and_the_quartiles_of_all() {
        // 5000 grasps of values 0..5000 in one group, 10 in another.
        let big = Distribution {
            group: 0,
            values: (0..5000).map(|g| (g, g as f64)).collect(),
            median: 2499.5,
            q1: 1249.75,
            q3: 3749.25,
        };
        let small = Distribution {
            group: 1,
            values: (0..10).map(|g| (5000 + g, 1.0)).collect(),
            median: 1.0,
            q1: 1.0,
            q3: 1.0,
        };
        let groups = Groups::assigned("g", vec!["big".into(), "small".into()], &[]);
        let labels = Labels {
            signal: "s".into(),
            unit: String::new(),
            time: "t".into(),
        };
        let (f, grasps) = distributions(&groups, &[big, small], &labels, 3);
        let FigureKind::Chart(c) = &f.kind else {
            panic!("a chart")
        };
        assert_eq!(grasps[0].len(), STRIP_POINTS);
        assert_eq!(c.series[0].y.len(), STRIP_POINTS);
        // Distinct grasps, each drawn at its own value; the small group whole.
        let mut seen = grasps[0].clone();
        seen.dedup();
        assert_eq!(seen.len(), STRIP_POINTS);
        assert!((grasps[0].iter().zip(&c.series[0].y)).all(|(&g, &y)| g as f64 == y));
        assert_eq!(grasps[1], (5000..5010).collect::<Vec<_>>());
        // The name counts every grasp; the medians are those given, of all of them.
        assert_eq!(c.series[0].name, "big (n=5000)");
        assert_eq!(c.series[2].y, [2499.5, 1.0]);
        assert!(f.subtitle.unwrap().contains("sample"));
    }

    #[test]
    fn a_zoomed_heatmap_keeps_the_columns_in_the_time_range_and_their_colours() {
        let s = crate::compare::tests::two_sensor_session();
        let traces = [
            Trace {
                grasp: 0,
                t: vec![0.0, 0.1, 0.2, 0.3],
                v: vec![1.0, 2.0, 3.0, 4.0],
            },
            Trace {
                grasp: 1,
                t: vec![0.0, 0.1],
                v: vec![5.0, 6.0],
            },
        ];
        let labels = Labels {
            signal: "s".into(),
            unit: String::new(),
            time: "t".into(),
        };
        let h = heatmap(&s, &traces, &Groups::all(&s), 0.1, &labels);
        assert_eq!(h.rows, [0, 1]);
        let w = time_window(&h.figure, &h.times, 0.05, 0.25).expect("two columns in range");
        let FigureKind::Heatmap(m) = &w.kind else {
            panic!("a heatmap")
        };
        assert_eq!(m.columns, ["0.1", "0.2"]);
        assert_eq!(m.values[0], [2.0, 3.0]);
        assert_eq!(m.values[1][0], 6.0);
        assert!(m.values[1][1].is_nan());
        // The whole heatmap's colour range (1 to 6), not the window's (2 to 6).
        assert_eq!(m.colors.limits, Some([1.0, 6.0]));
        w.validate().expect("drawable");
        assert!(time_window(&h.figure, &h.times, 0.41, 0.5).is_none());
    }
}
