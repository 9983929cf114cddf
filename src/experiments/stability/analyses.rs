//! Analyses of a model (the paper's Figs. 2, 6, 8–11): basis images, reconstructions, usage by label.

use super::*;

/// The filter of the "filtered" basis images (the paper's Fig. 6b does not state its).
pub const FILTER: &str = "Gaussian kernel interpolation (Nadaraya–Watson) of the taxel values \
onto a grid of 4 pixels per taxel cell, σ = 0.6 cell; pixels farther than 0.75 cell from \
every taxel are left empty (background). Grid layouts use (column, row) as taxel \
coordinates; point layouts use positions divided by the taxel diameter.";
pub(super) const UPSAMPLE: usize = 4;
pub(super) const FILTER_SIGMA: f64 = 0.6;
pub(super) const FILTER_REACH: f64 = 0.75;

/// An image on a grid, row-major, `None` where there is no taxel (background).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridImage {
    pub rows: usize,
    pub cols: usize,
    pub pixels: Vec<Option<f64>>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BasisImage {
    pub basis: usize,
    /// The basis vector, one value per taxel (in the scaled units of the patches).
    pub values: Vec<f64>,
    /// The values on the sensor's grid (grid layouts only): Fig. 6a.
    pub raw: Option<GridImage>,
    /// Smoothed by [`FILTER`]: Fig. 6b.
    pub filtered: Option<GridImage>,
}

/// Taxel centres in cell units for drawing.
pub(super) fn taxel_coords(layout: &Layout) -> Vec<(f64, f64)> {
    match layout {
        Layout::Grid { .. } | Layout::SparseGrid { .. } => (0..layout.taxel_count())
            .map(|i| {
                let (r, c) = layout.grid_cell(i).unwrap_or((0, 0));
                (c as f64, r as f64)
            })
            .collect(),
        Layout::Points {
            positions, radius, ..
        } => {
            let d = (2.0 * radius).max(1e-9);
            positions.iter().map(|p| (p.x / d, p.y / d)).collect()
        }
    }
}

pub(super) fn raw_image(layout: &Layout, values: &[f64]) -> Option<GridImage> {
    let (rows, cols) = layout.grid_shape()?;
    let mut pixels = vec![None; rows * cols];
    for (i, &v) in values.iter().enumerate() {
        if let Some((r, c)) = layout.grid_cell(i)
            && r < rows
            && c < cols
        {
            pixels[r * cols + c] = Some(v);
        }
    }
    Some(GridImage { rows, cols, pixels })
}

pub(super) fn filtered_image(coords: &[(f64, f64)], values: &[f64]) -> Option<GridImage> {
    if coords.is_empty() {
        return None;
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in coords {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let cols = ((x1 - x0 + 1.0) * UPSAMPLE as f64).round().max(1.0) as usize;
    let rows = ((y1 - y0 + 1.0) * UPSAMPLE as f64).round().max(1.0) as usize;
    let mut pixels = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        for c in 0..cols {
            let px = x0 - 0.5 + (c as f64 + 0.5) / UPSAMPLE as f64;
            let py = y0 - 0.5 + (r as f64 + 0.5) / UPSAMPLE as f64;
            let (mut num, mut den, mut nearest) = (0.0, 0.0, f64::MAX);
            for (&(x, y), &v) in coords.iter().zip(values) {
                let d2 = (px - x).powi(2) + (py - y).powi(2);
                nearest = nearest.min(d2);
                let w = (-d2 / (2.0 * FILTER_SIGMA * FILTER_SIGMA)).exp();
                num += w * v;
                den += w;
            }
            pixels.push((nearest.sqrt() <= FILTER_REACH && den > 0.0).then(|| num / den));
        }
    }
    Some(GridImage { rows, cols, pixels })
}

/// A patch, the bases its code uses and their coefficients, and the reconstruction
/// (Fig. 2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reconstruction {
    pub grasp: usize,
    pub sensor: usize,
    pub failure: bool,
    pub patch: Vec<f64>,
    /// (basis, coefficient), largest |coefficient| first.
    pub terms: Vec<(usize, f64)>,
    pub reconstruction: Vec<f64>,
    /// ||patch − reconstruction|| / ||patch||.
    pub relative_error: f64,
}

