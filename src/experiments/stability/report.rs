//! The grasp-stability pipeline's report as an analysis result with the first paper's
//! figures: score against the number of bases (Fig. 5), the β × γ map at the chosen number
//! of bases, basis images raw and filtered (Fig. 6), confusion maps (Fig. 7), per-label
//! basis usage (Figs. 8–9), the usage differential (Fig. 10), the coefficient differential
//! (Fig. 11) and a patch's reconstruction (Fig. 2).

use crate::catalogue::MethodId;
use crate::experiments::figure_id::FigureId;
use std::collections::BTreeMap;

use super::{
    BasisUsage, CvScheme, GridImage as PatchImage, GridResult, PipelineInputs, StabilityOptions,
    StabilityReport,
};
use crate::experiments::links::{GraspLinks, basis_links, grasps_text};
use crate::experiments::result::{
    AnalysisKind, AnalysisResult, FigureDetails, ModelSize, SizeReason, distinct_sorted, now_unix,
};
use crate::figures::{
    Axis, AxisTitle, BarGroup, ColorScale, ErrorDisplay, ErrorRange, Figure, FigureKind, GridImage,
    Heatmap, ImageGrid, Orientation, Series, SeriesStyle,
};
use crate::svm::eval::{Confusion, CvResult};

fn image(caption: String, img: &PatchImage) -> GridImage {
    let values = (0..img.rows)
        .map(|r| {
            (0..img.cols)
                .map(|c| {
                    img.pixels
                        .get(r * img.cols + c)
                        .copied()
                        .flatten()
                        .unwrap_or(f64::NAN)
                })
                .collect()
        })
        .collect();
    GridImage { caption, values }
}

fn confusion(title: &str, cv: &CvResult, success: &str, failure: &str) -> Figure {
    confusion_map(title, &cv.confusion, success, failure).subtitle(format!(
        "weighted success rate {:.1}%, failure recall {:.1}%",
        100.0 * cv.weighted_success_rate,
        100.0 * cv.failure_recall
    ))
}

/// The confusion map of a grasp-stability classifier: the share of each true outcome
/// predicted as each (rows and columns: success, failure).
pub fn confusion_map(title: &str, confusion: &Confusion, success: &str, failure: &str) -> Figure {
    let m = confusion.matrix;
    let share = |t: usize, p: usize| {
        let total = m[t][0] + m[t][1];
        if total == 0 {
            f64::NAN
        } else {
            m[t][p] as f64 / total as f64
        }
    };
    let mut heat = Heatmap {
        x: AxisTitle {
            title: "predicted".into(),
            unit: String::new(),
        },
        y: AxisTitle {
            title: "true outcome".into(),
            unit: String::new(),
        },
        columns: vec![success.into(), failure.into()],
        rows: vec![success.into(), failure.into()],
        values: vec![
            vec![share(0, 0), share(0, 1)],
            vec![share(1, 0), share(1, 1)],
        ],
        colors: ColorScale::viridis("share of the true class", ""),
        annotate: true,
        marked: Vec::new(),
    };
    heat.colors.limits = Some([0.0, 1.0]);
    Figure::new(title, FigureKind::Heatmap(heat))
}

fn signed_bars(title: &str, y: &str, name: &str, values: &[f64]) -> Figure {
    let mut f = Figure::bars(
        title,
        AxisTitle {
            title: "basis".into(),
            unit: String::new(),
        },
        Axis::new(y, ""),
        (1..=values.len()).map(|i| i.to_string()).collect(),
        vec![BarGroup::new(name, values.to_vec())],
    );
    if let FigureKind::Bars(b) = &mut f.kind {
        b.sign_colors = true;
    }
    f
}

/// What one basis does for each label, shown when its image is clicked.
fn basis_detail(u: &BasisUsage, b: usize, ok: &str, bad: &str) -> Figure {
    let at = |v: &[f64]| v.get(b).copied().unwrap_or(f64::NAN);
    Figure::bars(
        format!("Basis {}: usage by label", b + 1),
        AxisTitle {
            title: "label".into(),
            unit: String::new(),
        },
        Axis::new(format!("share using basis {}", b + 1), "").including(0.0, 1.0),
        vec![ok.into(), bad.into()],
        vec![
            BarGroup::new(
                "grasps",
                vec![at(&u.grasp_usage_success), at(&u.grasp_usage_failure)],
            ),
            BarGroup::new(
                "patches",
                vec![at(&u.patch_usage_success), at(&u.patch_usage_failure)],
            ),
        ],
    )
    .subtitle(format!(
        "usage differential {:+.3}; mean |coefficient| when used: {ok} {:.3}, {bad} {:.3} \
         (differential {:+.3})",
        at(&u.usage_differential),
        at(&u.mean_abs_coef_success),
        at(&u.mean_abs_coef_failure),
        at(&u.coefficient_differential),
    ))
}

