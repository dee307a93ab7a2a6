"""Doxygen's INPUT_FILTER for the C headers: turns their plain comments into doc comments.

capi/minkq.h and mpi/minkq_mpi.h document every declaration in ordinary C comments (a block
before a declaration, a trailing one after a member or enumerator). Doxygen reads only doc
comments, so this filter, run on each header as Doxygen reads it, marks them: the first
comment becomes the file's description, a comment that starts a line documents what follows,
a comment after code on its line documents that code. Section rules (`/* ---- Name ---- */`)
stay plain. The headers themselves are not changed.
"""
import re
import sys

SECTION = re.compile(r"^\s*/\* -{3,}")
LEADING = re.compile(r"^(\s*)/\*(?![*!])")
TRAILING = re.compile(r"^(\s*\S.*?)/\*(?![*!<])")


def doc_comments(lines):
    first = True
    for line in lines:
        if SECTION.match(line):
            yield line
        elif LEADING.match(line):
            yield LEADING.sub(r"\1/*! \\file " if first else r"\1/** ", line, count=1)
            first = False
        elif TRAILING.match(line) and not line.lstrip().startswith("*"):
            yield TRAILING.sub(r"\1/**< ", line, count=1)
        else:
            yield line


if __name__ == "__main__":
    with open(sys.argv[1], encoding="utf-8") as header:
        sys.stdout.writelines(doc_comments(header))
