#!/usr/bin/env bash
# Mutation testing (cargo-mutants) of the modules whose numbers users trust. Not in CI: it
# rebuilds the crate once per mutant. Rerun a scope when its module changes, and record the
# counts (caught / missed / unviable / timeouts) in docs/testing.md.
#
#   cargo install cargo-mutants
#   scripts/mutants.sh                 # every scope
#   scripts/mutants.sh scores svm-eval # some
#   scripts/mutants.sh --list learners # only count a scope's mutants
#   scripts/mutants.sh --iterate scores # re-test only the mutants its last run missed
#
# Each scope mutates one module (--file, narrowed to functions where noted) and builds and
# runs only the test targets that guard it: the targets go to every cargo call (-C), so
# the build of a mutant links those alone instead of every test binary, and the test
# names after -- filter what runs. Mutants are built in place (the checkout's own target/
# and ../shared/datasets are used), so leave the checkout alone while it runs:
# cargo-mutants restores every file when a mutant is done or the run is interrupted.
#
# The crate (not its dependencies, which keep their own opt-level 3) is built at
# opt-level 1 without debug info: an incremental rebuild of a mutant takes about half the
# time of the dev profile's opt-level 2, and the dependencies are reused (a profile of its
# own would rebuild them all in a directory of its own). Other cargo commands in this
# checkout rebuild the crate at the dev settings afterwards.
#
# Results: target/mutants/<scope>/mutants.out/{caught,missed,unviable,timeout}.txt
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_PROFILE_DEV_OPT_LEVEL=1 CARGO_PROFILE_DEV_DEBUG=false

list=
iterate=()
case ${1:-} in
--list)
    list=--list
    shift
    ;;
--iterate)
    # Re-test only what the scope's last run did not catch (after adding tests).
    iterate=(--iterate)
    shift
    ;;
esac

run() {
    local scope=$1
    shift
    if [ -n "$list" ]; then
        printf '%s: %s mutants\n' "$scope" "$(cargo mutants --list --no-default-features "$@" | wc -l)"
        return
    fi
    mkdir -p "target/mutants/$scope"
    nice -n 10 cargo mutants --no-default-features --in-place --minimum-test-timeout 120 \
        "${iterate[@]}" --output "target/mutants/$scope" "$@" || true
    for outcome in caught missed unviable timeout; do
        local f="target/mutants/$scope/mutants.out/$outcome.txt"
        printf '%s %s: %s\n' "$scope" "$outcome" "$( [ -f "$f" ] && wc -l <"$f" || echo 0)"
    done
}

# A diff that adds the lines of function $2 in file $1, for --in-diff: it keeps a scope
# to that function (--re does not filter the "delete field" mutants, which name no function).
function_diff() {
    local file=$1 name=$2 start end
    start=$(grep -n "^pub fn $name\b\|^fn $name\b" "$file" | cut -d: -f1)
    end=$(awk -v s="$start" 'NR > s && /^}/ { print NR; exit }' "$file")
    local out="target/mutants/$name.diff"
    mkdir -p target/mutants
    {
        printf -- '--- a/%s\n+++ b/%s\n@@ -%d,0 +%d,%d @@\n' "$file" "$file" \
            $((start - 1)) "$start" $((end - start + 1))
        sed -n "${start},${end}p" "$file" | sed 's/^/+/'
    } >"$out"
    echo "$out"
}

# The test functions of integration-test files: with a module path (e.g. `sparse::`) they
# are the filters of a scope that runs the library's unit tests too, since one filter
# applies to every test binary and an integration test's name has no module path.
tests_in() {
    grep -h -A1 '#\[test\]' "$@" | grep -o 'fn [a-z0-9_]*' | cut -c4-
}

sparse_tests=(-C --lib -C --test=sparse_dictionary -C --test=sparse_feature_sign
    -- -- sparse:: $(tests_in tests/sparse_*.rs))

