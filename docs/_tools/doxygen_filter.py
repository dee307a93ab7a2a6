"""Doxygen's INPUT_FILTER for the headers: turns their plain comments into doc comments.

capi/minkq.h, capi/minkq_async.h and mpi/minkq_mpi.h document every declaration in ordinary C comments (a block
before a declaration, a trailing one after a member or enumerator). Doxygen reads only doc
comments, so this filter, run on each header as Doxygen reads it, marks them: the first
comment becomes the file's description, a comment that starts a line documents what follows,
a comment after code on its line documents that code. Section rules (`/* ---- Name ---- */`)
and comments on preprocessor lines stay plain. The headers themselves are not changed.

capi/minkq.hpp (C++) does the same with `//` comments: a run of leading `//` lines documents
what follows (the first run describes the file), a trailing `//` documents its line's code;
section rules (`// ----`, with their continuation lines), `// NOLINT` or `// namespace`
remarks and lines holding a string literal (whose `//` may be inside it) stay plain.
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
        elif TRAILING.match(line) and not line.lstrip().startswith(("*", "#")):  # not `#endif /* GUARD */`
            yield TRAILING.sub(r"\1/**< ", line, count=1)
        else:
            yield line


CXX_SECTION = re.compile(r"^\s*// -{3,}")
CXX_LEADING = re.compile(r"^(\s*)//(?![/!])")
CXX_TRAILING = re.compile(r"^(\s*\S.*?)//(?![/!<])(?!\s*(NOLINT|namespace\b))")


def cxx_doc_comments(lines):
    first, in_section = True, False
    for line in lines:
        if CXX_SECTION.match(line):
            in_section = True
            yield line
        elif CXX_LEADING.match(line):
            if not in_section:
                yield CXX_LEADING.sub(r"\1/// \\file\n\1///" if first else r"\1///", line, count=1)
                first = False
            else:
                yield line
        else:
            in_section = False
            yield CXX_TRAILING.sub(r"\1///<", line, count=1) if '"' not in line else line


if __name__ == "__main__":
    with open(sys.argv[1], encoding="utf-8") as header:
        sys.stdout.writelines((cxx_doc_comments if sys.argv[1].endswith(".hpp") else doc_comments)(header))
