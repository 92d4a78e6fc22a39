#!/usr/bin/env python3
"""The folder layering of the project, checked (docs/ARCHITECTURE.md, "Layout").

    python3 scripts/check_layers.py [ROOT]      check the tree at ROOT (default: the current folder)
    python3 scripts/check_layers.py --self-test  check that each rule catches a planted fault

The library folders form a strict order, bottom first (LAYERS). A file in a layered folder may
include ("X/...") only its own folder or a folder below it. Programs (TOP: apps, bindings,
tests, fuzz) sit above every layer and may include any of them. The checks, each failing the run
(exit 1) with file:line where there is one:

  1. an include of a higher layer, a program folder or an unknown folder of the tree;
  2. two folders that include each other;
  3. a namespace that does not match the folder: the core folders (CORE) declare `mppi` and
     helpers nested in it (mppi::detail, mppi::models, ...); every other layer X declares
     mppi::X or a namespace nested in it (`namespace mppi { namespace X {` counts). Anonymous
     namespaces are free, and so are the namespaces of third-party libraries (THIRD_PARTY),
     e.g. for a YAML::convert specialisation. Programs are free;
  4. two source files in the layered folders with the same name (two effects.hpp), wherever
     they are.

Python 3 standard library only.
"""
import collections
import os
import re
import sys
import tempfile

# Bottom first. A folder may include only folders strictly before it in this list, or itself.
LAYERS = ['base', 'mppi', 'dynamics', 'costs', 'factory', 'vulkan', 'plot', 'chassis', 'sim', 'laptime',
          'cli', 'ocs', 'sysid', 'evidence', 'diagnose', 'ros']
# Programs: above every layer, may include any layer (and each other's local headers).
TOP = ['apps', 'bindings', 'tests', 'fuzz']
# Folders whose code is in namespace mppi itself (and helpers nested in it).
CORE = {'base', 'mppi', 'dynamics', 'costs', 'factory'}
# Namespaces of libraries the code may open to specialise or forward-declare their names.
THIRD_PARTY = {'std', 'YAML', 'httplib', 'nlohmann', 'Eigen', 'CLI', 'pybind11', 'cv', 'tbb',
               'Catch', 'benchmark'}
SOURCE_EXT = ('.hpp', '.cpp', '.h', '.glsl', '.comp')
CXX_EXT = ('.hpp', '.cpp', '.h')
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def source_files(root, folder):
    base = os.path.join(root, folder)
    for dirpath, dirnames, filenames in os.walk(base):
        dirnames[:] = sorted(d for d in dirnames if d not in ('node_modules',) and not d.startswith('.'))
        for name in sorted(filenames):
            if name.endswith(SOURCE_EXT):
                path = os.path.join(dirpath, name)
                yield os.path.relpath(path, root).replace(os.sep, '/')


def tree_folders(root):
    return {d for d in os.listdir(root) if os.path.isdir(os.path.join(root, d)) and not d.startswith('.')}


# ---- namespaces ---------------------------------------------------------------------------------
RAW = re.compile(r'(?:u8|u|U|L)?R"([^()\\\s]{0,16})\(')


