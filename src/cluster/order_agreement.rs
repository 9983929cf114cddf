//! A novelty threshold chosen without labels: the agreement of an online learner's
//! clusterings across random orders of the same grasps (the second paper leaves the choice
//! open, Sec. VII: "automatically selecting this threshold makes for interesting future
//! work").
//!
//! An online clusterer sees the grasps once, in one order, so where it draws its boundaries
//! depends on the order. At a threshold that finds groups the data really has, every order
//! finds the same groups; too low a threshold splits the groups, and where it splits them
//! depends on which grasps came first; too high a threshold merges groups, and which ones
//! merge depends on the order as well. This is clustering stability (Ben-Hur, Elisseeff &
//! Guyon 2002; Lange, Roth, Braun & Buhmann 2004), with the random orders as the
//! perturbation. Agreement is the mean adjusted Rand index over every pair of orders: the
//! ARI is corrected for chance, so partitions into many small clusters do not agree by
//! chance as they do under the NMI. A threshold at which most orders end with a single
//! cluster agrees trivially and found no structure, so it cannot be chosen.
//!
//! Only the clusterings enter: no labels, no scores against labels.

/// The score that names the threshold chosen without labels in a clustering result.
pub const CHOSEN_THRESHOLD: &str = "threshold chosen without labels";

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::scores::adjusted_rand_index;

/// How a novelty threshold is chosen without labels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThresholdCriterion {
    /// The threshold whose clusterings agree most across random orders (mean pairwise ARI).
    #[default]
    OrderAgreement,
}

impl ThresholdCriterion {
    pub fn text(self) -> &'static str {
        match self {
            ThresholdCriterion::OrderAgreement => "agreement across orders",
        }
    }
}

/// A threshold criterion's name that names none.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{0}` is not stability (order-agreement)")]
pub struct UnknownCriterion(pub String);

impl FromStr for ThresholdCriterion {
    type Err = UnknownCriterion;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "stability" | "order-agreement" => Ok(ThresholdCriterion::OrderAgreement),
            other => Err(UnknownCriterion(other.into())),
        }
    }
}

/// The agreement of the clusterings at one threshold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThresholdAgreement {
    pub threshold: f64,
    /// Mean ARI over the pairs of orders.
    pub agreement: f64,
    /// Standard deviation of the pairwise ARIs.
    pub sd: f64,
    /// Orders whose clustering has at least two clusters.
    pub clustered: usize,
    pub orders: usize,
}

impl ThresholdAgreement {
    /// Whether the threshold found structure: at least half the orders found two clusters
    /// or more.
    pub fn eligible(&self) -> bool {
        self.orders >= 2 && 2 * self.clustered >= self.orders
    }
}

/// The label-free choice and the curve it was made on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThresholdChoice {
    pub criterion: ThresholdCriterion,
    pub threshold: f64,
    pub agreement: f64,
    /// Every threshold's agreement, in ascending threshold order.
    pub curve: Vec<ThresholdAgreement>,
}

fn clusters(c: &[usize]) -> usize {
    let mut v = c.to_vec();
    v.sort_unstable();
    v.dedup();
    v.len()
}

/// The agreement of `clusterings` (each a cluster id per grasp, grasps in the same order):
/// mean and standard deviation of the ARI over all pairs.
pub fn agreement(threshold: f64, clusterings: &[&[usize]]) -> ThresholdAgreement {
    let mut aris = Vec::new();
    for (i, a) in clusterings.iter().enumerate() {
        for b in &clusterings[i + 1..] {
            aris.push(adjusted_rand_index(a, b));
        }
    }
    let n = aris.len().max(1) as f64;
    let mean = aris.iter().sum::<f64>() / n;
    let var = aris.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    ThresholdAgreement {
        threshold,
        agreement: mean,
        sd: var.sqrt(),
        clustered: clusterings.iter().filter(|c| clusters(c) >= 2).count(),
        orders: clusterings.len(),
    }
}

