#!/usr/bin/env python3
"""The docs check (make test, rostest docs_check): what README.md, CHANGELOG.md, docs/ and the package
READMEs name must exist today.

  - a link [text](path) to a file of the repository, and a path in `code` that names a file or folder of
    the repository (config/..., launch/..., scripts/..., src/..., docs/..., bags/..., results/ is made by
    the tools and not checked);
  - `make TARGET`: a target of the Makefile;
  - `roslaunch launch/X.launch arg:=value`: the launch file, and each arg declared in it (or in the files
    it includes);
  - `rosrun PKG NAME`: a script or executable of that package (its scripts/ folder, or an executable its
    CMakeLists.txt builds);
  - generated tables current: scripts/settings_tables.py --check;
  - sizes: README.md at most 400 lines of at most 200 characters, each package README (src/*/README.md)
    at most 300 lines, docs/PERFORMANCE.md at most 500 lines.
Prints each problem with its file and line; exits 1 when there is any.

    scripts/docs/check_docs.py [FILE.md ...]      (default: every doc of the workspace)
"""
import pathlib
import re
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

ROOT = pathlib.Path(__file__).resolve().parents[2]
CHECKED_ROOTS = ("config/", "launch/", "scripts/", "src/", "docs/", "bags/", ".ci/")
LINK = re.compile(r"\[[^\]]*\]\(([^)#\s]+)(#[^)]*)?\)")
CODE = re.compile(r"`([^`\n]+)`")
MAKE = re.compile(r"\bmake ([a-z][a-z0-9_-]*)")
ROSLAUNCH = re.compile(r"roslaunch (?:-p \S+ )?(\S+\.launch)((?: +[A-Za-z_][A-Za-z0-9_]*:=\S*)*)")
ROSRUN = re.compile(r"rosrun ([a-z_][a-z0-9_]*) ([A-Za-z0-9_.-]+)")
PATH_TOKEN = re.compile(r"^[A-Za-z0-9_./*-]+$")
# (file relative to the root, or a glob of them) -> (most lines, longest line in characters or None)
SIZE_LIMITS = {"README.md": (400, 200), "src/*/README.md": (300, None), "docs/PERFORMANCE.md": (500, None)}


def docs():
    files = [ROOT / "README.md", ROOT / "CHANGELOG.md"] + sorted((ROOT / "docs").rglob("*.md"))
    files += sorted(ROOT.glob("src/*/README.md")) + sorted(ROOT.glob("bags/README.md"))
    files += sorted(ROOT.glob("scripts/*/README.md"))
    return [f for f in files if f.is_file()]


def make_targets():
    text = (ROOT / "Makefile").read_text()
    return set(re.findall(r"^([a-z][a-z0-9_-]*):", text, re.M))


def launch_args(path):
    """The args a launch file declares at its top level (those of the files it includes are its own to set)."""
    return {a.get("name") for a in ElementTree.parse(path).getroot().findall("arg")}


def package_programs(package):
    pkg = ROOT / "src" / package
    if not pkg.is_dir():
        return None
    names = {p.name for p in (pkg / "scripts").glob("*")} if (pkg / "scripts").is_dir() else set()
    cmake = "\n".join(p.read_text() for p in [pkg / "CMakeLists.txt"] + list((pkg / "cmake").glob("*.cmake")) if p.is_file())
    names |= set(re.findall(r"add_executable\(\s*([A-Za-z0-9_]+)", cmake))
    names |= {pathlib.Path(p).name for p in re.findall(r"catkin_install_python\(PROGRAMS ([^)]*)\)", cmake) for p in p.split()}
    return names


def existing(token, doc):
    """Does a path-like token name something in the repository (relative to the root or to the doc)?"""
    token = token.rstrip("/.,;:")
    if "*" in token:
        return any(ROOT.glob(token)) or any(doc.parent.glob(token))
    return (ROOT / token).exists() or (doc.parent / token).exists()


def shown(doc):
    """The doc's path as a problem names it: relative to the root when it is inside the workspace."""
    try:
        return str(doc.relative_to(ROOT))
    except ValueError:
        return str(doc)


def size_problems(doc, lines):
    problems = []
    for pattern, (most_lines, longest) in SIZE_LIMITS.items():
        if not any(doc == match.resolve() for match in ROOT.glob(pattern)):
            continue
        if len(lines) > most_lines:
            problems.append("%s: %d lines, at most %d" % (shown(doc), len(lines), most_lines))
        for number, line in enumerate(lines, 1):
            if longest is not None and len(line) > longest:
                problems.append("%s:%d: %d characters, at most %d" % (shown(doc), number, len(line), longest))
    return problems


def check_file(doc, targets):
    lines = doc.read_text().splitlines()
    problems = size_problems(doc, lines)
    in_code_block = False
    for number, line in enumerate(lines, 1):
        if line.strip().startswith("```"):
            in_code_block = not in_code_block
        where = "%s:%d" % (shown(doc), number)
        for link, _ in LINK.findall(line):
            if not re.match(r"[a-z]+://|mailto:", link) and not existing(link, doc):
                problems.append("%s: link to %s: no such file" % (where, link))
        code = "\n".join(CODE.findall(line)) if not in_code_block else line
        tokens = code.split()
        for token in tokens:
            if token.startswith(CHECKED_ROOTS) and PATH_TOKEN.match(token.rstrip("/.,;:")) and not existing(token, doc):
                problems.append("%s: %s: no such file or folder" % (where, token))
        for target in MAKE.findall(code):
            if target not in targets:
                problems.append("%s: make %s: no such target in the Makefile" % (where, target))
        for launch, args in ROSLAUNCH.findall(code):
            path = ROOT / launch if (ROOT / launch).is_file() else doc.parent / launch
            if not path.is_file():
                problems.append("%s: roslaunch %s: no such launch file" % (where, launch))
                continue
            declared = launch_args(path)
            for arg in re.findall(r"([A-Za-z_][A-Za-z0-9_]*):=", args):
                if arg not in declared:
                    problems.append("%s: roslaunch %s %s:=: no such arg" % (where, launch, arg))
        for package, program in ROSRUN.findall(code):
            programs = package_programs(package)
            if programs is not None and program not in programs:
                problems.append("%s: rosrun %s %s: no such program in the package" % (where, package, program))
    return problems


def check(files):
    """Every problem of these docs, and of the generated settings tables."""
    targets = make_targets()
    problems = []
    for doc in files:
        problems += check_file(doc, targets)
    tables = subprocess.run([sys.executable, str(ROOT / "scripts" / "settings_tables.py"), "--check"],
                            capture_output=True, text=True)
    if tables.returncode != 0:
        problems.append("settings tables not current: %s" % tables.stdout.strip())
    return problems


def main():
    files = [pathlib.Path(a).resolve() for a in sys.argv[1:]] or docs()
    problems = check(files)
    for problem in problems:
        print(problem)
    print("check_docs: %d files, %d problems" % (len(files), len(problems)))
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
