//! The catalogue of methods: every method the workbench fits is declared here once, with
//! its command-line key, its title, the kind of task it solves, the score it is measured
//! by, its inputs and the knobs that set its size. Frontiers, robustness sweeps, the
//! sweeps, paper-figures, the command line and the window take their method lists and
//! names from here.
//!
//! The papers' nine methods have their protocols written out in `experiments/` and
//! `models/`. Every other method implements [`Classifier`] in a module of its own and is
//! registered with one line of [`classifiers!`]: the protocols, the command line, the model
//! file and the window then reach it through the trait, with no edit of their own.

mod classifier;

use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

pub use classifier::{Classifier, ClassifierError, Fitted, Size, Training};

/// The registry of trait methods: `Variant => module::Type,` declares the module, its id
/// and its place in every list.
macro_rules! classifiers {
    ($($Variant:ident => $module:ident :: $Type:ident,)*) => {
        $(mod $module;)*

        /// A method that implements [`Classifier`] in its own module.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum ClassifierId {
            $($Variant,)*
        }

        impl ClassifierId {
            /// Every registered method, in the registry's order.
            pub const ALL: &[ClassifierId] = &[$(ClassifierId::$Variant,)*];

            /// The method behind the id.
            pub fn method(self) -> &'static dyn Classifier {
                match self {
                    $(ClassifierId::$Variant => &$module::$Type,)*
                }
            }
        }
    };
}

classifiers! {
    TemporalSvm => temporal_svm::TemporalSvm,
    DtwKnn => dtw_knn::DtwKnn,
}

/// A method of the catalogue. Saved as its key with `_` for `-` (`sparse_svm`, `kmeans`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MethodId {
    /// Sparse coding of the key-frame patches + linear SVM (the first paper).
    SparseSvm,
    /// Linear SVM on the scaled raw key-frame values (the first paper's baseline).
    RawSvm,
    /// Discriminative supervised OIESGP experts (the second paper).
    Ds,
    /// Generative supervised OIESGP experts.
    Gs,
    /// Discriminative unsupervised experts: online clustering at a novelty threshold.
    Du,
    /// Generative unsupervised experts with the extreme-value novelty.
    Gu,
    /// Sequential k-means on the per-grasp Table I features.
    KMeans,
    /// The sequential self-organising map on the Table I features.
    Som,
    /// The offline RBF SVM on the Table I features.
    RbfSvm,
    /// A method of the registry, reached through its trait.
    Classifier(ClassifierId),
}

/// What a method learns to do, and so which protocols can run it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Task {
    /// Success or failure of a grasp from its key frame (the first paper).
    Stability,
    /// The object of a grasp, supervised: online (DS, GS) or offline (RBF SVM).
    Recognition,
    /// Grasps grouped without labels, scored against the objects.
    Clustering,
}

/// What a method reads from a session.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Input {
    /// The key-frame patches of each sensor.
    Patches,
    /// Per-step feature sequences (one frontier per feature set).
    Sequences,
    /// The per-grasp Table I features of the second paper.
    TableOne,
}

/// A knob that sets a method's size (what a frontier sweeps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SizeKnob {
    /// The parameter's name, as in the papers.
    pub name: &'static str,
    pub meaning: &'static str,
}

/// Everything declared about one method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodInfo {
    pub id: MethodId,
    /// The command-line name (`--method ds`).
    pub key: &'static str,
    /// Older command-line names still accepted.
    pub aliases: &'static [&'static str],
    pub title: &'static str,
    pub task: Task,
    pub input: Input,
    /// The score its results are measured by, as charts and tables name it.
    pub score: &'static str,
    pub size_knobs: &'static [SizeKnob],
    /// Whether a robustness sweep of its task runs it unless asked not to (DU and GU run
    /// on request: at thresholds that give a useful partition they grow tens of clusters,
    /// and every cluster is a GP to score each step against).
    pub robustness_default: bool,
}

const EXPERTS: &[SizeKnob] = &[
    SizeKnob {
        name: "capacity",
        meaning: "basis vectors per expert",
    },
    SizeKnob {
        name: "tau",
        meaning: "steps of input history",
    },
];