scope() {
    case $1 in
    scores) run scores --file src/cluster/scores.rs -C --lib -- cluster::scores ;;
    scores-indices)
        # The indices and their contingency table: the file but for `pairs` and `entropy`.
        run scores-indices --file src/cluster/scores.rs --exclude-re '(replace|in) (pairs|entropy)\b' \
            -C --lib -- cluster::scores ;;
    svm-eval) run svm-eval --file src/svm/eval.rs -C --test=svm_eval ;;
    svm-eval-confusion)
        # The confusion counts and their rates (eq. 4), the folds' index lists and `gather`:
        # the file but for the folds' construction, `cross_validate` and `mean_se`.
        run svm-eval-confusion --file src/svm/eval.rs --re 'Confusion::|Folds::|gather' \
            -C --test=svm_eval ;;
    stability-selection)
        # The grid's selection and parsimony rule.
        run stability-selection --file src/experiments/stability.rs \
            --in-diff "$(function_diff src/experiments/stability.rs choose)" \
            -C --test=stability_pipeline -- parsimony ;;
    learners-novelty)
        # The part of `learners` that assigns grasps to objects: DU's novelty (eq. 28)
        # and learning step, GU's step and joint novelty and its winner.
        run learners-novelty --file src/learners/du.rs --file src/learners/gu.rs \
            --re 'du_novelty|Du::learn|Gu::step_novelty|Gu::joint_novelty|Gu::winner_among' \
            -C --lib -C --test=learners_unsupervised \
            -- -- learners:: $(tests_in tests/learners_unsupervised.rs) ;;
    learners-du-gu-rest)
        # The rest of DU's and GU's assignment: the parameters' validation, DU's and GU's
        # final re-assignment, GU's learning step and its grasp counts (`--re 'Gu::learn'`
        # also takes in the accessor `Gu::learner`). Disjoint from learners-novelty.
        run learners-du-gu-rest --file src/learners/du.rs --file src/learners/gu.rs \
            --re 'DuParams::validate|Du::assign|confirmed_decision|GuParams::validate|Gu::learn|Gu::assign|Gu::winner |Gu::grasps_drawn|Gu::trained' \
            -C --lib -C --test=learners_unsupervised \
            -- -- learners:: $(tests_in tests/learners_unsupervised.rs) ;;
    learners)
        run learners --file 'src/learners/*.rs' \
            -C --lib -C --test=learners_supervised -C --test=learners_unsupervised \
            -- -- learners:: $(tests_in tests/learners_*.rs) ;;
    learners-ds | learners-gs | learners-mod | learners-evt)
        # One file of `learners` each (ds.rs, gs.rs, mod.rs, evt.rs), with the `learners`
        # scope's tests: DU and GU are built on DS and GS and use mod.rs and evt.rs.
        run "$1" --file "src/learners/${1#learners-}.rs" \
            -C --lib -C --test=learners_supervised -C --test=learners_unsupervised \
            -- -- learners:: $(tests_in tests/learners_*.rs) ;;
    learners-du-gu-other)
        # The rest of du.rs and gu.rs: what learners-novelty and learners-du-gu-rest leave
        # out (their --re, excluded here), so the three scopes cover the two files once.
        run learners-du-gu-other --file src/learners/du.rs --file src/learners/gu.rs \
            --exclude-re 'du_novelty|Du::learn|Gu::step_novelty|Gu::joint_novelty|Gu::winner_among' \
            --exclude-re 'DuParams::validate|Du::assign|confirmed_decision|GuParams::validate|Gu::learn|Gu::assign|Gu::winner |Gu::grasps_drawn|Gu::trained' \
            -C --lib -C --test=learners_supervised -C --test=learners_unsupervised \
            -- -- learners:: $(tests_in tests/learners_*.rs) ;;
    sparse)
        run sparse --file 'src/sparse/*.rs' "${sparse_tests[@]}" ;;
    # One file of `sparse` each (together the `sparse` scope), with the tests that guard
    # it. Feature-sign search has its own test target: the dictionary tests use it too,
    # but a broken solver runs to its iteration cap on every patch there, 40–90 s a mutant.
    sparse-feature-sign)
        run "$1" --file src/sparse/feature_sign.rs -C --lib -C --test=sparse_feature_sign \
            -- -- sparse::feature_sign $(tests_in tests/sparse_feature_sign.rs) ;;
    sparse-dual) run "$1" --file src/sparse/dual.rs -C --test=sparse_dictionary ;;
    sparse-dictionary)
        # With the module's unit tests (the re-seeding of unused bases is tested there).
        run "$1" --file src/sparse/dictionary.rs -C --lib -C --test=sparse_dictionary \
            -- -- sparse::dictionary $(tests_in tests/sparse_dictionary.rs) ;;
    sparse-eps-l1) run "$1" --file src/sparse/eps_l1.rs -C --test=sparse_dictionary ;;
    sparse-init)
        run "$1" --file src/sparse/init.rs -C --lib -C --test=sparse_dictionary \
            -- -- sparse:: $(tests_in tests/sparse_dictionary.rs) ;;
    sparse-dense)
        # The kernels' own unit tests with the library's others: a mutant of `dot`, which
        # is inlined into every solver, rebuilds most of the crate, 47–70 s a build when
        # the integration tests are linked too.
        run "$1" --file src/sparse/dense.rs -C --lib -- -- sparse:: ;;
    sparse-mod) run "$1" --file src/sparse/mod.rs "${sparse_tests[@]}" ;;
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
