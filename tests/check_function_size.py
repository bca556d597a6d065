#!/usr/bin/env python3
"""Checks the project's function size rule: no function over 120 lines. A function that long
does more than one thing; split it into functions that each do one. Reads every C and C++ file
under the root, build outputs aside (tests/source_files.py), with Universal Ctags, which gives
each function's (and lambda's) first and last line.

    check_function_size.py [ROOT]

Table code is exempt: a function that is one long table (test vectors, a switch that maps each
recorded call to its replay) is listed in ROOT/tests/function_size_exemptions.txt, one
`PATH FUNCTION  # why` a line. An exemption that names no function over the limit is stale and
fails the check, so the list shrinks as the tables do.

Prints each function over the limit as PATH:LINE: NAME is N lines (limit 120), each stale
exemption, and exits 1 if there is any; exits 77 (a skip) where Universal Ctags is missing."""
import os
import shutil
import subprocess
import sys

from source_files import source_files

MAX_LINES = 120
SOURCE_SUFFIXES = ('.c', '.cc', '.cpp', '.h', '.hpp', '.inc')
EXEMPTIONS = 'tests/function_size_exemptions.txt'
SKIP = 77
# Functions and lambdas only, in C and C++ (.h files as C++; .inc files, which ctags would not
# read, too), each with its line and end line; --excmd=number keeps source text (tabs and all)
# out of the output, so every field splits on tabs.
CTAGS_ARGS = ['--languages=C,C++', '--langmap=C++:+.inc', '--kinds-C=f', '--kinds-C++=f',
              '--fields=+ne', '--excmd=number', '--sort=no', '-L', '-', '-f', '-']
# The fields in which ctags names what a tag lies in (at most one per tag).
SCOPE_KINDS = ('function', 'class', 'struct', 'union', 'namespace')


def ctags_missing():
    """Why Universal Ctags cannot be run (another ctags lacks the end lines), or None."""
    if shutil.which('ctags') is None:
        return 'ctags is not installed (Debian: universal-ctags)'
    version = subprocess.run(['ctags', '--version'], capture_output=True, text=True).stdout
    if 'Universal Ctags' not in version:
        return 'ctags is not Universal Ctags (Debian: universal-ctags), so gives no end lines'
    return None


def display_name(name, scope):
    """The name a report shows: ctags names a lambda __anon<hash>, so it is shown as a lambda in
    the function or namespace around it."""
    if not name.startswith('__anon'):
        return name
    named = [part for part in scope.split('::') if part and not part.startswith('__anon')]
    return f'lambda in {named[-1] if named else "file scope"}'


def functions(root):
    """(path, line, name, line count) of every function and lambda in the tree's C and C++ files."""
    paths = source_files(root, SOURCE_SUFFIXES)
    run = subprocess.run(['ctags'] + CTAGS_ARGS, cwd=root, input='\n'.join(paths) + '\n',
                         capture_output=True, text=True, check=True)
    found = []
    for tag in run.stdout.splitlines():
        name, path, _, *extension_fields = tag.split('\t')
        fields = dict(f.split(':', 1) for f in extension_fields if ':' in f)
        if 'line' not in fields or 'end' not in fields:
            continue
        line, end = int(fields['line']), int(fields['end'])
        scope = next((fields[kind] for kind in SCOPE_KINDS if kind in fields), '')
        found.append((path, line, display_name(name, scope), end - line + 1))
    return found


def read_exemptions(root):
    """{(path, function name): why} from the exemptions file (none where it is absent); a line
    not of the form `PATH FUNCTION  # why` is returned in the second list."""
    exemptions, malformed = {}, []
    try:
        with open(os.path.join(root, EXEMPTIONS), encoding='utf-8') as f:
            lines = f.read().splitlines()
    except FileNotFoundError:
        return exemptions, malformed
    for number, text in enumerate(lines, 1):
        entry, _, why = text.partition('#')
        if not entry.strip():
            continue
        words = entry.split()
        if len(words) != 2 or not why.strip():
            malformed.append(f'{EXEMPTIONS}:{number}: expected `PATH FUNCTION  # why`: {text}')
            continue
        exemptions[tuple(words)] = why.strip()
    return exemptions, malformed


def check(root):
    """The check's findings, one printable line each: the functions over MAX_LINES lines that no
    exemption names, the stale exemptions, and the malformed exemption lines."""
    exemptions, findings = read_exemptions(root)
    oversized = [f for f in functions(root) if f[3] > MAX_LINES]
    for path, line, name, lines in oversized:
        if (path, name) not in exemptions:
            findings.append(f'{path}:{line}: {name} is {lines} lines (limit {MAX_LINES})')
    still_oversized = {(path, name) for path, _, name, _ in oversized}
    for path, name in exemptions:
        if (path, name) not in still_oversized:
            findings.append(f'{EXEMPTIONS}: {path} {name} is not over {MAX_LINES} lines '
                            '(stale exemption: remove it)')
    return findings


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..')
    missing = ctags_missing()
    if missing:
        print(f'skipped: {missing}')
        return SKIP
    findings = check(root)
    for finding in findings:
        print(finding)
    print(f'{len(findings)} problem(s): functions over {MAX_LINES} lines or stale exemptions'
          if findings else f'every function within {MAX_LINES} lines, exemptions aside')
    return 1 if findings else 0


if __name__ == '__main__':
    sys.exit(main())
