#!/usr/bin/env bash
# Time `import mcap` and report its peak memory (GNU time at /usr/bin/time).
#
#   scripts/bench-import.sh           a 10-minute bag at 100 Hz with three 24-taxel sensors,
#                                     joint states and grasp events (the target: under 2 s
#                                     in release)
#   scripts/bench-import.sh camera    100 s of two 100 Hz tactile topics beside a 640 × 480
#                                     camera at 30 Hz, uncompressed (2.8 GB) and zstd, and the
#                                     same without the camera (the target: peak memory under
#                                     100 MB, time about that of reading the file once)
#
# Needs Python with `pip install rosbags mcap mcap-ros2-support` to write the bags, into a
# temporary folder under $TMPDIR (about 5.5 GB for `camera`), removed afterwards.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cargo build --release --no-default-features
measure() { # bag spec
    /usr/bin/time -v target/release/tactile-workbench import mcap "$1" \
        -o "$dir/session.json" --spec "$2" > "$dir/out.txt" 2> "$dir/time.txt"
    echo "$(basename "$1"): $(du -sh "$1" | cut -f1), \
$(grep -E 'Elapsed \(wall' "$dir/time.txt" | sed 's/.*: //') wall, \
$(grep -E 'User time' "$dir/time.txt" | sed 's/.*: //') s user, \
$(grep -E 'System time' "$dir/time.txt" | sed 's/.*: //') s sys, \
$(grep -E 'Maximum resident' "$dir/time.txt" | sed 's/.*: //') KiB peak"
}
if [ "${1:-}" = camera ]; then
    python3 tests/fixtures/make_fixtures.py --bench-camera "$dir"
    for bag in camera-plain camera-zstd tactile-only; do
        # Reading the file once (from the page cache after the first read), to compare.
        cat "$dir/$bag"/*.mcap > /dev/null
        start=$(date +%s.%N); cat "$dir/$bag"/*.mcap > /dev/null; end=$(date +%s.%N)
        echo "$bag: reading the file once takes $(echo "$end - $start" | bc) s"
        for run in 1 2 3; do measure "$dir/$bag" "$dir/camera.spec.json"; done
    done
else
    python3 tests/fixtures/make_fixtures.py --bench "$dir"
    for run in 1 2 3; do measure "$dir/bench" "$dir/bench.spec.json"; done
fi
cat "$dir/out.txt"
ls -l "$dir/session.json"
