#!/usr/bin/env python3
"""Checks the layering: the estimator libraries (slam, shadow, bayes, motion) know no image and write
no file.

In libs/<mod>/src and libs/<mod>/include of those four modules (the tests may use what they need):
  - no #include of OpenCV (<opencv2/...>, <opencv/...>) and no use of the cv:: namespace;
  - no #include of the front end or of a higher module (immslam/frontend, tracking, system, app, viz,
    io, sim, eval);
  - no file output: no <fstream>, std::ofstream / fstream, fopen, imwrite, MRPT's CFileOutputStream /
    CFileGZOutputStream.
In libs/<mod>/CMakeLists.txt, the library's own link dependencies (immslam_add_library and
target_link_libraries of immslam_<mod>) name no OpenCV (OpenCV_LIBS, opencv_*) and none of the modules
above. Comments and string literals are not searched for calls.

Usage: share/scripts/audit-layering.py [--root DIR]     audit the tree at DIR (default: this project)
       share/scripts/audit-layering.py --self-test      plant violations in temporary copies of the four
                                                        modules and check that each one is reported
Exit status 1 with one "file:line: what" line per violation.
"""
import argparse
import pathlib
import re
import shutil
import sys
import tempfile

from cxx_source import blank

MODULES = ("slam", "shadow", "bayes", "motion")
HIGHER = ("frontend", "tracking", "system", "app", "viz", "io", "sim", "eval")
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]')
FORBIDDEN_INCLUDES = [
    (re.compile(r"^opencv2?/"), "includes OpenCV"),
    (re.compile(r"^immslam/(%s)/" % "|".join(HIGHER)), "includes a module above the estimators"),
    (re.compile(r"^fstream$"), "includes <fstream> (file output)"),
]
FORBIDDEN_CODE = [
    (re.compile(r"\bcv::"), "uses OpenCV (cv::)"),
    (re.compile(r"\b(std::)?o?fstream\b"), "file stream (file output)"),
    (re.compile(r"\bfopen\s*\("), "fopen (file output)"),
    (re.compile(r"\bimwrite\s*\("), "imwrite (file output)"),
    (re.compile(r"\bCFile(GZ)?OutputStream\b"), "MRPT file output stream"),
]
FORBIDDEN_LINKS = [
    (re.compile(r"OpenCV_LIBS|\bopencv_\w+", re.I), "links OpenCV"),
    (re.compile(r"\bimmslam::(%s)\b" % "|".join(HIGHER)), "links a module above the estimators"),
]


def audit_sources(root, mod):
    found = []
    for sub in ("src", "include"):
        base = root / "libs" / mod / sub
        if not base.is_dir():
            continue
        for f in sorted(base.rglob("*")):
            if not f.is_file() or f.suffix not in (".h", ".hpp", ".cpp", ".cc", ".cxx", ".ipp"):
                continue
            text = f.read_text(errors="replace")
            rel = f.relative_to(root)
            for no, line in enumerate(text.split("\n"), 1):
                m = INCLUDE.match(line)
                if m:
                    for pat, what in FORBIDDEN_INCLUDES:
                        if pat.search(m.group(1)):
                            found.append(f"{rel}:{no}: {what}: {line.strip()}")
            for no, line in enumerate(blank(text).split("\n"), 1):
                if INCLUDE.match(line):
                    continue
                for pat, what in FORBIDDEN_CODE:
                    if pat.search(line):
                        found.append(f"{rel}:{no}: {what}: {line.strip()}")
    return found


def library_calls(text, mod):
    """(first line, text) of the calls that define the library's own link dependencies."""
    heads = re.compile(r"\b(immslam_add_library\s*\(\s*%s\b|target_link_libraries\s*\(\s*immslam_%s\b)" % (mod, mod))
    for m in heads.finditer(text):
        depth, j = 0, text.index("(", m.start())
        for k in range(j, len(text)):
            depth += {"(": 1, ")": -1}.get(text[k], 0)
            if depth == 0:
                yield text.count("\n", 0, m.start()) + 1, text[m.start() : k + 1]
                break


