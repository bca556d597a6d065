#!/usr/bin/env python3
"""Checks that every #include of a project header respects ecrf's layers: data flows one way,
images -> trainer -> encoder -> bytes -> decoder -> pixels, and each folder includes only the
folders below it (no decoder file sees an encoder or trainer header).

Reads every C and C++ file (.c .cc .cpp .h .hpp .inc) under the root, build outputs aside
(tests/source_files.py). A file in a folder that has no rule below is an error too, so a new
folder cannot go unchecked. Includes count whether quoted or in angle brackets (system headers
aside) and whether written from the root or relative to the file.

    check_layers.py [ROOT]

Prints each violation as FILE:LINE: folder/ may not include HEADER, and exits 1 if there is any."""
import os
import re
import sys

from source_files import source_files

SOURCE_SUFFIXES = ('.c', '.cc', '.cpp', '.h', '.hpp', '.inc')
# What the trainer and the command-line tools build on.
_TRAINER = ['format', 'decoder', 'include', 'trainer', 'encoder']
# folder -> the folders its files may include (its own is always allowed); `include` is the
# public C API (<ecrf/...>). The most specific folder of a file applies.
ALLOWED = {
    'include': [],
    'format': [],
    'decoder': ['format', 'include'],
    # The conformance vectors and costly streams, built from the format alone; the tests and the
    # `ecrf conformance` command both use them.
    'conformance': ['format', 'decoder'],
    'trainer/data': ['format', 'decoder'],
    'trainer/model': ['format', 'decoder', 'trainer/data'],
    # The encoder codes a format-level scene description; the trainer describes its model so.
    'encoder': ['format', 'decoder'],
    'trainer/scenes': ['format', 'decoder', 'trainer/data'],
    'trainer/rate': ['format', 'decoder', 'trainer/data', 'trainer/model', 'encoder'],
    'trainer/train': ['format', 'decoder', 'include', 'trainer/model', 'encoder', 'trainer/data',
                      'trainer/scenes', 'trainer/rate'],
    'tools': _TRAINER + ['conformance'],
    # The project's own benchmark programs. The decoder timing program times what a user's C
    # program does, so it shares the C example's helpers (reading and decoding a stream file, the
    # orbit camera) rather than copy them; the budget cost program times the costly streams that
    # `ecrf bench budgets` and the tests use.
    'benchmarks': _TRAINER + ['examples', 'conformance'],
    'python': ['include', 'format', 'decoder'],
    # Programs a user builds against an installed ecrf: the C API and the trainer library only.
    'examples': ['include', 'trainer'],
    # Tests see every layer they test, and their own helpers.
    'tests': _TRAINER + ['conformance', 'tools', 'python'],
}
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def folder_of(path):
    for folder in sorted(ALLOWED, key=len, reverse=True):
        if path == folder or path.startswith(folder + '/'):
            return folder
    return None


def included_path(root, path, bracket, header):
    """The root-relative path an #include names, or None for a system header."""
    if header.startswith('ecrf/'):
        return 'include/' + header
    beside = os.path.normpath(os.path.join(os.path.dirname(path), header)).replace(os.sep, '/')
    if bracket == '"' and not os.path.exists(os.path.join(root, header)) \
            and os.path.exists(os.path.join(root, beside)):
        return beside
    top = header.split('/', 1)[0]
    if bracket == '<' and ('/' not in header or not os.path.isdir(os.path.join(root, top))):
        return None
    return os.path.normpath(header).replace(os.sep, '/')


def violations(root):
    """(path, line number, message) of every include that breaks the layers."""
    found = []
    for path in source_files(root, SOURCE_SUFFIXES):
        folder = folder_of(path)
        if folder is None:
            found.append((path, 1, f'{os.path.dirname(path) or "."}/ has no layer rule in '
                                   f'tests/check_layers.py'))
            continue
        allowed = [folder] + ALLOWED[folder]
        with open(os.path.join(root, path), encoding='utf-8') as f:
            for number, line in enumerate(f, 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                target = included_path(root, path, m.group(1), m.group(2))
                if target is None:
                    continue
                if not any(target == a or target.startswith(a + '/') for a in allowed):
                    found.append((path, number, f'{folder}/ may not include {m.group(2)}'))
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..')
    errors = violations(root)
    for path, number, message in errors:
        print(f'{path}:{number}: {message}')
    print(f'{len(errors)} layering violation(s)' if errors else 'layers respected')
    return 1 if errors else 0


if __name__ == '__main__':
    sys.exit(main())
