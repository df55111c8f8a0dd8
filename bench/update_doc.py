#!/usr/bin/env python3
"""Replaces one named section of docs/benchmarks.md (between BEGIN/END markers) with new text.

Usage: update_doc.py SECTION FILE_WITH_MARKDOWN   (or '-' for stdin)
Each benchmark script owns one section, so they can run in any order.
"""
import pathlib
import sys

DOC = pathlib.Path(__file__).resolve().parent.parent / "docs" / "benchmarks.md"
HEADER = (
    "# Benchmarks\n\n"
    "Every figure here was measured by the scripts in `bench/`, zeroset and the peer tools side by "
    "side in one run on the same machine (2 cores). Times are medians of repeated runs; compare the "
    "ratios, not the absolute times. Each section names the command that regenerates it.\n"
)


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    name, src = sys.argv[1], sys.argv[2]
    body = sys.stdin.read() if src == "-" else pathlib.Path(src).read_text()
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    block = f"{begin}\n{body.rstrip()}\n{end}"
    text = DOC.read_text() if DOC.exists() else HEADER
    if begin in text and end in text:
        head, rest = text.split(begin, 1)
        _, tail = rest.split(end, 1)
        text = head + block + tail
    else:
        text = text.rstrip() + "\n\n" + block + "\n"
    DOC.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
