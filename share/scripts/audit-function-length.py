#!/usr/bin/env python3
"""Lists the functions of libs/ longer than MAX_FUNCTION_LINES and the source files longer than
MAX_FILE_LINES, except those in the allow-lists below (each with its reason).

A simple brace-matching scanner, no C++ parser: comments, string and character literals are blanked
out, then every '{' outside a function body is classified by the text before it (back to the last
';', '{' or '}'): a function body when that text holds a '(' and is not a namespace, class, struct,
union or enum head, a control statement or an initializer ('=' outside parentheses). The length of
a function is the number of lines from its opening to its closing brace, both included; lambdas and
blocks inside a function count towards it. The function's name is the identifier (with its
qualification) before the first '(' of its head.

Usage: share/scripts/audit-function-length.py [--list N] [paths...]
  paths    files or folders to scan (default: libs/ of the project); tests are never scanned
  --list N print the N longest functions (and the number over the limit) instead of checking
Exit status 1 if a function or file not allowed is over its limit. An allow-list entry that matches
nothing over the limit (any more) is reported, so the list shrinks when a function is split.
"""
import pathlib
import re
import sys

from cxx_source import blank

MAX_FUNCTION_LINES = 80
MAX_FILE_LINES = 600
SUFFIXES = {".cpp", ".h", ".hpp", ".cc"}

# Functions allowed over MAX_FUNCTION_LINES: (path relative to the project, qualified name, reason).
# Tables and data initialisers go here by name, each with its reason. None is needed today.
ALLOWED_FUNCTIONS = []

# Source files allowed over MAX_FILE_LINES: (path, reason).
ALLOWED_FILES = []

CLASS_HEAD = re.compile(r"^\s*(template\s*<.*>\s*)?(namespace|class|struct|union|enum)\b", re.S)
CONTROL = re.compile(r"^\s*(if|for|while|switch|catch|do|else|try)\b")
NAME = re.compile(r"((?:~?[A-Za-z_]\w*\s*(?:<[^()]*>)?\s*::\s*)*(?:operator\s*[^\s(]+|~?[A-Za-z_]\w*))\s*\($")


def blank_preprocessor(text):
    """The text with preprocessor lines (and their continuation lines) replaced by spaces."""
    out, cont = [], False
    for line in text.split("\n"):
        if cont or line.lstrip().startswith("#"):
            cont = line.rstrip().endswith("\\")
            out.append(" " * len(line))
        else:
            out.append(line)
    return "\n".join(out)


def is_function_head(head):
    h = head.strip()
    if "(" not in h or CLASS_HEAD.match(h) or CONTROL.match(h):
        return False
    depth = 0
    for c in h:
        depth += c == "("
        depth -= c == ")"
        if c == "=" and depth == 0:
            return False  # an initializer (a table), or a lambda assigned at namespace scope
    return True


def function_name(head):
    h = re.sub(r"\s+", " ", head.strip())
    depth, cut = 0, None
    for k, c in enumerate(h):
        if c == "(" and depth == 0:
            cut = k
            break
        depth += c == "<"
        depth -= c == ">"
    m = NAME.search(h[: cut + 1]) if cut is not None else None
    return re.sub(r"\s+", "", m.group(1)) if m else "?"


def functions(src):
    """(name, first line, number of lines) of every function body outside another one."""
    text = blank_preprocessor(blank(src))
    stack = []  # one entry per open brace: True for a function body
    head_start, out, start_line = 0, [], 0
    line = 1
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == "{":
            in_function = any(stack)
            is_fn = not in_function and is_function_head(text[head_start:i])
            if is_fn:
                start_line, name = line, function_name(text[head_start:i])
            stack.append(is_fn)
            head_start = i + 1
        elif c == "}":
            if stack and stack.pop():
                out.append((name, start_line, line - start_line + 1))
            head_start = i + 1
        elif c == ";":
            head_start = i + 1
    return out


def scan(paths, root):
    files = []
    for p in paths:
        p = pathlib.Path(p).resolve()
        found = [p] if p.is_file() else sorted(q for q in p.rglob("*") if q.suffix in SUFFIXES)
        files += [q for q in found if "tests" not in q.relative_to(root).parts and not q.name.endswith("_unittest.cpp")]
    return files


def main(argv):
    root = pathlib.Path(__file__).resolve().parents[2]
    listing = None
    if len(argv) >= 2 and argv[0] == "--list":
        listing, argv = int(argv[1]), argv[2:]
    paths = argv or [root / "libs"]
    rows, long_files = [], []
    for f in scan(paths, root):
        rel = f.resolve().relative_to(root).as_posix()
        src = f.read_text(errors="replace")
        n = src.count("\n")
        if n > MAX_FILE_LINES:
            long_files.append((rel, n))
        rows += [(length, rel, name, first) for name, first, length in functions(src)]
    rows.sort(reverse=True)
    over = [r for r in rows if r[0] > MAX_FUNCTION_LINES]
    if listing is not None:
        print(f"{len(over)} functions over {MAX_FUNCTION_LINES} lines; {len(long_files)} files over {MAX_FILE_LINES}")
        for length, rel, name, first in rows[:listing]:
            print(f"{length:5d}  {rel}:{first}  {name}")
        for rel, n in long_files:
            print(f"file {rel}: {n} lines")
        return 0
    allowed_fn = {(p, n) for p, n, _ in ALLOWED_FUNCTIONS}
    allowed_file = {p for p, _ in ALLOWED_FILES}
    bad = 0
    for length, rel, name, first in over:
        if (rel, name) not in allowed_fn:
            print(f"{rel}:{first}: {name} has {length} lines (limit {MAX_FUNCTION_LINES}): split it")
            bad += 1
    for rel, n in long_files:
        if rel not in allowed_file:
            print(f"{rel}: {n} lines (limit {MAX_FILE_LINES}): split it")
            bad += 1
    if not argv:
        # Entries that match nothing over the limit any more are stale: reported, to be removed.
        seen_fn = {(rel, name) for _, rel, name, _ in over}
        for p, n, _ in ALLOWED_FUNCTIONS:
            if (p, n) not in seen_fn:
                print(f"note: allow-list entry {p} {n} is not over {MAX_FUNCTION_LINES} lines (any more): remove it")
        seen_file = {rel for rel, _ in long_files}
        for p, _ in ALLOWED_FILES:
            if p not in seen_file:
                print(f"note: allow-list entry {p} is not over {MAX_FILE_LINES} lines (any more): remove it")
    allowed = sum(1 for _, rel, name, _ in over if (rel, name) in allowed_fn)
    print(f"{len(over)} functions over {MAX_FUNCTION_LINES} lines ({allowed} allowed), {len(long_files)} files over "
          f"{MAX_FILE_LINES}; {bad} problem(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
