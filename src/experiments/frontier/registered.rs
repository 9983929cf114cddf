//! A method of the registry ([`crate::catalogue::Classifier`]): its own sizes, scored by
//! repeated stratified 10-fold cross validation on the feature sequences.

use super::method::{
    FrontierItem, FrontierMethod, FrontierOutput, FrontierPrep, MethodPoints, SweepKnob, each_rep,
    wrong_item,
};
use super::*;
use crate::catalogue::{Classifier, ClassifierId, Size};
use crate::experiments::classifier::{
    ClassifierPrep, ClassifierScorer, classifier_err, cv_repetition, prepare_classifier,
};
use crate::experiments::feature_choice::{AUTO_FOLDS, choose_features};

/// Folds of a registered method's cross validation.
const CLASSIFIER_FOLDS: usize = 10;

/// The sizes swept: the given ones, else the method's own list.
fn sizes(params: &FrontierParams, c: &dyn Classifier) -> Vec<Size> {
    if params.sizes.is_empty() {
        c.sizes()
    } else {
        params.sizes.clone()
    }
}

impl FrontierMethod for ClassifierId {
    fn validate(&self, params: &FrontierParams) -> Result<(), ExperimentError> {
        for size in sizes(params, self.method()) {
            self.method().check(&size).map_err(classifier_err)?;
        }
        Ok(())
    }

    /// The catalogue's knobs, each with its values over the sizes swept.
    fn size_knobs(&self, params: &FrontierParams) -> Vec<SweepKnob> {
        let lists = FrontierParams::lists_of_sizes(&sizes(params, self.method()));
        (self.method().info().size_knobs.iter().zip(lists))
            .map(|(k, values)| SweepKnob {
                name: k.name,
                label: format!("{}: {}", k.name, k.meaning),
                // The method's own check says which knobs count.
                whole: false,
                values,
            })
            .collect()
    }

    /// Every combination of one value per knob.
    fn set_size_knobs(&self, params: &mut FrontierParams, lists: &[Vec<f64>]) {
        params.sizes = FrontierParams::sizes_of_lists(lists);
    }

    fn prepare(
        &self,
        session: &Session,
        params: &FrontierParams,
    ) -> Result<FrontierPrep, ExperimentError> {
        Ok(FrontierPrep::new(prepare_classifier(
            session,
            params.features,
            "object",
        )?))
    }

    fn items(&self, params: &FrontierParams) -> Vec<FrontierItem> {
        let sizes = 0..sizes(params, self.method()).len();
        each_rep(sizes, params.reps, |size, rep| FrontierItem::Classifier {
            size,
            rep,
        })
    }

    fn item(
        &self,
        _session: &Session,
        params: &FrontierParams,
        prep: &FrontierPrep,
        item: &FrontierItem,
        progress: &Progress,
    ) -> Result<FrontierOutput, ExperimentError> {
        let (Some(prep), FrontierItem::Classifier { size, rep }) =
            (prep.get::<ClassifierPrep>(), *item)
        else {
            return Err(wrong_item(item, params));
        };
        let sizes = sizes(params, self.method());
        let Some(size) = sizes.get(size) else {
            return Err(wrong_item(item, params));
        };
        let s = cv_repetition(
            self.method(),
            size,
            prep,
            CLASSIFIER_FOLDS,
            params.seed,
            rep,
            progress,
        )?;
        Ok(FrontierOutput::Classifier {
            accuracy: s.accuracy,
            train_us: s.train_us,
            predict_us: s.predict_us,
        })
    }

    /// One point per size, its knobs named as the method names them.
    fn points(
        &self,
        params: &FrontierParams,
        pairs: Vec<(FrontierItem, FrontierOutput)>,
    ) -> MethodPoints {
        let method = self.method();
        let knobs = method.info().size_knobs;
        let points = sizes(params, method)
            .iter()
            .enumerate()
            .map(|(i, size)| {
                let (mut acc, mut train, mut predict) = (Vec::new(), Vec::new(), Vec::new());
                for (item, out) in &pairs {
                    if let (
                        FrontierItem::Classifier { size: s, .. },
                        FrontierOutput::Classifier {
                            accuracy,
                            train_us,
                            predict_us,
                        },
                    ) = (item, out)
                        && *s == i
                    {
                        acc.push(*accuracy);
                        train.push(*train_us);
                        predict.push(*predict_us);
                    }
                }
                let named: Vec<(&str, f64)> =
                    knobs.iter().map(|k| k.name).zip(size.clone()).collect();
                let words = named
                    .iter()
                    .map(|(k, v)| format!("{k} {v}"))
                    .collect::<Vec<_>>()
                    .join(" · ");
                point(
                    words.clone(),
                    format!("{}: {words}", method.info().title),
                    named,
                    &acc,
                    train,
                    predict,
                )
            })
            .collect();
        MethodPoints {
            points,
            paper_default: None,
            score_name: format!("accuracy ({CLASSIFIER_FOLDS}-fold)"),
            unit: "grasp",
        }
    }

    /// Scored by the method's own cross validation at its default size.
    fn choose_features(
        &self,
        session: &Session,
        params: &FrontierParams,
        progress: &Progress,
    ) -> Result<FeatureChoice, ExperimentError> {
        let size = self.method().default_size();
        let scorer = ClassifierScorer {
            method: self.method(),
            size: &size,
        };
        choose_features(
            session,
            &scorer,
            "object",
            AUTO_FOLDS,
            params.seed,
            progress,
        )
    }
}