/// Confusion cell [true class, predicted class] (0 = success, 1 = failure, as the map's
/// rows and columns) → the session grasps in it. None for a report without its grasps.
fn confusion_links(
    figure: FigureId,
    r: &StabilityReport,
    cv: &CvResult,
    ok: &str,
    bad: &str,
) -> Option<GraspLinks> {
    let n = cv.predictions.len();
    if r.grasp_ids.len() != n || r.labels.len() != n {
        return None;
    }
    let class = |failure: usize| if failure == 1 { bad } else { ok };
    Some(GraspLinks::from_observations(
        figure,
        None,
        (0..n).map(|i| {
            (
                [r.labels[i] as usize, cv.predictions[i] as usize],
                r.grasp_ids[i],
            )
        }),
        |[t, p], grasps, _| {
            format!(
                "true {}, predicted {}: {}",
                class(t),
                class(p),
                grasps_text(grasps)
            )
        },
    ))
}

/// The nested cross-validation scores beside the others, named by protocol: the score of
/// the grid's selection that no selection saw, and the raw SVM under the same folds.
fn nested_scores(r: &StabilityReport) -> Vec<(String, f64)> {
    r.nested
        .iter()
        .flat_map(|n| {
            let name = match n.protocol {
                CvScheme::KFold { k } => format!("nested {k}-fold"),
                CvScheme::LeaveObjectsOut { .. } => "nested new objects".into(),
            };
            [
                (
                    format!("weighted success rate ({name})"),
                    n.weighted_success_rate,
                ),
                (format!("failure recall ({name})"), n.failure_recall),
                (
                    format!("raw linear SVM WSR ({name} folds)"),
                    n.raw_weighted_success_rate,
                ),
            ]
        })
        .collect()
}

/// Scores, timings and figures of a grasp-stability run.
pub fn stability_report(r: &StabilityReport) -> AnalysisResult {
    let p = &r.parsimonious;
    let cfg = p.config;
    let inputs = match r.options.settings.inputs {
        PipelineInputs::Codes => "",
        PipelineInputs::CodesAndRaw => ", codes+raw",
    };
    let label = format!(
        "sparse coding + SVM, K = {}, β = {}, γ = {}{inputs}",
        cfg.num_bases, cfg.beta, cfg.gamma
    );
    let figures = figures(r);
    let details = basis_usage_details(r, &figures);
    let links = links(r, &figures);
    AnalysisResult {
        held_out: None,
        methods: vec![MethodId::SparseSvm],
        kind: AnalysisKind::Stability,
        label,
        session: r.session.clone(),
        parameters: parameters(r),
        scores: scores(r),
        headline: Some((
            "weighted success rate (10-fold)".into(),
            p.kfold.weighted_success_rate,
        )),
        train_seconds: p.dictionary_secs.max(1e-6),
        predict_seconds_per_sample: None,
        created: now_unix(),
        figures,
        details,
        links,
        grasp_codes: r.grasp_codes.clone(),
        model_size: Some(model_size(r)),
    }
}

/// Every figure of the report, in the order shown: the grid's (when there is one), the
/// basis images, the confusion maps, the usage bars and a patch's reconstruction.
fn figures(r: &StabilityReport) -> Vec<(FigureId, Figure)> {
    let p = &r.parsimonious;
    let (ok, bad) = (r.success_class.as_str(), r.failure_class.as_str());
    let mut figures = Vec::new();
    if let Some(g) = &r.grid {
        figures.push((FigureId::ScoreVsBases, score_vs_bases(r, g)));
        figures.push((FigureId::BetaGamma, beta_gamma_map(g)));
    }
    figures.extend(basis_images(r));
    figures.push((
        FigureId::ConfusionKfold,
        confusion(&format!("Confusion map, {}", r.kfold_cv), &p.kfold, ok, bad),
    ));
    figures.push((
        FigureId::ConfusionObjects,
        confusion(
            &format!("Confusion map, {} (new objects)", r.objects_cv),
            &p.objects,
            ok,
            bad,
        ),
    ));
    figures.extend(usage_figures(r));
    if let Some(f) = reconstruction(r) {
        figures.push((FigureId::Reconstruction, f));
    }
    figures
}