def strip_code(text):
    """The text with comments, string and character literals and preprocessor lines blanked
    (newlines kept, so that offsets still give line numbers)."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in ' \t':
            out.append(c)
            i += 1
            continue
        if line_start and c == '#':  # a preprocessor line, with its continuations
            j = i
            while j < n and text[j] != '\n':
                if text[j] == '\\' and j + 1 < n and text[j + 1] == '\n':
                    j += 2
                    continue
                j += 1
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
            continue
        line_start = False
        if c == '\n':
            line_start = True
            out.append(c)
            i += 1
        elif text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            out.append(' ' * (j - i))
            i = j
        elif text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif RAW.match(text, i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            m = RAW.match(text, i)
            end = text.find(')' + m.group(1) + '"', m.end())
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif c in '"\'':
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(' ')  # a digit separator: 1'000'000
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != '\n':
                j += 2 if text[j] == '\\' else 1
            j = min(j + 1, n)
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return ''.join(out)


TOKEN = re.compile(r'\b(?:inline\s+)?namespace\s+((?:inline\s+)?[A-Za-z_]\w*(?:\s*::\s*(?:inline\s+)?[A-Za-z_]\w*)*)?\s*\{'
                   r'|(\{)|(\})|\w+|[^\w\s{}]')


FORWARD = re.compile(r'(?:template\s*<[^;{}]*>\s*)?(?:class|struct|union|enum(?:\s+class|\s+struct)?)\s+\w+'
                     r'(?:\s*:\s*[\w:]+)?')


def namespaces(text):
    """Yield (line, full name as a list of parts, forward declarations only) for every namespace
    opened at namespace scope; an anonymous one and what is inside it are left out. The third is
    true when the namespace's own content (its nested namespaces aside) is nothing but forward
    declarations (class X; struct Y; enum class Z : int;)."""
    code = strip_code(text)
    stack = []  # entries: [kind, parts, line, tokens or None]; kind 'ns', 'anon' or 'block'
    found = []

    def content(tok):
        if stack and stack[-1][0] == 'ns' and stack[-1][3] is not None:
            stack[-1][3].append(tok)

    for m in TOKEN.finditer(code):
        tok = m.group(0)
        if tok.startswith(('namespace', 'inline')) and tok.endswith('{'):
            line = code.count('\n', 0, m.start()) + 1
            if m.group(1) is None and stack and stack[-1][0] == 'ns':
                stack[-1][3] = None  # an anonymous namespace is content of the one around it
            if m.group(1) is None or any(e[0] != 'ns' for e in stack):
                stack.append(['anon' if m.group(1) is None else 'block', None, line, None])
                continue
            parts = [re.sub(r'^inline\s+', '', p.strip()) for p in m.group(1).split('::')]
            outer = stack[-1][1] if stack else []
            entry = ['ns', outer + parts, line, []]
            stack.append(entry)
            found.append(entry)
        elif m.group(2):
            if stack and stack[-1][0] == 'ns':
                stack[-1][3] = None
            stack.append(['block', None, 0, None])
        elif m.group(3):
            if stack:
                stack.pop()
        else:
            content(tok)
    result = []
    for line, parts, tokens in ((e[2], e[1], e[3]) for e in found):
        forward = tokens is not None and all(
            FORWARD.fullmatch(statement.strip()) for statement in ' '.join(tokens).split(';')
            if statement.strip())
        result.append((line, parts, forward))
    return result


def namespace_problems(path, text, folder):
    """Messages for the namespaces of one file in the layered folder `folder`."""
    problems = []
    if not path.endswith(CXX_EXT):
        return problems
    rank = {f: i for i, f in enumerate(LAYERS)}
    other_layers = set(LAYERS) - CORE

    def owner(parts):  # the layer whose namespace this is (None: not the project's)
        if parts[0] != 'mppi':
            return None
        return parts[1] if len(parts) > 1 and parts[1] in other_layers else 'mppi'

    for line, parts, forward in namespaces(text):
        name = '::'.join(parts)
        if parts[0] in THIRD_PARTY:
            continue
        if folder in CORE:
            if parts[0] != 'mppi':
                problems.append(f'{path}:{line}: namespace {name} in core folder {folder}/ '
                                f'(the core folders {"/, ".join(sorted(CORE))}/ declare namespace mppi)')
            elif len(parts) > 1 and parts[1] in other_layers:
                problems.append(f'{path}:{line}: namespace {name} in core folder {folder}/ '
                                f'(it is the namespace of {parts[1]}/; core declares namespace mppi)')
            continue
        if parts[:2] == ['mppi', folder]:
            continue
        # Forward declarations of a lower layer's types (class Controller; in namespace mppi),
        # and the bare `namespace mppi {` around `namespace <folder> {`, are not code of this
        # folder in another namespace.
        of = owner(parts)
        if forward and of is not None and rank.get(of, 0) < rank[folder]:
            continue
        problems.append(f'{path}:{line}: namespace {name} in {folder}/ (its code is in '
                        f'namespace mppi::{folder} or one nested in it; other namespaces only '
                        f'for forward declarations of a lower layer\'s types)')
    return problems


# ---- the checks ---------------------------------------------------------------------------------
def check(root):
    """All problems of the tree at root, and a summary of what was checked."""
    rank = {f: i for i, f in enumerate(LAYERS)}
    present = tree_folders(root)
    layered = [f for f in LAYERS if f in present]
    scanned = layered + [f for f in TOP if f in present]
    problems = []
    edges = collections.defaultdict(list)  # (from folder, to folder) -> [file:line]
    files = 0
    names = collections.defaultdict(list)
    for folder in scanned:
        for path in source_files(root, folder):
            files += 1
            if folder in rank:
                names[path.rsplit('/', 1)[-1]].append(path)
            with open(os.path.join(root, path), encoding='utf-8', errors='replace') as f:
                text = f.read()
            for number, line in enumerate(text.split('\n'), 1):
                m = INCLUDE.match(line)
                if not m or '/' not in m.group(1):
                    continue
                target = m.group(1).split('/', 1)[0]
                if target not in present:
                    continue  # not a folder of the tree: a generated or third-party header
                if target != folder:
                    edges[(folder, target)].append(f'{path}:{number}')
                if folder not in rank or target == folder:
                    continue
                if target not in rank:
                    kind = 'a program folder' if target in TOP else 'a folder outside the layers'
                    problems.append(f'{path}:{number}: includes "{m.group(1)}": {target}/ is {kind}; '
                                    f'{folder}/ (layer {rank[folder]}) may include only layers below it')
                elif rank[target] > rank[folder]:
                    problems.append(f'{path}:{number}: includes "{m.group(1)}": {target}/ (layer '
                                    f'{rank[target]}) is above {folder}/ (layer {rank[folder]})')
            if folder in rank:
                problems.extend(namespace_problems(path, text, folder))
    for (a, b), where in sorted(edges.items()):
        if a < b and (b, a) in edges:
            problems.append(f'{a}/ and {b}/ include each other: {a} -> {b} at {where[0]}'
                            f'{" (and %d more)" % (len(where) - 1) if len(where) > 1 else ""}; '
                            f'{b} -> {a} at {edges[(b, a)][0]}'
                            f'{" (and %d more)" % (len(edges[(b, a)]) - 1) if len(edges[(b, a)]) > 1 else ""}')
    for name, paths in sorted(names.items()):
        if len(paths) > 1:
            problems.append(f'{", ".join(paths)}: the same file name {name} twice in the layered folders')
    summary = (f'{files} files in {len(scanned)} folders; layers, bottom first: {" < ".join(layered)}; '
               f'programs on top: {", ".join(f for f in TOP if f in present)}; '
               f'{len(edges)} folder-to-folder include edges')
    return problems, summary


def self_test():
    """Plant one fault of each kind in a small tree; every one must be caught."""
    files = {
        'base/error.hpp': '#pragma once\nnamespace mppi {\nstruct Error {};\n}  // namespace mppi\n',
        'mppi/controller.hpp': '#pragma once\n#include "base/error.hpp"\n#include "sim/track.hpp"\n'
                               'namespace mppi {\n}\n',  # upward: mppi -> sim
        'sim/track.hpp': '#pragma once\n#include "base/error.hpp"\n#include "chassis/arbiter.hpp"\n'
                         'namespace mppi::sim {\nstruct Track {};\n}\n',
        'chassis/arbiter.hpp': '#pragma once\n#include "sim/track.hpp"\n'  # sim <-> chassis
                               'namespace mppi {\nstruct Arbiter {};\n}\n'  # wrong namespace
                               'namespace mppi { class Controller; namespace plot { class Figure; } }\n',
        'dynamics/effects.hpp': '#pragma once\nnamespace mppi {\n}\n',
        'evidence/effects.hpp': '#pragma once\nnamespace mppi { namespace evidence {\n} }\n',  # doubled name
        # these are fine and must not be reported
        'costs/cost.hpp': '#pragma once\n#include "base/error.hpp"\nnamespace YAML { class Node; }\n'
                          'namespace mppi {\nnamespace detail {\n}\nnamespace {\n}\n}\n'
                          'const char* s = R"x(namespace wrong { )x";\n',
        'plot/figure.cpp': '#include "base/error.hpp"\nnamespace {\nint f() { return 0; }\n}\n'
                           'namespace mppi::plot::detail {\n}\n',
        'apps/main.cpp': '#include "evidence/effects.hpp"\n#include "sim/track.hpp"\nnamespace app {\n}\n',
    }
    expected = {
        'upward include': lambda p: 'mppi/controller.hpp:3' in p and 'above mppi/' in p,
        'two-way pair': lambda p: 'chassis/ and sim/ include each other' in p,
        'wrong namespace': lambda p: 'chassis/arbiter.hpp:3: namespace mppi in chassis/' in p,
        'doubled name': lambda p: 'same file name effects.hpp' in p,
    }
    with tempfile.TemporaryDirectory() as root:
        for path, text in files.items():
            os.makedirs(os.path.dirname(os.path.join(root, path)), exist_ok=True)
            with open(os.path.join(root, path), 'w', encoding='utf-8') as f:
                f.write(text)
        problems, _ = check(root)
    ok = True
    for what, caught in expected.items():
        hits = [p for p in problems if caught(p)]
        print(f'self-test: {what}: {"caught" if hits else "MISSED"}')
        ok &= bool(hits)
    unexpected = [p for p in problems if not any(c(p) for c in expected.values())]
    # the pair's other half, chassis -> sim, is an upward include as well
    unexpected = [p for p in unexpected if not p.startswith('chassis/arbiter.hpp:2:')]
    for p in unexpected:
        print(f'self-test: reported what is allowed: {p}')
    ok &= not unexpected
    print('self-test: OK' if ok else 'self-test: FAILED')
    return 0 if ok else 1


def main(argv):
    if '--self-test' in argv[1:]:
        return self_test()
    args = [a for a in argv[1:] if not a.startswith('-')]
    root = args[0] if args else '.'
    problems, summary = check(root)
    for p in problems:
        print(p)
    if problems:
        print(f'check_layers: FAILED, {len(problems)} problem(s) ({summary})')
        return 1
    print(f'check_layers: OK ({summary})')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
