#!/usr/bin/env python3
"""Fails when an x86-only construct appears in our sources outside an x86 guard, so that the
workspace keeps building on arm64 (docs/ARM64.md).

C/C++ (*.c, *.cc, *.cpp, *.h, *.hpp): includes of the x86 intrinsic headers (*intrin.h, cpuid.h),
_mm_* / __m128 / __m256 / __m512 names, __builtin_ia32_*, __builtin_cpu_supports, inline asm and
target("sse...")-style attributes are allowed only inside a preprocessor branch whose condition
requires an x86 macro (__SSE2__, __x86_64__, __AVX2__, ...), or the #else of one that excludes it.
CMake (CMakeLists.txt, *.cmake): -msse*, -mavx*, -mfma, -march=native and the like are allowed only
inside an if() on CMAKE_SYSTEM_PROCESSOR matching an x86 name.

Prints file:line for each offence and exits 1 when there is any. With --junit FILE it also writes a
JUnit result (one test case, failing with the list) for `make test`; --self-test first checks the
checker itself on small temporary files (one more test case each).
"""
import argparse
import pathlib
import re
import sys
import tempfile
import xml.etree.ElementTree as ET

CPP_SUFFIXES = {".c", ".cc", ".cpp", ".cxx", ".h", ".hh", ".hpp", ".hxx"}
SKIP_DIRS = {"build", "devel", "install", ".git"}

X86_MACRO = r"(?:__SSE\w*__|__AVX\w*__|__FMA\w*__|__BMI\w*__|__POPCNT__|__F16C__|__MMX__|__x86_64__|__x86_64|" \
            r"__amd64__|__amd64|__i386__|__i386|_M_X64|_M_AMD64|_M_IX86)"
CPP_PATTERNS = [
    (re.compile(r"#\s*include\s*[<\"]\s*(\w*intrin\.h|cpuid\.h)\s*[>\"]"), "x86 intrinsics header"),
    (re.compile(r"\b_mm(?:256|512)?_\w+"), "x86 SIMD intrinsic"),
    (re.compile(r"\b__m(?:64|128|256|512)[id]?\b"), "x86 SIMD type"),
    (re.compile(r"\b__builtin_ia32_\w+"), "x86 builtin"),
    (re.compile(r"\b__builtin_cpu_(?:supports|init|is)\b"), "x86 CPU dispatch builtin"),
    (re.compile(r"(?:\b__asm__|\b__asm\b|\basm)\s*(?:volatile\b|__volatile__)?\s*[({]"), "inline assembly"),
    (re.compile(r"\btarget\s*\(\s*\"[^\"]*\b(?:sse|avx|fma|bmi|popcnt|f16c|arch=)", re.I), "x86 target attribute"),
]
CMAKE_FLAG = re.compile(r"(?<![\w-])-m(?:sse\w*|avx\w*|fma\w*|bmi\w*|popcnt|f16c|mmx|arch=native|tune=native|"
                        r"arch=x86[-\w]*|arch=i\d86)\b")


def strip_cpp_comments(text):
    """Blanks // and /* */ comments (keeping the newlines, so line numbers stay right)."""
    out, i, n = [], 0, len(text)
    while i < n:
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("".join(c if c == "\n" else " " for c in text[i:j]))
            i = j
        elif text[i] in "\"'":  # a literal: copied as is, so that "//" inside one is no comment
            quote, j = text[i], i + 1
            while j < n and text[j] != quote and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(text[i:j + 1])
            i = j + 1
        else:
            out.append(text[i])
            i += 1
    return "".join(out)


def _term_is_x86(term):
    term = term.strip().strip("()").strip()
    return re.fullmatch(r"(?:defined\s*\(?\s*)?" + X86_MACRO + r"\s*\)?", term) is not None


def condition_kind(cond):
    """'x86' if the condition holds only on x86, 'not-x86' if it is just the negation of an x86
    macro (its #else is then x86-only), None otherwise. Simple on purpose: a || of terms each
    requiring x86, or a && with at least one such term."""
    cond = cond.strip()
    negated = re.fullmatch(r"!\s*(.+)", cond)
    if negated and "&&" not in cond and "||" not in cond and _term_is_x86(negated.group(1)):
        return "not-x86"
    disjuncts = cond.split("||")
    if all(any(_term_is_x86(t) for t in d.split("&&") if not t.strip().startswith("!")) for d in disjuncts):
        return "x86"
    return None


def scan_cpp(path, text):
    offences = []
    stack = []  # per open #if: [guarded now?, kind of the first condition]
    lines = strip_cpp_comments(text).split("\n")
    k = 0
    while k < len(lines):
        line_no, line = k + 1, lines[k]
        while line.endswith("\\") and k + 1 < len(lines):  # continued directive
            k += 1
            line = line[:-1] + " " + lines[k]
        k += 1
        directive = re.match(r"\s*#\s*(ifdef|ifndef|if|elif|else|endif)\b(.*)", line)
        if directive:
            word, rest = directive.group(1), directive.group(2)
            if word == "ifdef":
                kind = "x86" if _term_is_x86(rest) else None
                stack.append([kind == "x86", kind])
            elif word == "ifndef":
                kind = "not-x86" if _term_is_x86(rest) else None
                stack.append([False, kind])
            elif word == "if":
                kind = condition_kind(rest)
                stack.append([kind == "x86", kind])
            elif word == "elif" and stack:
                stack[-1] = [condition_kind(rest) == "x86", None]
            elif word == "else" and stack:
                stack[-1] = [stack[-1][1] == "not-x86", None]
            elif word == "endif" and stack:
                stack.pop()
        if any(guarded for guarded, _ in stack):
            continue
        for pattern, what in CPP_PATTERNS:
            match = pattern.search(line)
            if match:
                offences.append(f"{path}:{line_no}: {what} outside an x86 guard: {match.group(0).strip()}")
                break
    return offences


