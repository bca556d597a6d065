"""The source files of a tree, for the checks run over it (check_layers.py, check_file_sizes.py,
check_function_size.py): every file with one of the given suffixes, build outputs aside (the
folders .gitignore names at the root: build*, run*, out*; any folder holding a CMakeCache.txt),
and hidden folders and node_modules too."""
import os

BUILD_OUTPUTS = ('build', 'run', 'out')


def source_files(root, suffixes):
    """Paths relative to root, '/'-separated and sorted, of the files whose names end with one of
    `suffixes`."""
    found = []
    for dirpath, dirnames, files in os.walk(root):
        if os.path.samefile(dirpath, root):
            dirnames[:] = [d for d in dirnames if not d.startswith(BUILD_OUTPUTS)]
        elif 'CMakeCache.txt' in files:
            dirnames[:] = []
            continue
        dirnames[:] = [d for d in dirnames if not d.startswith('.') and d != 'node_modules']
        for name in files:
            if name.endswith(tuple(suffixes)):
                path = os.path.relpath(os.path.join(dirpath, name), root)
                found.append(path.replace(os.sep, '/'))
    return sorted(found)
