//! A self-organising map (Kohonen 1982), trained sequentially: one sample at a time, its
//! best-matching unit (BMU) and the BMU's grid neighbours move towards it,
//! w_j ← w_j + η(s) h_bj(s) (x − w_j), with a Gaussian neighbourhood
//! h_bj = exp(−‖g_b − g_j‖² / (2 σ(s)²)) over the units' grid positions g and learning rate
//! η and radius σ following schedules over training progress s ∈ [0, 1]. The second paper's
//! "sequential SOM" baseline (Sec. VII-A, [9]); each unit is a cluster.

use ndarray::{Array2, ArrayView1, ArrayView2};
use serde::{Deserialize, Serialize};

use super::ClusterError;
use crate::rng::Rng;

/// A value that decays over training progress s ∈ [0, 1] from `start` to `end`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Schedule {
    /// start + s (end − start).
    Linear { start: f64, end: f64 },
    /// start (end/start)^s: the same ratio per step, the usual SOM choice.
    Exponential { start: f64, end: f64 },
}

impl Schedule {
    pub fn at(&self, s: f64) -> f64 {
        match *self {
            Schedule::Linear { start, end } => start + s * (end - start),
            Schedule::Exponential { start, end } => start * (end / start).powf(s),
        }
    }

    fn validate(&self, name: &'static str, max: f64) -> Result<(), ClusterError> {
        let (Schedule::Linear { start, end } | Schedule::Exponential { start, end }) = *self;
        for v in [start, end] {
            if !(v.is_finite() && v > 0.0 && v <= max) {
                return Err(ClusterError::invalid(
                    name,
                    format!("start and end must lie in (0, {max}], got {start} → {end}"),
                ));
            }
        }
        Ok(())
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SomParams {
    /// Grid shape: rows × cols units.
    pub rows: usize,
    pub cols: usize,
    /// Passes over the data, each in a fresh random order.
    pub passes: usize,
    /// η(s), in (0, 1].
    pub learning_rate: Schedule,
    /// σ(s), the neighbourhood radius in grid units.
    pub radius: Schedule,
    /// Seed of the initial weights (randomly chosen samples) and of the orders.
    pub seed: u64,
}

impl Default for SomParams {
    fn default() -> Self {
        SomParams {
            rows: 2,
            cols: 5,
            passes: 20,
            learning_rate: Schedule::Exponential {
                start: 0.5,
                end: 0.01,
            },
            radius: Schedule::Exponential {
                start: 2.5,
                end: 0.3,
            },
            seed: 0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SelfOrganisingMap {
    pub rows: usize,
    pub cols: usize,
    /// (rows·cols) × d unit weights; unit (r, c) is row r·cols + c.
    pub weights: Array2<f64>,
}

impl SomParams {
    pub fn validate(&self) -> Result<(), ClusterError> {
        if self.rows == 0 || self.cols == 0 {
            return Err(ClusterError::invalid(
                "rows/cols",
                format!(
                    "the grid needs at least one unit, got {} × {}",
                    self.rows, self.cols
                ),
            ));
        }
        if self.passes == 0 {
            return Err(ClusterError::invalid("passes", "needs at least one pass"));
        }
        self.learning_rate.validate("learning_rate", 1.0)?;
        self.radius.validate("radius", f64::MAX)?;
        Ok(())
    }

    pub fn units(&self) -> usize {
        self.rows * self.cols
    }

    /// Fit on the rows of `data` (samples × features).
    pub fn fit(&self, data: ArrayView2<f64>) -> Result<SelfOrganisingMap, ClusterError> {
        self.validate()?;
        super::check_data(data)?;
        let mut rng = Rng::new(self.seed);
        let n = data.nrows();
        let mut weights = Array2::zeros((self.units(), data.ncols()));
        // Distinct samples while there are enough, so no two units start identical.
        let picks = rng.permutation(n);
        for (u, mut w) in weights.rows_mut().into_iter().enumerate() {
            let i = picks.get(u).copied().unwrap_or_else(|| rng.below(n));
            w.assign(&data.row(i));
        }
        let mut som = SelfOrganisingMap {
            rows: self.rows,
            cols: self.cols,
            weights,
        };
        let total = (self.passes * n).max(2) - 1;
        let mut step = 0;
        for _ in 0..self.passes {
            for i in rng.permutation(n) {
                let s = step as f64 / total as f64;
                som.update(data.row(i), self.learning_rate.at(s), self.radius.at(s));
                step += 1;
            }
        }
        Ok(som)
    }
}

impl SelfOrganisingMap {
    fn grid(&self, unit: usize) -> (f64, f64) {
        ((unit / self.cols) as f64, (unit % self.cols) as f64)
    }

    fn update(&mut self, x: ArrayView1<f64>, rate: f64, radius: f64) {
        let (br, bc) = self.grid(self.bmu(x));
        let inv_two_var = 1.0 / (2.0 * radius * radius);
        for u in 0..self.weights.nrows() {
            let (r, c) = self.grid(u);
            let d2 = (r - br).powi(2) + (c - bc).powi(2);
            let h = rate * (-d2 * inv_two_var).exp();
            if h > 1e-12 {
                self.weights
                    .row_mut(u)
                    .zip_mut_with(&x, |w, &x| *w += h * (x - *w));
            }
        }
    }

    /// Best-matching unit: the unit nearest `x` (ties to the lower index).
    pub fn bmu(&self, x: ArrayView1<f64>) -> usize {
        super::nearest_row(self.weights.view(), x)
    }

    /// BMU of every row of `data`: the cluster of each sample.
    pub fn assign(&self, data: ArrayView2<f64>) -> Result<Vec<usize>, ClusterError> {
        super::check_width(data, self.weights.ncols())?;
        Ok(data.rows().into_iter().map(|x| self.bmu(x)).collect())
    }

    /// Mean distance from each sample to its BMU (the quantisation error).
    pub fn quantisation_error(&self, data: ArrayView2<f64>) -> Result<f64, ClusterError> {
        let units = self.assign(data)?;
        let total: f64 = units
            .iter()
            .zip(data.rows())
            .map(|(&u, x)| {
                self.weights
                    .row(u)
                    .iter()
                    .zip(x)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            })
            .sum();
        Ok(total / data.nrows() as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cluster::scores::normalized_mutual_info;

    #[test]
    fn schedules_run_from_start_to_end() {
        let e = Schedule::Exponential {
            start: 1.0,
            end: 0.01,
        };
        assert!((e.at(0.0) - 1.0).abs() < 1e-15);
        assert!((e.at(0.5) - 0.1).abs() < 1e-15);
        assert!((e.at(1.0) - 0.01).abs() < 1e-15);
        let l = Schedule::Linear {
            start: 2.0,
            end: 1.0,
        };
        assert!((l.at(0.25) - 1.75).abs() < 1e-15);
    }

    /// Points along a line: a 1 × 5 map orders itself, so neighbouring units hold
    /// neighbouring stretches of the line (the defining property of a SOM).
    #[test]
    fn one_dimensional_map_is_topologically_ordered() {
        let data = Array2::from_shape_fn((200, 1), |(i, _)| i as f64 / 199.0);
        let params = SomParams {
            rows: 1,
            cols: 5,
            passes: 30,
            learning_rate: Schedule::Exponential {
                start: 0.5,
                end: 0.01,
            },
            radius: Schedule::Exponential {
                start: 2.0,
                end: 0.2,
            },
            seed: 3,
        };
        let som = params.fit(data.view()).unwrap();
        let w: Vec<f64> = som.weights.column(0).to_vec();
        let increasing = w.windows(2).all(|p| p[0] < p[1]);
        let decreasing = w.windows(2).all(|p| p[0] > p[1]);
        assert!(increasing || decreasing, "{w:?}");
        // five units cover the line evenly: each unit takes about a fifth
        let units = som.assign(data.view()).unwrap();
        for u in 0..5 {
            let share = units.iter().filter(|&&x| x == u).count();
            assert!((25..=55).contains(&share), "unit {u}: {share}");
        }
        assert!(som.quantisation_error(data.view()).unwrap() < 0.08);
    }

    #[test]
    fn clusters_blobs_and_is_seeded() {
        let mut rng = Rng::new(9);
        // four blobs on the corners of a square, which a 2 × 2 map unfolds onto
        let mut data = Array2::zeros((120, 2));
        let mut truth = Vec::new();
        for i in 0..120 {
            let c = i % 4;
            data[[i, 0]] = 10.0 * (c / 2) as f64 + rng.normal();
            data[[i, 1]] = 10.0 * (c % 2) as f64 + rng.normal();
            truth.push(c);
        }
        let params = SomParams {
            rows: 2,
            cols: 2,
            ..Default::default()
        };
        let a = params.fit(data.view()).unwrap();
        assert_eq!(a, params.fit(data.view()).unwrap());
        assert_ne!(
            a,
            SomParams {
                seed: 1,
                ..params.clone()
            }
            .fit(data.view())
            .unwrap()
        );
        let pred = a.assign(data.view()).unwrap();
        let nmi = normalized_mutual_info(&truth, &pred);
        assert!(nmi > 0.95, "{nmi}");
    }

    #[test]
    fn bad_parameters_are_errors() {
        let data = Array2::from_shape_fn((10, 2), |(i, j)| (i + j) as f64);
        let bad = [
            SomParams {
                rows: 0,
                ..Default::default()
            },
            SomParams {
                passes: 0,
                ..Default::default()
            },
            SomParams {
                learning_rate: Schedule::Linear {
                    start: 1.5,
                    end: 0.1,
                },
                ..Default::default()
            },
            SomParams {
                radius: Schedule::Exponential {
                    start: 0.0,
                    end: 0.1,
                },
                ..Default::default()
            },
        ];
        for p in bad {
            assert!(p.fit(data.view()).is_err(), "{p:?}");
        }
    }
}
