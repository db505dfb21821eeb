#!/usr/bin/env python3
"""The import graph of a Rust crate, drawn from its own paths: every `use crate::...`,
`use super::...` and `crate::x::y` / `super::x` path in code (doc comments are skipped unless
--docs), each resolved to the file that defines it (through `pub use` re-exports).

Prints the files, the arrows (file -> file it uses; `(test)` when only test code uses it), the
circles (strongly connected components of more than one file, and of top-level folders), and,
given --layers, every arrow that runs back up the declared order.

    python3 tools/import_graph.py crates/synth/src \\
        --layers "error hash | world | motion | sensor | spec | generator | output | catalog"

A layer lists top-level modules (a folder or a file of src/), lowest first. The exit status is
1 when there is a circle or an upward arrow, so CI or a reviewer can run it as a check.
"""

import argparse
import os
import re
import sys
from collections import defaultdict

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
PATH_RE = re.compile(r"\b(crate|super|self)((?:::" + IDENT + r")+)")


def module_of(src, file):
    """Module path (tuple) of a source file: lib.rs -> (), a/b.rs -> (a, b), a/mod.rs -> (a,)."""
    rel = os.path.relpath(file, src)[: -len(".rs")].split(os.sep)
    if rel[-1] in ("lib", "main", "mod"):
        rel = rel[:-1]
    return tuple(rel)


def strip(text, docs):
    """Code of a file with string literals blanked and comments removed (doc comments kept
    when `docs`), line by line so that line numbers stay."""
    out = []
    for line in text.split("\n"):
        s = line.lstrip()
        if s.startswith("//"):
            is_doc = s.startswith("///") or s.startswith("//!")
            out.append(line if (docs and is_doc) else "")
            continue
        line = re.sub(r'"(?:\\.|[^"\\])*"', '""', line)
        out.append(line.split("//")[0])
    return "\n".join(out)


def expand(tree):
    """Expands a use tree `a::{b, c::{d, e}}` into paths."""
    tree = tree.strip()
    depth, start = 0, None
    for i, ch in enumerate(tree):
        if ch == "{":
            if depth == 0:
                start = i
            depth += 1
        elif ch == "}":
            depth -= 1
    if start is None:
        return [tree]
    prefix, inner = tree[:start], tree[start + 1 : tree.rfind("}")]
    parts, depth, cur = [], 0, ""
    for ch in inner:
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        cur += ch
    parts.append(cur)
    paths = []
    for p in parts:
        p = p.strip()
        if p:
            for q in expand(p):
                paths.append(prefix + q)
    return paths


def uses(code):
    """(line, path) of every `use` statement's leaf path (with `as` dropped)."""
    found = []
    for m in re.finditer(r"\buse\s+([^;]*);", code, re.S):
        line = code.count("\n", 0, m.start()) + 1
        for p in expand(m.group(1)):
            p = re.sub(r"\s+as\s+" + IDENT + "$", "", p.strip())
            found.append((line, re.sub(r"\s+", "", p)))
    return found


