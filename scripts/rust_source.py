"""Rust sources as the project's checks read them: comments and literals blanked, test code marked.

Shared by scripts/long-functions.sh and scripts/import-cycles.py. Needs nothing but python3: a
small lexer (enough for rustfmt'd code, not a parser) that keeps every character's line, so a
brace counter and a path scanner can read the code without tripping on `"{"` or `// }`.
"""

import re
import subprocess
from pathlib import Path

IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def blank(src):
    """`src` with comments and the contents of string and char literals replaced by spaces.

    Newlines are kept, so offsets and line numbers are those of the original. Lifetimes and
    labels (`'a`) stay; char literals (`'x'`, `'\\n'`, `b'{'`) are blanked.
    """
    out = list(src)
    n = len(src)
    i = 0

    def wipe(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = src[i]
        nxt = src[i + 1] if i + 1 < n else ""
        if c == "/" and nxt == "/":
            j = src.find("\n", i)
            j = n if j < 0 else j
            wipe(i, j)
            i = j
        elif c == "/" and nxt == "*":
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            wipe(i, j)
            i = j
        elif c in "rbc" and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            m = re.compile(r'(?:br|cr|r)(#*)"').match(src, i)
            if m:
                close = '"' + m.group(1)
                j = src.find(close, m.end())
                j = n if j < 0 else j + len(close)
                wipe(m.end(), j - len(close))
                i = j
            elif c in "bc" and nxt == '"':
                i += 1  # b"..." / c"...": the string itself is handled next round
            elif c == "b" and nxt == "'":
                i += 1
            else:
                m = IDENT.match(src, i)
                i = m.end()
        elif c == '"':
            j = i + 1
            while j < n and src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            wipe(i + 1, j)
            i = j + 1
        elif c == "'":
            if nxt == "\\":
                j = src.find("'", i + 3)  # '\'' has its quote at i + 2
                wipe(i + 1, j)
                i = j + 1
            elif i + 2 < n and src[i + 2] == "'":
                wipe(i + 1, i + 2)
                i += 3
            else:
                i += 1  # a lifetime or a label
        elif c.isalpha() or c == "_":
            i = IDENT.match(src, i).end()
        else:
            i += 1
    return "".join(out)


def matching(code, open_at):
    """The offset of the bracket closing the one at `open_at` in blanked `code`."""
    pairs = {"{": "}", "(": ")", "[": "]"}
    stack = []
    for k in range(open_at, len(code)):
        c = code[k]
        if c in pairs:
            stack.append(pairs[c])
        elif c in ")]}":
            if not stack or stack.pop() != c:
                raise ValueError(f"unbalanced {c!r} at offset {k}")
            if not stack:
                return k
    raise ValueError(f"unclosed bracket at offset {open_at}")


def item_end(code, start):
    """From `start` (after an item's attributes), the end of the item: its `;` or closing `}`.

    Returns (end offset, True if the item has a `{ … }` body).
    """
    k = start
    while k < len(code):
        c = code[k]
        if c in "([":
            k = matching(code, k) + 1
            continue
        if c == ";":
            return k, False
        if c == "{":
            return matching(code, k), True
        k += 1
    raise ValueError(f"item at offset {start} has no end")


ATTR = re.compile(r"#!?\[")
TEST_ATTR = re.compile(r"#\[\s*(?:cfg\s*\(\s*test\s*\)|test)\s*\]")


def skip_attributes(code, k):
    """The offset of the first non-space character after `k` that does not start an attribute."""
    while True:
        while k < len(code) and code[k].isspace():
            k += 1
        m = ATTR.match(code, k)
        if not m:
            return k
        k = matching(code, m.end() - 1) + 1


def test_regions(code):
    """Half-open offset ranges of items marked `#[cfg(test)]` or `#[test]` (a `#[cfg(test)]
    mod name;` covers its declaration, so its file is never read)."""
    regions = []
    for m in TEST_ATTR.finditer(code):
        if any(a <= m.start() < b for a, b in regions):
            continue
        start = skip_attributes(code, m.end())
        end, _ = item_end(code, start)
        regions.append((m.start(), end + 1))
    return regions


def in_regions(offset, regions):
    """Whether `offset` lies in one of `regions`."""
    return any(a <= offset < b for a, b in regions)


def line_of(code, offset):
    """The 1-based line of `offset`."""
    return code.count("\n", 0, offset) + 1


def module_decls(code, regions):
    """The names of `mod name;` declarations outside test regions."""
    decls = []
    for m in re.finditer(r"(?<![A-Za-z0-9_])mod\s+([A-Za-z_][A-Za-z0-9_]*)\s*;", code):
        if not in_regions(m.start(), regions):
            decls.append(m.group(1))
    return decls


class SourceFile:
    """One module file: its path, module path within its crate, blanked code and test regions."""

    def __init__(self, path, modpath, crate):
        self.path = path
        self.modpath = modpath
        self.crate = crate
        self.src = path.read_text(encoding="utf-8")
        self.code = blank(self.src)
        self.regions = test_regions(self.code)

    def child_dir(self):
        """Where `mod x;` in this file looks for x.rs or x/mod.rs."""
        if self.path.name in ("lib.rs", "main.rs", "mod.rs") or not self.modpath:
            return self.path.parent
        return self.path.parent / self.path.stem


def crate_files(root_file, crate):
    """Every non-test module file reached from a crate root by `mod x;`, depth first."""
    files, queue = [], [(Path(root_file), ())]
    while queue:
        path, modpath = queue.pop()
        f = SourceFile(path, modpath, crate)
        files.append(f)
        for name in module_decls(f.code, f.regions):
            base = f.child_dir()
            for cand in (base / f"{name}.rs", base / name / "mod.rs"):
                if cand.exists():
                    queue.append((cand, modpath + (name,)))
                    break
            else:
                raise FileNotFoundError(f"{f.path}: `mod {name};` has no file")
    return files


def tracked_rust_files(repo):
    """Every tracked .rs file of the repository (git ls-files), as paths."""
    out = subprocess.run(
        ["git", "-C", str(repo), "ls-files", "*.rs"], capture_output=True, text=True, check=True
    ).stdout
    return [Path(repo) / p for p in out.split()]


def crate_roots(repo):
    """(crate name, root files) for the workspace and the fuzz package: each crate's lib.rs /
    main.rs / bin, benches, examples and fuzz targets (not tests/, which are tests)."""
    repo = Path(repo)
    crates = []
    manifests = [repo / "Cargo.toml", *sorted(repo.glob("crates/*/Cargo.toml"))]
    manifests += [m for m in [repo / "fuzz/Cargo.toml"] if m.exists()]
    for manifest in manifests:
        base = manifest.parent
        name = re.search(r'^name\s*=\s*"([^"]+)"', manifest.read_text(), re.M).group(1)
        roots = [p for p in (base / "src/lib.rs", base / "src/main.rs") if p.exists()]
        for sub in ("src/bin", "benches", "examples", "fuzz_targets"):
            roots += sorted((base / sub).glob("*.rs"))
        crates.append((name, roots))
    return crates
