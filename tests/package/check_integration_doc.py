#!/usr/bin/env python3
"""package.integration_doc_matches_example: docs/integration.md shows the example's
code as it is, so that the guide compiles as written.

Usage: check_integration_doc.py DOC EXAMPLE_DIR SUBPROJECT_CMAKELISTS

Rules: the ```cpp blocks of DOC, in order, joined with one blank line between
them, are exactly EXAMPLE_DIR/main.cpp; the first ```cmake block is exactly
EXAMPLE_DIR/CMakeLists.txt; any later ```cmake block (the FetchContent way in)
appears verbatim in SUBPROJECT_CMAKELISTS, which the package.fetchcontent_subproject
test builds. Exit status 1 naming the first difference otherwise.
"""
import difflib
import pathlib
import re
import sys


def fenced_blocks(text, language):
    """Contents of the ```<language> fenced blocks of a Markdown text, in order."""
    pattern = re.compile(r"^```" + re.escape(language) + r"[ \t]*\n(.*?)^```[ \t]*$",
                         re.MULTILINE | re.DOTALL)
    return [m.group(1) for m in pattern.finditer(text)]


def compare(shown, actual, doc, path):
    if shown == actual:
        return True
    diff = difflib.unified_diff(actual.splitlines(), shown.splitlines(),
                                fromfile=str(path), tofile=f"{doc} (code blocks)", lineterm="")
    print(f"{doc}: its code differs from {path}:", file=sys.stderr)
    print("\n".join(list(diff)[:40]), file=sys.stderr)
    return False


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    doc = pathlib.Path(sys.argv[1])
    example = pathlib.Path(sys.argv[2])
    subproject = pathlib.Path(sys.argv[3])
    text = doc.read_text(encoding="utf-8")
    cpp = fenced_blocks(text, "cpp")
    cmake = fenced_blocks(text, "cmake")
    if len(cpp) < 2 or not cmake:
        print(f"{doc}: expected the example split over several ```cpp blocks and its "
              f"```cmake block, found {len(cpp)} and {len(cmake)}", file=sys.stderr)
        return 1
    ok = compare("\n".join(cpp), (example / "main.cpp").read_text(encoding="utf-8"), doc,
                 example / "main.cpp")
    ok &= compare(cmake[0], (example / "CMakeLists.txt").read_text(encoding="utf-8"), doc,
                  example / "CMakeLists.txt")
    tested = subproject.read_text(encoding="utf-8")
    for block in cmake[1:]:
        if block not in tested:
            print(f"{doc}: this CMake block is not in {subproject}:\n{block}", file=sys.stderr)
            ok = False
    if ok:
        print(f"{doc}: {len(cpp)} C++ blocks = main.cpp, CMake blocks = CMakeLists.txt "
              f"and {len(cmake) - 1} excerpt(s) of {subproject.name}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
