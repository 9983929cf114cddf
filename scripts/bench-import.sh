#!/usr/bin/env bash
# Time `import mcap` on a 10-minute ROS 2 bag at 100 Hz with three 24-taxel sensors, joint
# states and grasp events (the target: under 2 s in release), and report its peak memory.
# Needs Python with `pip install rosbags mcap mcap-ros2-support` to write the bag (into a
# temporary folder, removed afterwards) and GNU time at /usr/bin/time.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 tests/fixtures/make_fixtures.py --bench "$dir"
du -sh "$dir/bench"
cargo build --release --no-default-features
for run in 1 2 3; do
    /usr/bin/time -v target/release/tactile-workbench import mcap "$dir/bench" \
        -o "$dir/session.json" --spec "$dir/bench.spec.json" > "$dir/out.txt" 2> "$dir/time.txt"
    echo "run $run: $(grep -E 'Elapsed \(wall' "$dir/time.txt" | sed 's/.*: //') wall, \
$(grep -E 'Maximum resident' "$dir/time.txt" | sed 's/.*: //') KiB peak"
done
cat "$dir/out.txt"
ls -l "$dir/session.json"
