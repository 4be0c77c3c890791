#!/usr/bin/env python3
"""Lists the gtest cases (TEST / TEST_F / TEST_P) whose body contains no assertion.

A body counts as asserting if it holds an EXPECT_* / ASSERT_* / FAIL() / ADD_FAILURE() / GTEST_SKIP
(a skip is reported apart), or calls a helper defined in the same file whose body asserts (one level
of helpers, found by name). Trivially-true assertions (EXPECT_TRUE(true), SUCCEED()) do not count.
DISABLED_ tests are listed apart: ctest registers them as disabled and never runs them.

Usage: share/scripts/audit-assertions.py [paths...]   (default: every tests folder of the project)
Exit status 1 if any assertion-free test is found.
"""
import pathlib
import re
import sys

ASSERT = re.compile(r"\b(EXPECT_[A-Z_0-9]+|ASSERT_[A-Z_0-9]+|FAIL|ADD_FAILURE|ADD_FAILURE_AT)\s*\(")
TRIVIAL = re.compile(r"\b(EXPECT_TRUE|ASSERT_TRUE)\s*\(\s*true\s*\)|\b(EXPECT_FALSE|ASSERT_FALSE)\s*\(\s*false\s*\)|\bSUCCEED\s*\(\s*\)")
TEST = re.compile(r"^\s*(TEST|TEST_F|TEST_P)\s*\(\s*(\w+)\s*,\s*(\w+)\s*\)", re.M)
FUNC = re.compile(r"^[ \t]*(?:[\w:<>,&*\s]+?)\b(\w+)\s*\([^;{}]*\)\s*(?:const\s*)?(?:->[^{;]*)?\{", re.M)


def strip_comments(s):
    s = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), s, flags=re.S)
    s = re.sub(r"//[^\n]*", "", s)
    return s


def body_at(s, start):
    """The text between the brace at or after start and its match."""
    i = s.index("{", start)
    depth = 0
    for j in range(i, len(s)):
        if s[j] == "{":
            depth += 1
        elif s[j] == "}":
            depth -= 1
            if depth == 0:
                return s[i + 1 : j]
    return s[i + 1 :]


def asserts(text):
    return bool(ASSERT.search(TRIVIAL.sub("", text)))


def audit(path):
    s = strip_comments(path.read_text(errors="replace"))
    tests = [(m.start(), m.group(2) + "." + m.group(3)) for m in TEST.finditer(s)]
    test_starts = {p for p, _ in tests}
    helpers = set()  # names of non-test functions in this file whose bodies assert
    for m in FUNC.finditer(s):
        if m.start() in test_starts or m.group(1) in ("if", "for", "while", "switch", "catch"):
            continue
        try:
            if asserts(body_at(s, m.end() - 1)):
                helpers.add(m.group(1))
        except ValueError:
            pass
    out = []
    for pos, name in tests:
        b = body_at(s, pos)
        if asserts(b):
            continue
        called = {c for c in re.findall(r"\b(\w+)\s*\(", b)} & helpers
        if called:
            continue
        kind = "skip-only" if "GTEST_SKIP" in b else "no assertion"
        if ".DISABLED_" in name or name.startswith("DISABLED_"):
            kind = "disabled, not run by ctest"
        out.append((name, kind))
    return out


def main():
    root = pathlib.Path(__file__).resolve().parents[2]
    args = sys.argv[1:] or [str(p) for p in sorted(root.glob("libs/*/tests"))] + [str(root / "tests")]
    files = []
    for a in args:
        p = pathlib.Path(a)
        files += sorted(p.rglob("*_unittest.cpp")) if p.is_dir() else [p]
    bad = 0
    for f in files:
        for name, kind in audit(f):
            print(f"{f.relative_to(root) if f.is_absolute() and root in f.parents else f}: {name} ({kind})")
            bad += kind != "disabled, not run by ctest"
    print(f"{bad} assertion-free test(s) in {len(files)} file(s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
