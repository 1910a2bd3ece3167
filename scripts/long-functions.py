#!/usr/bin/env python3
"""Lists functions in non-test Rust code longer than a limit (default 150 lines).

Scans crates/*/src, crates/*/examples, crates/*/benches and benches/ (not tests/ directories),
skips items under `#[cfg(test)]` (test modules and test-only functions), and measures each
function from its `fn` line to its closing brace, inclusive. Braces are counted on the source
with comments, strings and character literals blanked out, so a `{` in a format string does not
count. Exit status 1 when any function is over the limit.

Usage: scripts/long-functions.py [LIMIT] [--all]   (--all: print every function's length)
"""
import glob
import os
import re
import sys

FN = re.compile(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)")


def blank(src):
    """The source with comments, strings and char literals replaced by spaces (newlines kept)."""
    out = []
    i, n = 0, len(src)
    while i < n:
        c = src[i]
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif src.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", src[i:j]))
            i = j
        elif (m := re.compile(r'b?r(#*)"').match(src, i)) and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            end = '"' + m.group(1)
            j = src.find(end, m.end())
            j = n if j < 0 else j + len(end)
            out.append(re.sub(r"[^\n]", " ", src[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            j += 1
            out.append(re.sub(r"[^\n]", " ", src[i:j]))
            i = j
        elif c == "'" and (m := re.compile(r"'(\\(x[0-9a-fA-F]{2}|u\{[0-9a-fA-F]+\}|.)|[^\\'\n])'").match(src, i)):
            out.append(" " * (m.end() - i))
            i = m.end()
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(path):
    """(name, first line, line count) of each function outside `#[cfg(test)]` items."""
    code = blank(open(path, encoding="utf-8").read())
    line_of = lambda pos: code.count("\n", 0, pos) + 1
    found = []
    depth = 0
    skip_until = None  # depth at which a #[cfg(test)] item ends
    pending_test = False
    open_fns = []  # (name, start pos, depth of its body)
    fn_wait = None  # a fn seen, waiting for its body's `{` (or `;` for a declaration)
    i = 0
    while i < len(code):
        if code.startswith("#[cfg(test)]", i):
            pending_test = True
            i += len("#[cfg(test)]")
            continue
        m = FN.match(code, i)
        if m and (i == 0 or not (code[i - 1].isalnum() or code[i - 1] == "_")):
            fn_wait = (m.group(1), i)
            i = m.end()
            continue
        c = code[i]
        if c == "{":
            depth += 1
            if pending_test and skip_until is None:
                skip_until = depth
            pending_test = False
            if fn_wait is not None:
                if skip_until is None:
                    open_fns.append((fn_wait[0], fn_wait[1], depth))
                fn_wait = None
        elif c == "}":
            if open_fns and open_fns[-1][2] == depth:
                name, start, _ = open_fns.pop()
                first = line_of(start)
                found.append((name, first, line_of(i) - first + 1))
            if skip_until == depth:
                skip_until = None
            depth -= 1
        elif c == ";":
            # A `;` ends a declaration without a body (a trait method), unless it sits inside
            # the signature's brackets (`[u8; 4]`), and ends a `#[cfg(test)] use …;`.
            if fn_wait is not None and not inside_brackets(code[fn_wait[1]:i]):
                fn_wait = None
            if not in_attr(code, i):
                pending_test = False
        i += 1
    return found


def inside_brackets(sig):
    """Whether the end of a signature is inside its parentheses or square brackets."""
    return sig.count("(") > sig.count(")") or sig.count("[") > sig.count("]")


def in_attr(code, pos):
    line_start = code.rfind("\n", 0, pos) + 1
    return code[line_start:pos].lstrip().startswith("#")


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    limit = int(args[0]) if args else 150
    show_all = "--all" in sys.argv
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    files = []
    for pattern in ("crates/*/src/**/*.rs", "crates/*/examples/**/*.rs", "crates/*/benches/**/*.rs", "benches/**/*.rs"):
        files += glob.glob(os.path.join(root, pattern), recursive=True)
    rows = []
    for f in sorted(set(files)):
        rel = os.path.relpath(f, root)
        if "/tests/" in "/" + rel:
            continue
        for name, first, length in functions(f):
            rows.append((length, rel, first, name))
    rows.sort(reverse=True)
    over = [r for r in rows if r[0] > limit]
    for length, rel, first, name in rows if show_all else over:
        print(f"{length:5} {rel}:{first} {name}")
    longest = rows[0] if rows else None
    print(f"{len(rows)} functions in {len(set(files))} files; {len(over)} over {limit} lines"
          + (f"; longest {longest[0]} ({longest[1]}:{longest[2]} {longest[3]})" if longest else ""))
    sys.exit(1 if over else 0)


if __name__ == "__main__":
    main()
