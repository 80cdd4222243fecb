#!/usr/bin/env python3
"""Checks the parts of aperture against their table (cmake/AperturePart.cmake).

A part may include its own headers, the headers of the parts the table lists for it, and what
those parts may include; a library header (APERTURE_PART_LIBRARIES) only from the part that
owns it and the parts that may include that one. Every .cpp and .h under core/, cameras/,
apps/, bench/measure/ and python/src/ belongs to a part, and a part's folder holds at most 20 of them.
docs/architecture.md lists the same arrows.

    check_parts.py [ROOT]          check the tree (exit 1 on any violation, each one listed)
    check_parts.py --self-test     show that a wrong-way include, a stray file, an overfull
                                   folder and a docs arrow unlike the table are each reported
"""
import os
import re
import sys

MAX_SOURCES = 20
SOURCE_ROOTS = ("core", "cameras", "apps", "bench/measure", "python/src")
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^">]+)[">]', re.M)


def cmake_list(text, name):
    """The quoted rows of `set(NAME "a: b c" ...)`, comments dropped."""
    block = re.search(r"set\(%s\s*\n(.*?)\n\)" % name, text, re.S)
    if not block:
        sys.exit("check_parts: %s not found in cmake/AperturePart.cmake" % name)
    rows = {}
    for line in block.group(1).splitlines():
        row = re.match(r'\s*"([^":]+):([^"]*)"', line)
        if row:
            rows[row.group(1).strip()] = row.group(2).split()
    return rows


def read_table(root):
    text = open(os.path.join(root, "cmake", "AperturePart.cmake")).read()
    return cmake_list(text, "APERTURE_PARTS"), cmake_list(text, "APERTURE_PART_LIBRARIES")


def visible_parts(parts):
    """For each part, the parts it may include: itself and the closure of its arrows."""
    seen = {}

    def closure(part):
        if part not in seen:
            seen[part] = {part}
            for dep in parts[part]:
                if dep not in parts:
                    sys.exit("check_parts: %s lists %s, which is not a part" % (part, dep))
                seen[part] |= closure(dep)
        return seen[part]

    for part in parts:
        closure(part)
    return seen


def part_of(path, parts):
    folder = os.path.dirname(path)
    return folder if folder in parts else None


def source_files(root):
    for top in SOURCE_ROOTS:
        for dirpath, _, names in os.walk(os.path.join(root, top)):
            for name in names:
                if name.endswith((".cpp", ".h")):
                    yield os.path.relpath(os.path.join(dirpath, name), root).replace(os.sep, "/")


def violations(files, parts, libraries):
    """files: {path: text}. Returns the list of messages."""
    visible = visible_parts(parts)
    found = []
    counts = {}
    for path, text in sorted(files.items()):
        part = part_of(path, parts)
        if part is None:
            found.append("%s: in no part (cmake/AperturePart.cmake lists the part folders)" % path)
            continue
        counts[part] = counts.get(part, 0) + 1
        for bracket, header in INCLUDE.findall(text):
            if bracket == '"':
                target = part_of(header, parts)
                if target is None and header.startswith(SOURCE_ROOTS):
                    found.append("%s includes %s, which is in no part" % (path, header))
                elif target is not None and target not in visible[part]:
                    found.append("%s includes %s: %s may not see %s" % (path, header, part, target))
            else:
                for prefix, owners in libraries.items():
                    if header.startswith(prefix) and not any(o in visible[part] for o in owners):
                        found.append("%s includes <%s>: only %s (and what may see it) may"
                                     % (path, header, " ".join(owners)))
    for part, count in sorted(counts.items()):
        if count > MAX_SOURCES:
            found.append("%s holds %d source files (at most %d): split it" % (part, count, MAX_SOURCES))
    return found


def documented_arrows(root):
    """The arrows docs/architecture.md lists ("A → B C" lines of its code block)."""
    text = open(os.path.join(root, "docs", "architecture.md"), encoding="utf-8").read()
    return {m.group(1): m.group(2).split() for m in re.finditer(r"^(\S+) → (.+)$", text, re.M)}


def arrow_differences(parts, documented):
    """Messages for each part whose arrows docs/architecture.md gives otherwise."""
    found = []
    for part in sorted(set(parts) | set(documented)):
        if parts.get(part, []) != documented.get(part, []) and (parts.get(part) or part in documented):
            found.append("docs/architecture.md: %s → %s, the table says %s" % (
                part, " ".join(documented.get(part, [])) or "(nothing)",
                " ".join(parts.get(part, [])) or "(nothing)"))
    return found


def read_tree(root):
    return {p: open(os.path.join(root, p), encoding="utf-8").read() for p in source_files(root)}


def self_test(root):
    parts, libraries = read_table(root)
    files = read_tree(root)
    clean = violations(files, parts, libraries)
    assert not clean, "the tree itself has violations:\n" + "\n".join(clean)

    wrong_way = dict(files)
    wrong_way["core/util/error.h"] += '\n#include "apps/cli/commands.h"\n'
    got = violations(wrong_way, parts, libraries)
    assert got == ["core/util/error.h includes apps/cli/commands.h: core/util may not see apps/cli"], got

    library = dict(files)
    library["apps/services/view.cpp"] += "\n#include <CLI/CLI.hpp>\n"
    got = violations(library, parts, libraries)
    assert len(got) == 1 and got[0].startswith("apps/services/view.cpp includes <CLI/CLI.hpp>"), got

    stray = dict(files)
    stray["core/stray.cpp"] = ""
    got = violations(stray, parts, libraries)
    assert got == ["core/stray.cpp: in no part (cmake/AperturePart.cmake lists the part folders)"], got

    full = dict(files)
    for k in range(MAX_SOURCES + 1):
        full["core/util/extra_%d.h" % k] = ""
    got = violations(full, parts, libraries)
    assert len(got) == 1 and got[0].startswith("core/util holds"), got
    documented = documented_arrows(root)
    assert not arrow_differences(parts, documented)
    documented["core/mesh"] = ["core/util"]
    got = arrow_differences(parts, documented)
    assert got == ["docs/architecture.md: core/mesh → core/util, the table says core/aov"], got
    print("check_parts self-test: a wrong-way include, a library header, a stray file, an "
          "overfull folder and an arrow the docs give otherwise are each reported")


def main():
    args = sys.argv[1:]
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if args and args[0] == "--self-test":
        self_test(args[1] if len(args) > 1 else here)
        return 0
    root = args[0] if args else here
    parts, libraries = read_table(root)
    found = violations(read_tree(root), parts, libraries)
    found += arrow_differences(parts, documented_arrows(root))
    for message in found:
        print(message)
    print("check_parts: %d parts, %d violations" % (len(parts), len(found)))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