/// The threshold whose clusterings agree most across orders, among those that found
/// structure (ties to the lower threshold); None if none did.
/// `per_threshold`: each threshold with its orders' clusterings.
pub fn choose_threshold(
    criterion: ThresholdCriterion,
    per_threshold: &[(f64, Vec<&[usize]>)],
) -> Option<ThresholdChoice> {
    let mut curve: Vec<ThresholdAgreement> = per_threshold
        .iter()
        .map(|(t, c)| agreement(*t, c))
        .collect();
    curve.sort_by(|a, b| a.threshold.total_cmp(&b.threshold));
    let best =
        curve
            .iter()
            .filter(|a| a.eligible())
            .fold(None::<&ThresholdAgreement>, |best, a| match best {
                Some(b) if b.agreement >= a.agreement => Some(b),
                _ => Some(a),
            })?;
    Some(ThresholdChoice {
        criterion,
        threshold: best.threshold,
        agreement: best.agreement,
        curve: curve.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// 4 groups of 10 items, item i in group i / 10.
    const GROUPS: usize = 4;
    const SIZE: usize = 10;

    fn group(i: usize) -> usize {
        i / SIZE
    }

    /// What an order-dependent clusterer might leave at three kinds of threshold, each order
    /// drawn with its own stream: the groups themselves (cluster ids permuted), every group
    /// split at a random point, or random pairs of groups merged.
    fn orders(kind: &str, n: usize) -> Vec<Vec<usize>> {
        (0..n)
            .map(|o| {
                let mut rng = Rng::stream(9, o as u64);
                let ids = rng.permutation(2 * GROUPS);
                let cut: Vec<usize> = (0..GROUPS).map(|_| 1 + rng.below(SIZE - 1)).collect();
                let merge = rng.permutation(GROUPS);
                (0..GROUPS * SIZE)
                    .map(|i| match kind {
                        "groups" => ids[group(i)],
                        "split" => 2 * group(i) + usize::from(i % SIZE >= cut[group(i)]),
                        "merged" => merge[group(i)] / 2,
                        _ => 0,
                    })
                    .collect()
            })
            .collect()
    }

    fn views(c: &[Vec<usize>]) -> Vec<&[usize]> {
        c.iter().map(Vec::as_slice).collect()
    }

    #[test]
    fn identical_partitions_agree_fully_and_independent_ones_near_zero() {
        let same = orders("groups", 5);
        let a = agreement(0.1, &views(&same));
        assert!((a.agreement - 1.0).abs() < 1e-12 && a.sd < 1e-12, "{a:?}");
        let random: Vec<Vec<usize>> = (0..6)
            .map(|o| {
                let mut rng = Rng::stream(3, o);
                (0..200).map(|_| rng.below(8)).collect()
            })
            .collect();
        let r = agreement(0.1, &views(&random));
        assert!(r.agreement.abs() < 0.05, "{r:?}");
        assert_eq!((r.orders, r.clustered), (6, 6));
    }

    /// The threshold whose orders find the groups beats those that split or merge them at
    /// random, and one cluster in every order (perfect, trivial agreement) is never chosen.
    #[test]
    fn the_choice_is_the_threshold_that_finds_the_groups_whatever_the_order() {
        let (split, groups, merged, one) = (
            orders("split", 8),
            orders("groups", 8),
            orders("merged", 8),
            orders("one", 8),
        );
        let per_threshold = vec![
            (0.7, views(&one)),
            (0.1, views(&split)),
            (0.5, views(&merged)),
            (0.3, views(&groups)),
        ];
        let c = choose_threshold(ThresholdCriterion::OrderAgreement, &per_threshold).unwrap();
        assert_eq!(c.threshold, 0.3);
        let t: Vec<f64> = c.curve.iter().map(|a| a.threshold).collect();
        assert_eq!(t, [0.1, 0.3, 0.5, 0.7]);
        assert!(!c.curve[3].eligible() && c.curve[3].agreement == 1.0);
        assert!(c.curve[0].agreement < 0.9 && c.curve[2].agreement < 0.9);
        let nothing = vec![(0.7, views(&one))];
        assert!(choose_threshold(ThresholdCriterion::OrderAgreement, &nothing).is_none());
    }

    #[test]
    fn the_criterion_parses_its_names() {
        for name in ["stability", "order-agreement"] {
            assert_eq!(
                name.parse::<ThresholdCriterion>(),
                Ok(ThresholdCriterion::OrderAgreement)
            );
        }
        assert!("labels".parse::<ThresholdCriterion>().is_err());
    }
}
