#!/usr/bin/env bash
# Lists every function over 80 lines outside tests (the project's rule), longest first; exits 1
# if there is one. Tests are tests/ directories, `#[cfg(test)]` items and the module files they
# declare, and `#[test]` functions; benches and examples count. A function's lines run from its
# `fn` line to its closing brace. Usage: scripts/long-functions.sh [MAX_LINES=80]
set -euo pipefail
cd "$(dirname "$0")/.."
exec python3 - "${1:-80}" <<'PY'
import re
import sys

sys.path.insert(0, "scripts")
from rust_source import crate_files, crate_roots, in_regions, item_end, line_of

limit = int(sys.argv[1])
FN = re.compile(r"(?<![A-Za-z0-9_])fn\s+([A-Za-z_][A-Za-z0-9_]*)")
seen, long = set(), []
for crate, roots in crate_roots("."):
    for root in roots:
        for f in crate_files(root, crate):
            if f.path in seen:
                continue
            seen.add(f.path)
            for m in FN.finditer(f.code):
                if in_regions(m.start(), f.regions):
                    continue
                end, body = item_end(f.code, m.end())
                if not body:
                    continue  # a trait's declaration
                first, last = line_of(f.code, m.start()), line_of(f.code, end)
                if last - first + 1 > limit:
                    long.append((last - first + 1, f"{f.path}:{first}", m.group(1)))
for lines, where, name in sorted(long, reverse=True):
    print(f"{lines:5} {where} fn {name}")
print(f"{len(long)} functions over {limit} lines outside tests ({len(seen)} files read)",
      file=sys.stderr)
sys.exit(1 if long else 0)
PY
