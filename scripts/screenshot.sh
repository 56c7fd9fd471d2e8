#!/usr/bin/env bash
# Runs the real viewer window under Xvfb (software GL) as a first launch would (fresh settings,
# learning at once), saves screenshots of the whole screen, and prints the frame rate and frame
# times the viewer measured (its --fps-log lines).
#
#   scripts/screenshot.sh [SECONDS] [OUT.png] [VIEWER ARGS...]
#
# SECONDS after launch (default 12) may be a list, "6,12": one screenshot each, OUT-6.png and
# OUT-12.png, and for each pair the number of pixels that differ over the plots (ImageMagick
# `compare -metric AE`; the controls, the top bar and the timeline bar are left out).
# VIEWER ARGS go to the viewer example: --scene FILE|NAME (FILE may be an .svg drawing),
# --learner light|visibility|paper, --cells N, --growth N|max, --paused.
#
# docs/viewer.png is `scripts/screenshot.sh 12 docs/viewer.png`: the default launch (the floor
# plan, 20 cells per second). The growth check is `scripts/screenshot.sh 6,12 /tmp/growth.png`;
# the large-scene frame rate `scripts/screenshot.sh 4 /tmp/big.png --scene floorplan-1000`
# (while it learns: once the learner stops, the window draws no more frames). With xdotool
# installed the pointer is parked on the top bar's status text, so no hover readout or tooltip
# covers the picture.
#
# Needs: xvfb-run, Xvfb and ImageMagick's `import` and `compare` (apt-get install -y
# --no-install-recommends xvfb imagemagick) and Mesa's GL (libgl1-mesa-dri, libegl-mesa0;
# present on the dev image).
set -euo pipefail
cd "$(dirname "$0")/.."
TIMES="${1:-12}"
OUT="${2:-docs/viewer.png}"
shift $(( $# > 2 ? 2 : $# ))
# The plots: right of the controls panel, below the top bar, above the timeline bar.
PLOTS="1010x712+268+48"

if ! command -v xvfb-run >/dev/null || ! command -v import >/dev/null; then
    echo "installing xvfb and imagemagick" >&2
    apt-get install -y --no-install-recommends xvfb xauth imagemagick >/dev/null \
        || { apt-get update >/dev/null && apt-get install -y --no-install-recommends xvfb xauth imagemagick >/dev/null; }
fi

# VIEWER_BIN=path runs that viewer binary instead of building one (to compare two builds).
if [ -n "${VIEWER_BIN:-}" ]; then
    BIN="$VIEWER_BIN"
else
    nice -n 10 cargo build --release -p flatland-viewer --example viewer
    BIN="${CARGO_TARGET_DIR:-target}/release/examples/viewer"
fi
mkdir -p "$(dirname "$OUT")"
LOG="$(mktemp)"
RUNTIME_DIR="$(mktemp -d)"
IFS=',' read -r -a SHOTS <<<"$TIMES"
shot_name() {
    if [ "${#SHOTS[@]}" -eq 1 ]; then echo "$OUT"; else echo "${OUT%.png}-$1.png"; fi
}
NAMES=()
for t in "${SHOTS[@]}"; do NAMES+=("$(shot_name "$t")"); done

# A stale WAYLAND_DISPLAY would make winit try Wayland: unset it. --fresh ignores remembered
# settings so the picture is the same on every machine.
env -u WAYLAND_DISPLAY XDG_RUNTIME_DIR="$RUNTIME_DIR" \
    xvfb-run -a -s "-screen 0 1280x800x24" bash -c '
        bin="$1"; log="$2"; times="$3"; names="$4"; shift 4
        "$bin" --fresh --fps-log "$@" 2>"$log" &
        pid=$!
        start=$(date +%s%N)
        if command -v xdotool >/dev/null; then xdotool mousemove 1100 12 || true; fi
        read -r -a ts <<<"$times"; read -r -a ns <<<"$names"
        for i in "${!ts[@]}"; do
            wait_ms=$(( ${ts[$i]} * 1000 - ($(date +%s%N) - start) / 1000000 ))
            if [ "$wait_ms" -gt 0 ]; then sleep "$(printf "%d.%03d" $((wait_ms / 1000)) $((wait_ms % 1000)))"; fi
            import -window root "${ns[$i]}"
        done
        kill "$pid"
        wait "$pid" || true
    ' _ "$BIN" "$LOG" "${SHOTS[*]}" "${NAMES[*]}" "$@"

echo "viewer log (fps measured by the app over the last second, every 2 s):"
cat "$LOG"
# The window must have drawn and trained: fps lines in the log, and pictures that are not blank.
if ! grep -q '^fps' "$LOG"; then
    echo "error: the viewer logged no frames" >&2
    exit 1
fi
for name in "${NAMES[@]}"; do
    spread="$(identify -format '%[fx:standard_deviation]' "$name")"
    if awk -v s="$spread" 'BEGIN { exit !(s < 0.02) }'; then
        echo "error: $name looks blank (standard deviation $spread)" >&2
        exit 1
    fi
    echo "saved $name"
done
for (( i = 1; i < ${#NAMES[@]}; i++ )); do
    a="${NAMES[$((i - 1))]}"; b="${NAMES[$i]}"
    changed="$(compare -metric AE "$a[$PLOTS]" "$b[$PLOTS]" null: 2>&1 || true)"
    echo "pixels that differ over the plots, ${SHOTS[$((i - 1))]} s to ${SHOTS[$i]} s: $changed"
done
rm -rf "$LOG" "$RUNTIME_DIR"
