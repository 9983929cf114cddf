//! Group statistics against aligned time: each grasp's trace of one signal, the band of a
//! group (mean ± sd, or median with quartiles) on a common time grid, and for a single
//! frame per grasp the distribution of each group's values.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::align::Event;
use super::groups::Groups;
use super::signal::{Signal, StepOutputs};
use crate::session::Session;

/// One grasp's signal against its aligned time.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    pub grasp: usize,
    pub t: Vec<f64>,
    pub v: Vec<f64>,
}

/// The traces of `signal` for `grasps`, aligned at `event` (grasps the session lacks are
/// left out). Grasps are independent: computed in parallel.
pub fn traces(
    session: &Session,
    outputs: &[StepOutputs],
    signal: Signal,
    event: Event,
    grasps: &[usize],
) -> Vec<Trace> {
    (grasps.par_iter())
        .filter(|&&g| g < session.grasps.len())
        .map(|&g| Trace {
            grasp: g,
            t: event.times(session, g),
            v: signal.values(session, g, outputs),
        })
        .collect()
}

/// How a band spreads around its centre.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Spread {
    /// Mean, and mean ± one (population) standard deviation.
    #[default]
    MeanSd,
    /// Median, and the first and third quartiles.
    MedianQuartiles,
}

impl Spread {
    pub const ALL: [Spread; 2] = [Spread::MeanSd, Spread::MedianQuartiles];

    pub fn text(self) -> &'static str {
        match self {
            Spread::MeanSd => "mean ± sd",
            Spread::MedianQuartiles => "median, quartiles",
        }
    }
}

/// One group's band on the time grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    pub group: usize,
    /// Grasps of the group with at least one value.
    pub grasps: usize,
    pub t: Vec<f64>,
    pub centre: Vec<f64>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
}

/// A time of the grid enters a band when at least this share of the group's grasps has a
/// value there: a band's tail held up by one or two long grasps would read as the group's.
pub const MIN_SHARE: f64 = 0.2;

