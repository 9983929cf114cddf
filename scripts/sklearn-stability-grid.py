"""scikit-learn's version of the 108-cell grid that `bench-stability` times, for the ratio
by CPU measured in one window (docs/grasp-stability.md).

The same work as ours: each of the 72 electrodes z-scored over all grasps and split into
3 patches of 24; for K = 5, 10, ..., 60 and lambda in {0.5, 1, 2} a batch dictionary
(0.5 ||x - a D||^2 + lambda ||a||_1, unit-norm atoms, SVD start, at most 100 iterations,
relative tolerance 1e-5: our defaults); for gamma in {0.5, 1, 2} every patch coded with
the lasso at gamma; a grasp's features are its three codes; a linear SVM (squared hinge,
C = 1, balanced classes, standardised features) scored by stratified 10-fold cross
validation with the weighted success rate (the mean of the two classes' recalls).
Coordinate descent for learning and coding (scikit-learn's faster choice here).

Run with one BLAS thread so that CPU time is work, not waiting (an optional last argument
caps the learning iterations: 40 gives as many in all as ours take):
    python -m venv /tmp/skv && /tmp/skv/bin/pip install scikit-learn
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 /tmp/skv/bin/python \
        scripts/sklearn-stability-grid.py ../shared/datasets/bts3/biotac-palmdown-grasps.csv [40]
"""

import csv
import resource
import sys
import time
import warnings

import numpy as np
from sklearn.decomposition import DictionaryLearning, sparse_encode
from sklearn.exceptions import ConvergenceWarning
from sklearn.model_selection import StratifiedKFold, cross_val_predict
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import LinearSVC


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    electrodes = [i for i, h in enumerate(header) if "biotac_" in h]
    slipped = header.index("slipped")
    x = np.array([[float(r[i]) for i in electrodes] for r in body])
    y = np.array([r[slipped].strip().lower() in ("1", "true", "yes") for r in body])
    return x, y


def main(path, max_iter):
    warnings.simplefilter("ignore", ConvergenceWarning)
    x, y = load(path)
    z = (x - x.mean(axis=0)) / x.std(axis=0)
    grasps = z.shape[0]
    patches = z.reshape(grasps * 3, 24)
    folds = StratifiedKFold(n_splits=10, shuffle=True, random_state=0)
    svm = make_pipeline(
        StandardScaler(),
        LinearSVC(C=1.0, loss="squared_hinge", class_weight="balanced", dual=False),
    )
    t0, c0 = time.perf_counter(), cpu()
    best = None
    for k in range(5, 61, 5):
        for lam in (0.5, 1.0, 2.0):
            dl = DictionaryLearning(
                n_components=k,
                alpha=lam,
                max_iter=max_iter,
                tol=1e-5,
                fit_algorithm="cd",
                random_state=0,
            ).fit(patches)
            print(
                f"K {k}, lambda {lam}: {dl.n_iter_} iterations, {cpu() - c0:.1f} s CPU so far",
                file=sys.stderr,
                flush=True,
            )
            for gam in (0.5, 1.0, 2.0):
                codes = sparse_encode(
                    patches, dl.components_, algorithm="lasso_cd", alpha=gam
                )
                features = codes.reshape(grasps, 3 * k)
                pred = cross_val_predict(svm, features, y, cv=folds)
                wsr = 0.5 * (np.mean(pred[y]) + np.mean(~pred[~y]))
                if best is None or wsr > best[0]:
                    best = (wsr, k, lam, gam)
    wall, cpu_secs = time.perf_counter() - t0, cpu() - c0
    print(
        f"108-cell grid (scikit-learn): {wall:.1f} s wall, {cpu_secs:.1f} s CPU; "
        f"best K {best[1]}, lambda {best[2]}, gamma {best[3]} at {100 * best[0]:.2f} %"
    )


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 100)
