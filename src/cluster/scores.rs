//! External clustering scores against true labels (the second paper, Sec. V-D2): purity,
//! the adjusted Rand index (Hubert & Arabie 1985) and the normalised mutual information
//! (Strehl & Ghosh 2002).
//!
//! Labels are arbitrary `usize` ids: they need not be contiguous, and ids that no sample
//! carries play no part (only the contingency table of the ids that occur is used).
//!
//! Conventions, the same as scikit-learn's `adjusted_rand_score` and
//! `normalized_mutual_info_score` (so that its test vectors apply):
//! - NMI uses the arithmetic mean of the two entropies as the normaliser,
//!   NMI = I(T; P) / ((H(T) + H(P)) / 2), scikit-learn's default `average_method`
//!   (it equals the V-measure). Logarithms are natural, though NMI does not depend on the base.
//! - Empty input: every score is 1 (there is nothing to disagree on).
//! - Both labellings a single group (or both all singletons): ARI and NMI are 1.
//! - One labelling a single group and the other not: NMI is 0 (no information is shared).
//!
//! Every score is finite: ARI lies in [-1, 1], purity and NMI in [0, 1].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// The three scores of the paper's Table IV for one clustering.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusterScores {
    pub purity: f64,
    pub ari: f64,
    pub nmi: f64,
}

/// Purity, ARI and NMI of `pred` against `truth`.
///
/// # Panics
/// If the two slices differ in length (a caller's bug, not a data condition).
pub fn scores(truth: &[usize], pred: &[usize]) -> ClusterScores {
    let table = Contingency::new(truth, pred);
    ClusterScores {
        purity: table.purity(),
        ari: table.adjusted_rand_index(),
        nmi: table.normalized_mutual_info(),
    }
}

/// Share of samples that belong to the majority class of their cluster:
/// (1/n) Σ_clusters max_class n_class,cluster. 1 when every sample is its own cluster.
///
/// # Panics
/// If the two slices differ in length.
pub fn purity(truth: &[usize], pred: &[usize]) -> f64 {
    Contingency::new(truth, pred).purity()
}

/// Adjusted Rand index (Hubert & Arabie 1985): the Rand index corrected for chance,
/// 1 for identical partitions, about 0 for independent ones, negative below chance.
///
/// # Panics
/// If the two slices differ in length.
pub fn adjusted_rand_index(truth: &[usize], pred: &[usize]) -> f64 {
    Contingency::new(truth, pred).adjusted_rand_index()
}

/// Normalised mutual information with the arithmetic-mean normaliser (scikit-learn's default).
///
/// # Panics
/// If the two slices differ in length.
pub fn normalized_mutual_info(truth: &[usize], pred: &[usize]) -> f64 {
    Contingency::new(truth, pred).normalized_mutual_info()
}

/// Mutual information I(T; P) between the two labellings, in nats.
///
/// # Panics
/// If the two slices differ in length.
pub fn mutual_info(truth: &[usize], pred: &[usize]) -> f64 {
    Contingency::new(truth, pred).mutual_info()
}

/// The contingency table of the ids that occur. Ordered maps keep every floating-point
/// sum in the same order from run to run.
struct Contingency {
    n: usize,
    cells: BTreeMap<(usize, usize), usize>,
    class_sizes: BTreeMap<usize, usize>,
    cluster_sizes: BTreeMap<usize, usize>,
}

/// Number of unordered pairs among `k` items, exact.
fn pairs(k: usize) -> u128 {
    let k = k as u128;
    k * k.saturating_sub(1) / 2
}

/// −Σ p ln p over the group sizes.
fn entropy(sizes: &BTreeMap<usize, usize>, n: usize) -> f64 {
    let n = n as f64;
    sizes
        .values()
        .map(|&s| {
            let p = s as f64 / n;
            -p * p.ln()
        })
        .sum()
}

