#!/usr/bin/env python3
"""No import circle in any crate: the house rule of ARCHITECTURE.md ("data flows one way"),
checked on the source, so a circle that comes back fails `./dev test`.

For every library crate of the workspace (the module tree under its `src/lib.rs`), a module is
a file (`a/b.rs` or `a/b/mod.rs` is module `a::b`; `lib.rs` is the root). Module M depends on
module N when M's code (its tests excluded: everything from the first `#[cfg(test)]` on) names
N through `crate::...` or `super::...`, in a `use` (braces expanded, `pub use` re-exports
included) or inline in an expression or type. A path names the deepest module it reaches
(`crate::a::b::Thing` names `a::b` when `a/b.rs` exists, else `a`). `mod x;` declarations are
not dependencies. A circle is any cycle in that graph, a module and its own parent included.

Usage: tools/module_graph.py [CRATE_DIR...]   (default: every crate with a src/lib.rs)
Prints each crate's verdict; exits 1 if any crate has a circle, naming its modules.
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def modules_of(src):
    """Module path (tuple) -> file, for the tree under src/."""
    found = {}
    for path in src.rglob('*.rs'):
        rel = path.relative_to(src).with_suffix('')
        parts = list(rel.parts)
        if parts[0] == 'bin':
            continue  # binaries are crates of their own
        if parts == ['lib']:
            parts = []
        elif parts == ['main']:
            continue
        elif parts[-1] == 'mod':
            parts = parts[:-1]
        found[tuple(parts)] = path
    return found


def strip(text):
    """The code without comments and string contents, up to the first `#[cfg(test)]`."""
    out, i, n = [], 0, len(text)
    while i < n:
        if text.startswith('#[cfg(test)]', i):
            break
        ch = text[i]
        if text.startswith('//', i):
            i = text.find('\n', i)
            i = n if i < 0 else i
        elif text.startswith('/*', i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith('/*', i):
                    depth, i = depth + 1, i + 2
                elif text.startswith('*/', i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif raw := re.match(r'b?r(#*)"', text[i : i + 260]) if ch in 'br' and (
            i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')
        ) else None:
            close = '"' + raw.group(1)
            end = text.find(close, i + raw.end())
            i = n if end < 0 else end + len(close)
            out.append('""')
        elif ch == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == '\\' else 1
            i += 1
            out.append('""')
        elif ch == "'" and re.match(r"'(\\.[^']*|[^'\\])'", text[i : i + 12]):
            i += len(re.match(r"'(\\.[^']*|[^'\\])'", text[i : i + 12]).group(0))
            out.append("' '")
        else:
            out.append(ch)
            i += 1
    return ''.join(out)


def expand(tree):
    """`a::{b, c::{d, e}}` -> ['a::b', 'a::c::d', 'a::c::e'] (whitespace removed)."""
    tree = re.sub(r'\s+as\s+\w+', '', tree)  # `a::b as c` names a::b
    tree = re.sub(r'\s+', '', tree)
    brace = tree.find('{')
    if brace < 0:
        return [tree]
    head, body = tree[:brace], tree[brace + 1 : tree.rfind('}')]
    items, depth, start = [], 0, 0
    for i, ch in enumerate(body):
        if ch == '{':
            depth += 1
        elif ch == '}':
            depth -= 1
        elif ch == ',' and depth == 0:
            items.append(body[start:i])
            start = i + 1
    items.append(body[start:])
    return [path for item in items if item for path in expand(head + item)]


def referenced_paths(code):
    """Every `crate::`/`super::`/`self::` path named in the code."""
    paths = []
    for m in re.finditer(r'\buse\s+([^;]+);', code):
        paths.extend(expand(m.group(1)))
    paths.extend(m.group(0) for m in re.finditer(r'\b(?:crate|super)(?:::\w+)+', code))
    return paths


def target(module, path, modules):
    """The deepest module a path from `module` names, or None (outside the crate)."""
    parts = path.split('::')
    if parts[0] == 'crate':
        base, rest = [], parts[1:]
    elif parts[0] in ('super', 'self'):
        base = list(module)
        rest = parts
        while rest and rest[0] in ('super', 'self'):
            if rest[0] == 'super':
                if not base:
                    return None
                base = base[:-1]
            rest = rest[1:]
    else:
        return None
    best = tuple(base)
    for part in rest:
        candidate = best + (part,)
        if candidate in modules:
            best = candidate
        else:
            break
    return best if best in modules else None


def circles(crate):
    src = crate / 'src'
    modules = modules_of(src)
    edges = {m: set() for m in modules}
    for module, file in modules.items():
        for path in referenced_paths(strip(file.read_text())):
            to = target(module, path, modules)
            if to is not None and to != module:
                edges[module].add(to)
    # Strongly connected components (Tarjan): any of more than one module is a circle.
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted('::'.join(m) or 'crate' for m in component))

    sys.setrecursionlimit(10000)
    for v in modules:
        if v not in index:
            visit(v)
    return len(modules), out


def main(args):
    crates = [Path(a).resolve() for a in args] or sorted(
        p.parent.parent for p in ROOT.glob('*/src/lib.rs')
    )
    failed = False
    for crate in crates:
        count, found = circles(crate)
        name = crate.relative_to(ROOT) if crate.is_relative_to(ROOT) else crate
        if found:
            failed = True
            for component in found:
                print(f'{name}: import circle among {", ".join(component)}')
        else:
            print(f'{name}: {count} modules, no import circle')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
