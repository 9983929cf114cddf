//! Putting features on a common scale: per-column z-scoring of patches and SVM inputs
//! (`Standardizer`: a constant column keeps its offset and unit scale) and the per-feature
//! z-score or min-max maps of the Table I features (`Normaliser`: a constant feature maps
//! to 0). The two treat constant columns differently on purpose of their callers: patches
//! of a dead taxel stay centred and comparable across sessions, while a constant Table I
//! feature carries no information into a distance. They also round differently (divide by
//! sd, multiply by 1/spread), and the published figures of each pipeline rest on its own.

use std::borrow::Cow;

use ndarray::{Array2, ArrayView1, ArrayView2};
use serde::{Deserialize, Serialize};

use super::FeatureError;

/// Per-column z-scoring: `(v − mean) / sd`, with sd = 1 for constant columns.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Standardizer {
    pub mean: Vec<f64>,
    /// Population standard deviation (divides by n); 1 where a column is constant.
    pub sd: Vec<f64>,
}

impl Standardizer {
    /// Fit on every row of `x`.
    pub fn fit(x: ArrayView2<f64>) -> Self {
        let all: Vec<usize> = (0..x.nrows()).collect();
        Self::fit_rows(x, &all)
    }

    /// Fit on the rows `rows` of `x` (in that order), as [`Standardizer::fit`] on those
    /// rows gathered: a cross-validation fold needs no copy of its training rows.
    pub fn fit_rows(x: ArrayView2<f64>, rows: &[usize]) -> Self {
        let (n, d) = (rows.len(), x.ncols());
        let mut mean = vec![0.0; d];
        let mut m2 = vec![0.0; d];
        for &i in rows {
            for (m, v) in mean.iter_mut().zip(&*contiguous(x.row(i))) {
                *m += v;
            }
        }
        let nf = n.max(1) as f64;
        mean.iter_mut().for_each(|m| *m /= nf);
        for &i in rows {
            for ((s, m), v) in m2.iter_mut().zip(&mean).zip(&*contiguous(x.row(i))) {
                let e = v - m;
                *s += e * e;
            }
        }
        let sd = m2
            .iter()
            .zip(&mean)
            .map(|(s, m)| {
                let sd = (s / nf).sqrt();
                if sd > 1e-12 * (1.0 + m.abs()) {
                    sd
                } else {
                    1.0
                }
            })
            .collect();
        Standardizer { mean, sd }
    }

    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Scale one row into `out`.
    #[inline]
    pub fn transform_into(&self, row: ArrayView1<f64>, out: &mut [f64]) {
        let ms = self.mean.iter().zip(&self.sd);
        for (o, (v, (m, sd))) in out.iter_mut().zip(contiguous(row).iter().zip(ms)) {
            *o = (v - m) / sd;
        }
    }

    pub fn transform(&self, x: ArrayView2<f64>) -> Array2<f64> {
        let mut out = x.to_owned();
        for mut row in out.rows_mut() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (*v - self.mean[j]) / self.sd[j];
            }
        }
        out
    }
}

/// How features are put on a common scale before distances are taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Normalisation {
    /// (x − mean) / sd per feature (population sd).
    ZScore,
    /// (x − min) / (max − min) per feature, into [0, 1]; the paper min-max normalises its
    /// per-step features, and on the Table I features it gives the better k-means scores.
    #[default]
    MinMax,
}

/// A per-feature affine map x ↦ (x − offset) · scale, fitted on one set of samples and
/// applied to others (e.g. fitted on the training folds only).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Normaliser {
    pub kind: Normalisation,
    pub offset: Vec<f64>,
    pub scale: Vec<f64>,
}

impl Normaliser {
    /// Fit on the rows of `data`. A constant feature maps to 0 (scale 0), since it carries
    /// no information and must not produce a division by zero.
    pub fn fit(kind: Normalisation, data: ArrayView2<f64>) -> Result<Normaliser, FeatureError> {
        check_data(data)?;
        let n = data.nrows() as f64;
        let mut offset = Vec::with_capacity(data.ncols());
        let mut scale = Vec::with_capacity(data.ncols());
        for col in data.columns() {
            // Work on values divided by the largest magnitude, so squares and differences of
            // values near f64::MAX do not overflow; `scale` is 1/spread in the original units.
            // (Below 1e150 nothing overflows: plain arithmetic, bit for bit as always.)
            let m = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let unit = if m > 1e150 { m } else { 1.0 };
            let (o, spread) = match kind {
                Normalisation::ZScore => {
                    let mean = col.iter().map(|v| v / unit).sum::<f64>() / n;
                    let var = col
                        .iter()
                        .map(|v| (v / unit - mean) * (v / unit - mean))
                        .sum::<f64>()
                        / n;
                    (mean * unit, var.sqrt())
                }
                Normalisation::MinMax => {
                    let min = col.iter().copied().fold(f64::INFINITY, f64::min);
                    let max = col.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    (min, max / unit - min / unit)
                }
            };
            offset.push(o);
            // A spread at rounding level of the values counts as constant.
            scale.push(if spread > 1e-12 * (1.0 / unit + (o / unit).abs()) {
                1.0 / spread / unit
            } else {
                0.0
            });
        }
        Ok(Normaliser {
            kind,
            offset,
            scale,
        })
    }

    pub fn transform(&self, data: ArrayView2<f64>) -> Result<Array2<f64>, FeatureError> {
        check_width(data, self.offset.len())?;
        let mut out = data.to_owned();
        for (mut col, (&o, &s)) in out
            .columns_mut()
            .into_iter()
            .zip(self.offset.iter().zip(&self.scale))
        {
            col.mapv_inplace(|v| {
                let d = (v - o) * s;
                // v − o overflows only for values near f64::MAX of opposite signs.
                if d.is_finite() { d } else { v * s - o * s }
            });
        }
        Ok(out)
    }
}

/// Samples to scale must exist and be finite.
pub(crate) fn check_data(data: ArrayView2<f64>) -> Result<(), FeatureError> {
    if data.nrows() == 0 || data.ncols() == 0 {
        return Err(FeatureError::InvalidData(format!(
            "needs samples and features, got {} × {}",
            data.nrows(),
            data.ncols()
        )));
    }
    if let Some(((r, c), _)) = data.indexed_iter().find(|(_, v)| !v.is_finite()) {
        return Err(FeatureError::InvalidData(format!(
            "sample {r}, feature {c} is not finite"
        )));
    }
    Ok(())
}

/// Samples to transform must be finite and have the fitted width.
pub(crate) fn check_width(data: ArrayView2<f64>, width: usize) -> Result<(), FeatureError> {
    check_data(data)?;
    if data.ncols() != width {
        return Err(FeatureError::InvalidData(format!(
            "the model has {width} features, the data {}",
            data.ncols()
        )));
    }
    Ok(())
}

/// A row as a slice, borrowed when it is contiguous (nearly always), so that the loops over
/// it run on a slice rather than through ndarray's strided iterator.
fn contiguous(row: ArrayView1<'_, f64>) -> Cow<'_, [f64]> {
    match row.to_slice() {
        Some(r) => Cow::Borrowed(r),
        None => Cow::Owned(row.to_vec()),
    }
}
