//! The one place that says which object answers for which method: the rest of the
//! robustness sweep reaches a method through [`robustness_method`].

use super::method::RobustnessMethod;
use super::stability_tasks::{RawSvm, SparseSvm};
use super::supervised::Supervised;
use super::table_one::{RbfSvm, TableClusterer};
use super::unsupervised::Unsupervised;
use crate::catalogue::{ClassifierId, MethodId};
use crate::experiments::clustering::UnsupervisedLearner;
use crate::experiments::recognition::SupervisedLearner;

pub(super) fn robustness_method(id: MethodId) -> RobustnessMethod {
    use RobustnessMethod::{Recognition, Stability};
    match id {
        MethodId::SparseSvm => Stability(&SparseSvm),
        MethodId::RawSvm => Stability(&RawSvm),
        MethodId::Ds => Recognition(&Supervised(SupervisedLearner::Ds)),
        MethodId::Gs => Recognition(&Supervised(SupervisedLearner::Gs)),
        MethodId::Du => Recognition(&Unsupervised(UnsupervisedLearner::Du)),
        MethodId::Gu => Recognition(&Unsupervised(UnsupervisedLearner::Gu)),
        MethodId::KMeans => Recognition(&TableClusterer::KMeans),
        MethodId::Som => Recognition(&TableClusterer::Som),
        MethodId::RbfSvm => Recognition(&RbfSvm),
        // The registry's own list holds every id for as long as the program runs.
        MethodId::Classifier(c) => Recognition(
            ClassifierId::ALL
                .iter()
                .find(|&&r| r == c)
                .expect("ClassifierId::ALL lists every id"),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalogue::{Input, Task};
    use crate::experiments::robustness::Family;

    /// The task kind a sweep runs a method on is the task the catalogue declares.
    #[test]
    fn every_method_runs_on_its_catalogue_task() {
        for m in MethodId::all() {
            let family = match m.task() {
                Task::Stability => Family::Stability,
                Task::Recognition | Task::Clustering => Family::Recognition,
            };
            assert_eq!(robustness_method(m).family(), family, "{m}");
        }
    }

    /// A recognition method prepares the inputs the catalogue says it reads.
    #[test]
    fn recognition_needs_follow_the_catalogue_inputs() {
        for m in MethodId::all() {
            let RobustnessMethod::Recognition(r) = robustness_method(m) else {
                continue;
            };
            let needs = r.needs();
            assert_eq!(needs.sequences, m.input() == Input::Sequences, "{m}");
            assert_eq!(needs.table, m.input() == Input::TableOne, "{m}");
            // Only the methods that learn from every kept grasp copy their sequences.
            assert_eq!(
                needs.subset_sequences,
                m.task() == Task::Clustering && m.input() == Input::Sequences,
                "{m}"
            );
        }
    }
}
