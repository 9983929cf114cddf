//! Sequential (online) k-means, MacQueen (1967): the first k samples seed the k centres,
//! then each further sample moves its nearest centre towards itself with step 1/n_k, n_k the
//! number of samples that centre has absorbed, so each centre stays the running mean of its
//! samples. The second paper's baseline (Sec. VII-A, [8]).

use ndarray::{Array2, ArrayView1, ArrayView2};
use serde::{Deserialize, Serialize};

use super::ClusterError;
use crate::rng::Rng;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequentialKMeansParams {
    /// Number of centres.
    pub k: usize,
    /// Passes over the data (MacQueen's algorithm is one pass); later passes keep the counts.
    pub passes: usize,
    /// Seed of the presentation order (a fresh random order per pass).
    pub seed: u64,
}

impl Default for SequentialKMeansParams {
    fn default() -> Self {
        SequentialKMeansParams {
            k: 10,
            passes: 1,
            seed: 0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequentialKMeans {
    /// k × d centres.
    pub centres: Array2<f64>,
    /// Samples absorbed by each centre during fitting (the seeding sample included).
    pub counts: Vec<usize>,
}

impl SequentialKMeansParams {
    pub fn validate(&self) -> Result<(), ClusterError> {
        if self.k == 0 {
            return Err(ClusterError::invalid("k", "needs at least one centre"));
        }
        if self.passes == 0 {
            return Err(ClusterError::invalid("passes", "needs at least one pass"));
        }
        Ok(())
    }

    /// Fit on the rows of `data` (samples × features), presented in a random order drawn
    /// from `seed` (a new order each pass).
    pub fn fit(&self, data: ArrayView2<f64>) -> Result<SequentialKMeans, ClusterError> {
        let mut rng = Rng::new(self.seed);
        let orders: Vec<Vec<usize>> = (0..self.passes)
            .map(|_| rng.permutation(data.nrows()))
            .collect();
        self.fit_in_order(data, &orders)
    }

    /// Fit presenting the rows of `data` in the given orders, one per pass (each a sequence
    /// of row indices; the first k samples of the first pass seed the centres).
    pub fn fit_in_order(
        &self,
        data: ArrayView2<f64>,
        orders: &[Vec<usize>],
    ) -> Result<SequentialKMeans, ClusterError> {
        self.validate()?;
        super::check_data(data)?;
        if data.nrows() < self.k {
            return Err(ClusterError::invalid(
                "k",
                format!(
                    "{} centres need at least as many samples, got {}",
                    self.k,
                    data.nrows()
                ),
            ));
        }
        if orders.len() != self.passes {
            return Err(ClusterError::invalid(
                "orders",
                format!(
                    "one order per pass: {} passes, {} orders",
                    self.passes,
                    orders.len()
                ),
            ));
        }
        if let Some(&bad) = orders.iter().flatten().find(|&&i| i >= data.nrows()) {
            return Err(ClusterError::invalid(
                "orders",
                format!("row {bad} is out of range ({} samples)", data.nrows()),
            ));
        }
        let first: &[usize] = orders.first().map(Vec::as_slice).unwrap_or(&[]);
        if first.len() < self.k {
            return Err(ClusterError::invalid(
                "orders",
                format!(
                    "the first pass must present at least k = {} samples",
                    self.k
                ),
            ));
        }
        let mut centres = Array2::zeros((self.k, data.ncols()));
        for (c, &i) in first[..self.k].iter().enumerate() {
            centres.row_mut(c).assign(&data.row(i));
        }
        let mut model = SequentialKMeans {
            centres,
            counts: vec![1; self.k],
        };
        for (pass, order) in orders.iter().enumerate() {
            let skip = if pass == 0 { self.k } else { 0 };
            for &i in &order[skip..] {
                model.update(data.row(i));
            }
        }
        Ok(model)
    }
}

impl SequentialKMeans {
    /// MacQueen's update: the nearest centre moves 1/n_k of the way to the sample.
    fn update(&mut self, x: ArrayView1<f64>) {
        let j = self.nearest(x);
        self.counts[j] += 1;
        let step = 1.0 / self.counts[j] as f64;
        let mut c = self.centres.row_mut(j);
        c.zip_mut_with(&x, |c, &x| *c += step * (x - *c));
    }

    /// Index of the nearest centre (squared Euclidean distance; ties to the lower index).
    pub fn nearest(&self, x: ArrayView1<f64>) -> usize {
        super::nearest_row(self.centres.view(), x)
    }

    /// Nearest centre of every row of `data`.
    pub fn assign(&self, data: ArrayView2<f64>) -> Result<Vec<usize>, ClusterError> {
        super::check_width(data, self.centres.ncols())?;
        Ok(data.rows().into_iter().map(|x| self.nearest(x)).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cluster::scores::adjusted_rand_index;

    /// Three well separated blobs, 30 samples each.
    fn blobs(seed: u64) -> (Array2<f64>, Vec<usize>) {
        let mut rng = Rng::new(seed);
        let centres = [[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]];
        let mut data = Array2::zeros((90, 2));
        let mut truth = Vec::new();
        for i in 0..90 {
            let c = i % 3;
            data[[i, 0]] = centres[c][0] + rng.normal();
            data[[i, 1]] = centres[c][1] + rng.normal();
            truth.push(c);
        }
        (data, truth)
    }

    #[test]
    fn macqueen_update_keeps_running_means() {
        // 1-D, k = 2, order given: seeds 0 and 10, then 1, 2 join the first, 11 the second.
        let data = Array2::from_shape_vec((5, 1), vec![0.0, 10.0, 1.0, 2.0, 11.0]).unwrap();
        let params = SequentialKMeansParams {
            k: 2,
            passes: 1,
            seed: 0,
        };
        let m = params
            .fit_in_order(data.view(), &[vec![0, 1, 2, 3, 4]])
            .unwrap();
        assert!((m.centres[[0, 0]] - 1.0).abs() < 1e-15);
        assert!((m.centres[[1, 0]] - 10.5).abs() < 1e-15);
        assert_eq!(m.counts, vec![3, 2]);
        assert_eq!(m.assign(data.view()).unwrap(), vec![0, 1, 0, 0, 1]);
    }

    #[test]
    fn separates_blobs_and_is_seeded() {
        let (data, truth) = blobs(1);
        let mut best = f64::NEG_INFINITY;
        for seed in 0..5 {
            let params = SequentialKMeansParams {
                k: 3,
                passes: 2,
                seed,
            };
            let a = params.fit(data.view()).unwrap();
            let b = params.fit(data.view()).unwrap();
            assert_eq!(a, b);
            let pred = a.assign(data.view()).unwrap();
            best = best.max(adjusted_rand_index(&truth, &pred));
        }
        assert!(best > 0.99, "{best}");
    }

    #[test]
    fn bad_parameters_are_errors() {
        let (data, _) = blobs(2);
        let p = SequentialKMeansParams {
            k: 0,
            ..Default::default()
        };
        assert!(p.fit(data.view()).is_err());
        let p = SequentialKMeansParams {
            k: 100,
            ..Default::default()
        };
        assert!(p.fit(data.view()).is_err());
        let p = SequentialKMeansParams {
            passes: 0,
            ..Default::default()
        };
        assert!(p.fit(data.view()).is_err());
        let mut bad = data.clone();
        bad[[3, 1]] = f64::NAN;
        assert!(SequentialKMeansParams::default().fit(bad.view()).is_err());
        let m = SequentialKMeansParams::default().fit(data.view()).unwrap();
        assert!(m.assign(Array2::zeros((2, 3)).view()).is_err());
    }
}
