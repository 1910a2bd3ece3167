#!/usr/bin/env python3
"""Finds module cycles inside each crate of crates/*: two or more modules that use each other.

A module is a file of the crate's src/ (its root, lib.rs or main.rs, is not a module of the
graph: it declares them all). Module A uses module B when A's source, outside `#[cfg(test)]`
items, names B through the crate root or a parent: `crate::B`, `super::B`, `self::B` (in the
root), in a path or a `use` group (`use crate::{B::X, C}`), or names an item the root
re-exports from B (`crate::X` with `pub use B::X` in the root). Test-only modules (declared
under `#[cfg(test)]`) are left out. Comments, strings and character literals are blanked
first, so a path in a doc comment does not count.

Each cycle is printed as the modules of one strongly connected component, with one place
where each of its edges is named. Exit status 1 when a crate not allowed has a cycle.

Usage: scripts/module-cycles.py [--crate NAME]... [--allow NAME]... [CRATE_DIR]...
  --crate NAME   only this crate (directory name `load` or package name `bdpm-load`)
  --allow NAME   report this crate's cycles but do not fail on them
  CRATE_DIR      a crate's directory (crates/load), instead of --crate
"""
import glob
import importlib.util
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The comment/string blanking of scripts/long-functions.py, so both scripts read code alike.
_spec = importlib.util.spec_from_file_location(
    "long_functions", os.path.join(ROOT, "scripts", "long-functions.py"))
_long = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_long)
blank = _long.blank

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
PATH_START = re.compile(r"\b(crate|super|self)((?:\s*::\s*super)*)\s*::\s*")


def strip_test_items(code):
    """`code` with every `#[cfg(test)]` item (up to its `;` or its closing brace) blanked."""
    out = list(code)
    i = 0
    while True:
        i = code.find("#[cfg(test)]", i)
        if i < 0:
            return "".join(out)
        j = i + len("#[cfg(test)]")
        depth = 0
        while j < len(code):
            c = code[j]
            if c == "{":
                depth += 1
            elif c == "}":
                depth -= 1
                if depth == 0:
                    j += 1
                    break
            elif c == ";" and depth == 0:
                j += 1
                break
            j += 1
        for k in range(i, j):
            if out[k] != "\n":
                out[k] = " "
        i = j


def group_names(text, start):
    """The first name of each top-level entry of the `{…}` group opening at `start`, with the
    names each entry binds (`a::X as Y` binds Y, `a::{X, Y}` binds X and Y): a list of
    (first segment, bound names)."""
    depth, j = 0, start
    while j < len(text):
        if text[j] == "{":
            depth += 1
        elif text[j] == "}":
            depth -= 1
            if depth == 0:
                break
        j += 1
    inner = text[start + 1:j]
    entries, depth, cur = [], 0, ""
    for c in inner:
        if c == "," and depth == 0:
            entries.append(cur)
            cur = ""
            continue
        depth += c == "{"
        depth -= c == "}"
        cur += c
    entries.append(cur)
    out = []
    for e in entries:
        e = " ".join(e.split())
        m = re.match(IDENT, e)
        if not m:
            continue
        if "{" in e:
            bound = re.findall(IDENT + r"(?=\s*(?:,|\}|$| as ))", e[e.index("{"):])
        else:
            alias = re.search(r"\bas\s+(" + IDENT + r")\s*$", e)
            bound = [alias.group(1) if alias else e.split("::")[-1].strip()]
        out.append((m.group(0), bound))
    return out


def references(code):
    """(position, number of `super`s, first name) of each `crate::`/`super::`/`self::` path,
    one per entry of a `{…}` group."""
    refs = []
    for m in PATH_START.finditer(code):
        supers = (1 if m.group(1) == "super" else 0) + m.group(2).count("super")
        kind = "self" if m.group(1) == "self" and not supers else ("crate" if m.group(1) == "crate" else "super")
        rest = m.end()
        if rest < len(code) and code[rest] == "{":
            for first, _ in group_names(code, rest):
                refs.append((m.start(), kind, supers, first))
        else:
            n = re.match(IDENT, code[rest:])
            if n:
                refs.append((m.start(), kind, supers, n.group(0)))
    return refs


def inline_depth(code, pos):
    """How many inline `mod NAME {` blocks enclose `pos`."""
    depth, stack = 0, []
    for m in re.finditer(r"\bmod\s+" + IDENT + r"\s*\{|[{}]", code[:pos]):
        t = m.group(0)
        if t == "{" or t.startswith("mod"):
            stack.append(t.startswith("mod"))
        elif stack:
            stack.pop()
        depth = sum(stack)
    return depth


