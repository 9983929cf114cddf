#!/usr/bin/env bash
# Mutation testing (cargo-mutants) of the modules whose numbers users trust. Not in CI: it
# rebuilds the crate once per mutant. Rerun a scope when its module changes, and record the
# counts (caught / missed / unviable) in docs/testing.md.
#
#   cargo install cargo-mutants
#   scripts/mutants.sh                 # every scope
#   scripts/mutants.sh scores svm-eval # some
#
# Each scope mutates one module (--file) and runs only the tests that guard it (the
# arguments after -- go to cargo test). Mutants are built in place (the checkout's own
# target/ and ../shared/datasets are used), so leave the checkout alone while it runs:
# cargo-mutants restores every file when a mutant is done or the run is interrupted.
# Results: target/mutants/<scope>/mutants.out/{caught,missed,unviable,timeout}.txt
set -euo pipefail
cd "$(dirname "$0")/.."

run() {
    local scope=$1
    shift
    mkdir -p "target/mutants/$scope"
    nice -n 10 cargo mutants --no-default-features --in-place --timeout 600 \
        --output "target/mutants/$scope" "$@" || true
    for outcome in caught missed unviable timeout; do
        local f="target/mutants/$scope/mutants.out/$outcome.txt"
        printf '%s %s: %s\n' "$scope" "$outcome" "$( [ -f "$f" ] && wc -l <"$f" || echo 0)"
    done
}

scope() {
    case $1 in
    scores) run scores --file src/cluster/scores.rs -- --lib cluster::scores ;;
    scores-pairs-entropy)
        # The part of `scores` whose counts docs/testing.md records.
        run scores-pairs-entropy --file src/cluster/scores.rs --re 'entropy|pairs' -- --lib cluster::scores ;;
    svm-eval) run svm-eval --file src/svm/eval.rs -- --test svm_eval ;;
    stability-selection)
        # The grid's selection and parsimony rule.
        run stability-selection --file src/experiments/stability.rs \
            --re 'choose' -- --test stability_pipeline parsimony ;;
    sparse)
        run sparse --file 'src/sparse/*.rs' \
            -- --lib --test sparse_dictionary --test sparse_feature_sign sparse ;;
    learners)
        run learners --file 'src/learners/*.rs' \
            -- --test learners_supervised --test learners_unsupervised ;;
    *)
        echo "unknown scope $1" >&2
        exit 2
        ;;
    esac
}

if [ $# -eq 0 ]; then
    set -- scores svm-eval stability-selection sparse learners
fi
for s in "$@"; do
    scope "$s"
done
