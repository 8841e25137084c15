#!/usr/bin/env python3
"""The workspace's import graph: which module of a crate uses which.

Usage: python3 tools/imports.py [--check] [--mermaid CRATE] [ROOT]

Reads every workspace member's `src/` (production code only: a module
block under `#[cfg(test)]` or `#[cfg(any(test, kani))]` and the `tests`
module are skipped, as are comments), resolves each `crate::`, `super::`
and `self::` path (in `use` trees and in code) to the module file that
defines it, and prints per crate:

- the import circles between files (strongly connected components of
  the file graph: `a.rs` uses `b.rs`, which uses `a.rs`), and
- the import circles between top-level modules (every file under
  `estimation/` counts as `estimation`), which a file graph can miss.

A `mod` declaration and a `pub use` re-export are not uses: a parent that
only declares its children and re-exports their items does not depend on
them. `--check` exits 1 when any crate has a circle; `--mermaid CRATE`
prints the crate's top-level module graph as a Mermaid flowchart (the
README's architecture section shows the kernel's).
"""

import re
import sys
from pathlib import Path

CFG_TEST = re.compile(r"#\[cfg\((test|any\(test,\s*kani\)|kani)\)\]")


def members(root):
    text = (root / "Cargo.toml").read_text()
    block = re.search(r"members\s*=\s*\[([^\]]*)\]", text).group(1)
    return [m for m in re.findall(r'"([^"]+)"', block)]


def crate_name(path):
    text = (path / "Cargo.toml").read_text()
    return re.search(r'^name\s*=\s*"([^"]+)"', text, re.M).group(1)


def strip_comments(src):
    src = re.sub(r"/\*.*?\*/", "", src, flags=re.S)
    out = []
    for line in src.splitlines():
        # Strings may hold `//` (URLs); drop string literals first.
        line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
        out.append(line.split("//")[0])
    return out


def production_lines(src):
    """The lines outside test- and proof-only module blocks."""
    lines = strip_comments(src)
    keep, skip_depth, depth, pending = [], None, 0, False
    for line in lines:
        if skip_depth is None and CFG_TEST.search(line):
            pending = True
        opening = line.count("{")
        closing = line.count("}")
        if skip_depth is None and pending and re.search(r"\bmod\s+\w+\s*\{", line):
            skip_depth = depth
            pending = False
        elif skip_depth is None and pending and re.search(r"\bmod\s+\w+\s*;", line):
            pending = False
            # `#[cfg(test)] mod tests;` in another file: that file is skipped.
            keep.append("//testmod " + re.search(r"\bmod\s+(\w+)", line).group(1))
            depth += opening - closing
            continue
        elif pending and line.strip() and not line.strip().startswith("#"):
            pending = False
        depth += opening - closing
        if skip_depth is None:
            keep.append(line)
        elif depth <= skip_depth:
            skip_depth = None
    return keep


def module_files(src_dir):
    """Module path (tuple) → file, for a crate's src/ tree."""
    mods = {}
    for f in sorted(src_dir.rglob("*.rs")):
        rel = f.relative_to(src_dir)
        parts = list(rel.parts)
        if parts[0] == "bin":
            continue
        if parts[-1] in ("lib.rs", "main.rs") and len(parts) == 1:
            mods[()] = f
            continue
        parts[-1] = parts[-1][:-3]
        if parts[-1] == "mod":
            parts = parts[:-1]
        mods[tuple(parts)] = f
    return mods


def use_paths(text):
    """Every path a `use` tree in `text` names, as segment lists."""
    out = []

    def expand(prefix, tree):
        tree = tree.strip()
        if not tree:
            return
        m = re.match(r"^([\w:]*?)::\{(.*)\}$", tree, re.S)
        if m or tree.startswith("{"):
            head = m.group(1) if m else ""
            inner = m.group(2) if m else tree[1:-1]
            depth, cur, items = 0, "", []
            for ch in inner:
                if ch == "{":
                    depth += 1
                elif ch == "}":
                    depth -= 1
                if ch == "," and depth == 0:
                    items.append(cur)
                    cur = ""
                else:
                    cur += ch
            items.append(cur)
            base = prefix + ([s for s in head.split("::") if s] if head else [])
            for it in items:
                expand(base, it)
            return
        tree = re.sub(r"\s+as\s+\w+$", "", tree)
        out.append(prefix + [s for s in tree.split("::") if s])

    for m in re.finditer(r"\buse\s+([^;]+);", text, re.S):
        expand([], re.sub(r"\s+", "", m.group(1)) if "{" in m.group(1) else m.group(1).strip())
    return out