def scan_cmake(path, text):
    offences = []
    stack = []  # per open if(): guarded now?
    for line_no, raw in enumerate(text.split("\n"), 1):
        line = re.sub(r"#.*", "", raw)
        command = re.match(r"\s*(if|elseif|else|endif)\s*\((.*)", line, re.I)
        if command:
            word, rest = command.group(1).lower(), command.group(2)
            x86 = "CMAKE_SYSTEM_PROCESSOR" in rest and re.search(r"x86|amd64|i[3-6x]86", rest, re.I) is not None \
                and not re.search(r"\bNOT\b", rest)
            if word == "if":
                stack.append(x86)
            elif word == "elseif" and stack:
                stack[-1] = x86
            elif word == "else" and stack:
                stack[-1] = False
            elif word == "endif" and stack:
                stack.pop()
        if any(stack):
            continue
        match = CMAKE_FLAG.search(line)
        if match:
            offences.append(f"{path}:{line_no}: x86-only compiler flag outside an x86 if(): {match.group(0)}")
    return offences


def scan_file(path, shown):
    text = path.read_text(encoding="utf-8", errors="replace")
    if path.suffix in CPP_SUFFIXES:
        return scan_cpp(shown, text)
    if path.name == "CMakeLists.txt" or path.suffix == ".cmake":
        return scan_cmake(shown, text)
    return []


def scan_tree(root):
    offences, count = [], 0
    for path in sorted(root.rglob("*")):
        if not path.is_file() or SKIP_DIRS & set(path.relative_to(root).parts):
            continue
        if path.suffix in CPP_SUFFIXES or path.name == "CMakeLists.txt" or path.suffix == ".cmake":
            count += 1
            offences += scan_file(path, path.relative_to(root.parent))
    return offences, count


# Self-test: (name, file name, content, line numbers that must be flagged).
SELF_TESTS = [
    ("flags_unguarded_intrinsic", "a.cpp",
     "#include <emmintrin.h>\nint f() {\n  __m128i v = _mm_add_epi32(_mm_setzero_si128(), _mm_setzero_si128());\n"
     "  return _mm_cvtsi128_si32(v);\n}\n", [1, 3, 4]),
    ("passes_guarded_intrinsic", "b.cpp",
     "// _mm_add_epi32 in a comment is fine\n#if defined(__SSE2__)\n#include <emmintrin.h>\n"
     "int f() { return _mm_cvtsi128_si32(_mm_add_epi32(_mm_setzero_si128(), _mm_setzero_si128())); }\n"
     "#else\nint f() { return 0; }\n#endif\n", []),
    ("else_of_negated_guard", "c.h",
     "#ifndef __x86_64__\nint g() { return _mm_popcnt_u32(3); }\n#else\nint g() { return _mm_popcnt_u32(3); }\n"
     "#endif\n#if defined(__aarch64__) || defined(__SSE2__)\n__m128i h;\n#endif\n", [2, 7]),
    ("cmake_flags", "CMakeLists.txt",
     "add_compile_options(-Wall -march=native)\nif(CMAKE_SYSTEM_PROCESSOR MATCHES \"x86_64|AMD64\")\n"
     "  add_compile_options(-mavx2)\nelse()\n  add_compile_options(-msse4.2)\nendif()\n", [1, 5]),
]


def run_self_tests():
    """Returns [(name, failure message or None)]."""
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, file_name, content, expected in SELF_TESTS:
            path = pathlib.Path(tmp) / name / file_name
            path.parent.mkdir()
            path.write_text(content)
            found = scan_file(path, path.name)
            lines = sorted({int(o.split(":")[1]) for o in found})
            problem = None if lines == expected else \
                f"expected offences on lines {expected}, found {lines}:\n" + "\n".join(found)
            results.append((name, problem))
    return results


def write_junit(path, cases):
    suite = ET.Element("testsuite", name="check_portable", tests=str(len(cases)),
                       failures=str(sum(1 for _, p in cases if p)), errors="0")
    for name, problem in cases:
        case = ET.SubElement(suite, "testcase", classname="check_portable", name=name)
        if problem:
            first, _, rest = problem.partition("\n")
            failure = ET.SubElement(case, "failure", message=first)
            failure.text = rest  # test_summary.py prints the message, then this
    path.parent.mkdir(parents=True, exist_ok=True)
    ET.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=str(pathlib.Path(__file__).resolve().parent.parent / "src"),
                        help="folder to scan (default: the workspace's src/)")
    parser.add_argument("--junit", help="also write a JUnit XML result to this file")
    parser.add_argument("--self-test", action="store_true", help="first check the checker on temporary files")
    args = parser.parse_args()

    cases = []
    if args.self_test:
        for name, problem in run_self_tests():
            cases.append(("self_test_" + name, problem))
            if problem:
                print(f"check_portable: self-test {name} FAILED: {problem}")
    root = pathlib.Path(args.root).resolve()
    offences, count = scan_tree(root)
    for offence in offences:
        print(offence)
    problem = None
    if count == 0:
        problem = f"no C++ or CMake files under {root}"
    elif offences:
        problem = f"{len(offences)} x86-only constructs outside an x86 guard:\n" + "\n".join(offences)
    cases.append(("src_has_no_unguarded_x86_constructs", problem))
    failed = [name for name, p in cases if p]
    print(f"check_portable: {count} files scanned, {len(offences)} offences"
          + (f", self-test failures: {len(failed) - (1 if problem else 0)}" if args.self_test else ""))
    if args.junit:
        write_junit(pathlib.Path(args.junit), cases)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
