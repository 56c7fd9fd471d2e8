#!/usr/bin/env bash
# Writes what the CLI computes on every bundled scene, times and memory stripped, so two builds
# can be diffed bit for bit (`diff -r A B` after a refactor must print nothing):
#   fit-SCENE-PRESET.json     flatland fit --json --preset PRESET (both networks)
#   model-SCENE-PRESET.json   the model that fit wrote (--out), its summary's times stripped
#   solve-SCENE-fit-PRESET.json  flatland solve --json --kernel <that model>
#   solve-SCENE-KERNEL.json      flatland solve --json --kernel exact | light (the light-driven learner)
# Usage: scripts/outputs.sh OUT_DIR [FLATLAND_BINARY]   (default: this tree's target/release/flatland)
# Needs jq. Every run is seeded (the commands' default seed), so a difference is a change.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:?usage: scripts/outputs.sh OUT_DIR [FLATLAND_BINARY]}"
bin="${2:-$root/target/release/flatland}"
[[ -x "$bin" ]] || { echo "outputs.sh: $bin is not an executable (build it: cargo build --release)" >&2; exit 2; }
command -v jq >/dev/null || { echo "outputs.sh: needs jq" >&2; exit 2; }
mkdir -p "$out"
out="$(cd "$out" && pwd)"
models="$(mktemp -d)"
trap 'rm -rf "$models"' EXIT
# Wall times (`…_s`) and the memory peak differ run to run; paths name the output folder.
strip='with_entries(select(.key | test("_s$|^peak_memory") | not))
       | if has("kernel") then .kernel |= sub(".*/"; "") else . end
       | if has("scene") then .scene |= sub(".*/"; "") else . end'
run() { # NAME ARGS…: runs the binary, keeps its JSON stripped, its stderr beside it
  local name="$1"; shift
  if ! "$bin" "$@" --json 2>"$out/$name.err" | jq -S "$strip" >"$out/$name.json"; then
    echo "outputs.sh: \`flatland $*\` failed (see $out/$name.err)" >&2; exit 1
  fi
}
count=0
for scene in "$root"/scenes/*.ron; do
  name="$(basename "$scene" .ron)"
  for preset in visibility paper; do
    model="$models/$name-$preset.json"
    run "fit-$name-$preset" fit --scene "$scene" --preset "$preset" --out "$model"
    run "solve-$name-fit-$preset" solve --scene "$scene" --kernel "$model"
    jq -S 'walk(if type == "object" then with_entries(select(.key | test("_s$") | not)) else . end)' \
      "$model" >"$out/model-$name-$preset.json"
    count=$((count + 3))
  done
  for kernel in exact light; do
    run "solve-$name-$kernel" solve --scene "$scene" --kernel "$kernel"
    count=$((count + 1))
  done
done
rm -f "$out"/*.err
echo "wrote $count stripped outputs of $bin to $out"
