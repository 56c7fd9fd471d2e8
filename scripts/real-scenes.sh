#!/usr/bin/env bash
# Writes docs/REAL-SCENES.md: every kernel `flatland solve` offers, with default arguments, on
# generated floor plans and halls no default was ever chosen on (seeds 21-26), as a user would
# run them. Each row is one `flatland solve --json` run; "total" is the command's wall time
# (scene load, the choice of mesh with its exact solves on N and 2N elements, build, solve; the
# 2N solve is the reference the error is measured against). Run from the repository root after `cargo build --release`:
#     scripts/real-scenes.sh [target/release/flatland]
set -euo pipefail
bin=${1:-target/release/flatland}
# A command still running after this many seconds is stopped and reported as such.
limit=${LIMIT:-240}
work=$(mktemp -d)
out=docs/REAL-SCENES.md
tmp=$(mktemp "docs/.REAL-SCENES.md.XXXX")
trap 'rm -rf "$work" "$tmp"' EXIT

scenes=(
  "floorplan 300 21" "floorplan 300 22" "hall 300 23" "hall 300 24"
  "floorplan 1000 25" "hall 1000 26" "floorplan 3000 27" "hall 3000 28"
)
kernels=(exact light visibility hr clustered uniform-exact)

{
  echo "# Real scenes: the lit scene with every kernel, default arguments"
  echo
  echo "Written by \`scripts/real-scenes.sh\` on $(nproc) cores ($(date -u +%Y-%m-%d)); every number is"
  echo "measured by it. Scenes: \`flatland scene KIND --size N --seed S\`, seeds never used to choose a"
  echo "default. Error: relative L2 of the solved reflected radiosity B − E against the exact kernel's"
  echo "solve on twice the elements (so it includes the mesh's own discretization error, estimated"
  echo "in the last column). \"Estimate\" is the light-driven learner's own estimate of its error against the"
  echo "exact kernel on the same elements. Build: building the kernel representation; total: the"
  echo "whole command, reference solve included. Times are wall-clock on a shared machine."
  echo
  echo "| scene | edges | elements | kernel | basis functions | build s | total s | peak MB | B − E error | estimate | discretization |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|"
} >"$tmp"

for spec in "${scenes[@]}"; do
  read -r kind size seed <<<"$spec"
  scene="$work/$kind-$size-$seed.json"
  "$bin" scene "$kind" --size "$size" --seed "$seed" --out "$scene" >/dev/null
  edges=$(python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['edges']))" "$scene")
  for kernel in "${kernels[@]}"; do
    start=$(date +%s.%N)
    set +e
    json=$(/usr/bin/time -f "%M" -o "$work/mem" timeout "$limit" "$bin" solve --scene "$scene" --kernel "$kernel" --json 2>"$work/err")
    rc=$?
    set -e
    if [ "$rc" -eq 0 ]; then
      total=$(python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.2f}')" "$start" "$(date +%s.%N)")
      python3 - "$kind $size/$seed" "$edges" "$total" "$(tail -n 1 "$work/mem")" "$json" >>"$tmp" <<'EOF2'
import json, sys
label, edges, total, mem_kb, text = sys.argv[1:]
j = json.loads(text)
basis = j.get("basis_functions")
est = j.get("estimated_rel_l2_reflected")
note = j.get("note")
kernel = j["kernel"] + (" ¹" if note else "")
print(f"| {label} | {edges} | {j['elements']} | {kernel} | {basis if basis is not None else '—'} | "
      f"{j['build_s']:.2f} | {total} | {int(mem_kb) / 1024:.0f} | {j['rel_l2_reflected']:.4f} | "
      f"{'' if est is None else f'{est:.4f}'} | {j['discretization_error_estimate']:.4f} |")
EOF2
    elif [ "$rc" -eq 124 ]; then
      echo "| $kind $size/$seed | $edges | | $kernel | did not finish in $limit s | | | | | | |" >>"$tmp"
    else
      echo "| $kind $size/$seed | $edges | | $kernel | failed: $(head -c 200 "$work/err" | tr '\n|' '  ') | | | | | | |" >>"$tmp"
    fi
  done
done

{
  echo
  echo "¹ HR cannot go below its initial linking (one link per facing pair of surface edges): it"
  echo "built that instead of the default 400 links and says so."
} >>"$tmp"
mv "$tmp" "$out"
echo "wrote $out"
