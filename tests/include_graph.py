#!/usr/bin/python3
"""The engine's include graph: every #include points down the layers (docs/ARCHITECTURE.md §2),
and no two files include each other, directly or through others (a file is its .h and .cpp).
Also checks the checker on a hand-made graph with a cycle and an upward include."""
import os
import re
import sys
from pathlib import Path

# What each folder may include (its own files and the layers below it).
ALLOWED = {
    "kernels": {"kernels"},
    "probes": {"probes", "kernels"},
    "datasets": {"datasets", "kernels"},
    "engine": {"engine", "datasets", "kernels"},
    "results": {"results", "datasets", "kernels", "probes"},
    "experiment": {"experiment", "engine", "datasets", "kernels", "results", "probes"},
    "jobs": {"jobs", "experiment", "engine", "datasets", "kernels", "results", "probes"},
    "app": {"app", "jobs", "experiment", "engine", "datasets", "kernels", "results", "probes"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def graph_of(files):
    """files: {path: text} → {component: {components it includes}} (component = path minus
    extension), only includes of the engine's folders."""
    g = {}
    for path, text in files.items():
        comp = path.rsplit(".", 1)[0]
        deps = g.setdefault(comp, set())
        for inc in INCLUDE.findall(text):
            if Path(inc).parts[0] in ALLOWED and inc.rsplit(".", 1)[0] != comp:
                deps.add(inc.rsplit(".", 1)[0])
    return g


def upward(files):
    bad = []
    for path, text in files.items():
        folder = Path(path).parts[0]
        for inc in INCLUDE.findall(text):
            target = Path(inc).parts[0]
            if target in ALLOWED and target not in ALLOWED[folder]:
                bad.append(f"{path} includes {inc} ({folder} may not include {target})")
    return bad


def cycles(g):
    """Strongly connected components of more than one component (Tarjan, iterative)."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in sorted(g):
        if root in index:
            continue
        work = [(root, iter(sorted(g.get(root, ()))))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(g.get(w, ())))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
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


def main():
    # The checker itself, on a graph made by hand: a → b → c → a is one cycle, d → a none;
    # engine/x.h including jobs/y.h points up.
    toy = {"jobs/a.h": '#include "jobs/b.h"', "jobs/b.cpp": '#include "jobs/c.h"',
           "jobs/c.h": '#include "jobs/a.h"\n#include "kernels/k.h"', "jobs/d.cpp": '#include "jobs/a.h"',
           "engine/x.h": '#include "jobs/y.h"'}
    assert cycles(graph_of(toy)) == [["jobs/a", "jobs/b", "jobs/c"]], cycles(graph_of(toy))
    assert upward(toy) == ["engine/x.h includes jobs/y.h (engine may not include jobs)"], upward(toy)

    root = Path(os.environ.get("SIRL_SOURCE_DIR", Path(__file__).resolve().parent.parent))
    files = {}
    for folder in ALLOWED:
        for p in sorted((root / folder).glob("*")):
            if p.suffix in (".h", ".cpp"):
                files[f"{folder}/{p.name}"] = p.read_text(encoding="utf-8")
    assert len(files) > 100, f"only {len(files)} source files under {root}"
    problems = upward(files) + [f"include cycle: {' → '.join(c)}" for c in cycles(graph_of(files))]
    for p in problems:
        print(p)
    if problems:
        sys.exit(1)
    print(f"{len(files)} files: every include points down the layers, no include cycle")


if __name__ == "__main__":
    main()