impl Contingency {
    fn new(truth: &[usize], pred: &[usize]) -> Self {
        assert_eq!(
            truth.len(),
            pred.len(),
            "truth and pred must label the same samples"
        );
        let mut cells = BTreeMap::new();
        let mut class_sizes = BTreeMap::new();
        let mut cluster_sizes = BTreeMap::new();
        for (&t, &p) in truth.iter().zip(pred) {
            *cells.entry((t, p)).or_insert(0) += 1;
            *class_sizes.entry(t).or_insert(0) += 1;
            *cluster_sizes.entry(p).or_insert(0) += 1;
        }
        Contingency {
            n: truth.len(),
            cells,
            class_sizes,
            cluster_sizes,
        }
    }

    fn purity(&self) -> f64 {
        if self.n == 0 {
            return 1.0;
        }
        let mut majority: BTreeMap<usize, usize> = BTreeMap::new();
        for (&(_, cluster), &count) in &self.cells {
            let best = majority.entry(cluster).or_insert(0);
            *best = (*best).max(count);
        }
        majority.values().sum::<usize>() as f64 / self.n as f64
    }

    fn adjusted_rand_index(&self) -> f64 {
        // With index = Σ C(n_ij, 2), a = Σ C(a_i, 2), b = Σ C(b_j, 2), N = C(n, 2):
        // ARI = (index − ab/N) / ((a + b)/2 − ab/N) = 2 (N index − ab) / (N (a + b) − 2ab),
        // evaluated in exact integers so that the degenerate cases are recognised exactly.
        let index: u128 = self.cells.values().map(|&c| pairs(c)).sum();
        let a: u128 = self.class_sizes.values().map(|&c| pairs(c)).sum();
        let b: u128 = self.cluster_sizes.values().map(|&c| pairs(c)).sum();
        let total = pairs(self.n);
        let numerator = 2 * (total * index) as i128 - 2 * (a * b) as i128;
        let denominator = (total * (a + b)) as i128 - 2 * (a * b) as i128;
        // The denominator is 0 only when a = b ∈ {0, N}: both labellings are one group or
        // both are all singletons (or n < 2), i.e. they agree perfectly.
        if denominator == 0 {
            return 1.0;
        }
        (numerator as f64 / denominator as f64).clamp(-1.0, 1.0)
    }

    fn mutual_info(&self) -> f64 {
        if self.n == 0 {
            return 0.0;
        }
        let n = self.n as f64;
        let mi: f64 = self
            .cells
            .iter()
            .map(|(&(t, p), &c)| {
                let c = c as f64;
                let ab = (self.class_sizes[&t] * self.cluster_sizes[&p]) as f64;
                (c / n) * (n * c / ab).ln()
            })
            .sum();
        // Rounding can leave −1e-17 where the true value is 0.
        mi.max(0.0)
    }