/// The papers' methods, in the order lists show them (the registry's follow).
pub const CATALOGUE: [MethodInfo; 9] = [
    MethodInfo {
        id: MethodId::SparseSvm,
        key: "sparse-svm",
        aliases: &[],
        title: "sparse coding + SVM",
        task: Task::Stability,
        input: Input::Patches,
        score: "weighted success rate",
        size_knobs: &[SizeKnob {
            name: "num_bases",
            meaning: "basis vectors of the dictionary",
        }],
        robustness_default: true,
    },
    MethodInfo {
        id: MethodId::RawSvm,
        key: "raw-svm",
        aliases: &["linear-svm"],
        title: "raw linear SVM",
        task: Task::Stability,
        input: Input::Patches,
        score: "weighted success rate",
        size_knobs: &[],
        robustness_default: true,
    },
    MethodInfo {
        id: MethodId::Ds,
        key: "ds",
        aliases: &[],
        title: "DS",
        task: Task::Recognition,
        input: Input::Sequences,
        score: "accuracy (final 20%)",
        size_knobs: EXPERTS,
        robustness_default: true,
    },
    MethodInfo {
        id: MethodId::Gs,
        key: "gs",
        aliases: &[],
        title: "GS",
        task: Task::Recognition,
        input: Input::Sequences,
        score: "accuracy (final 20%)",
        size_knobs: EXPERTS,
        robustness_default: true,
    },
    MethodInfo {
        id: MethodId::Du,
        key: "du",
        aliases: &[],
        title: "DU",
        task: Task::Clustering,
        input: Input::Sequences,
        score: "NMI",
        size_knobs: EXPERTS,
        robustness_default: false,
    },
    MethodInfo {
        id: MethodId::Gu,
        key: "gu",
        aliases: &[],
        title: "GU",
        task: Task::Clustering,
        input: Input::Sequences,
        score: "NMI",
        size_knobs: EXPERTS,
        robustness_default: false,
    },
    MethodInfo {
        id: MethodId::KMeans,
        key: "kmeans",
        aliases: &["k-means"],
        title: "k-means",
        task: Task::Clustering,
        input: Input::TableOne,
        score: "NMI",
        size_knobs: &[SizeKnob {
            name: "k",
            meaning: "clusters",
        }],
        robustness_default: true,
    },
    MethodInfo {
        id: MethodId::Som,
        key: "som",
        aliases: &[],
        title: "SOM",
        task: Task::Clustering,
        input: Input::TableOne,
        score: "NMI",
        size_knobs: &[SizeKnob {
            name: "k",
            meaning: "map units",
        }],
        robustness_default: true,
    },
    MethodInfo {
        id: MethodId::RbfSvm,
        key: "rbf-svm",
        aliases: &[],
        title: "RBF SVM",
        task: Task::Recognition,
        input: Input::TableOne,
        score: "accuracy (k-fold)",
        size_knobs: &[SizeKnob {
            name: "c",
            meaning: "box constraint (and gamma: the kernel width)",
        }],
        robustness_default: true,
    },
];

impl MethodId {
    /// Every method: the papers', then the registry's.
    pub fn all() -> impl Iterator<Item = MethodId> {
        CATALOGUE
            .iter()
            .map(|m| m.id)
            .chain(ClassifierId::ALL.iter().map(|&c| MethodId::Classifier(c)))
    }

    pub fn info(self) -> &'static MethodInfo {
        match self {
            MethodId::Classifier(c) => c.method().info(),
            paper => CATALOGUE
                .iter()
                .find(|m| m.id == paper)
                .expect("every paper method is in the catalogue"),
        }
    }

    /// The registered method behind the id, for the protocols that run any of them.
    pub fn classifier(self) -> Option<&'static dyn Classifier> {
        match self {
            MethodId::Classifier(c) => Some(c.method()),
            _ => None,
        }
    }

    pub fn key(self) -> &'static str {
        self.info().key
    }

    pub fn title(self) -> &'static str {
        self.info().title
    }

    pub fn task(self) -> Task {
        self.info().task
    }

    pub fn input(self) -> Input {
        self.info().input
    }

    pub fn score_name(self) -> &'static str {
        self.info().score
    }

    /// DS, GS, DU and GU run on feature sequences (one result per feature set).
    pub fn uses_features(self) -> bool {
        self.input() == Input::Sequences
    }

    /// The keys of `methods`, for an error's "is not one of …".
    pub fn keys(methods: impl Iterator<Item = MethodId>) -> String {
        methods.map(|m| m.key()).collect::<Vec<_>>().join(", ")
    }
}

impl std::fmt::Display for MethodId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.title())
    }
}

/// A name that is no method's key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{name}` is not one of {}", MethodId::keys(MethodId::all()))]
pub struct UnknownMethod {
    pub name: String,
}

impl FromStr for MethodId {
    type Err = UnknownMethod;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        MethodId::all()
            .find(|m| m.key() == s || m.info().aliases.contains(&s))
            .ok_or_else(|| UnknownMethod { name: s.into() })
    }
}

impl Serialize for MethodId {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.key().replace('-', "_"))
    }
}

impl<'de> Deserialize<'de> for MethodId {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.replace('_', "-")
            .parse()
            .map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_is_declared_once_and_its_key_reads_back() {
        let mut keys: Vec<&str> = MethodId::all()
            .flat_map(|m| std::iter::once(m.key()).chain(m.info().aliases.iter().copied()))
            .collect();
        let n = keys.len();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), n, "a key or alias names two methods");
        for m in MethodId::all() {
            assert_eq!(m.info().id, m);
            assert_eq!(m.key().parse::<MethodId>().unwrap(), m);
            let json = serde_json::to_string(&m).unwrap();
            assert_eq!(serde_json::from_str::<MethodId>(&json).unwrap(), m);
        }
        assert_eq!(
            MethodId::all().count(),
            CATALOGUE.len() + ClassifierId::ALL.len()
        );
        let e = "svm".parse::<MethodId>().unwrap_err().to_string();
        assert!(
            e.contains("`svm`") && e.contains("sparse-svm, raw-svm"),
            "{e}"
        );
    }

    #[test]
    fn older_names_still_read() {
        // The names model files and results were saved with before the registry.
        let saved = [
            ("sparse_svm", MethodId::SparseSvm),
            ("raw_svm", MethodId::RawSvm),
            ("ds", MethodId::Ds),
            ("kmeans", MethodId::KMeans),
            ("rbf_svm", MethodId::RbfSvm),
        ];
        for (name, id) in saved {
            assert_eq!(serde_json::to_string(&id).unwrap(), format!("\"{name}\""));
            assert_eq!(
                serde_json::from_str::<MethodId>(&format!("\"{name}\"")).unwrap(),
                id
            );
        }
        assert_eq!(
            serde_json::from_str::<MethodId>("\"k_means\"").unwrap(),
            MethodId::KMeans
        );
        assert_eq!("linear-svm".parse::<MethodId>().unwrap(), MethodId::RawSvm);
    }
}
