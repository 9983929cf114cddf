//! The one place that says which object answers for which method: the rest of the
//! frontier reaches a method through [`frontier_method`].

use super::method::FrontierMethod;
use super::sparse::SparseSvm;
use super::supervised::Supervised;
use super::table_one::{RbfSvm, TableClusterer};
use super::unsupervised::Unsupervised;
use crate::catalogue::{ClassifierId, MethodId};
use crate::experiments::clustering::UnsupervisedLearner;
use crate::experiments::recognition::SupervisedLearner;

/// The frontier's object of a method; None for a method without a size knob (raw-svm).
pub(super) fn frontier_method(id: MethodId) -> Option<&'static dyn FrontierMethod> {
    let method: &'static dyn FrontierMethod = match id {
        MethodId::RawSvm => return None,
        MethodId::SparseSvm => &SparseSvm,
        MethodId::Ds => &Supervised(SupervisedLearner::Ds),
        MethodId::Gs => &Supervised(SupervisedLearner::Gs),
        MethodId::Du => &Unsupervised(UnsupervisedLearner::Du),
        MethodId::Gu => &Unsupervised(UnsupervisedLearner::Gu),
        MethodId::KMeans => &TableClusterer::KMeans,
        MethodId::Som => &TableClusterer::Som,
        MethodId::RbfSvm => &RbfSvm,
        // The registry's own list holds every id for as long as the program runs.
        MethodId::Classifier(c) => ClassifierId::ALL.iter().find(|&&r| r == c)?,
    };
    Some(method)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_with_a_size_knob_has_a_frontier_object() {
        for m in MethodId::all() {
            assert_eq!(
                frontier_method(m).is_some(),
                !m.info().size_knobs.is_empty(),
                "{m}"
            );
        }
    }
}
