#!/usr/bin/env python3
"""Finds import circles within each crate and between the workspace's crates; exits 1 if any.

Within a crate: a module depends on another when its code (tests aside) names an item of it
through `use crate::…`, `use super::…`, `use child::…` or an inline `crate::…` / `super::…`
path; a re-export (`pub use a::X` in lib.rs) is followed to the module that defines X. The
check is levelled, as the module tree is: under each module, its children must form no circle,
counting for a child everything in its subtree. A module and its own descendants may use each
other (a type whose impl is split over child files does), so only circles between siblings,
at any depth, are reported. `--strict` also counts a parent's own file as one of the siblings.

Between crates: the workspace's Cargo.toml files, normal and dev-dependencies (a dev-dependency
circle gives a crate's unit tests a second copy of the crate, with types that do not match).

Usage: scripts/import-cycles.py [-v]   (-v: every module's arrows)
"""

import re
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rust_source import crate_files, crate_roots, in_regions, matching  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
NAME = r"[A-Za-z_][A-Za-z0-9_]*"
ITEM = re.compile(
    rf"(?<![A-Za-z0-9_])(?:struct|enum|trait|type|fn|const|static|union|mod)\s+({NAME})"
    rf"|macro_rules!\s*({NAME})"
)
USE = re.compile(r"(?<![A-Za-z0-9_])use\s+")
INLINE = re.compile(rf"(?<![A-Za-z0-9_:])(?:crate|super)(?:\s*::\s*{NAME})+")


def use_trees(code, regions):
    """Every `use` statement outside tests, flattened: (segments, name it binds or '*')."""
    out = []
    for m in USE.finditer(code):
        if in_regions(m.start(), regions):
            continue
        end = m.end()
        depth = 0
        while code[end] != ";" or depth:
            depth += code[end] == "{"
            depth -= code[end] == "}"
            end += 1
        out += flatten(code[m.end() : end], [])
    return out


def flatten(tree, prefix):
    """`a::{b, c::d as e, f::*}` with `prefix` → ([…a, b], 'b'), ([…a, c, d], 'e'), ([…a, f], '*')."""
    tree = re.sub(r"\s+", " ", tree).strip().lstrip(":").strip()
    brace = tree.find("{")
    if brace >= 0:
        head = [s.strip() for s in tree[:brace].split("::") if s.strip()]
        close = matching(tree, brace)
        out, depth, start = [], 0, brace + 1
        for k in range(brace + 1, close + 1):
            c = tree[k]
            depth += c == "{"
            depth -= c == "}"
            if (c == "," and depth == 0) or k == close:
                part = tree[start:k].strip()
                if part:
                    out += flatten(part, prefix + head)
                start = k + 1
        return out
    alias = None
    if " as " in tree:
        tree, alias = (s.strip() for s in tree.split(" as "))
    segs = prefix + [s.strip() for s in tree.split("::") if s.strip()]
    if segs[-1] == "*":
        return [(segs[:-1], "*")]
    if segs[-1] == "self":
        segs = segs[:-1]
    return [(segs, alias or segs[-1])]


class Crate:
    """A crate's module tree, each module's top-level items and imports."""

    def __init__(self, name, root):
        self.name = name
        self.files = {f.modpath: f for f in crate_files(root, name)}
        self.items = {m: top_level_items(f) for m, f in self.files.items()}
        self.uses = {m: use_trees(f.code, f.regions) for m, f in self.files.items()}

    def absolute(self, module, segs):
        """`segs` as written in `module`, made absolute within the crate; None if external."""
        head, rest = segs[0], list(segs[1:])
        if head == "crate":
            return rest
        if head == "self":
            return list(module) + rest
        if head == "super":
            base = list(module[:-1])
            while rest and rest[0] == "super":
                base, rest = base[:-1], rest[1:]
            return base + rest
        if tuple(module) + (head,) in self.files:
            return list(module) + [head] + rest
        return None

    def resolve(self, segs, seen=()):
        """The module defining what absolute path `segs` names (following re-exports)."""
        module = ()
        k = 0
        while k < len(segs) and module + (segs[k],) in self.files:
            module += (segs[k],)
            k += 1
        if k == len(segs) or segs[k] in self.items[module]:
            return module
        name = segs[k]
        if (module, name) in seen:
            return module
        seen = seen + ((module, name),)
        for path, bound in self.uses[module]:
            if bound == name:
                target = self.absolute(module, path)
                return module if target is None else self.resolve(target + segs[k + 1 :], seen)
        for path, bound in self.uses[module]:
            if bound == "*":
                target = self.absolute(module, path)
                if target is not None:
                    found = self.resolve(target + [name] + segs[k + 1 :], seen)
                    if found != tuple(target):
                        return found
        return module

    def edges(self):
        """module → the modules it names, with one place each is named from (for the report)."""
        out = defaultdict(dict)
        for module, f in self.files.items():
            paths = [(p, "use") for p, _ in self.uses[module]]
            for m in INLINE.finditer(f.code):
                if not in_regions(m.start(), f.regions):
                    segs = [s.strip() for s in m.group(0).split("::")]
                    paths.append((segs, "path"))
            for segs, how in paths:
                if not segs:
                    continue
                target = self.absolute(module, segs)
                if target is None:
                    continue
                dep = self.resolve(target)
                if dep != module:
                    out[module].setdefault(dep, f"{f.path.relative_to(ROOT)}: {'::'.join(segs)}")
        return out


