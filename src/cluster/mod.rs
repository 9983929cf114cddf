//! Clustering baselines and clustering scores (the second paper, Sec. VII-A, Table IV):
//! external scores against true labels (purity, ARI, NMI).

pub mod scores;

pub use scores::{
    ClusterScores, adjusted_rand_index, mutual_info, normalized_mutual_info, purity, scores,
};