/// The best score per number of bases with its standard error over folds (Fig. 5).
fn score_vs_bases(r: &StabilityReport, g: &GridResult) -> Figure {
    let k: Vec<f64> = g
        .best_per_num_bases
        .iter()
        .map(|c| c.config.num_bases as f64)
        .collect();
    let wsr: Vec<f64> = g
        .best_per_num_bases
        .iter()
        .map(|c| c.fold_wsr_mean)
        .collect();
    let mut s =
        Series::new("best (β, γ) per number of bases", k, wsr).style(SeriesStyle::LineMarkers);
    s.error = Some(ErrorRange {
        display: ErrorDisplay::Bars,
        lower: g
            .best_per_num_bases
            .iter()
            .map(|c| c.fold_wsr_mean - c.fold_wsr_se)
            .collect(),
        upper: g
            .best_per_num_bases
            .iter()
            .map(|c| c.fold_wsr_mean + c.fold_wsr_se)
            .collect(),
    });
    Figure::chart(
        "Weighted success rate against the number of bases",
        Axis::new("number of bases", ""),
        Axis::new("weighted success rate (fold mean)", ""),
        vec![s],
    )
    .ref_line(
        Orientation::Vertical,
        g.parsimonious.config.num_bases as f64,
        "parsimonious choice",
    )
    .ref_line(
        Orientation::Vertical,
        g.best.config.num_bases as f64,
        "best",
    )
    .subtitle(format!(
        "{}; bars: ± 1 standard error over folds",
        r.selection_cv
    ))
}

/// The score over β × γ at the best cell's number of bases, the best cell marked.
fn beta_gamma_map(g: &GridResult) -> Figure {
    let nb = g.best.config.num_bases;
    let cells: Vec<_> = g
        .cells
        .iter()
        .filter(|c| c.config.num_bases == nb)
        .collect();
    let betas = distinct_sorted(cells.iter().map(|c| c.config.beta));
    let gammas = distinct_sorted(cells.iter().map(|c| c.config.gamma));
    let mut values = vec![vec![f64::NAN; gammas.len()]; betas.len()];
    let mut marked = Vec::new();
    for c in &cells {
        let (Some(i), Some(j)) = (
            betas.iter().position(|&b| b == c.config.beta),
            gammas.iter().position(|&x| x == c.config.gamma),
        ) else {
            continue;
        };
        values[i][j] = c.fold_wsr_mean;
        if c.config == g.best.config {
            marked.push([i, j]);
        }
    }
    Figure::new(
        format!("Weighted success rate over β × γ at K = {nb}"),
        FigureKind::Heatmap(Heatmap {
            x: AxisTitle {
                title: "γ (coding penalty)".into(),
                unit: String::new(),
            },
            y: AxisTitle {
                title: "β (learning penalty)".into(),
                unit: String::new(),
            },
            columns: gammas.iter().map(|v| format!("{v}")).collect(),
            rows: betas.iter().map(|v| format!("{v}")).collect(),
            values,
            colors: ColorScale::viridis("weighted success rate", ""),
            annotate: true,
            marked,
        }),
    )
    .subtitle("the best cell is marked")
}

/// The basis images raw and, when there are raw ones, filtered (Fig. 6); none for a sensor
/// without a layout.
fn basis_images(r: &StabilityReport) -> Vec<(FigureId, Figure)> {
    let mut figures = Vec::new();
    let raw: Vec<GridImage> = r
        .analyses
        .basis_images
        .iter()
        .filter_map(|b| {
            b.raw
                .as_ref()
                .map(|img| image(format!("basis {}", b.basis + 1), img))
        })
        .collect();
    if raw.is_empty() {
        return figures;
    }
    figures.push((
        FigureId::BasesRaw,
        Figure::new(
            "Basis images",
            FigureKind::ImageGrid(ImageGrid {
                images: raw,
                columns: 10,
                colors: ColorScale::diverging("basis weight", ""),
            }),
        )
        .subtitle(format!(
            "K = {}, drawn in the sensor's layout",
            r.parsimonious.config.num_bases
        )),
    ));
    let filtered: Vec<GridImage> = r
        .analyses
        .basis_images
        .iter()
        .filter_map(|b| {
            b.filtered
                .as_ref()
                .map(|img| image(format!("basis {}", b.basis + 1), img))
        })
        .collect();
    if !filtered.is_empty() {
        figures.push((
            FigureId::BasesFiltered,
            Figure::new(
                "Basis images, filtered",
                FigureKind::ImageGrid(ImageGrid {
                    images: filtered,
                    columns: 10,
                    colors: ColorScale::diverging("basis weight", ""),
                }),
            )
            .subtitle(r.analyses.filter.clone()),
        ));
    }
    figures
}

