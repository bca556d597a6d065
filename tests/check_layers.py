#!/usr/bin/env python3
"""Checks that every #include "..." in the sources respects ecrf's layers: data flows one way,
images -> trainer -> encoder -> bytes -> decoder -> pixels, and each folder includes only the
folders below it (no decoder file sees an encoder or trainer header). Prints each violation as
FILE:LINE: folder may not include HEADER, and exits 1 if there is any."""
import os
import re
import sys

# folder -> the folders its files may include (its own is always allowed)
ALLOWED = {
    'format': [],
    'decoder': ['format', 'include'],
    'trainer/data': ['format', 'decoder'],
    'trainer/model': ['format', 'decoder', 'trainer/data'],
    'encoder': ['format', 'decoder', 'trainer/data', 'trainer/model'],
    'trainer/scenes': ['format', 'decoder', 'trainer/data'],
    'trainer/rate': ['format', 'decoder', 'trainer/data', 'trainer/model', 'encoder'],
    'trainer/train': ['format', 'decoder', 'include', 'trainer/model', 'encoder', 'trainer/data',
                      'trainer/scenes', 'trainer/rate'],
    # The conformance command rebuilds the vectors that tests/common describes.
    'tools': ['format', 'decoder', 'include', 'trainer', 'encoder', 'tests/common'],
    'python': ['include', 'format', 'decoder'],
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def folder_of(path):
    for folder in sorted(ALLOWED, key=len, reverse=True):
        if path == folder or path.startswith(folder + '/'):
            return folder
    return None


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..')
    errors = 0
    for top in ['format', 'decoder', 'encoder', 'trainer', 'tools', 'python']:
        for dirpath, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if not name.endswith(('.h', '.cc')):
                    continue
                path = os.path.relpath(os.path.join(dirpath, name), root)
                folder = folder_of(path)
                allowed = [folder] + ALLOWED[folder]
                with open(os.path.join(root, path), encoding='utf-8') as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        header = m.group(1)
                        target = 'include' if header.startswith('ecrf/') else header
                        if not any(target == a or target.startswith(a + '/') for a in allowed):
                            print(f'{path}:{number}: {folder}/ may not include {header}')
                            errors += 1
    print(f'{errors} layering violation(s)' if errors else 'layers respected')
    return 1 if errors else 0


if __name__ == '__main__':
    sys.exit(main())