def top_level_items(f):
    """Names of the items at a file's top level (outside tests): what `use` can reach there."""
    depth, names = 0, set()
    marks = {m.start(): m for m in ITEM.finditer(f.code)}
    for k, c in enumerate(f.code):
        if c == "{":
            depth += 1
        elif c == "}":
            depth -= 1
        elif depth == 0 and k in marks and not in_regions(k, f.regions):
            names.add(marks[k].group(1) or marks[k].group(2))
    return names


def is_within(a, b):
    """Whether module `a` is `b` or lies under it."""
    return a[: len(b)] == b


def cycles(graph):
    """The strongly connected components of more than one node (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def module_circles(crate):
    """Circles among the children of every module of `crate`, with a witness per arrow."""
    edges = crate.edges()
    found = []
    for parent in sorted(crate.files):
        children = [m for m in crate.files if len(m) == len(parent) + 1 and is_within(m, parent)]

        def node_of(m, children=children):
            under = [c for c in children if is_within(m, c)]
            return under[0] if under else None

        graph, witness = defaultdict(set), {}
        for src, deps in edges.items():
            a = node_of(src)
            for dst, where in deps.items():
                b = node_of(dst)
                if a is not None and b is not None and a != b:
                    graph[a].add(b)
                    witness.setdefault((a, b), where)
        for comp in cycles(graph):
            arrows = [
                (a, b, witness[(a, b)]) for a in comp for b in comp if (a, b) in witness
            ]
            found.append((parent, comp, arrows))
    return found


def manifest(path):
    """A Cargo.toml's package name and its dependency names per table (`dependencies`,
    `dev-dependencies`, `build-dependencies`): a few lines of TOML reading, so the check needs
    no python package (tomllib is 3.11+)."""
    name, deps, table = None, defaultdict(set), None
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        header = re.fullmatch(r"\[\[?([^\[\]]+)\]\]?", line)
        if header:
            parts = header.group(1).strip().split(".")
            table = parts[0]
            if len(parts) > 1 and table.endswith("dependencies"):
                deps[table].add(parts[1].strip().strip('"'))
            continue
        key = re.match(r'"?([A-Za-z0-9_-]+)"?\s*(?:\.|=)', line)
        if not key:
            continue
        if table == "package" and key.group(1) == "name" and name is None:
            name = re.search(r'=\s*"([^"]+)"', line).group(1)
        elif table and table.endswith("dependencies"):
            deps[table].add(key.group(1))
    return name, deps


def crate_circles():
    """Circles in the workspace's crate graph: normal dependencies, then with dev-dependencies."""
    manifests = [manifest(p) for p in [ROOT / "Cargo.toml", *sorted(ROOT.glob("crates/*/Cargo.toml"))]]
    members = {name for name, _ in manifests}
    normal, dev = defaultdict(set), defaultdict(set)
    for me, deps in manifests:
        normal[me] = (deps["dependencies"] | deps["build-dependencies"]) & members
        dev[me] = normal[me] | (deps["dev-dependencies"] & members)
    known = cycles(normal)
    return known, [c for c in cycles(dev) if c not in known]


def main():
    verbose = "-v" in sys.argv
    bad = 0
    normal, dev = crate_circles()
    for comp in normal:
        print(f"crate circle: {' ↔ '.join(comp)}")
    for comp in dev:
        print(f"crate circle through dev-dependencies: {' ↔ '.join(comp)}")
    bad += len(normal) + len(dev)
    modules = 0
    for name, roots in crate_roots(ROOT):
        for root in roots:
            if root.parent.name in ("benches", "examples", "fuzz_targets") and root.name != "main.rs":
                crate = Crate(f"{name} ({root.relative_to(ROOT)})", root)
            else:
                crate = Crate(name, root)
            modules += len(crate.files)
            for parent, comp, arrows in module_circles(crate):
                bad += 1
                show = lambda m: "::".join(("crate",) + m)  # noqa: E731
                print(f"{crate.name}: circle under {show(parent)}: {', '.join(map(show, comp))}")
                for a, b, where in arrows:
                    print(f"    {show(a)} → {show(b)}   ({where})")
            if verbose:
                for src, deps in sorted(crate.edges().items()):
                    print(f"  {crate.name} {'::'.join(src) or 'crate'} → {sorted(deps)}")
    print(f"{bad} import circles ({modules} modules, {len(crate_roots(ROOT))} packages)", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
