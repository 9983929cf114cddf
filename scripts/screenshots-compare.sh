#!/usr/bin/env bash
# Screenshots of the Compare view on the real datasets, in a real window under Xvfb:
# iCub total pressure by object (one band per object), BTS3 successes against failures as
# distributions (hand total, and one electrode picked from the searched tree), and on iCub a
# DS model's true class probability for correct and wrong recognitions.
#
#   scripts/screenshots-compare.sh [OUT_DIR] [WIDTHxHEIGHT]   (default: docs/screenshots 1400x900)
#
# The window keeps its state in a data folder of its own (XDG_DATA_HOME under target/),
# which holds the DS model: taught trials 1–3 of each iCub object, so that it gets some
# of the other grasps wrong. Needs ../shared/datasets, Xvfb, xdotool and ImageMagick.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/screenshots}
size=${2:-1400x900}
data=../shared/datasets
mkdir -p "$out"
work=target/screenshot-compare
rm -rf "$work/xdg"
# The window's data folder (eframe's storage under XDG_DATA_HOME), with the model kept.
models=$work/xdg/tactileworkbench/models
mkdir -p "$models"
trap 'kill $(jobs -p) 2>/dev/null || true' EXIT

cargo build
bin=target/debug/tactile-workbench
$bin subset "$data/icub-grasp" --trials 1..3 --name "iCub trials 1-3" -o "$work/icub-1-3.json"
$bin fit ds "$work/icub-1-3.json" -o "$models/ds-icub-1-3.json"

export DISPLAY=:96
Xvfb $DISPLAY -screen 0 "${size}x24" >/dev/null 2>&1 &
sleep 1
w=${size%x*}
h=${size#*x}
shot() { # NAME FILE [ACTIONS: a function of xdotool steps]
    local name=$1 file=$2 actions=${3:-}
    XDG_DATA_HOME="$PWD/$work/xdg" $bin --view compare "$file" >/dev/null 2>&1 &
    local pid=$!
    sleep 8
    local win
    win=$(xdotool search --name "Tactile Workbench" | head -1)
    xdotool windowfocus --sync "$win" 2>/dev/null || true
    xdotool windowmove "$win" 0 0 windowsize "$win" "$w" "$h" 2>/dev/null || true
    sleep 3
    if [ -n "$actions" ]; then
        $actions
        sleep 4
    fi
    import -window root "$out/$name.png"
    kill $pid
    wait $pid 2>/dev/null || true
}
# The form panel is min(250, 22 % of the width) wide at the right; its fields' heights do
# not move with the window's size, so a click is placed from the panel's left edge.
panel=$((w * 22 / 100 < 250 ? w * 22 / 100 : 250))
at() { # X Y: click X points into the form panel, Y from the window's top
    xdotool mousemove $((w - panel + $1)) "$2" click 1
    sleep 2
}
search() { # TEXT: into the signal tree's search field
    xdotool type --delay 50 "$1"
    sleep 2
}
# BTS3: electrode 7 of the middle finger, searched for in the tree and clicked.
electrode() {
    at 125 364
    search "mf taxel 7"
    at 40 413
}
# iCub: the DS model's outputs, grouped correct vs wrong, its true class probability.
ds() {
    at 59 196
    at 105 246
    at 89 114
    at 98 187
    at 120 390
    search "true class"
    at 100 437
}
shot compare-icub "$data/icub-grasp"
shot compare-bts3-electrode "$data/bts3/biotac-palmdown-grasps.csv" electrode
shot compare-icub-ds "$data/icub-grasp" ds
echo "screenshots in $out"
