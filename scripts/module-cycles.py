#!/usr/bin/env python3
"""Finds import cycles between the source files of a crate.

Each file is a module (src/a/b.rs and src/a/b/mod.rs are `a::b`). A file depends on another
when it names an item of it: `crate::a::b…`, `super::…`, `self::…` or a child module declared
with `mod`. Declaring a child module (`mod x;`) is not a dependency; naming its items is.
Tests (`#[cfg(test)]` modules in their own files) are left out: they may use everything.

    scripts/module-cycles.py CRATE_DIR...

Prints the cycles found (one per line, as module paths) and exits 1 if there is any.
"""
import os
import re
import sys


def modules(src):
    mods = {}
    for root, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            path = os.path.join(root, f)
            rel = os.path.relpath(path, src)[:-3].split(os.sep)
            if rel[-1] in ("mod", "lib", "main"):
                rel = rel[:-1]
            if rel and rel[-1] == "tests":
                continue
            mods["::".join(rel)] = path
    return mods


def strip_tests(text):
    # Drop inline `#[cfg(test)] mod tests { ... }` blocks (to the end of the file: they come last).
    m = re.search(r"#\[cfg\(test\)\]\s*mod \w+\s*\{", text)
    return text[: m.start()] if m else text


def inline_depth(text):
    """For each offset, how many inline `mod name { … }` blocks enclose it."""
    depth = [0] * (len(text) + 1)
    for m in re.finditer(r"\bmod \w+\s*\{", text):
        level, i = 1, m.end()
        while i < len(text) and level:
            level += {"{": 1, "}": -1}.get(text[i], 0)
            i += 1
        for j in range(m.end(), i):
            depth[j] += 1
    return depth


def deps(mod, text, mods):
    text = strip_tests(re.sub(r"//[^\n]*", "", text))
    depth = inline_depth(text)
    parts = mod.split("::") if mod else []
    found = set()
    is_dir = True  # resolved below per reference kind

    def resolve(path):
        # The longest prefix of `path` that is a module.
        for n in range(len(path), 0, -1):
            cand = "::".join(path[:n])
            if cand in mods:
                return cand
        return None

    for m in re.finditer(r"\bcrate((?:::\w+)+)", text):
        target = resolve(m.group(1).strip(":").split("::"))
        if target is not None:
            found.add(target)
    for m in re.finditer(r"\b((?:super::)+)((?:\w+::)*\w+)", text):
        # In an inline module, `super` is first the enclosing modules of the same file.
        ups = m.group(1).count("super::") - depth[m.start()]
        if ups <= 0:
            continue
        base = parts[: len(parts) - ups] if ups <= len(parts) else []
        target = resolve(base + m.group(2).split("::")) or ("::".join(base) if "::".join(base) in mods else None)
        if target is not None:
            found.add(target)
    # `use super::{a, b}` groups
    for m in re.finditer(r"\buse ((?:super::)+)\{([^}]*)\}", text):
        ups = m.group(1).count("super::") - depth[m.start()]
        if ups <= 0:
            continue
        base = parts[: len(parts) - ups]
        for item in m.group(2).split(","):
            item = item.strip().split(" as ")[0]
            if not item:
                continue
            target = resolve(base + item.split("::")) or ("::".join(base) if "::".join(base) in mods else None)
            if target is not None:
                found.add(target)
    # Items of declared child modules named by path (`child::Item`).
    for m in re.finditer(r"(?:^|[^:\w])(\w+)::\w+", text):
        child = "::".join(parts + [m.group(1)])
        if child in mods:
            found.add(child)
    found.discard(mod)
    return found


def cycles(graph):
    seen, stack, onstack, out = set(), [], set(), []

    def visit(n):
        seen.add(n)
        stack.append(n)
        onstack.add(n)
        for d in sorted(graph.get(n, ())):
            if d in onstack:
                out.append(stack[stack.index(d):] + [d])
            elif d not in seen:
                visit(d)
        stack.pop()
        onstack.discard(n)

    for n in sorted(graph):
        if n not in seen:
            visit(n)
    return out


def main():
    bad = False
    for crate in sys.argv[1:]:
        src = os.path.join(crate, "src")
        mods = modules(src)
        graph = {m: deps(m, open(p, encoding="utf-8").read(), mods) for m, p in mods.items()}
        for c in cycles(graph):
            bad = True
            print(f"{crate}: " + " -> ".join(x or "(root)" for x in c))
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