def root_exports(code, modules):
    """Items the root re-exports from its modules: name -> module (`pub use m::{X, Y}`)."""
    out = {}
    for m in re.finditer(r"\buse\s+(?:(?:crate|self)\s*::\s*)?(" + IDENT + r")\s*::\s*", code):
        module = m.group(1)
        if module not in modules:
            continue
        rest = m.end()
        if code[rest:rest + 1] == "{":
            for _, bound in group_names(code, rest):
                for b in bound:
                    out[b] = module
        else:
            tail = re.match(r"[^;]*", code[rest:]).group(0)
            alias = re.search(r"\bas\s+(" + IDENT + r")\s*$", tail.strip())
            out[alias.group(1) if alias else tail.split("::")[-1].strip()] = module
    return out


def crate_graph(src):
    """(modules, edges) of the crate whose source folder is `src`: edges map (a, b) to the
    first line of a that names b."""
    root_file = next((os.path.join(src, f) for f in ("lib.rs", "main.rs")
                      if os.path.exists(os.path.join(src, f))), None)
    if root_file is None:
        return [], {}
    root_code = blank(open(root_file, encoding="utf-8").read())
    test_only = set(re.findall(r"#\[cfg\(test\)\]\s*(?:pub(?:\([a-z]+\))?\s+)?mod\s+(" + IDENT + r")\s*;", root_code))
    files = sorted(glob.glob(os.path.join(src, "*.rs")))
    modules = [os.path.basename(f)[:-3] for f in files
               if os.path.basename(f) not in ("lib.rs", "main.rs")]
    modules = [m for m in modules if m not in test_only]
    exports = root_exports(strip_test_items(root_code), set(modules))
    edges = {}
    for module in modules:
        code = strip_test_items(blank(open(os.path.join(src, module + ".rs"), encoding="utf-8").read()))
        for pos, kind, supers, name in references(code):
            if kind == "self":
                continue  # a file module's own items or inline submodules
            if kind == "super" and supers <= inline_depth(code, pos):
                continue  # an inline module's parent: this same file
            target = name if name in modules else exports.get(name)
            if target and target != module:
                edges.setdefault((module, target), code.count("\n", 0, pos) + 1)
    return modules, edges


def cycles(modules, edges):
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    succ = {m: sorted(b for (a, b) in edges if a == m) for m in modules}
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in succ[v]:
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

    for m in modules:
        if m not in index:
            visit(m)
    return sorted(out)


def package_name(crate_dir):
    try:
        text = open(os.path.join(crate_dir, "Cargo.toml"), encoding="utf-8").read()
    except OSError:
        return None
    m = re.search(r'^name\s*=\s*"([^"]+)"', text, re.M)
    return m.group(1) if m else None


def main():
    argv = sys.argv[1:]
    wanted, allowed, dirs = set(), set(), []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("--crate", "--allow") and i + 1 < len(argv):
            (wanted if a == "--crate" else allowed).add(argv[i + 1])
            i += 2
            continue
        if a in ("-h", "--help"):
            print(__doc__)
            return 0
        if a.startswith("-"):
            print(f"unknown argument {a}\n{__doc__}", file=sys.stderr)
            return 2
        dirs.append(os.path.abspath(a))
        i += 1
    if not dirs:
        dirs = sorted(d for d in glob.glob(os.path.join(ROOT, "crates", "*")) if os.path.isdir(d))
    failed = found = 0
    for d in dirs:
        src = d if os.path.basename(d) == "src" else os.path.join(d, "src")
        crate_dir = os.path.dirname(src)
        names = {os.path.basename(crate_dir), package_name(crate_dir)}
        if wanted and not names & wanted:
            continue
        if not os.path.isdir(src):
            print(f"{d}: no src/ folder", file=sys.stderr)
            return 2
        found += 1
        modules, edges = crate_graph(src)
        label = package_name(crate_dir) or os.path.basename(crate_dir)
        rel = os.path.relpath(src, ROOT)
        comps = cycles(modules, edges)
        allow = bool(names & allowed)
        for comp in comps:
            tag = "allowed cycle" if allow else "cycle"
            print(f"{label}: {tag}: {' <-> '.join(m + '.rs' for m in comp)}")
            for (a, b), line in sorted(edges.items()):
                if a in comp and b in comp:
                    print(f"    {rel}/{a}.rs:{line} uses {b}")
        if comps and not allow:
            failed += 1
    if wanted and not found:
        print(f"no crate named {', '.join(sorted(wanted))}", file=sys.stderr)
        return 2
    outside = " outside the allowed crates" if allowed else ""
    if failed:
        print(f"{found} crates; {failed} with module cycles{outside}")
    else:
        print(f"{found} crates; no module cycles{outside}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
