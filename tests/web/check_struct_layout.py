#!/usr/bin/env python3
"""Checks the C struct layout that the web viewer writes by hand (the LAYOUT table of
web/viewer.js) against include/ecrf/decoder.h. Each offset and size of the table becomes a static
assertion compiled for wasm32 (clang --target=wasm32, or emcc), so the header and the compiler's
ABI decide, not a second table; and every field the viewer reads or writes (INFO.name, ...) must
be in the table. Prints each difference and exits 1; exits 77 (ctest: skipped) when no compiler
here targets wasm32.

    check_struct_layout.py SOURCE_DIR [VIEWER_JS]    (VIEWER_JS: default SOURCE_DIR/web/viewer.js)
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

SKIPPED = 77


def read_layout(js):
    """{struct: {field or 'sizeof': bytes}} from `const LAYOUT = {...};`, and the problems."""
    m = re.search(r'^\s*const LAYOUT = \{\n(.*?)^\s*\};', js, re.S | re.M)
    if not m:
        return {}, ['no `const LAYOUT = {...};` table']
    layout, problems = {}, []
    for struct, body in re.findall(r'(\w+): \{(.*?)\}', m.group(1), re.S):
        fields = layout.setdefault(struct, {})
        for item in filter(None, (i.strip() for i in body.split(','))):
            entry = re.fullmatch(r'(\w+): (\d+)', item)
            if entry:
                fields[entry.group(1)] = int(entry.group(2))
            else:
                problems.append(f'{struct}: `{item}` is not `field: bytes`')
    return layout, problems


def unknown_uses(js, layout):
    """Fields used through an alias (const INFO = LAYOUT.ecrf_scene_info) that the table lacks."""
    aliases = dict(re.findall(r'\b(\w+) = LAYOUT\.(\w+)', js))
    problems = []
    for alias, struct in aliases.items():
        if struct not in layout:
            problems.append(f'{alias} = LAYOUT.{struct}: no such struct in the table')
            continue
        for field in sorted(set(re.findall(rf'\b{alias}\.(\w+)', js))):
            if field not in layout[struct]:
                problems.append(f'{alias}.{field}: {struct} has no {field} in the table')
    return problems


def assertions(layout):
    lines = ['#include <stddef.h>', '#include "ecrf/decoder.h"']
    for struct, fields in layout.items():
        for field, value in fields.items():
            expr = f'sizeof({struct})' if field == 'sizeof' else f'offsetof({struct}, {field})'
            lines.append(f'_Static_assert({expr} == {value}, '
                         f'"web/viewer.js: {struct} {field} {value} is not the header\'s");')
    return '\n'.join(lines) + '\n'


def wasm32_compilers():
    if shutil.which('clang'):
        yield ['clang', '--target=wasm32', '-ffreestanding']
    if shutil.which('emcc'):
        yield ['emcc']


def compile_for_wasm32(source, include_dir):
    """(compiler, diagnostics or '') for the first compiler that targets wasm32; (None, '') if none."""
    with tempfile.TemporaryDirectory() as tmp:
        probe, checks = os.path.join(tmp, 'probe.c'), os.path.join(tmp, 'layout.c')
        with open(probe, 'w') as f:
            f.write('_Static_assert(sizeof(void*) == 4 && _Alignof(unsigned long long) == 8, "");\n')
        with open(checks, 'w') as f:
            f.write(source)
        for cc in wasm32_compilers():
            run = lambda path: subprocess.run(cc + ['-std=c99', '-fsyntax-only', '-I', include_dir,
                                                    path], capture_output=True, text=True)
            if run(probe).returncode != 0:
                continue
            result = run(checks)
            return cc[0], (result.stdout + result.stderr) if result.returncode else ''
    return None, ''


def main():
    root = sys.argv[1]
    viewer = sys.argv[2] if len(sys.argv) > 2 else os.path.join(root, 'web', 'viewer.js')
    with open(viewer, encoding='utf-8') as f:
        js = f.read()
    layout, problems = read_layout(js)
    problems += unknown_uses(js, layout)
    for struct in ['ecrf_scene_info', 'ecrf_camera', 'ecrf_render_options', 'ecrf_scene_field']:
        if 'sizeof' not in layout.get(struct, {}):
            problems.append(f'{struct}: the table has no sizeof')
    compiler, diagnostics = compile_for_wasm32(assertions(layout), os.path.join(root, 'include'))
    if compiler is None and not problems:
        print('skipped: neither clang --target=wasm32 nor emcc is installed')
        return SKIPPED
    if diagnostics:
        problems.append(f'{compiler} for wasm32 disagrees with the table:\n{diagnostics}')
    for p in problems:
        print(f'FAIL: {viewer}: {p}')
    if problems:
        return 1
    count = sum(len(fields) for fields in layout.values())
    print(f'web/viewer.js: {count} offsets and sizes of {len(layout)} structs match decoder.h '
          f'on wasm32 ({compiler})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
