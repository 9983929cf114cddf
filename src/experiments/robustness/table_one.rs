//! The baselines on the second paper's per-grasp Table I features: sequential k-means and
//! the SOM (NMI on the kept grasps), and the RBF SVM (stratified k-fold accuracy).

use super::*;

const TABLE_ONE: Needs = Needs {
    sequences: false,
    subset_sequences: false,
    table: true,
};

/// A clusterer of the Table I rows.
pub(super) enum TableClusterer {
    KMeans,
    Som,
}

impl RecognitionMethod for TableClusterer {
    fn needs(&self) -> Needs {
        TABLE_ONE
    }

    /// The NMI of k clusters of the kept grasps' test rows.
    fn score(&self, r: &RecognitionRep) -> Result<f64, ExperimentError> {
        let (_, test) = r.table()?;
        let data = gather(test.view(), &r.subset);
        let (k, seed) = (r.k, r.cluster_seed);
        let pred = match self {
            TableClusterer::KMeans => SequentialKMeansParams { k, passes: 1, seed }
                .fit(data.view())
                .and_then(|m| m.assign(data.view())),
            TableClusterer::Som => som_setup(k, seed)
                .fit(data.view())
                .and_then(|m| m.assign(data.view())),
        }?;
        Ok(scores(&r.sub_labels, &pred).nmi)
    }
}

pub(super) struct RbfSvm;

impl RecognitionMethod for RbfSvm {
    fn needs(&self) -> Needs {
        TABLE_ONE
    }

    /// Stratified k-fold accuracy: trained on the training rows of the training folds
    /// (thinned by a training perturbation), tested on the test rows of the test fold.
    fn score(&self, r: &RecognitionRep) -> Result<f64, ExperimentError> {
        let (train_x, test_x) = r.table()?;
        let (params, prep) = (r.params, r.prep);
        let rc = &params.recognition;
        let labels = &prep.labels;
        let fold_seed = Rng::stream(params.seed, r.rep as u64).next_u64();
        let fold_of = stratified_folds(labels, rc.svm_folds, fold_seed);
        let mut aux = Rng::stream(params.seed, SVM_STREAM + r.rep as u64);
        let mut correct = 0usize;
        for f in 0..rc.svm_folds {
            let train: Vec<usize> = (0..labels.len()).filter(|&i| fold_of[i] != f).collect();
            let test: Vec<usize> = (0..labels.len()).filter(|&i| fold_of[i] == f).collect();
            let kept = training_kept(r.pert, labels, prep.n_classes, &train, false, &mut aux);
            let train: Vec<usize> = train
                .iter()
                .zip(&kept)
                .filter(|(_, k)| **k)
                .map(|(&i, _)| i)
                .collect();
            let y: Vec<usize> = train.iter().map(|&i| labels[i]).collect();
            let model = rc.svm.fit(gather(train_x.view(), &train).view(), &y)?;
            let pred = model.predict(gather(test_x.view(), &test).view())?;
            correct += test
                .iter()
                .zip(&pred)
                .filter(|(i, p)| labels[**i] == **p)
                .count();
        }
        Ok(correct as f64 / labels.len().max(1) as f64)
    }
}
