//! A frontier's work: its items (one per size and repetition), preparing the session,
//! computing one item, and assembling the points, each asked of the method's object.

use super::*;

/// Check the parameters against the session and prepare what every item shares.
pub fn prepare_frontier(
    session: &Session,
    params: &FrontierParams,
) -> Result<FrontierPrep, ExperimentError> {
    params.checked()?.prepare(session, params)
}

/// What an item costs relative to the others of its frontier: the experts' update grows
/// with their capacity, a dictionary's learning and coding with its bases, the clusterers
/// with their centres; an RBF SVM's or a registered method's cross validation costs about
/// the same at every size.
pub fn item_cost(item: &FrontierItem) -> f64 {
    match *item {
        // A sparse GP's update grows with its basis vectors, and with their square past a
        // few tens.
        FrontierItem::Recognition { capacity, .. } => {
            let c = capacity as f64;
            c + c * c / 50.0
        }
        FrontierItem::Dictionary { num_bases, .. } => num_bases as f64,
        FrontierItem::Clusters { k, .. } => k as f64,
        FrontierItem::Threshold { .. }
        | FrontierItem::Svm { .. }
        | FrontierItem::Classifier { .. } => 1.0,
    }
}

/// The items of a frontier, in the order its points are assembled: every size (or knob
/// value) with its repetitions in order.
pub fn frontier_items(params: &FrontierParams) -> Vec<FrontierItem> {
    // No size knob: no items (validate says why).
    frontier_method(params.method).map_or_else(Vec::new, |m| m.items(params))
}

/// Compute one item.
pub fn frontier_item(
    session: &Session,
    params: &FrontierParams,
    prep: &FrontierPrep,
    item: &FrontierItem,
    progress: &Progress,
) -> Result<FrontierOutput, ExperimentError> {
    match frontier_method(params.method) {
        Some(m) => m.item(session, params, prep, item, progress),
        None => Err(wrong_item(item, params)),
    }
}

/// Sweep the method's size knobs on `session`.
pub fn run_frontier(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<Frontier, ExperimentError> {
    let start = Instant::now();
    // Choosing the inputs costs about AUTO_REPETITIONS of the frontier's average item.
    let costs: Vec<f64> = frontier_items(params).iter().map(item_cost).collect();
    let auto = match params.features.is_auto() {
        true => {
            crate::experiments::recognition::AUTO_REPETITIONS * costs.iter().sum::<f64>()
                / costs.len().max(1) as f64
        }
        false => 0.0,
    };
    let parts = progress.parts(&[auto, costs.iter().sum()]);
    let (params, feature_choice) = choose_auto_features(session, params, &parts[0])?;
    let params = &params;
    let progress = &parts[1];
    let prep = prepare_frontier(session, params)?;
    let items = frontier_items(params);
    let label = params.label();
    progress.set(0.0, format!("frontier {label}: starting"));
    let outputs = compute_items(
        &items,
        progress,
        &format!("frontier {label}"),
        "runs",
        item_cost,
        |item, part| frontier_item(session, params, &prep, item, part),
    )?;
    let frontier = assemble_frontier(
        &session.meta.name,
        params,
        &items,
        outputs,
        start.elapsed().as_secs_f64(),
    )?;
    Ok(Frontier {
        feature_choice,
        ..frontier
    })
}

/// `params` with `auto` replaced by the feature set chosen by cross validation on the
/// object labels at the method's default size (DS, GS: the paper's capacity and tau; DU,
/// GU: their experts' size, scored by DS's and GS's experts; a registered method: its
/// default size), and that choice; or as they are.
pub fn choose_auto_features(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<(FrontierParams, Option<FeatureChoice>), ExperimentError> {
    if !params.features.is_auto() {
        return Ok((params.clone(), None));
    }
    progress.set(0.0, "auto features: cross validation");
    let choice = match frontier_method(params.method) {
        Some(m) => m.choose_features(session, params, progress)?,
        None => return Err(no_sequences(params.method)),
    };
    let chosen = FrontierParams {
        features: choice.chosen,
        ..params.clone()
    };
    Ok((chosen, Some(choice)))
}

/// The frontier from every item's output (in item order): the points, the best and the
/// recommended point, the Pareto fronts.
pub fn assemble_frontier(
    session: &str,
    params: &FrontierParams,
    items: &[FrontierItem],
    outputs: Vec<FrontierOutput>,
    wall_seconds: f64,
) -> Result<Frontier, ExperimentError> {
    if items.len() != outputs.len() {
        return Err(ExperimentError::Data(format!(
            "{} items but {} outputs",
            items.len(),
            outputs.len()
        )));
    }
    let pairs: Vec<(FrontierItem, FrontierOutput)> = items.iter().copied().zip(outputs).collect();
    let MethodPoints {
        points,
        paper_default,
        score_name,
        unit,
    } = params.checked()?.points(params, pairs);
    let (best, recommended) =
        recommend(&points, params.cost).ok_or_else(|| ExperimentError::Data("no sizes".into()))?;
    let front = |axis: CostAxis| {
        let x: Vec<f64> = points.iter().map(|p| p.cost(axis)).collect();
        let y: Vec<f64> = points.iter().map(|p| p.score).collect();
        crate::figures::pareto_front(&x, &y)
    };
    Ok(Frontier {
        session: session.to_string(),
        params: params.clone(),
        score_name,
        unit: unit.into(),
        pareto_training: front(CostAxis::Training),
        pareto_prediction: front(CostAxis::Prediction),
        points,
        best,
        recommended,
        paper_default,
        wall_seconds,
        feature_choice: None,
    })
}
