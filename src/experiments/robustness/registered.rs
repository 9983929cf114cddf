//! A method of the registry ([`crate::catalogue::Classifier`]) at its default size, under
//! the online protocol's split.

use super::*;
use crate::catalogue::ClassifierId;

impl RecognitionMethod for ClassifierId {
    fn needs(&self) -> Needs {
        Needs {
            sequences: true,
            ..Needs::default()
        }
    }

    /// Its accuracy on the test part, trained on the taught and the kept training grasps.
    fn score(&self, r: &RecognitionRep) -> Result<f64, ExperimentError> {
        let train: Vec<usize> = (r.teach.iter().copied())
            .chain((r.order[..r.n_train].iter().zip(&r.keep)).filter_map(|(&g, &k)| k.then_some(g)))
            .collect();
        let seed = Rng::stream(r.params.seed, CLASSIFIER_STREAM + r.rep as u64).next_u64();
        Ok(train_test(
            self.method(),
            &self.method().default_size(),
            r.train_seqs,
            r.test_seqs,
            &r.prep.labels,
            r.prep.n_classes,
            &train,
            &r.order[r.n_train..],
            seed,
            &Progress::new(),
        )?
        .accuracy)
    }
}