    fn normalized_mutual_info(&self) -> f64 {
        let (k_true, k_pred) = (self.class_sizes.len(), self.cluster_sizes.len());
        // Both labellings with zero entropy (empty input, or one group each): a perfect match.
        if k_true <= 1 && k_pred <= 1 {
            return 1.0;
        }
        let mi = self.mutual_info();
        let normaliser =
            0.5 * (entropy(&self.class_sizes, self.n) + entropy(&self.cluster_sizes, self.n));
        if mi <= 0.0 || normaliser <= 0.0 {
            return 0.0;
        }
        (mi / normaliser).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    /// scikit-learn `test_perfect_matches`: every score is 1.
    #[test]
    fn perfect_matches_score_one() {
        let cases: [(&[usize], &[usize]); 5] = [
            (&[], &[]),
            (&[0], &[1]),
            (&[0, 0, 0], &[0, 0, 0]),
            (&[0, 1, 0], &[42, 7, 42]),
            (&[0, 1, 2], &[42, 7, 2]),
        ];
        for (t, p) in cases {
            let s = scores(t, p);
            assert_eq!(
                s,
                ClusterScores {
                    purity: 1.0,
                    ari: 1.0,
                    nmi: 1.0
                },
                "{t:?} vs {p:?}"
            );
        }
    }

    /// scikit-learn `test_non_consecutive_labels` (0.24 to 2 places); exactly 8/33 by hand:
    /// index 2, a = 6, b = 3, N = 15, expected 1.2, max 4.5.
    #[test]
    fn ari_with_gaps_in_the_ids() {
        let truth = [0, 0, 0, 1, 1, 1];
        let a = adjusted_rand_index(&truth, &[0, 1, 0, 1, 2, 2]);
        let b = adjusted_rand_index(&truth, &[0, 4, 0, 4, 2, 2]);
        assert!(close(a, 8.0 / 33.0, 1e-15), "{a}");
        assert_eq!(a, b);
        let c = adjusted_rand_index(&[0, 0, 0, 2, 2, 2], &[0, 1, 0, 1, 2, 2]);
        assert_eq!(a, c);
    }

    /// The examples of scikit-learn's `adjusted_rand_score` documentation, checked by hand.
    #[test]
    fn ari_documented_examples() {
        // index 1, a = 1, b = 2, N = 6: (1 − 1/3) / (3/2 − 1/3) = 4/7
        assert!(close(
            adjusted_rand_index(&[0, 0, 1, 2], &[0, 0, 1, 1]),
            4.0 / 7.0,
            1e-15
        ));
        assert!(close(
            adjusted_rand_index(&[0, 0, 1, 1], &[0, 0, 1, 2]),
            4.0 / 7.0,
            1e-15
        ));
        // One group against all singletons: 0.
        assert_eq!(adjusted_rand_index(&[0, 0, 0, 0], &[0, 1, 2, 3]), 0.0);
        // Below chance: −0.5 and −4/31 (= −0.12903225806451613).
        assert!(close(
            adjusted_rand_index(&[0, 0, 1, 1], &[0, 1, 0, 1]),
            -0.5,
            1e-15
        ));
        assert!(close(
            adjusted_rand_index(&[0, 1, 2, 0, 3, 4, 5, 1], &[1, 1, 0, 0, 2, 2, 2, 2]),
            -0.12903225806451613,
            1e-15
        ));
    }

    /// scikit-learn `test_adjustment_for_chance`: independent uniform labellings of 100
    /// samples into 2, 10, 50, 90 groups score within a few hundredths of 0.
    #[test]
    fn ari_is_near_zero_by_chance() {
        let mut rng = Rng::new(42);
        for k in [2, 10, 50, 90] {
            for _ in 0..10 {
                let a: Vec<usize> = (0..100).map(|_| rng.below(k)).collect();
                let b: Vec<usize> = (0..100).map(|_| rng.below(k)).collect();
                let ari = adjusted_rand_index(&a, &b);
                assert!(ari.abs() < 0.06, "k {k}: {ari}");
            }
        }
    }

    /// scikit-learn's homogeneity/completeness tests give the V-measure, which equals the
    /// arithmetic NMI: 0.81, 0.73, 0.52 to 2 places; the full values from mpmath.
    #[test]
    fn nmi_known_values() {
        let cases: [(&[usize], &[usize], f64); 5] = [
            (&[0, 0, 0, 1, 1, 1], &[0, 0, 0, 1, 2, 2], 0.8132898335036762),
            (&[0, 0, 1, 1, 2, 2], &[0, 0, 1, 1, 1, 1], 0.733680436651211),
            (&[0, 0, 0, 1, 1, 1], &[0, 1, 0, 1, 2, 2], 0.5158037429793888),
            (&[0, 0, 0, 2, 2, 2], &[0, 1, 0, 1, 2, 2], 0.5158037429793888),
            (&[0, 0, 0, 1, 1, 1], &[0, 4, 0, 4, 2, 2], 0.5158037429793888),
        ];
        for (t, p, want) in cases {
            let got = normalized_mutual_info(t, p);
            assert!(close(got, want, 1e-14), "{t:?} vs {p:?}: {got}");
            assert!(close(normalized_mutual_info(p, t), want, 1e-14));
        }
    }

    /// scikit-learn `test_adjusted_mutual_info_score`: MI = 0.41022 nats; NMI from mpmath.
    #[test]
    fn mutual_info_known_value() {
        let a = [1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3];
        let b = [1, 1, 1, 1, 2, 1, 2, 2, 2, 2, 3, 1, 3, 3, 3, 2, 2];
        assert!(close(mutual_info(&a, &b), 0.4102186227404535, 1e-14));
        assert!(close(
            normalized_mutual_info(&a, &b),
            0.3783499278720409,
            1e-14
        ));
    }

    /// I(T; T) = H(T); nothing to share on empty input or with a single group.
    #[test]
    fn mutual_info_of_a_labelling_with_itself_is_its_entropy() {
        assert_eq!(mutual_info(&[], &[]), 0.0);
        assert_eq!(mutual_info(&[3, 3, 3], &[0, 1, 2]), 0.0);
        assert!(close(
            mutual_info(&[0, 0, 1, 1], &[5, 5, 9, 9]),
            2f64.ln(),
            1e-15
        ));
        // Sizes 1, 1, 2 of 4: H = 2 (1/4) ln 4 + (1/2) ln 2 = 1.5 ln 2.
        assert!(close(
            mutual_info(&[0, 1, 2, 2], &[0, 1, 2, 2]),
            1.5 * 2f64.ln(),
            1e-15
        ));
    }

    /// scikit-learn `test_exactly_zero_info_score`: one class against all singletons.
    #[test]
    fn nmi_is_exactly_zero_without_shared_information() {
        for n in [10, 100, 1000, 10000] {
            let ones = vec![1; n];
            let singletons: Vec<usize> = (0..n).collect();
            assert_eq!(normalized_mutual_info(&ones, &singletons), 0.0);
            assert_eq!(normalized_mutual_info(&singletons, &ones), 0.0);
        }
    }

    #[test]
    fn purity_by_hand() {
        // clusters {0,0}, {0,1}, {1,1}: majorities 2 + 1 + 2 of 6
        assert!(close(
            purity(&[0, 0, 0, 1, 1, 1], &[0, 1, 0, 1, 2, 2]),
            5.0 / 6.0,
            1e-15
        ));
        // one cluster: the largest class share
        assert!(close(purity(&[3, 3, 3, 7, 9], &[5; 5]), 0.6, 1e-15));
        // all singletons: 1, even though the clustering is useless
        assert_eq!(purity(&[0, 0, 1, 1], &[0, 1, 2, 3]), 1.0);
        // purity is not symmetric
        assert_eq!(purity(&[0, 1, 2, 3], &[0, 0, 1, 1]), 0.5);
    }

    /// One cluster, all singletons, empty input: defined values, never NaN.
    #[test]
    fn degenerate_partitions_are_finite_and_defined() {
        let truth = [0, 0, 1, 1, 2, 2];
        let one = [9; 6];
        let singles = [10, 20, 30, 40, 50, 60];
        let s = scores(&truth, &one);
        assert!(close(s.purity, 1.0 / 3.0, 1e-15));
        assert_eq!(s.ari, 0.0);
        assert_eq!(s.nmi, 0.0);
        let s = scores(&truth, &singles);
        assert_eq!(s.purity, 1.0);
        assert_eq!(s.ari, 0.0);
        // NMI = ln 3 / ((ln 3 + ln 6) / 2)
        let want = 3f64.ln() / (0.5 * (3f64.ln() + 6f64.ln()));
        assert!(close(s.nmi, want, 1e-15));
        assert_eq!(scores(&[], &[]).nmi, 1.0);
        assert_eq!(scores(&one, &singles).ari, 0.0);
        assert_eq!(scores(&singles, &singles).ari, 1.0);
        assert_eq!(scores(&singles, &singles).nmi, 1.0);
    }

    #[test]
    fn scores_do_not_depend_on_the_names_of_ids() {
        let mut rng = Rng::new(5);
        let truth: Vec<usize> = (0..60).map(|_| rng.below(4)).collect();
        let pred: Vec<usize> = (0..60).map(|_| rng.below(6)).collect();
        let renamed: Vec<usize> = pred.iter().map(|&p| 1000 - 7 * p).collect();
        let a = scores(&truth, &pred);
        let b = scores(&truth, &renamed);
        assert!(close(a.purity, b.purity, 1e-15));
        assert!(close(a.ari, b.ari, 1e-15));
        assert!(close(a.nmi, b.nmi, 1e-15));
        assert!(close(a.ari, adjusted_rand_index(&pred, &truth), 1e-15));
    }
}
