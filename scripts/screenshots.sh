#!/usr/bin/env bash
# Screenshots of every workbench view, in a real window under Xvfb, on results computed
# from the bundled sample sessions (short runs: 2 repetitions).
#
#   scripts/screenshots.sh [OUT_DIR] [WIDTHxHEIGHT] [live]   (default: docs/screenshots 1400x900)
#
# With `live`, only the Live view's screenshots (a served stream) are taken.
# Run it at 1400x900 and at 1000x700 (into another folder) to check the layout holds.
# The projects are kept in target/screenshot-projects and reused; delete it to recompute.
# Needs Xvfb, xdotool and ImageMagick's `import`
# (Debian/Ubuntu: apt-get install xvfb xdotool imagemagick). The dev build is used (it is
# optimised; a release build of the window takes far longer to compile).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/screenshots}
size=${2:-1400x900}
mkdir -p "$out"
work=target/screenshot-projects
mkdir -p "$work"
trap 'kill $(jobs -p) 2>/dev/null || true' EXIT

# `serve` (the live view's stream) needs the Foxglove SDK's server.
cargo build --features serve
bin=target/debug/tactile-workbench

# Results to show: one project per experiment.
[ -f "$work/stability.json" ] ||
    $bin paper-figures sample-sessions/grasp-stability.json --experiment stability \
        -o "$work/fig-stability" --project "$work/stability.json"
for e in recognition clustering baselines; do
    [ -f "$work/$e.json" ] ||
        $bin paper-figures sample-sessions/object-recognition.json --experiment $e --reps 2 \
            -o "$work/fig-$e" --project "$work/$e.json"
done
[ -f "$work/robustness.json" ] ||
    $bin paper-figures sample-sessions/grasp-stability.json --experiment robustness-stability \
        --reps 2 -o "$work/fig-robustness" --project "$work/robustness.json"
# The speed view's frontiers, on the recognition sample (every method, 2 repetitions).
[ -f "$work/frontier.json" ] ||
    $bin paper-figures sample-sessions/object-recognition.json --experiment frontier --reps 2 \
        -o "$work/fig-frontier" --project "$work/frontier.json"
projects=("$work"/stability.json "$work"/recognition.json "$work"/clustering.json \
    "$work"/baselines.json "$work"/robustness.json)

export DISPLAY=:97
Xvfb $DISPLAY -screen 0 "${size}x24" >/dev/null 2>&1 &
sleep 1
shot() { # VIEW NAME [xdotool actions...]
    local view=$1 name=$2
    shift 2
    $bin --view "$view" "${projects[@]}" >/dev/null 2>&1 &
    local pid=$!
    sleep 6
    local win
    win=$(xdotool search --name "Tactile Workbench" | head -1)
    xdotool windowfocus --sync "$win" 2>/dev/null || true
    # The window opens at 1400 x 900: fit it to the screen.
    xdotool windowmove "$win" 0 0 windowsize "$win" "${size%x*}" "${size#*x}" 2>/dev/null || true
    sleep 2
    if [ $# -gt 0 ]; then
        xdotool "$@"
        sleep 2
    fi
    import -window root "$out/$name.png"
    kill $pid
    wait $pid 2>/dev/null || true
}
if [ "${3:-}" != live ]; then
shot stability stability
shot recognition recognition
shot clustering clustering
shot baselines baselines
# The recognition sample first, so the frontiers of its session are the ones shown.
projects=("$work"/frontier.json "$work"/recognition.json "$work"/clustering.json \
    "$work"/baselines.json "$work"/stability.json)
shot speed-accuracy speed-accuracy
projects=("$work"/stability.json "$work"/recognition.json "$work"/clustering.json \
    "$work"/baselines.json "$work"/robustness.json)
shot robustness robustness
# Replay: select the first grasp in the browser.
shot replay replay mousemove 120 190 click 1
fi

# Live: a served iCub stream (trials 16–20) recognised by DS trained on trials 1–15, the
# class distribution settling as the hand closes. Without the dataset, the simulated
# recognition sample stands in.
icub=../shared/datasets/icub-grasp
if [ ! -f "$work/live-test.json" ]; then
    if [ -d "$icub" ]; then
        $bin import icub "$icub" -o "$work/icub.json"
        src="$work/icub.json"
    else
        src=sample-sessions/object-recognition.json
    fi
    $bin subset "$src" --trials 1..15 -o "$work/live-train.json"
    $bin subset "$src" --trials 16..20 -o "$work/live-test.json"
    $bin fit ds "$work/live-train.json" -o "$work/live-ds.json"
fi
$bin serve "$work/live-test.json" --rate 1 --port 8799 --write-spec "$work/live.spec.json" \
    >/dev/null 2>&1 &
serve_pid=$!
# The Live view's form: the fields typed, then Connect; two moments of the stream. The form
# panel is min(250, 22 % of the width) wide at the right; its fields' heights do not move.
w=${size%x*}
panel=$((w * 22 / 100 < 250 ? w * 22 / 100 : 250))
fx=$((w - panel / 2))
live_form() {
    local y=78
    for text in "ws://127.0.0.1:8799" "$PWD/$work/live.spec.json" "$PWD/$work/live-ds.json"; do
        xdotool mousemove $fx $y click 1 key ctrl+a type --delay 20 "$text"
        sleep 1
        y=$((y + 41))
    done
    xdotool mousemove $((w - panel + 41)) 294 click 1
    sleep 8
}
$bin --view live >/dev/null 2>&1 &
pid=$!
sleep 6
win=$(xdotool search --name "Tactile Workbench" | head -1)
xdotool windowfocus --sync "$win" 2>/dev/null || true
xdotool windowmove "$win" 0 0 windowsize "$win" "${size%x*}" "${size#*x}" 2>/dev/null || true
sleep 2
live_form
import -window root "$out/live.png"
sleep 3
import -window root "$out/live-settled.png"
kill $pid $serve_pid
wait $pid $serve_pid 2>/dev/null || true
# The Compare view on the real datasets (when they are beside the checkout).
[ -d ../shared/datasets ] && scripts/screenshots-compare.sh "$out" "$size"
echo "screenshots in $out"
