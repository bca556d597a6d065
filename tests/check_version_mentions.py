#!/usr/bin/env python3
"""Checks that the documents state the versions the code has. Two versions, not to be confused:
the library's (ECRF_VERSION_* in include/ecrf/decoder.h, from which CMake takes the project version
and the SONAME) and the bitstream's (kVersionMajor.kVersionMinor in format/container.h, with
SPEC.md's own document version beside it). Each statement below must be found, and must name the
current version; prints each mismatch and exits 1.

    check_version_mentions.py SOURCE_DIR
"""
import os
import re
import sys


def read(root, path):
    with open(os.path.join(root, path), encoding='utf-8') as f:
        return f.read()


def library_version(root):
    header = read(root, 'include/ecrf/decoder.h')
    return [int(re.search(rf'^#define ECRF_VERSION_{part} (\d+)$', header, re.M).group(1))
            for part in ('MAJOR', 'MINOR', 'PATCH')]


def bitstream_version(root):
    container = read(root, 'format/container.h')
    return [int(re.search(rf'constexpr uint8_t kVersion{part} = (\d+);', container).group(1))
            for part in ('Major', 'Minor')]


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..')
    major, minor, _ = library_version(root)
    soversion = f'0.{minor}' if major == 0 else f'{major}'  # before 1.0 a minor release breaks ABI
    bitstream = '.'.join(map(str, bitstream_version(root)))
    spec = read(root, 'SPEC.md')
    document = re.search(r'^# .*, version ([0-9.]+) of this document', spec, re.M)
    document = document.group(1) if document else '(no version in the title of SPEC.md)'

    # (file, pattern whose group 1 is a version, what it must be, every match or the first only)
    mentions = [
        ('docs/embedding.md', r'SONAME `libecrf_decoder\.so\.([0-9.]+)`', soversion, 'all'),
        ('examples/CMakeLists.txt', r'find_package\(ecrf ([0-9.]+) ', f'{major}.{minor}', 'all'),
        ('SPEC.md', r'the bitstream is at version ([0-9.]+)\)', bitstream, 'all'),
        ('SPEC.md', r'\| version_major \| u8 \| (\d+) for this specification', bitstream.split('.')[0],
         'all'),
        # The newest entry of the change history (section 9) is this document and this bitstream.
        ('SPEC.md', r'^\*\*([0-9.]+) of this document\*\*', document, 'first'),
        ('SPEC.md', r'^\*\*[0-9.]+ of this document\*\* \((?:bitstream version|the bitstream is '
                    r'unchanged at version) ([0-9.]+)', bitstream, 'first'),
        ('SPEC.md', r'^\(1\.1 to ([0-9.]+); the bitstream', document, 'all'),
        ('tools/cmd_conformance.cc', r'"SPEC\.md ([0-9.]+)"', document, 'all'),
        ('tests/conformance/manifest.json', r'"spec": "SPEC\.md ([0-9.]+)"', document, 'all'),
    ]
    failures = 0
    for path, pattern, expected, which in mentions:
        found = re.findall(pattern, read(root, path), re.M)
        if which == 'first':
            found = found[:1]
        if not found:
            print(f'FAIL: {path}: no statement matching /{pattern}/ (reworded? update this check)')
            failures += 1
        for version in found:
            if version != expected:
                print(f'FAIL: {path}: states {version} where /{pattern}/ must name {expected}')
                failures += 1
    if failures:
        return 1
    print(f'{len(mentions)} version statements agree: library {major}.{minor} (SONAME '
          f'.so.{soversion}), bitstream {bitstream}, SPEC.md {document}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