def resolve(segs, here, mods):
    """The module a path from module `here` lands in, or None if external."""
    if not segs:
        return None
    if segs[0] == "crate":
        base, rest = (), segs[1:]
    elif segs[0] == "super":
        # `super` of a file module a/b.rs (module a::b) is a.
        base, rest = here[:-1], segs[1:]
        while rest and rest[0] == "super":
            base, rest = base[:-1], rest[1:]
    elif segs[0] == "self":
        base, rest = here, segs[1:]
    else:
        return None
    target = base
    for s in rest:
        if target + (s,) in mods:
            target = target + (s,)
        else:
            break
    return target


def crate_graph(src_dir):
    mods = module_files(src_dir)
    edges = {m: set() for m in mods}
    test_only = set()
    for mod, f in list(mods.items()):
        for l in production_lines(f.read_text()):
            if l.startswith("//testmod"):
                test_only.add(mod + (l.split()[1],))
    for mod in test_only:
        mods.pop(mod, None)
        edges.pop(mod, None)
    for mod, f in mods.items():
        lines = production_lines(f.read_text())
        text = "\n".join(l for l in lines if not l.startswith("//testmod"))
        # Re-exports and module declarations are structure, not use.
        uses_text = re.sub(r"\bpub(\([^)]*\))?\s+use\s+[^;]+;", "", text, flags=re.S)
        paths = use_paths(uses_text)
        code = re.sub(r"\buse\s+[^;]+;", "", uses_text, flags=re.S)
        paths += [p.split("::") for p in re.findall(r"\b(?:crate|super|self)(?:::\w+)+", code)]
        for segs in paths:
            t = resolve(segs, mod, mods)
            if t is not None and t != mod and t in mods:
                edges[mod].add(t)
    for m in list(edges):
        if m not in mods:
            del edges[m]
    return mods, edges


def sccs(edges):
    """Tarjan's strongly connected components, iteratively."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            advanced = False
            for w in it:
                if w not in edges:
                    continue
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                    advanced = True
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
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
    return out


def name(mod):
    return "::".join(mod) if mod else "(root)"


def top_level(edges):
    top = {}
    for a, bs in edges.items():
        if not a:
            continue
        ta = a[:1]
        top.setdefault(ta, set())
        for b in bs:
            if b and b[:1] != ta:
                top[ta].add(b[:1])
    return top


def main(argv):
    check = "--check" in argv
    mermaid = argv[argv.index("--mermaid") + 1] if "--mermaid" in argv else None
    rest = [a for i, a in enumerate(argv) if not a.startswith("--") and (i == 0 or argv[i - 1] != "--mermaid")]
    root = Path(rest[0]) if rest else Path(__file__).resolve().parent.parent
    circles = 0
    for member in members(root):
        path = root / member
        crate = crate_name(path)
        mods, edges = crate_graph(path / "src")
        if mermaid == crate:
            print("flowchart LR")
            for a, bs in sorted(top_level(edges).items()):
                for b in sorted(bs):
                    print(f"  {a[0]} --> {b[0]}")
            return 0
        files = sccs(edges)
        tops = sccs(top_level(edges))
        n_edges = sum(len(v) for v in edges.values())
        if mermaid:
            continue
        print(f"{crate}: {len(mods)} modules, {n_edges} imports, "
              f"{len(files)} file circle(s), {len(tops)} top-level circle(s)")
        for comp in files:
            print("  file circle: " + " ↔ ".join(name(m) for m in comp))
        for comp in tops:
            print("  top-level circle: " + " ↔ ".join(name(m) for m in comp))
        circles += len(files) + len(tops)
    if mermaid:
        print(f"no workspace crate named {mermaid}", file=sys.stderr)
        return 2
    if check and circles:
        print(f"{circles} import circle(s)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