/// Per-basis statistics by label (success / failure), Figs. 8–11.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BasisUsage {
    /// Share of the label's grasps whose code (any of its patches) uses the basis
    /// (Figs. 8 and 9).
    pub grasp_usage_success: Vec<f64>,
    pub grasp_usage_failure: Vec<f64>,
    /// success − failure (Fig. 10: negative = used more by failed grasps).
    pub usage_differential: Vec<f64>,
    /// Share of the label's patches whose code uses the basis.
    pub patch_usage_success: Vec<f64>,
    pub patch_usage_failure: Vec<f64>,
    /// Mean |coefficient| over the label's patches that use the basis (0 if none).
    pub mean_abs_coef_success: Vec<f64>,
    pub mean_abs_coef_failure: Vec<f64>,
    /// success − failure of the above (Fig. 11: negative = stronger in failed grasps).
    pub coefficient_differential: Vec<f64>,
    /// Mean |coefficient| over all the label's patches (zeros included), and its
    /// differential, for comparison.
    pub mean_abs_coef_all_success: Vec<f64>,
    pub mean_abs_coef_all_failure: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Analyses {
    pub config: Config,
    pub basis_images: Vec<BasisImage>,
    pub filter: String,
    /// One representative patch per label (a patch with the label's typical number of
    /// active bases, the one with the largest norm among those).
    pub reconstructions: Vec<Reconstruction>,
    pub usage: BasisUsage,
    /// Mean non-zero coefficients per patch: all, success, failure (the paper: 4.43 vs 2.59).
    pub active_bases_per_patch: [f64; 3],
    /// Share of zero coefficients: all, success, failure (the paper: 86.31 %).
    pub sparsity: [f64; 3],
}

/// The reconstruction of one patch (grasp g, sensor s) by its code.
pub fn reconstruct(
    data: &StabilityData,
    dict: &Dictionary,
    gamma: f64,
    grasp: usize,
    sensor: usize,
) -> Result<Reconstruction, StabilityError> {
    if grasp >= data.grasp_count() || sensor >= data.sensor_count() {
        return Err(StabilityError::param(format!(
            "no patch for grasp {grasp}, sensor {sensor}"
        )));
    }
    let row = grasp * data.sensor_count() + sensor;
    let patch = data.x.row(row);
    let code = dict
        .encode(data.x.slice(ndarray::s![row..row + 1, ..]), gamma)
        .map_err(StabilityError::sparse)?;
    Ok(reconstruction_of(
        data,
        dict,
        grasp,
        sensor,
        patch,
        code.row(0),
    ))
}

pub(super) fn reconstruction_of(
    data: &StabilityData,
    dict: &Dictionary,
    grasp: usize,
    sensor: usize,
    patch: ArrayView1<f64>,
    code: ArrayView1<f64>,
) -> Reconstruction {
    let mut terms: Vec<(usize, f64)> = code
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(j, v)| (j, *v))
        .collect();
    terms.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
    let rec = dict.reconstruct(code);
    let err = (&patch - &rec).mapv(|v| v * v).sum().sqrt();
    let nrm = patch.dot(&patch).sqrt();
    Reconstruction {
        grasp,
        sensor,
        failure: data.labels[grasp],
        patch: patch.to_vec(),
        terms,
        reconstruction: rec.to_vec(),
        relative_error: if nrm > 0.0 { err / nrm } else { 0.0 },
    }
}