def audit_cmake(root, mod):
    f = root / "libs" / mod / "CMakeLists.txt"
    if not f.is_file():
        return [f"{f.relative_to(root)}:1: missing"]
    text = re.sub(r"#[^\n]*", "", f.read_text())
    found = []
    for first, call in library_calls(text, mod):
        for off, line in enumerate(call.split("\n")):
            for pat, what in FORBIDDEN_LINKS:
                if pat.search(line):
                    found.append(f"{f.relative_to(root)}:{first + off}: {what}: {line.strip()}")
    return found


def audit(root):
    found = []
    for mod in MODULES:
        found += audit_sources(root, mod)
        found += audit_cmake(root, mod)
    return found


def self_test(root):
    """Each planted violation must be reported with its file and line; the clean copy must pass."""
    plants = [
        ("libs/slam/src/planted.cpp", "// comment: cv::Mat and std::ofstream are fine here\n#include <opencv2/core.hpp>\n", 2, "OpenCV"),
        ("libs/shadow/include/immslam/shadow/planted.h", "#pragma once\n#include <immslam/frontend/frontend.h>\n", 2, "above"),
        ("libs/bayes/src/planted.cpp", "#include <cstdio>\nvoid f() {\n  const char* s = \"fopen(\";\n  fopen(s, \"w\");\n}\n", 4, "fopen"),
        ("libs/motion/src/planted.cpp", "void g() {\n  std::ofstream out(\"x\");\n}\n", 2, "file stream"),
        ("libs/slam/include/immslam/slam/planted.h", "#pragma once\n#include <fstream>\n", 2, "fstream"),
        ("libs/shadow/src/planted.cpp", "void h(cv::Mat& m);\n", 1, "cv::"),
    ]
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        copy = pathlib.Path(tmp)
        for mod in MODULES:
            shutil.copytree(root / "libs" / mod, copy / "libs" / mod,
                            ignore=shutil.ignore_patterns("tests", "build*"))
        clean = audit(copy)
        if clean:
            print("self-test: the unmodified copy is not clean:\n  " + "\n  ".join(clean))
            ok = False
        for path, text, line, word in plants:
            p = copy / path
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_text(text)
            hits = [h for h in audit(copy) if h.startswith(f"{path}:{line}:") and word in h]
            if len(hits) != 1 or len(audit(copy)) != 1:
                print(f"self-test: planted violation {path}:{line} ({word}) reported as {audit(copy)}")
                ok = False
            p.unlink()
        cm = copy / "libs" / "shadow" / "CMakeLists.txt"
        original = cm.read_text()
        cm.write_text(original.replace("PUBLIC_DEPS", "PUBLIC_DEPS ${OpenCV_LIBS} immslam::frontend", 1))
        hits = audit(copy)
        whats = sorted(h.split(": ")[1] for h in hits if h.startswith("libs/shadow/CMakeLists.txt:4:"))
        if len(hits) != 2 or whats != ["links OpenCV", "links a module above the estimators"]:
            print(f"self-test: planted link dependency reported as {hits}")
            ok = False
        cm.write_text(original + "\n# immslam::frontend in a comment is fine\n"
                      "immslam_add_test(t SOURCES tests/t.cpp DEPS immslam::tracking)\n")
        if audit(copy):
            print(f"self-test: a test's dependency or a comment was reported: {audit(copy)}")
            ok = False
    print("self-test: " + ("every planted violation reported, the clean tree passes" if ok else "FAILED"))
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parents[2])
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    root = a.root.resolve()
    if a.self_test:
        return 0 if self_test(root) else 1
    found = audit(root)
    for f in found:
        print(f)
    print(f"audit-layering: {len(found)} violation(s) in libs/{{{','.join(MODULES)}}}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