/// The grid step of a session's times: its frame period (the median gap between frames of
/// its grasps), or 1 s for a session of single frames.
pub fn grid_step(session: &Session) -> f64 {
    let mut gaps: Vec<f64> = (session.grasps.iter())
        .flat_map(|g| g.frames.windows(2).map(|w| w[1].t - w[0].t).take(8))
        .filter(|d| d.is_finite() && *d > 0.0)
        .take(4096)
        .collect();
    if gaps.is_empty() {
        return 1.0;
    }
    let mid = gaps.len() / 2;
    *gaps.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Quantile `q` of sorted `v` by linear interpolation between order statistics (R's type
/// 7, numpy's default); NaN for no values.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (pos - lo as f64) * (sorted[hi] - sorted[lo])
}

/// Each group's band of `traces` on a grid of `step` seconds (a value goes to the nearest
/// grid time); groups without values give no band.
pub fn bands(traces: &[Trace], groups: &Groups, spread: Spread, step: f64) -> Vec<Band> {
    let step = if step.is_finite() && step > 0.0 {
        step
    } else {
        1.0
    };
    let bin = |t: f64| (t / step).round() as i64;
    // Per group: the grid's first bin and every grasp's (bin, value).
    let mut per_group: Vec<Vec<(i64, f64)>> = vec![Vec::new(); groups.names.len()];
    let mut grasps = vec![0usize; groups.names.len()];
    for tr in traces {
        let Some(Some(g)) = groups.of.get(tr.grasp) else {
            continue;
        };
        let before = per_group[*g].len();
        per_group[*g].extend(
            (tr.t.iter().zip(&tr.v))
                .filter(|(t, v)| t.is_finite() && v.is_finite())
                .map(|(&t, &v)| (bin(t), v)),
        );
        grasps[*g] += usize::from(per_group[*g].len() > before);
    }
    (per_group.into_par_iter().enumerate())
        .filter(|(_, pts)| !pts.is_empty())
        .map(|(g, pts)| {
            let lo = pts.iter().map(|p| p.0).min().unwrap_or(0);
            let hi = pts.iter().map(|p| p.0).max().unwrap_or(0);
            let mut cells: Vec<Vec<f64>> = vec![Vec::new(); (hi - lo + 1) as usize];
            for (b, v) in pts {
                cells[(b - lo) as usize].push(v);
            }
            let least = (MIN_SHARE * grasps[g] as f64).ceil().max(1.0) as usize;
            let mut band = Band {
                group: g,
                grasps: grasps[g],
                t: Vec::new(),
                centre: Vec::new(),
                lower: Vec::new(),
                upper: Vec::new(),
            };
            for (k, mut cell) in cells.into_iter().enumerate() {
                if cell.len() < least {
                    continue;
                }
                let (c, l, u) = summary(&mut cell, spread);
                band.t.push((lo + k as i64) as f64 * step);
                band.centre.push(c);
                band.lower.push(l);
                band.upper.push(u);
            }
            band
        })
        .collect()
}

/// Centre, lower and upper of `values` (reordered) under `spread`.
fn summary(values: &mut [f64], spread: Spread) -> (f64, f64, f64) {
    match spread {
        Spread::MeanSd => {
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let sd = (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt();
            (mean, mean - sd, mean + sd)
        }
        Spread::MedianQuartiles => {
            values.sort_unstable_by(f64::total_cmp);
            (
                quantile(values, 0.5),
                quantile(values, 0.25),
                quantile(values, 0.75),
            )
        }
    }
}

/// One group's values at the event (a session of single frames: its only frame).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    pub group: usize,
    /// (grasp, value), in the traces' order.
    pub values: Vec<(usize, f64)>,
    pub median: f64,
    pub q1: f64,
    pub q3: f64,
}

/// Each group's distribution of the traces' values at aligned time 0 (the frame nearest
/// it); groups without values give none.
pub fn distributions(traces: &[Trace], groups: &Groups) -> Vec<Distribution> {
    let mut per_group: Vec<Vec<(usize, f64)>> = vec![Vec::new(); groups.names.len()];
    for tr in traces {
        let Some(Some(g)) = groups.of.get(tr.grasp) else {
            continue;
        };
        let at = (0..tr.t.len().min(tr.v.len()))
            .filter(|&k| tr.t[k].is_finite())
            .min_by(|&a, &b| tr.t[a].abs().total_cmp(&tr.t[b].abs()));
        if let Some(k) = at
            && tr.v[k].is_finite()
        {
            per_group[*g].push((tr.grasp, tr.v[k]));
        }
    }
    (per_group.into_iter().enumerate())
        .filter(|(_, v)| !v.is_empty())
        .map(|(g, values)| {
            let mut sorted: Vec<f64> = values.iter().map(|p| p.1).collect();
            sorted.sort_unstable_by(f64::total_cmp);
            Distribution {
                group: g,
                median: quantile(&sorted, 0.5),
                q1: quantile(&sorted, 0.25),
                q3: quantile(&sorted, 0.75),
                values,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn groups(of: &[Option<usize>], n: usize) -> Groups {
        let names = (0..n).map(|i| format!("g{i}")).collect();
        Groups::assigned("test", names, of)
    }

    fn trace(grasp: usize, t: &[f64], v: &[f64]) -> Trace {
        Trace {
            grasp,
            t: t.to_vec(),
            v: v.to_vec(),
        }
    }

    #[test]
    fn quantiles_interpolate_between_order_statistics() {
        // numpy.quantile([1, 2, 3, 4], [.25, .5, .75]) = [1.75, 2.5, 3.25].
        let v = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&v, 0.25), 1.75);
        assert_eq!(quantile(&v, 0.5), 2.5);
        assert_eq!(quantile(&v, 0.75), 3.25);
        assert_eq!(quantile(&[7.0], 0.25), 7.0);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn mean_sd_bands_by_hand() {
        // Group 0: grasps 0 and 1 at t = 0, 0.1 (values 1, 3 and 3, 7); grasp 1 also has
        // t = 0.2 (value 9) — one grasp of two is half the group, so that time stays.
        // Group 1: grasp 2 alone, at t = 0.1 only. Grasp 3 is in no group.
        let trs = [
            trace(0, &[0.0, 0.1], &[1.0, 3.0]),
            trace(1, &[0.0, 0.1, 0.2], &[3.0, 7.0, 9.0]),
            trace(2, &[0.1], &[4.0]),
            trace(3, &[0.0], &[100.0]),
        ];
        let g = groups(&[Some(0), Some(0), Some(1), None], 2);
        let b = bands(&trs, &g, Spread::MeanSd, 0.1);
        assert_eq!(b.len(), 2);
        assert_eq!(b[0].grasps, 2);
        assert_eq!(b[0].t.len(), 3);
        assert!((b[0].t[2] - 0.2).abs() < 1e-12);
        // t = 0: mean 2, sd 1; t = 0.1: mean 5, sd 2; t = 0.2: 9 alone, sd 0.
        assert_eq!(b[0].centre, [2.0, 5.0, 9.0]);
        assert_eq!(b[0].lower, [1.0, 3.0, 9.0]);
        assert_eq!(b[0].upper, [3.0, 7.0, 9.0]);
        assert_eq!((b[1].group, b[1].centre.as_slice()), (1, &[4.0][..]));
    }

    #[test]
    fn median_bands_drop_times_too_few_grasps_reach() {
        // Ten grasps at t = 0 with values 1..=10; one of them also at t = 1 (a tenth of
        // the group, under the fifth a time needs).
        let mut trs: Vec<Trace> = (0..10)
            .map(|i| trace(i, &[0.0], &[(i + 1) as f64]))
            .collect();
        trs[0] = trace(0, &[0.0, 1.0], &[1.0, 50.0]);
        let g = groups(&[Some(0); 10], 1);
        let b = bands(&trs, &g, Spread::MedianQuartiles, 1.0);
        assert_eq!(b[0].t, [0.0]);
        // numpy.quantile(range(1, 11), [.25, .5, .75]) = [3.25, 5.5, 7.75].
        assert_eq!(
            (b[0].lower[0], b[0].centre[0], b[0].upper[0]),
            (3.25, 5.5, 7.75)
        );
    }

    #[test]
    fn nearby_times_share_a_grid_time_and_missing_values_are_skipped() {
        // 0.04 and 0.06 round to 0 and 0.1 on a 0.1 s grid; NaN values count for nothing.
        let trs = [
            trace(0, &[0.04, 0.06], &[2.0, f64::NAN]),
            trace(1, &[-0.01, 0.11], &[4.0, 6.0]),
        ];
        let b = bands(&trs, &groups(&[Some(0), Some(0)], 1), Spread::MeanSd, 0.1);
        assert_eq!(b[0].centre, [3.0, 6.0]);
    }

    #[test]
    fn distributions_take_each_grasps_value_at_the_event() {
        let trs = [
            trace(0, &[-0.1, 0.0, 0.1], &[9.0, 1.0, 9.0]),
            trace(1, &[0.0], &[2.0]),
            trace(2, &[0.0], &[3.0]),
            trace(3, &[0.0], &[f64::NAN]),
        ];
        let d = distributions(&trs, &groups(&[Some(1), Some(1), Some(1), Some(0)], 2));
        // Group 0's only value is missing: no distribution.
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].group, 1);
        assert_eq!(d[0].values, [(0, 1.0), (1, 2.0), (2, 3.0)]);
        assert_eq!((d[0].q1, d[0].median, d[0].q3), (1.5, 2.0, 2.5));
    }
}