class Crate:
    def __init__(self, src, docs):
        self.src = src
        self.files = {}
        for root, _, names in os.walk(src):
            for n in sorted(names):
                if n.endswith(".rs"):
                    f = os.path.join(root, n)
                    self.files[module_of(src, f)] = f
        self.code = {m: strip(open(f).read(), docs) for m, f in self.files.items()}
        self.raw_code = {m: strip(open(f).read(), False) for m, f in self.files.items()}
        # Re-exports: module -> {name: absolute path it stands for}.
        self.reexports = defaultdict(dict)
        for m, code in self.raw_code.items():
            for _, p in uses("\n".join(l for l in code.split("\n") if re.match(r"\s*pub(\(crate\))?\s+use\b", l))):
                absolute = self.absolute(m, p)
                if absolute:
                    name = absolute[-1] if absolute[-1] not in ("self",) else absolute[-2]
                    self.reexports[m][name] = absolute

    def absolute(self, module, path):
        """Absolute segments of a path written in `module` (crate::, super::, self::, or a
        child module's name), or None for an outside crate."""
        segs = path.split("::")
        if segs[0] == "crate":
            return tuple(segs[1:])
        base = list(module)
        if segs[0] in ("super", "self"):
            while segs and segs[0] in ("super", "self"):
                if segs[0] == "super":
                    base = base[:-1]
                segs = segs[1:]
            return tuple(base + segs)
        if tuple(base + segs[:1]) in self.files:
            return tuple(base + segs)
        return None

    def resolve(self, segs, seen=0):
        """The module (file) that defines the item at absolute path `segs`."""
        mod = ()
        for i, s in enumerate(segs):
            if mod + (s,) in self.files:
                mod = mod + (s,)
                continue
            if s in self.reexports.get(mod, {}) and seen < 8:
                target = self.reexports[mod][s]
                return self.resolve(tuple(target) + tuple(segs[i + 1 :]), seen + 1)
            break
        return mod

    def arrows(self, skip_tests=False):
        """{(from, to): is_test_only}."""
        edges = {}
        for m, code in self.code.items():
            test_from = None
            for i, line in enumerate(code.split("\n")):
                if re.match(r"\s*#\[cfg\(test\)\]", line):
                    test_from = i + 1
                    break
            refs = uses(code)
            for mm in PATH_RE.finditer(code):
                refs.append((code.count("\n", 0, mm.start()) + 1, mm.group(0)))
            for line, p in refs:
                is_test = test_from is not None and line >= test_from
                if is_test and p.startswith("super"):
                    # Inside the file's `mod tests`: `super` is the file itself.
                    p = "self" + p[len("super"):]
                a = self.absolute(m, p)
                if a is None:
                    continue
                target = self.resolve(a)
                # A module using itself or its own files (a folder's mod.rs re-exporting them,
                # the crate root's map) is no arrow.
                if target[: len(m)] == m:
                    continue
                if is_test and skip_tests:
                    continue
                key = (m, target)
                edges[key] = edges.get(key, True) and is_test
        return edges


def name(m):
    return "::".join(m) if m else "lib"


def sccs(nodes, edges):
    """Strongly connected components (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    adj = defaultdict(list)
    for a, b in edges:
        adj[a].append(b)
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in adj[v]:
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
            out.append(comp)

    sys.setrecursionlimit(10000)
    for v in nodes:
        if v not in index:
            visit(v)
    return [c for c in out if len(c) > 1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("src", help="the crate's src/ folder")
    ap.add_argument("--layers", help="top-level modules lowest first, layers separated by |")
    ap.add_argument("--docs", action="store_true", help="count paths in doc comments too")
    ap.add_argument("--no-tests", action="store_true", help="leave out test code")
    ap.add_argument("--quiet", action="store_true", help="only the summary")
    args = ap.parse_args()

    crate = Crate(args.src, args.docs)
    edges = crate.arrows(args.no_tests)
    files = sorted(crate.files)
    group = lambda m: m[0] if m else "lib"

    if not args.quiet:
        print(f"files ({len(files)}):")
        for m in files:
            print(f"  {name(m)}  [{os.path.relpath(crate.files[m], args.src)}]")
        print(f"arrows ({len(edges)}):")
        for (a, b), test in sorted(edges.items()):
            print(f"  {name(a)} -> {name(b)}{'  (test)' if test else ''}")

    bad = False
    file_cycles = sccs(files, edges)
    group_edges = {(group(a), group(b)) for (a, b) in edges if group(a) != group(b)}
    group_cycles = sccs(sorted({group(m) for m in files}), group_edges)
    print(f"summary: {len(files)} files, {len(edges)} arrows "
          f"({sum(1 for t in edges.values() if t)} from test code only)")
    for c in file_cycles:
        bad = True
        print(f"CIRCLE of {len(c)} files: {', '.join(sorted(name(m) for m in c))}")
    for c in group_cycles:
        bad = True
        print(f"CIRCLE of {len(c)} top-level modules: {', '.join(sorted(c))}")
    if not file_cycles and not group_cycles:
        print("no circle (files and top-level modules)")

    if args.layers:
        layer = {}
        for i, part in enumerate(args.layers.split("|")):
            for g in part.split():
                layer[g] = i
        missing = sorted({group(m) for m in files} - set(layer) - {"lib"})
        if missing:
            print(f"not in any layer: {', '.join(missing)}")
            bad = True
        up = [(a, b, t) for (a, b), t in sorted(edges.items())
              if group(a) in layer and group(b) in layer and layer[group(a)] < layer[group(b)]]
        for a, b, t in up:
            print(f"UPWARD {name(a)} -> {name(b)}{'  (test)' if t else ''}")
        to_root = [(a, b) for (a, b) in edges if b == ()]
        for a, _ in sorted(to_root):
            print(f"UPWARD {name(a)} -> lib (the crate root)")
        print(f"{len(up) + len(to_root)} upward arrows against the layers: {args.layers}")
        bad |= bool(up or to_root)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