/// Basis usage per label (Figs. 8–9), the usage differential (Fig. 10) and the
/// coefficient differential (Fig. 11).
fn usage_figures(r: &StabilityReport) -> [(FigureId, Figure); 3] {
    let (ok, bad) = (r.success_class.as_str(), r.failure_class.as_str());
    let u = &r.analyses.usage;
    let k = u.grasp_usage_success.len();
    [
        (
            FigureId::BasisUsage,
            Figure::bars(
                "Basis usage per label",
                AxisTitle {
                    title: "basis".into(),
                    unit: String::new(),
                },
                Axis::new("share of grasps using the basis", "").including(0.0, 1.0),
                (1..=k).map(|i| i.to_string()).collect(),
                vec![
                    BarGroup::new(ok, u.grasp_usage_success.clone()),
                    BarGroup::new(bad, u.grasp_usage_failure.clone()),
                ],
            ),
        ),
        (
            FigureId::UsageDifferential,
            signed_bars(
                "Basis usage differential",
                &format!("usage ({ok}) − usage ({bad})"),
                "differential",
                &u.usage_differential,
            ),
        ),
        (
            FigureId::CoefficientDifferential,
            signed_bars(
                "Coefficient differential",
                &format!("mean |coefficient| ({ok}) − ({bad})"),
                "differential",
                &u.coefficient_differential,
            ),
        ),
    ]
}

/// The first reconstructed patch, each basis it uses scaled by its coefficient, and the
/// reconstruction, all in the sensor's layout (Fig. 2). None without a reconstruction or
/// a layout.
fn reconstruction(r: &StabilityReport) -> Option<Figure> {
    let (ok, bad) = (r.success_class.as_str(), r.failure_class.as_str());
    let rec = r.analyses.reconstructions.first()?;
    let shape = r
        .analyses
        .basis_images
        .first()
        .and_then(|b| b.raw.as_ref())?;
    let as_image = |caption: String, values: &[f64]| {
        let mut img = PatchImage {
            rows: shape.rows,
            cols: shape.cols,
            pixels: shape.pixels.clone(),
        };
        let mut k = 0;
        for px in img.pixels.iter_mut() {
            if px.is_some() {
                *px = values.get(k).copied();
                k += 1;
            }
        }
        image(caption, &img)
    };
    let mut images = vec![as_image("patch".into(), &rec.patch)];
    for &(b, coef) in rec.terms.iter().take(8) {
        if let Some(basis) = r.analyses.basis_images.iter().find(|x| x.basis == b) {
            images.push(as_image(
                format!("{coef:+.2} × basis {}", b + 1),
                &basis.values,
            ));
        }
    }
    images.push(as_image(
        format!("reconstruction (error {:.0}%)", 100.0 * rec.relative_error),
        &rec.reconstruction,
    ));
    Some(
        Figure::new(
            "A patch and its reconstruction",
            FigureKind::ImageGrid(ImageGrid {
                images,
                columns: 10,
                colors: ColorScale::diverging("standardised pressure", ""),
            }),
        )
        .subtitle(format!(
            "grasp {} ({}), sensor {}; {} bases used",
            rec.grasp + 1,
            if rec.failure { bad } else { ok },
            rec.sensor + 1,
            rec.terms.len()
        )),
    )
}

