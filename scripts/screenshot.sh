#!/usr/bin/env bash
# Runs the real viewer window under Xvfb (software GL), lets it train for a few seconds, and saves
# a screenshot of the whole screen to docs/viewer.png. Also prints the frame rate the viewer
# measured while training (its --fps-log lines).
#
#   scripts/screenshot.sh [SECONDS] [TARGET_CELLS] [OUT.png] [SCENE_FILE]
#
# docs/viewer.png is `scripts/screenshot.sh 25 400 docs/viewer.png scenes/maze.ron`. With xdotool
# installed the pointer is parked on the controls panel, so no hover readout covers the plots.
#
# Needs: xvfb-run, Xvfb and ImageMagick's `import` (apt-get install -y --no-install-recommends
# xvfb imagemagick) and Mesa's GL (libgl1-mesa-dri, libegl-mesa0; present on the dev image).
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-12}"
CELLS="${2:-400}"
OUT="${3:-docs/viewer.png}"
SCENE="${4:-}"

if ! command -v xvfb-run >/dev/null || ! command -v import >/dev/null; then
    echo "installing xvfb and imagemagick" >&2
    apt-get install -y --no-install-recommends xvfb xauth imagemagick >/dev/null \
        || { apt-get update >/dev/null && apt-get install -y --no-install-recommends xvfb xauth imagemagick >/dev/null; }
fi

nice -n 10 cargo build --release -p flatland-viewer --example viewer
BIN="${CARGO_TARGET_DIR:-target}/release/examples/viewer"
mkdir -p "$(dirname "$OUT")"
LOG="$(mktemp)"
RUNTIME_DIR="$(mktemp -d)"

# A stale WAYLAND_DISPLAY would make winit try Wayland: unset it. --fresh ignores remembered
# settings so the picture is the same on every machine.
env -u WAYLAND_DISPLAY XDG_RUNTIME_DIR="$RUNTIME_DIR" \
    xvfb-run -a -s "-screen 0 1280x800x24" bash -c '
        "$1" --fresh --cells "$2" --fps-log ${6:+--scene "$6"} 2>"$3" &
        pid=$!
        if command -v xdotool >/dev/null; then xdotool mousemove 130 790 || true; fi
        sleep "$4"
        import -window root "$5"
        kill "$pid"
        wait "$pid" || true
    ' _ "$BIN" "$CELLS" "$LOG" "$SECONDS_TO_RUN" "$OUT" "$SCENE"

echo "viewer log (fps measured by the app over the last second, every 2 s):"
cat "$LOG"
# The window must have drawn and trained: fps lines in the log, and a picture that is not blank.
if ! grep -q '^fps' "$LOG"; then
    echo "error: the viewer logged no frames" >&2
    exit 1
fi
spread="$(identify -format '%[fx:standard_deviation]' "$OUT")"
if awk -v s="$spread" 'BEGIN { exit !(s < 0.02) }'; then
    echo "error: $OUT looks blank (standard deviation $spread)" >&2
    exit 1
fi
rm -rf "$LOG" "$RUNTIME_DIR"
echo "saved $OUT"
