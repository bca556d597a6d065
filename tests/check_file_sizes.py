#!/usr/bin/env python3
"""Checks the project's size rule: no source file over 600 lines. A file that long holds more than
one concern; split it by concern. Reads every C, C++, JavaScript, Python and shell file under the
root, build outputs aside (tests/source_files.py).

    check_file_sizes.py [ROOT]

Prints each file over the limit as FILE: N lines (limit 600), and exits 1 if there is any."""
import os
import sys

from source_files import source_files

MAX_LINES = 600
SOURCE_SUFFIXES = ('.c', '.cc', '.cpp', '.h', '.hpp', '.inc', '.js', '.mjs', '.cjs', '.py', '.sh')


def oversized(root):
    """(path, line count) of every source file over MAX_LINES lines."""
    found = []
    for path in source_files(root, SOURCE_SUFFIXES):
        with open(os.path.join(root, path), 'rb') as f:
            lines = sum(1 for _ in f)
        if lines > MAX_LINES:
            found.append((path, lines))
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..')
    found = oversized(root)
    for path, lines in found:
        print(f'{path}: {lines} lines (limit {MAX_LINES})')
    print(f'{len(found)} file(s) over {MAX_LINES} lines' if found else
          f'every source file within {MAX_LINES} lines')
    return 1 if found else 0


if __name__ == '__main__':
    sys.exit(main())