/// A click on a basis image (raw or filtered) shows that basis's usage.
fn basis_usage_details(r: &StabilityReport, figures: &[(FigureId, Figure)]) -> Vec<FigureDetails> {
    let (ok, bad) = (r.success_class.as_str(), r.failure_class.as_str());
    let usage_items: Vec<(f64, Figure)> = r
        .analyses
        .basis_images
        .iter()
        .filter(|b| b.raw.is_some())
        .enumerate()
        .map(|(i, b)| (i as f64, basis_detail(&r.analyses.usage, b.basis, ok, bad)))
        .collect();
    [FigureId::BasesRaw, FigureId::BasesFiltered]
        .into_iter()
        .filter(|id| figures.iter().any(|(n, _)| n == id))
        .map(|name| FigureDetails {
            figure: name,
            selector: "basis".into(),
            items: usage_items.clone(),
        })
        .collect()
}

/// The grasps behind the confusion maps' cells and the basis images.
fn links(r: &StabilityReport, figures: &[(FigureId, Figure)]) -> Vec<GraspLinks> {
    let p = &r.parsimonious;
    let (ok, bad) = (r.success_class.as_str(), r.failure_class.as_str());
    let mut links: Vec<GraspLinks> = [
        (FigureId::ConfusionKfold, &p.kfold),
        (FigureId::ConfusionObjects, &p.objects),
    ]
    .into_iter()
    .filter_map(|(name, cv)| confusion_links(name, r, cv, ok, bad))
    .collect();
    // Image i of each basis grid shows the i-th basis that has such an image.
    let raw_bases: Vec<usize> = r
        .analyses
        .basis_images
        .iter()
        .filter(|b| b.raw.is_some())
        .map(|b| b.basis)
        .collect();
    let filtered_bases: Vec<usize> = r
        .analyses
        .basis_images
        .iter()
        .filter(|b| b.filtered.is_some())
        .map(|b| b.basis)
        .collect();
    for (name, bases) in [
        (FigureId::BasesRaw, &raw_bases),
        (FigureId::BasesFiltered, &filtered_bases),
    ] {
        if figures.iter().any(|(n, _)| *n == name) {
            links.push(basis_links(name, bases, &r.grasp_codes));
        }
    }
    links
}

fn parameters(r: &StabilityReport) -> BTreeMap<String, String> {
    let cfg = r.parsimonious.config;
    BTreeMap::from([
        ("num_bases".to_string(), cfg.num_bases.to_string()),
        ("beta".to_string(), cfg.beta.to_string()),
        ("gamma".to_string(), cfg.gamma.to_string()),
        ("scaling".to_string(), r.scaling.clone()),
        ("objective convention".to_string(), r.convention.clone()),
        ("model selection".to_string(), r.selection_cv.clone()),
        ("inputs".to_string(), r.options.settings.inputs.to_string()),
    ])
}

/// The recommended model's scores, the raw baseline's and the nested ones.
fn scores(r: &StabilityReport) -> Vec<(String, f64)> {
    let p = &r.parsimonious;
    [
        (
            "weighted success rate (10-fold)".into(),
            p.kfold.weighted_success_rate,
        ),
        ("failure recall (10-fold)".into(), p.kfold.failure_recall),
        (
            "weighted success rate (new objects)".into(),
            p.objects.weighted_success_rate,
        ),
        (
            "failure recall (new objects)".into(),
            p.objects.failure_recall,
        ),
        ("average sparsity".into(), p.sparsity),
        ("active bases per patch".into(), p.active_bases_per_patch),
        (
            "active bases per patch (success)".into(),
            r.analyses.active_bases_per_patch[1],
        ),
        (
            "active bases per patch (failure)".into(),
            r.analyses.active_bases_per_patch[2],
        ),
        ("dictionary objective F".into(), p.dictionary_objective),
        (
            "raw linear SVM WSR (10-fold)".into(),
            r.baseline.kfold.weighted_success_rate,
        ),
        (
            "raw linear SVM WSR (new objects)".into(),
            r.baseline.objects.weighted_success_rate,
        ),
    ]
    .into_iter()
    .chain(nested_scores(r))
    .collect()
}

/// The recommended model's size and why it has it.
fn model_size(r: &StabilityReport) -> ModelSize {
    let cfg = r.parsimonious.config;
    ModelSize {
        knobs: format!(
            "num_bases {}, beta {}, gamma {}",
            cfg.num_bases, cfg.beta, cfg.gamma
        ),
        reason: if r.grid.is_some() {
            SizeReason::Recommended
        } else if let Some(reason) = r.options.size_reason {
            reason
        } else if cfg == StabilityOptions::default().single {
            SizeReason::PaperDefault
        } else {
            SizeReason::User
        },
    }
}