/// The analyses of a model with dictionary `dict` coded with `gamma`.
pub fn analyse(
    data: &StabilityData,
    config: Config,
    dict: &Dictionary,
) -> Result<Analyses, StabilityError> {
    let codes = dict
        .encode(data.x.view(), config.gamma)
        .map_err(StabilityError::sparse)?;
    let k = dict.num_bases();
    let s = data.sensor_count();
    let coords = data.layout.as_ref().map(taxel_coords);
    let basis_images = (0..k)
        .map(|j| {
            let values = dict.atoms.row(j).to_vec();
            BasisImage {
                basis: j,
                raw: data.layout.as_ref().and_then(|l| raw_image(l, &values)),
                filtered: coords.as_ref().and_then(|c| filtered_image(c, &values)),
                values,
            }
        })
        .collect();
    // Usage and coefficients by label.
    let mut grasp_use = [vec![0.0; k], vec![0.0; k]];
    let mut patch_use = [vec![0.0; k], vec![0.0; k]];
    let mut coef_sum = [vec![0.0; k], vec![0.0; k]];
    let mut grasps_of = [0usize; 2];
    let mut active = [0usize; 2];
    for g in 0..data.grasp_count() {
        let l = data.labels[g] as usize;
        grasps_of[l] += 1;
        let mut used = vec![false; k];
        for sn in 0..s {
            let row = codes.row(g * s + sn);
            for (j, &v) in row.iter().enumerate() {
                if v != 0.0 {
                    used[j] = true;
                    patch_use[l][j] += 1.0;
                    coef_sum[l][j] += v.abs();
                    active[l] += 1;
                }
            }
        }
        for j in 0..k {
            if used[j] {
                grasp_use[l][j] += 1.0;
            }
        }
    }
    let div = |v: &[f64], n: f64| -> Vec<f64> {
        v.iter()
            .map(|x| if n > 0.0 { x / n } else { 0.0 })
            .collect()
    };
    let patches_of = [
        grasps_of[0] as f64 * s as f64,
        grasps_of[1] as f64 * s as f64,
    ];
    let mean_abs = |l: usize| -> Vec<f64> {
        (0..k)
            .map(|j| {
                if patch_use[l][j] > 0.0 {
                    coef_sum[l][j] / patch_use[l][j]
                } else {
                    0.0
                }
            })
            .collect()
    };
    let gu = [
        div(&grasp_use[0], grasps_of[0] as f64),
        div(&grasp_use[1], grasps_of[1] as f64),
    ];
    let ma = [mean_abs(0), mean_abs(1)];
    let diff = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>();
    let usage = BasisUsage {
        usage_differential: diff(&gu[0], &gu[1]),
        coefficient_differential: diff(&ma[0], &ma[1]),
        patch_usage_success: div(&patch_use[0], patches_of[0]),
        patch_usage_failure: div(&patch_use[1], patches_of[1]),
        mean_abs_coef_all_success: div(&coef_sum[0], patches_of[0]),
        mean_abs_coef_all_failure: div(&coef_sum[1], patches_of[1]),
        grasp_usage_success: gu[0].clone(),
        grasp_usage_failure: gu[1].clone(),
        mean_abs_coef_success: ma[0].clone(),
        mean_abs_coef_failure: ma[1].clone(),
    };
    let per_patch = |n: usize, p: f64| if p > 0.0 { n as f64 / p } else { 0.0 };
    let all_patches = patches_of[0] + patches_of[1];
    let active_bases_per_patch = [
        per_patch(active[0] + active[1], all_patches),
        per_patch(active[0], patches_of[0]),
        per_patch(active[1], patches_of[1]),
    ];
    let sparsity = active_bases_per_patch.map(|a| 1.0 - a / k as f64);
    // A representative patch per label.
    let mut reconstructions = Vec::new();
    for l in [false, true] {
        let typical = active_bases_per_patch[1 + l as usize].round() as usize;
        let pick = (0..data.x.nrows())
            .filter(|&r| data.labels[r / s] == l)
            .map(|r| {
                let nz = codes.row(r).iter().filter(|v| **v != 0.0).count();
                let nrm = data.x.row(r).dot(&data.x.row(r));
                (nz.abs_diff(typical), -nrm, r)
            })
            .min_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
        if let Some((_, _, r)) = pick {
            reconstructions.push(reconstruction_of(
                data,
                dict,
                r / s,
                r % s,
                data.x.row(r),
                codes.row(r),
            ));
        }
    }
    Ok(Analyses {
        config,
        basis_images,
        filter: FILTER.into(),
        reconstructions,
        usage,
        active_bases_per_patch,
        sparsity,
    })
}

/// Every grasp as a model sees it: each patch coded on `dict` with `gamma`, its
/// reconstruction, and the prediction and decision value of the cross validation `cv` (run
/// on these codes) from the fold that tested the grasp.
pub fn grasp_codes(
    data: &StabilityData,
    dict: &Dictionary,
    gamma: f64,
    cv: &CvResult,
) -> Result<Vec<GraspCode>, StabilityError> {
    let n = data.grasp_count();
    if cv.predictions.len() != n || cv.decisions.len() != n {
        return Err(StabilityError::data(format!(
            "a cross validation of {} grasps for {n} grasps",
            cv.predictions.len()
        )));
    }
    let codes = dict
        .encode(data.x.view(), gamma)
        .map_err(StabilityError::sparse)?;
    let s = data.sensor_count();
    let class = |failure: bool| {
        if failure {
            data.failure_name.clone()
        } else {
            data.success_name.clone()
        }
    };
    Ok((0..n)
        .map(|g| GraspCode {
            grasp: data.grasp_ids[g],
            truth: class(data.labels[g]),
            predicted: class(cv.predictions[g]),
            decision: cv.decisions[g],
            patches: (0..s)
                .map(|sensor| {
                    let r = g * s + sensor;
                    let rec = reconstruction_of(data, dict, g, sensor, data.x.row(r), codes.row(r));
                    PatchCode {
                        sensor,
                        patch: rec.patch,
                        terms: rec.terms,
                        reconstruction: rec.reconstruction,
                        relative_error: rec.relative_error,
                    }
                })
                .collect(),
        })
        .collect())
}
